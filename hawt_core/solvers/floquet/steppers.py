"""The time-marching one-step maps of the Floquet monodromy, one class per method (Radau IIA,
the paper's central differencing), each with its stage system assembled by a precomputed
scatter, one sparse LU per step or the low-rank stage update (lowrank.py).
"""

from __future__ import annotations

import math
import warnings
from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .coefficients import FourierCoefficients, PatternChanged
from .lowrank import (LOWRANK_MAX_FRACTION, LOWRANK_MIN_N, LOWRANK_VAR_TOL, LowRankUpdate,
                      varying_cover)

__all__ = ['RADAU_IIA', 'RadauStepper', 'MidpointStepper', 'make_stepper', 'STAGE_ORDERING']


# --------------------------------------------------------------------------------------------
# Radau IIA, 3 stages (Hairer & Wanner II, Table 5.6)
_s6 = math.sqrt(6.0)

RADAU_IIA = {
    "c": np.array([(4.0 - _s6) / 10.0, (4.0 + _s6) / 10.0, 1.0]),
    "A": np.array([
        [(88.0 - 7.0 * _s6) / 360.0, (296.0 - 169.0 * _s6) / 1800.0, (-2.0 + 3.0 * _s6) / 225.0],
        [(296.0 + 169.0 * _s6) / 1800.0, (88.0 + 7.0 * _s6) / 360.0, (-2.0 - 3.0 * _s6) / 225.0],
        [(16.0 - _s6) / 36.0, (16.0 + _s6) / 36.0, 1.0 / 9.0],
    ]),
}


_RADAU_W = np.linalg.inv(RADAU_IIA["A"])      # stage-derivative weights: K = W (X - x0) / h

_RADAU_RHO = _RADAU_W.sum(axis=1)

#: Fill-reducing ordering of the per-step stage LU: the minimum-degree ordering of A^T + A
#: halves the fill of the turbine's stage matrices against SuperLU's default COLAMD (three
#: blades on a flexible tower, N = 6: 3.0e5 vs 7.2e5 nonzeros, factor + solve 71 vs 154 ms)
STAGE_ORDERING = "MMD_AT_PLUS_A"

