"""The vacuum modes of one blade on the hub spinning at the operating point's speed: the
reference that names a turbine's blade modes in wind (analyses/labels.py).

In wind the aerodynamic coupling mixes the blade's structural families: a cyclic torsion mode
of a large blade carries as much flap strain energy as torsion, a heavily damped flap mode
splits into two real roots, and counting the modes of a family in frequency order then gives
"7th forward-whirl flap" to a torsion mode.  HAWCStab2's users name an aeroelastic mode
after the structural mode it grew from; so does hawt: each blade mode in wind is named after
the vacuum mode (undamped, clamped on the hub spinning at the same speed, same pitch and mesh:
assembly.SpinningBlade) whose shape its blades take most,

    share_j = sum_k |phi_j^H x_k|^2 / |phi_j|^2 / sum_k |x_k|^2

(x_k the k-th blade's part of the mode's rotating-frame eigenvector, phi_j the vacuum mode;
both as the deflections u and twists theta_1 of the nodes weighted by the square roots of
their lumped mass and torsional inertia, so the product is the kinetic energy's, in which
the vacuum modes are nearly orthogonal): the share of the blades' motion along phi_j, a
mass-weighted modal assurance criterion summed over the blades (a cyclic mode's blades move
in the same shape with different phases).  The vacuum modes' families are their strain
energy's (fem/energy.py), counted in frequency order: the structural names of blade_modes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..assembly import SpinningBlade
from ..results.tables import ordinal
from .blade_modes import energy_names, spinning_modes

__all__ = ["BladeReference", "vacuum_blade_reference", "REFERENCE_MODES"]

#: How many of the vacuum blade's lowest modes name the modes in wind (a turbine's band of
#: 25-50 per-rev holds 10-20 blade modes).
REFERENCE_MODES = 40


@dataclass(frozen=True)
class BladeReference:
    """The vacuum blade modes: ``families`` and ``indices`` (e.g. "torsion", 1), their
    frequencies [Hz], ``shapes`` (m, J): the weighted rows (u and theta_1 of the nodes) of
    each mode, ``rows`` (m,) the rows' indices in a blade's block of unknowns and ``weights``
    (m,) their weights."""

    families: tuple
    indices: tuple
    frequencies_hz: np.ndarray
    shapes: np.ndarray
    rows: np.ndarray
    weights: np.ndarray

    def shares(self, blades: np.ndarray) -> np.ndarray:
        """(J,): the share of the blades' motion ``blades`` (Nb, m) (each blade's rows,
        weighted) along each vacuum mode (module docstring); zeros for no motion."""
        total = float(np.sum(np.abs(blades) ** 2))
        if not total > 0:
            return np.zeros(len(self.families))
        proj = blades.conj() @ self.shapes                              # (Nb, J)
        norms = np.sum(np.abs(self.shapes) ** 2, axis=0)
        return np.sum(np.abs(proj) ** 2, axis=0) / norms / total

    def name(self, j: int) -> str:
        """e.g. '1st torsion'."""
        return f"{ordinal(self.indices[j])} {self.families[j]}"


def _rows(model):
    """(rows, weights) of a blade's block: the nodes' u (1..N, 3 components) and theta_1,
    weighted by the square roots of the nodes' lumped mass and torsional inertia (the
    section tables' m and i1 times half the adjacent cells' lengths), so that the weighted
    product is the kinetic energy's: the vacuum modes are then nearly orthogonal in it."""
    lay = model.layout
    b, off = lay.blade(0), lay.blade_offset(0)
    blade = model.turbine.blade
    sec = blade.sections
    h = np.asarray(model.beam.h, float)
    s = np.concatenate([[0.0], np.cumsum(h)])[1:]                    # the nodes 1..N [m]
    length = np.concatenate([h[:-1] + h[1:], h[-1:]]) / 2             # lumped lengths [m]
    frac = s / s[-1]
    mass = np.interp(frac, sec.stations, sec.mass) * length
    inertia = np.interp(frac, sec.stations, sec.i1) * length
    u = np.asarray(b.u[1:]) - off                                    # (N, 3)
    th = np.asarray(b.theta[1:])[:, 0] - off
    rows = np.concatenate([u.ravel(), th])
    weights = np.concatenate([np.repeat(np.sqrt(mass), 3), np.sqrt(inertia)])
    return rows, weights


def vacuum_blade_reference(model, count: int = REFERENCE_MODES) -> BladeReference:
    """The vacuum modes of ``model``'s blade (a TurbineModel: its turbine, mesh, pitch and
    rotor speed), structural damping off, the ``count`` lowest oscillatory ones."""
    turbine = model.turbine.without_structural_damping()
    blade = SpinningBlade(turbine, model.beam.elements, model.rotor_speed)
    if blade.n != model.beam.n:
        raise ValueError(f"the vacuum blade has {blade.n} unknowns, the turbine's blade "
                         f"{model.beam.n}: not the same mesh")
    _, lam, X, order, _ = spinning_modes(blade, count, "auto", 100.0)
    # the oscillatory ones (an undamped blade has no real exponents in the band)
    order = order[np.abs(lam[order].imag) > 1e-3 * np.abs(lam[order])]
    lam, X = lam[order], X[:, order]
    families, indices = energy_names(blade.beam, X)
    rows, weights = _rows(model)
    return BladeReference(families=tuple(families), indices=tuple(indices),
                          frequencies_hz=np.abs(lam.imag) / (2 * np.pi),
                          shapes=X[rows] * weights[:, None], rows=rows, weights=weights)


def blade_motion(model, reference: BladeReference, x: np.ndarray) -> np.ndarray:
    """(Nb, m): each blade's weighted rows of the turbine's vector ``x`` (model's layout)."""
    offsets = [model.layout.blade_offset(k) for k in range(model.n_blades)]
    return np.stack([x[off + reference.rows] for off in offsets]) * reference.weights

