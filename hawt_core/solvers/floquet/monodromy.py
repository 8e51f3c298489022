"""The monodromy of a linear periodic DAE restricted to its consistent subspace: the basis
from stiffly accurate settling steps, the march over one period (or T/Nb with Fast
Floquet), Monodromy.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
import scipy.linalg as sla

from .coefficients import DirectCoefficients, FourierCoefficients, LinearPeriodicDAE
from .steppers import RadauStepper, Stepper, make_stepper

__all__ = ['DEFAULT_STEPS', 'Monodromy', 'monodromy']


DEFAULT_STEPS = {"radau": 256, "paper": 1000}

_SETTLE_STEPS = 3


def _settle(coeffs, h: float, t_end: float, lowrank: Optional[bool] = False,
            stepper: Optional[Stepper] = None) -> tuple[np.ndarray, int]:
    """_SETTLE_STEPS Radau IIA steps of length h ending at t_end, applied to all differential
    unit vectors (the algebraic columns are irrelevant: a step depends on x0 only via E x0).
    ``stepper``: a Radau stepper to use (and whose low-rank data for h to share).  Returns the
    end values and the number of factorizations."""
    dae = coeffs.dae
    diff = np.flatnonzero(dae.differential)
    X0 = np.zeros((dae.n, diff.size))
    X0[diff, np.arange(diff.size)] = 1.0
    st = RadauStepper(coeffs, lowrank=lowrank) if stepper is None else stepper
    f0 = st.factorizations
    X, _ = st.march(X0, t_end - _SETTLE_STEPS * h, h, _SETTLE_STEPS)
    return X, st.factorizations - f0


def _consistent_basis(coeffs, h: float, t_end: float, dynamic_dim: Optional[int],
                      lowrank: Optional[bool] = False, stepper: Optional[Stepper] = None):
    """Basis Z (n x d) of consistent values at t_end, with Z_D orthonormal.

    d = numerical rank of the settling map with tiny steps (h/100): it is a near-projector onto
    the consistent subspace, so its nonzero singular values are >= ~1 while every inconsistent
    component (algebraic, position- and hidden-constraint violations) is annihilated; with
    time-varying constraints the steps of length h leave O(h^q) hidden-constraint violations
    (tiny singular values whose multipliers are 0), which the small steps push to roundoff.
    Z spans the top-d singular subspace of the settling map with the marching step h, i.e. the
    range of the last steps of the period map (so Phi Z lies in span Z up to O(h^q)).
    """
    diff = np.flatnonzero(coeffs.dae.differential)
    # with the low-rank path when it applies: per-step sparse LUs of these stage matrices
    # leave round-off at 1e-8 .. 1e-10 s0 (the turbine: d and the "no clear gap" warning then
    # depend on the fill-reducing ordering), the low-rank steps at 1e-11 .. 1e-12 s0
    Xs, f1 = _settle(coeffs, h * 1e-2, t_end, lowrank)
    if dynamic_dim is None:     # the left singular vectors are needed for the check below
        U_small, s_small, _ = np.linalg.svd(Xs[diff], full_matrices=False)
        d = _numerical_rank(s_small)
    else:
        s_small = np.linalg.svd(Xs[diff], compute_uv=False)
        d = int(dynamic_dim)
    X, f2 = _settle(coeffs, h, t_end, lowrank, stepper)
    U, s, Vt = np.linalg.svd(X[diff], full_matrices=False)
    Z = X @ (Vt[:d].T / s[:d])
    if d > 0 and dynamic_dim is None:
        # the two subspaces must agree to O(h^q); a large angle means the spurious (hidden
        # constraint) directions of the h-steps outweigh dynamic ones: badly scaled system
        Us = U_small[:, :d]
        ang = np.linalg.norm(Us - U[:, :d] @ (U[:, :d].T @ Us), 2)
        if ang > 1e-2:
            warnings.warn(f"consistent subspace: step-size dependent by {ang:.1e}; "
                          "reduce the step or rescale the variables", RuntimeWarning, stacklevel=3)
    return Z, s_small, d, f1 + f2


def _numerical_rank(s: np.ndarray, min_gap_decades: float = 4.0) -> int:
    """Rank at the largest gap in log10(s) at least min_gap_decades wide whose lower side is
    below 1e-6 s[0] (the nonzero singular values of the near-projector are >= ~1), or at least
    3 decades wide with the lower side below 10^-10.5 s[0], and whose upper side is above
    1e-12 s[0]: gaps inside the round-off tail (the annihilated components, ~1e-20 .. 1e-30
    s[0] with exact Jacobians) are not a rank."""
    if s.size == 0 or s[0] == 0:
        return 0
    ls = np.log10(np.maximum(s / s[0], 1e-300))
    gaps = ls[:-1] - ls[1:]
    # a gap of >= min_gap_decades below 1e-6, or of >= 3 decades into the round-off floor
    # (< 10^-10.5 s0: stiff components decayed to ~1e-8 s0 leave less than 4 decades)
    cand = [(g, i) for i, g in enumerate(gaps)
            if ls[i] > -12.0 and ((g >= min_gap_decades and ls[i + 1] < -6.0)
                                  or (g >= 3.0 and ls[i + 1] < -10.5))]
    if not cand:
        if ls[-1] < -10.0:
            warnings.warn("consistent subspace: no clear rank gap in the settling map; "
                          "pass dynamic_dim", RuntimeWarning, stacklevel=3)
            return int(np.sum(ls > -8.0))
        return s.size
    g, i = max(cand)
    return i + 1


# --------------------------------------------------------------------------------------------
@dataclass
class Monodromy:
    """Monodromy restricted to the consistent subspace.

    ``matrix`` is d x d; for Fast Floquet it is the reduced map ``Z_D^+ S^T Phi(T/Nb) Z`` whose
    eigenvalues raised to the power ``blades`` are the multipliers of Phi(T)."""
    matrix: np.ndarray                 # d' x d' in the coordinates of `basis`
    basis: np.ndarray                  # n x d': Z (radau) or the identity (paper)
    consistent_basis: np.ndarray       # Z (n x d), consistent at t = 0, Z_D orthonormal
    samples: list                      # rows `sample_rows` of Phi(t_m, 0) Z, t_m = m*T/M
    sample_rows: np.ndarray
    sample_times: np.ndarray           # over [0, T/Nb) for fast, [0, T) otherwise
    samples_per_period: int
    fast: bool
    blades: int
    method: str
    steps: int                         # steps per period
    marched_steps: int
    n_dynamic: int
    settle_singular_values: np.ndarray
    coefficients: object
    factorizations: int
    wall_time: float
    lowrank: bool = False              # marched with the low-rank stage update
    lowrank_info: dict = field(default_factory=dict)

    def eig(self) -> tuple[np.ndarray, np.ndarray]:
        """The d dynamic eigenpairs (mu, V) of ``matrix`` (columns of V in basis coordinates).

        For the full descriptor map of the "paper" method the spurious eigenvalues (algebraic
        variables, hidden constraints; |mu| ~ 1 because R(inf) = -1) are discarded: the d
        eigenvectors closest to the consistent subspace span(Z) are kept."""
        mu, V = sla.eig(self.matrix)
        d = self.n_dynamic
        if V.shape[0] == d:
            return mu, V
        Z = self.consistent_basis
        X = self.basis @ V
        D = self._diff
        C = np.linalg.lstsq(Z[D], X[D], rcond=None)[0]
        nD = np.linalg.norm(X[D], axis=0)
        res = np.linalg.norm(X[D] - Z[D] @ C, axis=0) / np.maximum(nD, 1e-300)
        res[nD <= 1e-8 * np.linalg.norm(X, axis=0)] = np.inf     # purely algebraic
        order = np.argsort(res, kind="stable")
        keep = np.sort(order[:d])
        self.selection_residuals = (res[order[:d]].max() if d else 0.0,
                                    res[order[d]] if d < res.size else np.inf)
        return mu[keep], V[:, keep]


def _closure_rows(rows: np.ndarray, S, blades: int) -> np.ndarray:
    rows = np.unique(rows)
    if S is None:
        return rows
    allr = set(rows.tolist())
    cur = rows
    Sa = abs(S).tocsr()
    for _ in range(blades):
        v = np.zeros(S.shape[0])
        v[cur] = 1.0
        cur = np.flatnonzero(Sa @ v)
        allr.update(cur.tolist())
    return np.array(sorted(allr), dtype=int)


def _make_coefficients(dae, coefficients, harmonics, tol):
    if isinstance(coefficients, (FourierCoefficients, DirectCoefficients)):
        return coefficients
    if coefficients == "fourier":
        return dae.fourier(harmonics=harmonics, tol=tol)
    if coefficients == "direct":
        return DirectCoefficients(dae)
    raise ValueError("coefficients must be 'fourier', 'direct' or a coefficient object")


def _grid(steps: int, samples: int, nb: int) -> tuple[int, int]:
    """Steps per period (multiple of nb) and a sample count M | steps, nb | M, M >= samples
    where possible."""
    steps = int(math.ceil(steps / nb) * nb)
    cands = [m for m in range(nb, steps + 1, nb) if steps % m == 0]
    good = [m for m in cands if m >= samples]
    M = min(good) if good else max(cands)
    return steps, M


def monodromy(dae: LinearPeriodicDAE, method: str = "radau", steps: Optional[int] = None,
              fast: Optional[bool] = None, coefficients="fourier", harmonics="auto",
              fourier_tol: float = 1e-10, samples: int = 128, observed=None,
              dynamic_dim: Optional[int] = None, store_all: bool = False,
              full: bool = False, lowrank: Optional[bool] = None) -> Monodromy:
    """March the consistent subspace over one period (or T/Nb with Fast Floquet).

    full=True marches all n unit vectors instead (the descriptor monodromy, n x n, for
    diagnostics: it shows the spurious multipliers); Monodromy.eig() then selects the d
    eigenvectors closest to the consistent subspace.

    lowrank: None (automatic) uses the low-rank stage update (one factorization of the mean
    stage matrix, Woodbury per step) when the harmonics of E(t), A(t) are confined to a few
    rows and columns (<= n/8 of them, n >= 64) and the coefficients are a Fourier series;
    True forces it, False factorizes every step."""
    t_start = time.perf_counter()
    if method not in ("radau", "paper"):
        raise ValueError("method must be 'radau' or 'paper'")
    if fast is None:
        fast = dae.S is not None
    if fast and dae.S is None:
        raise ValueError("fast=True needs S and blades")
    nb = dae.blades if fast else 1
    K = DEFAULT_STEPS[method] if steps is None else int(steps)
    K, M = _grid(K, samples, nb)
    h = dae.period / K
    coeffs = _make_coefficients(dae, coefficients, harmonics, fourier_tol)
    stepper = make_stepper(coeffs, method, lowrank=lowrank)
    share = method == "radau"      # the settling steps with h reuse its data
    Z, s, d, nf = _consistent_basis(coeffs, h, 0.0, dynamic_dim, lowrank=lowrank,
                                    stepper=stepper if share else None)
    if share:
        nf -= stepper.factorizations      # those are counted in stepper.factorizations
    diff = np.flatnonzero(dae.differential)
    if store_all:
        rows = np.arange(dae.n)
    else:
        rows = diff if observed is None else np.asarray(observed, dtype=int)
        rows = _closure_rows(rows, dae.S if fast else None, nb)
    nsteps = K // nb
    X0 = np.eye(dae.n) if full else Z
    Y, smp = stepper.march(X0, 0.0, h, nsteps, store_every=K // M, store_rows=rows)
    if fast:
        Y = np.asarray(dae.S.T @ Y)
    Mat = Y if full else np.linalg.lstsq(Z[diff], Y[diff], rcond=None)[0]
    mono = Monodromy(matrix=Mat, basis=X0, consistent_basis=Z, samples=smp, sample_rows=rows,
                     sample_times=np.arange(len(smp)) * (K // M) * h, samples_per_period=M,
                     fast=bool(fast), blades=nb, method=method, steps=K, marched_steps=nsteps,
                     n_dynamic=d, settle_singular_values=s, coefficients=coeffs,
                     factorizations=nf + stepper.factorizations,
                     wall_time=time.perf_counter() - t_start, lowrank=stepper.lowrank_used,
                     lowrank_info=dict(stepper.lowrank_info))
    mono._diff = diff
    return mono
