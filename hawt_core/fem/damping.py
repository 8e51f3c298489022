"""Structural damping of the beam elements (model.BeamDamping): the section operators both
discretizations add to their residual, and the conversion of modal damping ratios
(ElastoDyn's) into them.

The two viscous forms (docs/structural_damping.md):

- stiffness-proportional (Kelvin-Voigt, BeamDyn's ``mu``): the section loads carry a
  viscous part ``[F, M]_d = diag(mu) S d/dt[gamma, kappa]``.  The mixed elements hold the
  elastic section loads ``[F, M] = S [gamma, kappa]`` as unknowns in the deformed section's
  own components, so the strain rate is ``R d/dt[F, M]`` exactly and the viscous part is
  ``diag(mu) P d/dt[F, M]`` (P: the flexible directions; a rigid direction's load is a
  constraint force, undamped).  It enters the equilibrium rows where F, M do
  (``-int phi' F``), through the rates of the F, M unknowns: linear with constant
  coefficients, so dR/dydot stays constant.  Its products with the strains (``kappa x
  F_d``, ``gamma x F_d``) are second order in the small quantities and left out; it is zero
  in any rigid motion and in a steady state (objective: the rates are the material's).
- mass-proportional (HAWC2's m-terms): a distributed load ``-diag(alpha) mu_s v_rel`` with
  ``v_rel = [V - C (v + w x (x + u)), Omega - C w]``, the section's velocity relative to
  the beam's root frame (zero in a rigid rotation of the root frame, so a spinning rotor
  is not braked), algebraic in the unknowns.

Both in the section frame of the file's matrices, turned like them (prebend, sweep, pitch).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..model import MODAL_FAMILIES, BeamDamping

__all__ = ["DampingCoefficients", "section_operators", "plane_velocities"]

#: the section velocity components [v1, v2, v3, omega1, omega2, omega3] that bend in the
#: plane of each bending strain: kappa2 (about b2) moves u3 and turns about b2, kappa3
#: moves u2 and turns about b3
PLANE_VELOCITIES = {4: (2, 4), 5: (1, 5)}


def plane_velocities(strain: int) -> tuple:
    """The section velocity components of the bending plane of ``strain`` (4 or 5)."""
    return PLANE_VELOCITIES[strain]


@dataclass(frozen=True)
class DampingCoefficients:
    """Resolved damping of one beam: ``mu`` (6,) [s] per strain, ``alpha`` (6,) [1/s] per
    section velocity component (model.BeamDamping's two forms)."""

    mu: np.ndarray
    alpha: np.ndarray

    @classmethod
    def of(cls, damping: Optional[BeamDamping]) -> Optional["DampingCoefficients"]:
        """The explicit coefficients of ``damping`` (None when there is none); modal ratios
        are resolved by fem/damping_fit.py, not here."""
        if damping is None or not (any(damping.stiffness) or any(damping.mass)):
            return None
        return cls(np.asarray(damping.stiffness, float), np.asarray(damping.mass, float))

    def __add__(self, other: Optional["DampingCoefficients"]) -> "DampingCoefficients":
        if other is None:
            return self
        return DampingCoefficients(self.mu + other.mu, self.alpha + other.alpha)


def section_operators(coeffs: Optional[DampingCoefficients], compliance: np.ndarray,
                      mass_turned: np.ndarray, A6: Optional[np.ndarray]):
    """(mu_hat, alpha_mu) at P points: ``mu_hat`` (P, 6, 6) maps the section loads' rates
    to their viscous part, ``alpha_mu`` (P, 6, 6) the relative velocities to the
    mass-proportional load (both in the turned-b components the residual uses), each None
    when that form is zero.

    ``compliance`` (P, 6, 6) in the file's section frame (its zero rows are the rigid
    directions), ``mass_turned`` (P, 6, 6) the turned mass matrix, ``A6`` (P, 6, 6) the turn
    (None: the identity)."""
    if coeffs is None:
        return None, None
    turn = (lambda M: M) if A6 is None else (lambda M: A6 @ M @ A6.transpose(0, 2, 1))
    P = compliance.shape[0]
    mu_hat = alpha_mu = None
    if np.any(coeffs.mu):
        flexible = np.any(compliance != 0, axis=2)                      # (P, 6)
        diag = np.zeros((P, 6, 6))
        idx = np.arange(6)
        diag[:, idx, idx] = flexible * coeffs.mu[None, :]
        mu_hat = turn(diag)
    if np.any(coeffs.alpha):
        alpha_hat = turn(np.broadcast_to(np.diag(coeffs.alpha), (P, 6, 6)).copy())
        alpha_mu = alpha_hat @ mass_turned
    return mu_hat, alpha_mu


def modal_families(damping: Optional[BeamDamping]) -> dict:
    """{family: ratios} of ``damping.modal``, checked against model.MODAL_FAMILIES and
    for one or two ratios each (the family's first modes)."""
    if damping is None or not damping.modal:
        return {}
    out = {}
    for k, v in damping.modal.items():
        if k not in MODAL_FAMILIES:
            raise ValueError(f"damping.modal: family {k!r} is not allowed; allowed: "
                             f"{', '.join(MODAL_FAMILIES)}")
        out[k] = tuple(float(z) for z in v)
        if not 1 <= len(out[k]) <= 2:
            raise ValueError(f"damping.modal.{k}: {len(out[k])} ratios; allowed: 1 or 2 "
                             "(the family's first modes)")
    return out
