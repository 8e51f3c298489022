"""Mode-level quantities of a meshed beam: the strain energy of an eigenvector by section
direction (the family labels of blade modes) and an element-level bound of the discrete
spectrum (to discard numerical eigenvalues).
"""

from __future__ import annotations

import numpy as np

from .beam import BeamElements

__all__ = ['FAMILIES', 'classify_energy', 'frequency_bound']


FAMILIES = ("axial", "shear", "shear", "torsion", "flap", "lag")


def frequency_bound(props) -> float:
    """Element-level upper estimate of the discrete spectrum [rad/s].

    Largest over elements of ``sqrt(stiffness / inertia) / h`` for the second-order
    mechanisms (torsion, rotary bending ``sqrt(EI_k / I_k)/h`` - the hourglass-like rotation
    modes of the linear element - axial and shear) and ``sqrt(EI_k / m) / h^2`` for
    translational bending, plus the shear cut-off ``sqrt(GA / I)``.  The genuine discrete
    eigenvalues found so far stay below about 1.2 times this; 100 times it is the band.
    """
    R = props.compliance
    mu = props.mass
    h = props.h
    diagR = np.diagonal(R, axis1=1, axis2=2)           # (N, 6)
    with np.errstate(divide="ignore"):
        stiff = np.where(diagR > 0, 1.0 / np.where(diagR > 0, diagR, 1.0), 0.0)
    m = mu[:, 0, 0]
    inertia = np.diagonal(mu[:, 3:, 3:], axis1=1, axis2=2)  # about the reference line
    cands = []
    tiny = 1e-300
    for k in range(3):                                  # torsion, flap, lag rotations
        cands.append(np.sqrt(stiff[:, 3 + k] / np.maximum(inertia[:, k], tiny)) / h)
        cands.append(np.sqrt(stiff[:, k] / np.maximum(m, tiny)) / h)            # axial/shear
    for k in (1, 2):
        cands.append(np.sqrt(stiff[:, 3 + k] / np.maximum(m, tiny)) / h ** 2)
        cands.append(np.sqrt(stiff[:, k] / np.maximum(inertia[:, 3 - k], tiny)))
    w = np.max(np.stack(cands, 0))
    return float(w) if np.isfinite(w) and w > 0 else np.inf


def classify_energy(beam: BeamElements, x: np.ndarray) -> np.ndarray:
    """Strain energy of an eigenvector ``x`` (one beam) by direction
    [axial, shear2, shear3, torsion, flap, lag] (compliance-weighted section loads)."""
    _, _, _, _, F, M = beam.nodal(x[None])
    A = beam.props.element_frames()                  # loads back to the section frames
    FM = np.concatenate([np.einsum("nji,nj->ni", A, F[0]),
                         np.einsum("nji,nj->ni", A, M[0])], -1)     # (N, 6) complex
    strain = np.einsum("nij,nj->ni", beam.props.compliance, FM)
    return (beam.h[:, None] * np.real(np.conj(FM) * strain)).sum(0)