# --------------------------------------------------------------------------------------------
# marching
class _Assembler:
    """Sum of scaled pattern blocks into one CSC matrix (template with precomputed scatter)."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]):
        N = shape[0]
        keys = cols.astype(np.int64) * N + rows.astype(np.int64)
        uniq, self.inv = np.unique(keys, return_inverse=True)
        self.nnz = uniq.size
        self.indices = (uniq % N).astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(uniq // N, minlength=shape[1]))])
        self.shape = shape

    def matrix(self, vals: np.ndarray) -> sp.csc_matrix:
        data = np.bincount(self.inv, weights=vals, minlength=self.nnz)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=self.shape)


class Stepper:
    """One-step maps of E(t) x' = A(t) x, many right-hand sides at once (the marching of a
    method: its stage system, stage times and where x1 sits in the stage solution come from
    the subclass)."""

    method = ""

    def __init__(self, coeffs, lowrank: Optional[bool] = False):
        self.coeffs = coeffs
        self.version = None
        self.factorizations = 0
        self.lowrank = lowrank          # None: automatic, True: forced, False: never
        self.lowrank_used = False
        self.lowrank_info: dict = {}
        self._lr_cache: dict = {}

    def _build(self):
        raise NotImplementedError

    def stage_times(self, t: float, h: float) -> np.ndarray:
        raise NotImplementedError

    def matrices(self, h: float, Ed: np.ndarray, Ad: np.ndarray):
        """Stage matrix L and right-hand-side matrix R of one step (x1 = out(L^{-1} R x0));
        both are linear in the coefficient data Ed, Ad (rows: the stage times)."""
        raise NotImplementedError

    def out_rows(self, n: int) -> np.ndarray:
        """Rows of the stage solution that hold x1."""
        raise NotImplementedError

    def stage_index(self, idx: np.ndarray) -> np.ndarray:
        """Stage-system indices of the variables / equations ``idx``."""
        raise NotImplementedError

    def step(self, X: np.ndarray, h: float, Ed: np.ndarray, Ad: np.ndarray) -> np.ndarray:
        """Advance X (n x m) over one step; Ed, Ad: coefficient data at the stage times."""
        L, R = self.matrices(h, Ed, Ad)
        lu = spla.splu(L, permc_spec=STAGE_ORDERING)
        self.factorizations += 1
        Xs = lu.solve(np.asarray(R @ X))
        return Xs[self.out_rows(X.shape[0])]

    def _lowrank_for(self, h: float):
        """The low-rank update data for step h, or None (not applicable / not wanted)."""
        if self.lowrank is False:
            return None
        if h in self._lr_cache:
            return self._lr_cache[h]
        lr, why = None, ""
        if not isinstance(self.coeffs, FourierCoefficients):
            why = "coefficients are not a Fourier series"
        else:
            if self.version != self.coeffs.version:
                self._build()
            n = self.coeffs.dae.n
            R, C, cEv, cAv = varying_cover(
                self.coeffs, LOWRANK_VAR_TOL,
                None if self.lowrank else n // LOWRANK_MAX_FRACTION)
            self.lowrank_info.update(rows=R, cols=C)
            if self.lowrank is None and (R.size + C.size) * LOWRANK_MAX_FRACTION > n:
                why = (f"time variation not confined to few rows/columns "
                       f"(more than {n // LOWRANK_MAX_FRACTION} of n = {n})")
            elif self.lowrank is None and n < LOWRANK_MIN_N:
                why = f"small system (n = {n} < {LOWRANK_MIN_N}): factorizing is as fast"
            else:
                lr = LowRankUpdate(self, h, R, C, cEv, cAv)
        if lr is None and self.lowrank is True:
            raise ValueError(f"lowrank=True: {why}")
        self.lowrank_info["reason"] = why
        self._lr_cache[h] = lr
        return lr

    def march(self, X0: np.ndarray, t0: float, h: float, nsteps: int,
              store_every: int = 0, store_rows=None, chunk: int = 64):
        """March X0 from t0 over nsteps steps.  Returns (X_end, samples) where samples[i] are
        the rows ``store_rows`` of X at t0 + i*store_every*h (i = 0 .. nsteps/store_every - 1)."""
        X = np.array(X0, dtype=float, copy=True)
        samples = []
        if store_every:
            samples.append(X[store_rows].copy())
        lr = self._lowrank_for(h) if nsteps > 0 else None
        if lr is not None:
            ts = np.concatenate([self.stage_times(t0 + i * h, h) for i in range(nsteps)])
            betas = self.coeffs.basis(ts)[:, 1:].reshape(nsteps, -1)
            if not lr.check(self, X, h, betas, ts):
                if self.lowrank is True:
                    warnings.warn("lowrank=True: the low-rank stage update is inaccurate "
                                  f"({self.lowrank_info})", RuntimeWarning,
                                  stacklevel=4)
                else:
                    self._lr_cache[h] = lr = None
        if lr is not None:
            self.lowrank_used = True
            K = lr.K
            full_samples = bool(store_every) and not np.all(np.isin(store_rows, K))
            spos = None if not store_every or full_samples else np.searchsorted(K, store_rows)
            XK = X[K]
            for k in range(nsteps):
                sample = store_every and (k + 1) % store_every == 0 and k + 1 < nsteps
                if k + 1 == nsteps or (sample and full_samples):
                    X = lr.step(XK, betas[k], rows="all")
                    XK = X[K]
                    if sample:
                        samples.append(X[store_rows].copy())
                else:
                    XK = lr.step(XK, betas[k])
                    if sample:
                        samples.append(XK[spos].copy())
            return X, samples
        k = 0
        while k < nsteps:
            m = min(chunk, nsteps - k)
            ts = np.concatenate([self.stage_times(t0 + (k + i) * h, h) for i in range(m)])
            try:
                if self.version != self.coeffs.version:
                    self._build()
                Ed, Ad = self.coeffs.data_at(ts)
            except PatternChanged:
                continue        # pattern grew: rebuild templates and redo this chunk
            ns = ts.size // m
            for i in range(m):
                X = self.step(X, h, Ed[i * ns:(i + 1) * ns], Ad[i * ns:(i + 1) * ns])
                k += 1
                if store_every and k % store_every == 0 and k < nsteps:
                    samples.append(X[store_rows].copy())
        return X, samples


class RadauStepper(Stepper):
    """3-stage Radau IIA: stage equations ``E(t_j) sum_l w_jl (X_l - x0) / h = A(t_j) X_j``
    (w = RADAU_IIA["A"]^-1), x1 = X_3; unknowns and rows interleaved by stage."""

    method = "radau"

    def _build(self):
        c = self.coeffs
        n = c.dae.n
        pE, pA = c.pE, c.pA
        # unknowns and rows interleaved by stage (index 3 i + stage): the stage system keeps
        # the band structure of E and A, so the sparse LU has little fill
        rows, cols = [], []
        for j in range(3):
            for l in range(3):
                rows.append(3 * pE.rows + j)
                cols.append(3 * pE.cols + l)
        for j in range(3):
            rows.append(3 * pA.rows + j)
            cols.append(3 * pA.cols + j)
        self.lhs = _Assembler(np.concatenate(rows), np.concatenate(cols), (3 * n, 3 * n))
        self.rhs = _Assembler(np.concatenate([3 * pE.rows + j for j in range(3)]),
                              np.concatenate([pE.cols] * 3), (3 * n, n))
        self.version = c.version

    def stage_times(self, t: float, h: float) -> np.ndarray:
        return t + h * RADAU_IIA["c"]

    def matrices(self, h: float, Ed: np.ndarray, Ad: np.ndarray):
        vals = np.concatenate([((_RADAU_W / h)[:, :, None] * Ed[:, None, :]).ravel(),
                               (-Ad).ravel()])
        return (self.lhs.matrix(vals),
                self.rhs.matrix(((_RADAU_RHO / h)[:, None] * Ed).ravel()))

    def out_rows(self, n: int) -> np.ndarray:
        return np.arange(n) * 3 + 2

    def stage_index(self, idx: np.ndarray) -> np.ndarray:
        idx = np.asarray(idx, dtype=np.int64)
        return (3 * idx[:, None] + np.arange(3)[None, :]).ravel()


class MidpointStepper(Stepper):
    """The paper's finite elements in time: central differencing about t + h/2 on the
    differential rows (E row nonzero somewhere), the algebraic rows (zero rows of E)
    collocated at the new node t + h."""

    method = "paper"

    def _build(self):
        c = self.coeffs
        n = c.dae.n
        pE, pA = c.pE, c.pA
        alg_row = np.ones(n, dtype=bool)
        alg_row[pE.rows] = False
        self.a_mid = ~alg_row[pA.rows]
        self.a_end = alg_row[pA.rows]
        rows = np.concatenate([pE.rows, pA.rows[self.a_mid], pA.rows[self.a_end]])
        cols = np.concatenate([pE.cols, pA.cols[self.a_mid], pA.cols[self.a_end]])
        self.lhs = _Assembler(rows, cols, (n, n))
        self.rhs = _Assembler(np.concatenate([pE.rows, pA.rows[self.a_mid]]),
                              np.concatenate([pE.cols, pA.cols[self.a_mid]]), (n, n))
        self.version = c.version

    def stage_times(self, t: float, h: float) -> np.ndarray:
        return np.array([t + 0.5 * h, t + h])

    def matrices(self, h: float, Ed: np.ndarray, Ad: np.ndarray):
        Em, Am = Ed[0] / h, 0.5 * Ad[0][self.a_mid]
        return (self.lhs.matrix(np.concatenate([Em, -Am, -Ad[1][self.a_end]])),
                self.rhs.matrix(np.concatenate([Em, Am])))

    def out_rows(self, n: int) -> np.ndarray:
        return np.arange(n)

    def stage_index(self, idx: np.ndarray) -> np.ndarray:
        return np.asarray(idx, dtype=np.int64)


STEPPERS = {"radau": RadauStepper, "paper": MidpointStepper}


def make_stepper(coeffs, method: str, lowrank: Optional[bool] = False) -> Stepper:
    """The stepper of ``method`` ("radau" or "paper")."""
    return STEPPERS[method](coeffs, lowrank=lowrank)
