"""Modal damping ratios (ElastoDyn's BldFlDmp, BldEdDmp, TwrFADmp, TwrSSDmp) turned into
the beam's Rayleigh damping (fem/damping.py).

ElastoDyn damps each of its assumed modes L by ``C = 2 zeta_L K / omega_L`` with omega_L
the mode's frequency without centrifugal stiffening, tip mass or tower-top mass
(ElastoDyn.f90, Coeff: ``CBF = 0.01 BldFDamp K / (pi FreqBF(.., 1))``): a
stiffness-proportional damping per mode, so that the bare, clamped, non-rotating beam's mode
L has exactly the ratio zeta_L.  hawt's beam has no assumed modes; its damping is a
section property.  The rule kept: the bare clamped non-rotating beam (tip mass removed),
converged (FIT_ELEMENTS elements of order FIT_ORDER), has the deck's ratios in the named
modes: with one ratio for a family (bending plane), ``mu`` on that bending strain
(ElastoDyn's 2 zeta / omega when the mode bends in one plane); with two, also ``alpha`` on
that plane's velocities (Rayleigh: zeta = alpha / (2 omega) + mu omega / 2 through both modes).  The
coefficients solve the first-order eigenvalue sensitivities (left and right eigenvectors of
the beam's pencil), then, if they miss by more than 1e-7, one correction with the damped
eigenvalues (tests/test_structural_damping.py).  Coefficients are kept non-negative (a
negative one would drive slower motions unstable): ratios no non-negative pair reaches (the
second ratio larger than omega2/omega1 times the first) are fitted by least squares, warned.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
from scipy.optimize import nnls

from ..model import MODAL_FAMILIES, Beam
from .damping import DampingCoefficients, modal_families, plane_velocities
from .elements import discretize, pointwise_jacobian
from .energy import classify_energy

__all__ = ["fit_modal", "clamped_pencil", "clamped_modes", "mode_families", "refine"]

_CACHE: dict = {}
_CACHE_SIZE = 64


def clamped_pencil(elements, rates: bool = True, values: bool = True):
    """(A, E) dense (n, n): dR/dy and dR/dydot of the discretized beam ``elements`` at rest
    (root clamped and fixed, no gravity), by the Gauss-point complex steps (exact;
    fem/beam_jacobian.py); either is None when not asked for."""
    pw = pointwise_jacobian(elements)
    z = np.zeros(elements.n)

    def fun(Yd, Y, cap):
        z3 = np.zeros((Y.shape[0], 3))
        return elements.residual(Yd, Y, z3, z3, capture=cap)
    A = pw.matrix(fun, z, z).toarray() if values else None
    E = pw.matrix(fun, z, z, rates=True).toarray() if rates else None
    return A, E


def clamped_modes(A, E, count: int):
    """The ``count`` lowest oscillatory modes of the pencil: (lambda (m,), right (n, m),
    left (n, m)), by increasing frequency (``(A + lambda E) v = 0``)."""
    lam, vl, vr = sla.eig(A, -E, left=True, right=True)
    # oscillatory (not the real exponents of Kelvin-Voigt's -1/mu branch, whose round-off
    # imaginary parts would sort first)
    ok = np.isfinite(lam) & (lam.imag > 1e-3 * np.abs(lam))
    idx = np.flatnonzero(ok)
    idx = idx[np.argsort(lam[idx].imag)][:count]
    return lam[idx], vr[:, idx], vl[:, idx]


def mode_families(elements, vectors) -> np.ndarray:
    """(m,) the strain index (0..5) holding most of each mode's strain energy
    (fem/energy.py classify_energy, the blade-modes analysis' family labels)."""
    return np.array([int(np.argmax(classify_energy(elements, vectors[:, j])))
                     for j in range(vectors.shape[1])], int)


def refine(A, E, guesses, steps: int = 4):
    """The pencil's eigenvalues nearest ``guesses``, by inverse iteration on ``(A + s0 E)``
    (QZ on the whole pencil, whose algebraic part is badly scaled, leaves ~1e-6 in the
    damping ratios; a shifted solve near the mode leaves round-off)."""
    out = np.empty(len(guesses), complex)
    for i, s0 in enumerate(guesses):
        lu = sla.lu_factor(A + s0 * E)
        v = np.ones(A.shape[0], complex)
        for _ in range(steps):
            x = sla.lu_solve(lu, -(E @ v))
            rho = np.vdot(v, x) / np.vdot(v, v)
            v = x / np.linalg.norm(x)
        out[i] = s0 + 1.0 / rho
    return out


def _ratios(lam):
    return -lam.real / np.abs(lam)


#: The discretization the ratios are fitted on, whatever mesh an analysis uses: elements and
#: order (the p-version converges the first six modes of the real blades to 1e-5 on it,
#: docs/defaults.md), so the coefficients are the beam's, not a mesh's.
FIT_ELEMENTS, FIT_ORDER = 3, 6


def fit_modal(beam: Beam, gauss: int = 3) -> DampingCoefficients:
    """The Rayleigh coefficients that give ``beam``'s bare clamped beam (tip mass removed,
    discretized with FIT_ELEMENTS elements of order FIT_ORDER) the modal ratios of
    ``beam.damping.modal`` (module docstring).  They are then the beam's whatever mesh an
    analysis uses (on another mesh its ratios move with its frequencies, by that mesh's
    error).  Cached per section table, length and ratios."""
    families = modal_families(beam.damping)
    key = (id(beam.sections), float(beam.length), tuple(sorted(families.items())),
           int(gauss))
    hit = _CACHE.get(key)
    if hit is not None and hit[0] is beam.sections:
        return hit[1]
    bare = replace(beam, tip_mass=0.0, tip_inertia=(0.0, 0.0, 0.0), damping=None,
                   elements=FIT_ELEMENTS, order=FIT_ORDER)
    base = discretize(bare, gauss=gauss)
    A0, E0 = clamped_pencil(base)
    count = 4 * sum(len(z) for z in families.values()) + 8
    lam, vr, vl = clamped_modes(A0, E0, count)
    fam = mode_families(base, vr)
    # the named modes: the first len(z) modes of each family's bending strain
    targets, zeta = [], []
    for name, ratios in families.items():
        found = np.flatnonzero(fam == MODAL_FAMILIES[name])
        if len(found) < len(ratios):
            raise ValueError(f"damping.modal.{name}: the beam has {len(found)} {name} "
                             f"mode(s) among its lowest {count}; {len(ratios)} named")
        targets += list(found[:len(ratios)])
        zeta += list(ratios)
    # the unknown coefficients: mu of each family's strain, alpha of its plane if 2 ratios
    unknowns = []
    for name, ratios in families.items():
        d = MODAL_FAMILIES[name]
        mu = np.zeros(6)
        mu[d] = 1.0
        unknowns.append(DampingCoefficients(mu, np.zeros(6)))
        if len(ratios) == 2:
            al = np.zeros(6)
            al[list(plane_velocities(d))] = 1.0
            unknowns.append(DampingCoefficients(np.zeros(6), al))
    v, w = vr[:, targets], vl[:, targets]
    lam_t = refine(A0, E0, lam[targets])
    norm = np.einsum("nm,nk,km->m", np.conj(w), E0, v)
    S = np.empty((len(targets), len(unknowns)))
    Dl = np.empty((len(targets), len(unknowns)), complex)     # d lambda / d coefficient
    for j, c in enumerate(unknowns):
        # mu reads only the rates (dR/dydot), alpha only the values (dR/dy)
        stiff = bool(np.any(c.mu))
        A1, E1 = clamped_pencil(discretize(bare, gauss=gauss, damping=c), rates=stiff,
                                values=not stiff)
        dlam = (-lam_t * np.einsum("nm,nk,km->m", np.conj(w), E1 - E0, v) if stiff
                else -np.einsum("nm,nk,km->m", np.conj(w), A1 - A0, v))
        Dl[:, j] = dlam / norm
        S[:, j] = -Dl[:, j].real / np.abs(lam_t)
    zeta = np.asarray(zeta)
    coef, _ = nnls(S, zeta)
    fitted = _combine(unknowns, coef)
    # one correction on the damped pencil (the sensitivities are first order)
    # (the damped modes found near their first-order predictions, not by their rank)
    got = _ratios_of(discretize(bare, gauss=gauss, damping=fitted), lam_t + Dl @ coef)
    if np.max(np.abs(got - zeta)) > 1e-7:
        coef = np.maximum(coef + np.linalg.lstsq(S, zeta - got, rcond=None)[0], 0.0)
        fitted = _combine(unknowns, coef)
        got = _ratios_of(discretize(bare, gauss=gauss, damping=fitted), lam_t + Dl @ coef)
    worst = np.max(np.abs(got - zeta))
    if worst > 1e-4 * max(1.0, 100 * np.max(zeta)):
        warnings.warn(f"damping.modal: no non-negative Rayleigh damping gives these ratios "
                      f"{[float(z) for z in zeta]}; the closest gives "
                      f"{[round(float(z), 6) for z in got]}", stacklevel=3)
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.clear()
    _CACHE[key] = (beam.sections, fitted)
    return fitted


def _combine(unknowns, coef) -> DampingCoefficients:
    mu = sum(c * u.mu for c, u in zip(coef, unknowns))
    al = sum(c * u.alpha for c, u in zip(coef, unknowns))
    return DampingCoefficients(np.asarray(mu, float), np.asarray(al, float))


def _ratios_of(elements, guesses):
    """Damping ratios of the eigenvalues of ``elements``' clamped pencil nearest
    ``guesses``."""
    A, E = clamped_pencil(elements)
    return _ratios(refine(A, E, guesses))
