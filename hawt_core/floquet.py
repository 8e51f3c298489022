"""Generic Floquet machinery for linear time-periodic descriptor systems.

    E(t) x'(t) = A(t) x(t),     E(t + T) = E(t),  A(t + T) = A(t),

with ``E(t)`` singular (algebraic variables, Lagrange multipliers, index up to 3).  See
``docs/floquet.md`` for the method, the Fast Floquet formula and the references.

Main entry points::

    dae = LinearPeriodicDAE(E, A, period, differential, S=None, blades=None)
    res = floquet_analysis(dae, method="radau", steps=None, ...)   # -> FloquetResult
    mono = monodromy(dae, method="radau", steps=None, ...)          # -> Monodromy

Methods
-------
``"radau"`` (default)
    3-stage Radau IIA (order 5 for ODEs / index 1; stiffly accurate, L-stable; convergent for
    index-3 Hessenberg systems, Hairer & Wanner II, sec. VI.7 and VII.4).
``"paper"``
    The paper's finite elements in time: central differencing (implicit midpoint, equal to the
    trapezoidal rule for constant coefficients) on the differential rows, algebraic rows
    collocated at the new node; second order, 1000 steps per period by default.

The algebraic and hidden-constraint components are removed by a state-space reduction on the
consistent subspace: a basis ``Z`` (n x d) of consistent initial values at t = 0 is obtained from
the range of three Radau IIA steps ending at t = 0 (stiffly accurate steps annihilate every
inconsistent component of an index <= 3 system); only these d columns are marched and the
monodromy is the d x d matrix ``Z_D^+ Phi(T) Z`` (D: differential rows).  The result therefore
contains exactly ``d`` = dim(consistent subspace) multipliers.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "LinearPeriodicDAE",
    "FourierCoefficients",
    "DirectCoefficients",
    "Monodromy",
    "FloquetResult",
    "monodromy",
    "floquet_analysis",
    "RADAU_IIA",
]

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

DEFAULT_STEPS = {"radau": 256, "paper": 1000}
_SETTLE_STEPS = 3
#: Fill-reducing ordering of the per-step stage LU: the minimum-degree ordering of A^T + A
#: halves the fill of the turbine's stage matrices against SuperLU's default COLAMD (three
#: blades on a flexible tower, N = 6: 3.0e5 vs 7.2e5 nonzeros, factor + solve 71 vs 154 ms)
STAGE_ORDERING = "MMD_AT_PLUS_A"


# --------------------------------------------------------------------------------------------
# sparse patterns and coefficient providers
class _Pattern:
    """A fixed sparsity pattern (CSC order) of an n x n matrix."""

    def __init__(self, n: int, keys: np.ndarray):
        self.n = n
        self.keys = np.unique(np.asarray(keys, dtype=np.int64))   # key = col * n + row
        self.rows = (self.keys % n).astype(np.int64)
        self.cols = (self.keys // n).astype(np.int64)
        self.indptr = np.concatenate(
            [[0], np.cumsum(np.bincount(self.cols, minlength=n))]).astype(np.int64)
        self.indices = self.rows.astype(np.int32)

    @property
    def nnz(self) -> int:
        return self.keys.size

    @staticmethod
    def keys_of(mat, n: int) -> tuple[np.ndarray, np.ndarray]:
        m = _as_sparse(mat, n).tocoo()
        return m.col.astype(np.int64) * n + m.row.astype(np.int64), m.data

    def data_of(self, mat) -> Optional[np.ndarray]:
        """Values of ``mat`` on this pattern; None if ``mat`` has nonzeros outside it."""
        keys, vals = self.keys_of(mat, self.n)
        pos = np.searchsorted(self.keys, keys)
        pos_c = np.minimum(pos, self.nnz - 1) if self.nnz else pos
        ok = (pos < self.nnz) & (self.keys[pos_c] == keys) if self.nnz else np.zeros(keys.size, bool)
        if not np.all(ok | (vals == 0)):
            return None
        out = np.zeros(self.nnz)
        np.add.at(out, pos[ok], np.real(vals[ok]))
        return out

    def matrix(self, data: np.ndarray) -> sp.csc_matrix:
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


def _as_sparse(mat, n: int):
    if sp.issparse(mat):
        m = mat
    else:
        m = sp.csc_matrix(np.asarray(mat, dtype=float))
    if m.shape != (n, n):
        raise ValueError(f"coefficient matrix has shape {m.shape}, expected {(n, n)}")
    return m


class DirectCoefficients:
    """Evaluates E(t), A(t) by calling the user's callables at every requested time."""

    kind = "direct"

    def __init__(self, dae: "LinearPeriodicDAE", probe_times: Optional[Sequence[float]] = None):
        self.dae = dae
        n = dae.n
        if probe_times is None:   # irrational fractions of the period: catch time-varying zeros
            probe_times = dae.period * np.array([0.0, 0.1234567, 0.3819660, 0.7071068])
        ke, ka = [], []
        for t in probe_times:
            ke.append(_Pattern.keys_of(dae.E(float(t)), n)[0])
            ka.append(_Pattern.keys_of(dae.A(float(t)), n)[0])
        self.pE = _Pattern(n, np.concatenate(ke))
        self.pA = _Pattern(n, np.concatenate(ka))
        self.version = 0
        self.evaluations = 0

    def _data(self, which: str, t: float) -> np.ndarray:
        mat = (self.dae.E if which == "E" else self.dae.A)(float(t))
        pat = self.pE if which == "E" else self.pA
        d = pat.data_of(mat)
        if d is None:   # a new nonzero appeared: grow the pattern, invalidate templates
            keys = _Pattern.keys_of(mat, self.dae.n)[0]
            new = _Pattern(self.dae.n, np.concatenate([pat.keys, keys]))
            if which == "E":
                self.pE = new
            else:
                self.pA = new
            self.version += 1
            raise _PatternChanged()
        return d

    def data_at(self, times) -> tuple[np.ndarray, np.ndarray]:
        times = np.atleast_1d(np.asarray(times, dtype=float))
        self.evaluations += times.size
        Ed = np.empty((times.size, self.pE.nnz))
        Ad = np.empty((times.size, self.pA.nnz))
        for i, t in enumerate(times):
            Ed[i] = self._data("E", t)
            Ad[i] = self._data("A", t)
        return Ed, Ad


class _PatternChanged(Exception):
    pass


class FourierCoefficients:
    """Truncated Fourier series of E(t), A(t) on their union sparsity patterns.

    The data arrays of the sparse matrices sampled at ``2K + 1`` equally spaced times are
    transformed by a real FFT; the series reproduces any trigonometric polynomial of degree
    <= K exactly.  ``error`` is the largest relative deviation from a direct evaluation at
    check times that are not on the sampling grid.
    """

    kind = "fourier"
    version = 0

    def __init__(self, dae: "LinearPeriodicDAE", harmonics="auto", tol: float = 1e-10,
                 max_harmonics: int = 67):
        self.dae = dae
        n, T = dae.n, dae.period
        self.tol = tol
        cache: dict[float, tuple] = {}

        def sample(t):
            key = round(float(t) / T, 15)
            if key not in cache:
                cache[key] = (_as_sparse(dae.E(float(t)), n), _as_sparse(dae.A(float(t)), n))
            return cache[key]

        if harmonics == "auto":
            levels = []
            N = 5
            while (N - 1) // 2 <= max_harmonics:
                levels.append(N)
                N *= 3           # nested grids: every sample is reused at the next level
        else:
            K = int(harmonics)
            if K < 0:
                raise ValueError("harmonics must be >= 0")
            levels = [2 * K + 1]
        for li, N in enumerate(levels):
            ts = T * np.arange(N) / N
            mats = [sample(t) for t in ts]
            # check times: points of the next (3N) grid, i.e. not on this grid
            tc = T * (3 * np.array([0, N // 3, (2 * N) // 3, N - 1]) + 1) / (3 * N)
            chk = [sample(t) for t in tc]
            keysE = np.concatenate([_Pattern.keys_of(m[0], n)[0] for m in mats + chk])
            keysA = np.concatenate([_Pattern.keys_of(m[1], n)[0] for m in mats + chk])
            self.pE, self.pA = _Pattern(n, keysE), _Pattern(n, keysA)
            self._fit(np.array([self.pE.data_of(m[0]) for m in mats]),
                      np.array([self.pA.data_of(m[1]) for m in mats]), N)
            Ec, Ac = self.data_at(tc)
            Ed = np.array([self.pE.data_of(m[0]) for m in chk])
            Ad = np.array([self.pA.data_of(m[1]) for m in chk])
            errE = np.max(np.abs(Ec - Ed), initial=0.0) / max(np.max(np.abs(Ed), initial=0.0), 1e-300)
            errA = np.max(np.abs(Ac - Ad), initial=0.0) / max(np.max(np.abs(Ad), initial=0.0), 1e-300)
            self.error = float(max(errE, errA))
            self.samples = N
            if self.error <= tol:
                break
        self.evaluations = len(cache)
        if self.error > tol:
            warnings.warn(f"Fourier series of E(t), A(t) with {self.harmonics} harmonics has a "
                          f"relative truncation error {self.error:.2e} > tol {tol:.1e}",
                          RuntimeWarning, stacklevel=3)
        self._trim()

    def _fit(self, Ed: np.ndarray, Ad: np.ndarray, N: int):
        K = (N - 1) // 2
        self.harmonics = K
        self.k = np.arange(1, K + 1)
        self.cE = self._coef(Ed, N, K)
        self.cA = self._coef(Ad, N, K)

    @staticmethod
    def _coef(D: np.ndarray, N: int, K: int) -> np.ndarray:
        """Rows: [a0, a1..aK, b1..bK] with f = a0 + sum a_k cos(k w t) + b_k sin(k w t)."""
        F = np.fft.rfft(D, axis=0) / N
        a0 = F[0].real
        ak = 2.0 * F[1:K + 1].real
        bk = -2.0 * F[1:K + 1].imag
        return np.vstack([a0[None, :], ak, bk])

    def _trim(self):
        """Drop harmonics whose coefficients are below tol * scale in both E and A."""
        K = self.harmonics
        if K == 0:
            return
        sE = max(np.max(np.abs(self.cE), initial=0.0), 1e-300)
        sA = max(np.max(np.abs(self.cA), initial=0.0), 1e-300)
        keep = []
        for j in range(1, K + 1):
            mE = np.max(np.abs(self.cE[[j, K + j]]), initial=0.0) / sE
            mA = np.max(np.abs(self.cA[[j, K + j]]), initial=0.0) / sA
            if max(mE, mA) > 0.01 * self.tol:
                keep.append(j)
        keep = np.array(keep, dtype=int)
        rows = np.concatenate([[0], keep, K + keep]).astype(int)
        self.k = keep
        self.cE = self.cE[rows]
        self.cA = self.cA[rows]
        self.harmonics_kept = keep.size

    def basis(self, times) -> np.ndarray:
        th = self.dae.omega * np.atleast_1d(np.asarray(times, dtype=float))[:, None] * self.k[None, :]
        return np.hstack([np.ones((th.shape[0], 1)), np.cos(th), np.sin(th)])

    def data_at(self, times) -> tuple[np.ndarray, np.ndarray]:
        B = self.basis(times)
        return B @ self.cE, B @ self.cA

    def E(self, t: float) -> sp.csc_matrix:
        return self.pE.matrix(self.data_at([t])[0][0])

    def A(self, t: float) -> sp.csc_matrix:
        return self.pA.matrix(self.data_at([t])[1][0])


# --------------------------------------------------------------------------------------------
class LinearPeriodicDAE:
    """``E(t) x' = A(t) x`` with period ``period``.

    Parameters
    ----------
    E, A : callables t -> (n, n) scipy.sparse matrix (or dense array).
    period : T = 2 pi / Omega0.
    differential : bool (n,), True where the variable's derivative appears (ker E(t) must be
        spanned by the other unit vectors for all t).
    S : optional (n, n) signed permutation (orthogonal) for Fast Floquet, with the convention
        ``E(t + T/Nb) = S_rows E(t) S^T`` and ``A(t + T/Nb) = S_rows A(t) S^T``,
        ``S^Nb = I``.  Then ``x(t) -> S x(t - T/Nb)`` maps solutions to solutions and
        ``Phi(T) = (S^T Phi(T/Nb))^Nb`` (docs/floquet.md).  ``S_rows`` (relabelling of the
        equations) defaults to ``S``; it is only used by :meth:`check_symmetry`.
    blades : Nb, the number of identical equally spaced blades (required with S).
    """

    def __init__(self, E: Callable, A: Callable, period: float, differential,
                 S=None, blades: Optional[int] = None, S_rows=None):
        self.E = E
        self.A = A
        self.period = float(period)
        if not self.period > 0:
            raise ValueError("period must be positive")
        self.differential = np.asarray(differential, dtype=bool).ravel()
        self.n = self.differential.size
        self.S = None if S is None else sp.csr_matrix(S, dtype=float)
        self.S_rows = None if S_rows is None else sp.csr_matrix(S_rows, dtype=float)
        self.blades = None if blades is None else int(blades)
        if self.S is not None:
            if self.blades is None or self.blades < 2:
                raise ValueError("S given: blades (>= 2) is required")
            if self.S.shape != (self.n, self.n):
                raise ValueError("S must be n x n")
            P = sp.identity(self.n, format="csr")
            for _ in range(self.blades):
                P = self.S @ P
            if abs(P - sp.identity(self.n)).max() > 1e-12:
                raise ValueError("S^blades must be the identity")
            if abs(self.S @ self.S.T - sp.identity(self.n)).max() > 1e-12:
                raise ValueError("S must be orthogonal (a signed permutation)")
            dS = np.abs(self.S) @ self.differential.astype(float)
            if not np.array_equal(dS > 0.5, self.differential):
                raise ValueError("S must map differential variables to differential variables")

    @property
    def omega(self) -> float:
        return 2.0 * math.pi / self.period

    def fourier(self, harmonics="auto", tol: float = 1e-10, max_harmonics: int = 67) -> FourierCoefficients:
        """Fourier series of E(t), A(t) (see :class:`FourierCoefficients`)."""
        return FourierCoefficients(self, harmonics=harmonics, tol=tol, max_harmonics=max_harmonics)

    def check_symmetry(self, times: Optional[Sequence[float]] = None) -> float:
        """Largest relative residual of ``E(t+T/Nb) = S_rows E(t) S^T`` (and A) at ``times``."""
        if self.S is None:
            raise ValueError("no symmetry S given")
        tau = self.period / self.blades
        Sr = self.S if self.S_rows is None else self.S_rows
        if times is None:
            times = self.period * np.array([0.0, 0.137, 0.4142, 0.77])
        worst = 0.0
        for t in times:
            for f in (self.E, self.A):
                lhs = _as_sparse(f(float(t) + tau), self.n)
                rhs = Sr @ _as_sparse(f(float(t)), self.n) @ self.S.T
                scale = max(abs(lhs).max(), abs(rhs).max(), 1e-300)
                worst = max(worst, abs(lhs - rhs).max() / scale)
        return float(worst)


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


class _Stepper:
    """One-step maps of E(t) x' = A(t) x, many right-hand sides at once."""

    def __init__(self, coeffs, method: str, lowrank: Optional[bool] = False):
        self.coeffs = coeffs
        self.method = method
        self.version = None
        self.factorizations = 0
        self.lowrank = lowrank          # None: automatic, True: forced, False: never
        self.lowrank_used = False
        self.lowrank_info: dict = {}
        self._lr_cache: dict = {}

    def _build(self):
        c = self.coeffs
        n = c.dae.n
        pE, pA = c.pE, c.pA
        if self.method == "radau":
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
        else:
            # differential rows (E row nonzero somewhere): central differencing about t+h/2;
            # algebraic rows (zero rows of E): collocated at the new node t+h
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
        if self.method == "radau":
            return t + h * RADAU_IIA["c"]
        return np.array([t + 0.5 * h, t + h])

    def matrices(self, h: float, Ed: np.ndarray, Ad: np.ndarray):
        """Stage matrix L and right-hand-side matrix R of one step (x1 = out(L^{-1} R x0));
        both are linear in the coefficient data Ed, Ad (rows: the stage times)."""
        if self.method == "radau":
            vals = np.concatenate([((_RADAU_W / h)[:, :, None] * Ed[:, None, :]).ravel(),
                                   (-Ad).ravel()])
            return (self.lhs.matrix(vals),
                    self.rhs.matrix(((_RADAU_RHO / h)[:, None] * Ed).ravel()))
        Em, Am = Ed[0] / h, 0.5 * Ad[0][self.a_mid]
        return (self.lhs.matrix(np.concatenate([Em, -Am, -Ad[1][self.a_end]])),
                self.rhs.matrix(np.concatenate([Em, Am])))

    def out_rows(self, n: int) -> np.ndarray:
        """Rows of the stage solution that hold x1."""
        return np.arange(n) * 3 + 2 if self.method == "radau" else np.arange(n)

    def stage_index(self, idx: np.ndarray) -> np.ndarray:
        """Stage-system indices of the variables / equations ``idx``."""
        idx = np.asarray(idx, dtype=np.int64)
        if self.method == "radau":
            return (3 * idx[:, None] + np.arange(3)[None, :]).ravel()
        return idx

    def step(self, X: np.ndarray, h: float, Ed: np.ndarray, Ad: np.ndarray) -> np.ndarray:
        """Advance X (n x m) over one step; Ed, Ad: coefficient data at the stage times."""
        L, R = self.matrices(h, Ed, Ad)
        lu = spla.splu(L, permc_spec=STAGE_ORDERING)
        self.factorizations += 1
        Xs = lu.solve(np.asarray(R @ X))
        return Xs[2::3] if self.method == "radau" else Xs

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
            R, C, cEv, cAv = _varying_cover(
                self.coeffs, _LOWRANK_VAR_TOL,
                None if self.lowrank else n // _LOWRANK_MAX_FRACTION)
            self.lowrank_info.update(rows=R, cols=C)
            if self.lowrank is None and (R.size + C.size) * _LOWRANK_MAX_FRACTION > n:
                why = (f"time variation not confined to few rows/columns "
                       f"(more than {n // _LOWRANK_MAX_FRACTION} of n = {n})")
            elif self.lowrank is None and n < _LOWRANK_MIN_N:
                why = f"small system (n = {n} < {_LOWRANK_MIN_N}): factorizing is as fast"
            else:
                lr = _LowRank(self, h, R, C, cEv, cAv)
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
            except _PatternChanged:
                continue        # pattern grew: rebuild templates and redo this chunk
            ns = ts.size // m
            for i in range(m):
                X = self.step(X, h, Ed[i * ns:(i + 1) * ns], Ad[i * ns:(i + 1) * ns])
                k += 1
                if store_every and k % store_every == 0 and k < nsteps:
                    samples.append(X[store_rows].copy())
        return X, samples


# --------------------------------------------------------------------------------------------
# low-rank time variation: one factorization of the mean stage matrix + Woodbury updates
_LOWRANK_VAR_TOL = 1e-13      # harmonics below this x the row's largest coefficient: constant
_LOWRANK_MAX_FRACTION = 8     # automatic: varying rows + columns <= n / 8
_LOWRANK_MIN_N = 64           # automatic: not for smaller systems
_LOWRANK_CHECK_TOL = 1e-7     # first step vs a factorized step (relative): gross errors


def _varying_cover(coeffs: FourierCoefficients, tol: float, max_size: Optional[int] = None):
    """Rows R and columns C (sorted int arrays) such that every entry of E(t), A(t) with a
    non-negligible time variation lies in a row of R or a column of C (greedy cover), and the
    harmonic coefficients (rows 1.. of cE, cA) with the negligible variations set to zero.

    An entry's variation is negligible when the sum of its harmonic amplitudes is at most
    ``tol`` times the largest coefficient of its row (round-off of the FFT of a constant).
    With ``max_size`` the greedy cover stops as soon as it has more rows + columns (then
    R.size + C.size > max_size tells that the variation is not low-rank)."""
    n = coeffs.dae.n
    ents, cleaned = [], []
    for c, p in ((coeffs.cE, coeffs.pE), (coeffs.cA, coeffs.pA)):
        if c.shape[0] <= 1 or p.nnz == 0:
            cleaned.append(np.zeros((c.shape[0] - 1, p.nnz)))
            continue
        rowmax = np.zeros(n)
        np.maximum.at(rowmax, p.rows, np.abs(c).max(axis=0))
        var = np.abs(c[1:]).sum(axis=0) > tol * rowmax[p.rows]
        cleaned.append(np.where(var[None, :], c[1:], 0.0))
        ents.append((p.rows[var], p.cols[var]))
    r = np.concatenate([e[0] for e in ents]) if ents else np.zeros(0, np.int64)
    cc = np.concatenate([e[1] for e in ents]) if ents else np.zeros(0, np.int64)
    R, C = [], []
    while r.size and (max_size is None or len(R) + len(C) <= max_size):
        ur, nr = np.unique(r, return_counts=True)
        uc, nc = np.unique(cc, return_counts=True)
        if nr.max() >= nc.max():
            x = ur[np.argmax(nr)]
            R.append(x)
            keep = r != x
        else:
            x = uc[np.argmax(nc)]
            C.append(x)
            keep = cc != x
        r, cc = r[keep], cc[keep]
    return (np.array(sorted(R), dtype=np.int64), np.array(sorted(C), dtype=np.int64),
            cleaned[0], cleaned[1])


class _LowRank:
    """One step x1 = out(L(t)^{-1} R(t) x0) with L(t) = L0 + P_Rs a(t) + b(t) P_Cs^T.

    L0, R0: stage and right-hand-side matrices of the mean coefficients (one sparse LU per
    step size).  The harmonics of E(t), A(t) live in the rows R and columns C only, so with
    beta = the Fourier basis at the stage times (constant term excluded),
    a = sum_i beta_i A_i (the rows Rs of the harmonic stage matrices), b = sum_i beta_i B_i
    (their columns Cs, rows Rs removed), R(t) = R0 + P_Rs F(beta) + G(beta) P_C^T.  Woodbury:
    L^{-1} = L0^{-1} - L0^{-1} U (I + V^T L0^{-1} U)^{-1} V^T L0^{-1},  U = [P_Rs, b],
    V^T = [a; P_Cs^T]; every product with L0^{-1} is precomputed, so a step costs one n x n
    by n x d product plus products with the r = |Rs| + |Cs| low-rank directions."""

    def __init__(self, st: "_Stepper", h: float, R, C, cEv, cAv):
        c = st.coeffs
        n = c.dae.n
        ns = st.stage_times(0.0, h).size
        H = cEv.shape[0]
        m = ns * H
        Rs, Cs = st.stage_index(R), st.stage_index(C)
        nR, nC, nc = Rs.size, Cs.size, C.size
        L0, R0 = st.matrices(h, np.tile(c.cE[0], (ns, 1)), np.tile(c.cA[0], (ns, 1)))
        N = L0.shape[0]
        rmask = np.zeros(N, bool)
        rmask[Rs] = True
        cmask = np.zeros(N, bool)
        cmask[Cs] = True
        cmask_n = np.zeros(n, bool)
        cmask_n[C] = True
        Al, Bl, Fl, Gl, Rl = [], [], [], [], []
        for j in range(ns):
            for q in range(H):
                Ed = np.zeros((ns, c.pE.nnz))
                Ad = np.zeros((ns, c.pA.nnz))
                Ed[j], Ad[j] = cEv[q], cAv[q]
                Lq, Rq = st.matrices(h, Ed, Ad)
                for M, cm in ((Lq, cmask), (Rq, cmask_n)):
                    Mc = M.tocoo()
                    out = ~rmask[Mc.row] & ~cm[Mc.col]
                    if np.any(Mc.data[out] != 0):
                        raise AssertionError("low-rank cover misses a varying entry")
                Lr = Lq.tocsr()
                Al.append(Lr[Rs])
                B = Lq[:, Cs].toarray()
                B[Rs] = 0.0
                Bl.append(B)
                Rl.append(Rq)
                Fl.append(Rq.tocsr()[Rs].toarray())
                G = Rq[:, C].toarray()
                G[Rs] = 0.0
                Gl.append(G)
        # x0 enters a step only through the nonzero columns of R0 and of the harmonic R's (for
        # Radau the columns of E: the differential variables); march only those rows K
        Rabs = abs(R0).tocsc()
        for Rq in Rl:
            Rabs = Rabs + abs(Rq)
        K = np.union1d(np.flatnonzero(np.diff(Rabs.tocsc().indptr) > 0), C).astype(np.int64)
        posC = np.searchsorted(K, C)
        lu = spla.splu(L0.tocsc())
        st.factorizations += 1
        P = np.zeros((N, nR))
        P[Rs, np.arange(nR)] = 1.0
        nK = K.size
        blocks = [R0.tocsc()[:, K].toarray(), P] + Bl + Gl
        Y = lu.solve(np.asfortranarray(np.hstack(blocks)))
        W0, Wp = Y[:, :nK], Y[:, nK:nK + nR]                     # W0 = L0^-1 R0[:, K]
        o = nK + nR
        WB = np.ascontiguousarray(Y[:, o:o + m * nC].reshape(N, m, nC).transpose(1, 0, 2))
        WG = np.ascontiguousarray(Y[:, o + m * nC:o + m * (nC + nc)].reshape(N, m, nc)
                                  .transpose(1, 0, 2))          # (m, N, .)
        A_all = sp.vstack(Al).tocsr() if m else sp.csr_matrix((0, N))
        out = st.out_rows(n)
        self.n, self.m, self.nR, self.nC, self.K, self.posC = n, m, nR, nC, K, posC
        self.W0, self.Wp, self.WB, self.WG = W0, Wp, WB, WG
        # rows of x1: K (marching) and all n (samples outside K, the final value)
        self.rowsets = {}
        for key, rows in (("K", out[K]), ("all", out)):
            self.rowsets[key] = (np.ascontiguousarray(W0[rows]), np.ascontiguousarray(Wp[rows]),
                                 np.ascontiguousarray(WB[:, rows]),
                                 np.ascontiguousarray(WG[:, rows]))
        self.AW0 = (A_all @ W0).reshape(m, nR, nK)
        self.AWp = (A_all @ Wp).reshape(m, nR, nR)
        WBt = WB.transpose(1, 0, 2).reshape(N, m * nC)
        WGt = WG.transpose(1, 0, 2).reshape(N, m * nc)
        self.AWB = (A_all @ WBt).reshape(m, nR, m, nC)
        self.AWG = (A_all @ WGt).reshape(m, nR, m, nc)
        self.CW0, self.CWp = W0[Cs], Wp[Cs]
        self.CWB, self.CWG = WB[:, Cs], WG[:, Cs]                # (m, nC, nC), (m, nC, nc)
        self.F = np.ascontiguousarray(np.array(Fl).reshape(m, nR, n)[:, :, K])
        self.rank = nR + nC
        st.lowrank_info.update(rank=self.rank, terms=m, marched_rows=nK)

    def capacitance(self, beta: np.ndarray) -> np.ndarray:
        nR, nC = self.nR, self.nC
        Cm = np.eye(nR + nC)
        Cm[:nR, :nR] += np.tensordot(beta, self.AWp, 1)
        Cm[:nR, nR:] += np.einsum("i,iakc,k->ac", beta, self.AWB, beta)
        Cm[nR:, :nR] += self.CWp
        Cm[nR:, nR:] += np.tensordot(beta, self.CWB, 1)
        return Cm

    @staticmethod
    def _equilibrate(Cm: np.ndarray):
        """Row and column scalings r, c with diag(r) Cm diag(c) of unit max-norm rows/columns
        (the blocks of the capacitance matrix differ by many orders of magnitude)."""
        r = 1.0 / np.maximum(np.abs(Cm).max(axis=1), 1e-300)
        c = 1.0 / np.maximum(np.abs(Cm * r[:, None]).max(axis=0), 1e-300)
        return r, c

    def _solve(self, Cm: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        r, c = self._equilibrate(Cm)
        return c[:, None] * np.linalg.solve(Cm * r[:, None] * c[None, :], rhs * r[:, None])

    def _terms(self, XK: np.ndarray, beta: np.ndarray):
        """FX, XC and the Woodbury correction coefficients y of one step."""
        nR = self.nR
        FX = np.tensordot(beta, self.F, 1) @ XK
        XC = XK[self.posC]
        if self.rank == 0:
            return FX, XC, None
        aw = (np.tensordot(beta, self.AW0, 1) @ XK + np.tensordot(beta, self.AWp, 1) @ FX
              + np.einsum("i,iakc,k->ac", beta, self.AWG, beta) @ XC)
        cw = self.CW0 @ XK + self.CWp @ FX + np.tensordot(beta, self.CWG, 1) @ XC
        y = self._solve(self.capacitance(beta), np.vstack([aw, cw]))
        return FX, XC, y

    def step(self, XK: np.ndarray, beta: np.ndarray, rows: str = "K") -> np.ndarray:
        """x1 on the rows K (rows="K") or on all n rows (rows="all") from x0 on the rows K."""
        W0, Wp, WB, WG = self.rowsets[rows]
        FX, XC, y = self._terms(XK, beta)
        x1 = W0 @ XK
        if y is None:
            return x1
        nR = self.nR
        x1 += Wp @ FX
        x1 += np.tensordot(beta, WG, 1) @ XC
        x1 -= Wp @ y[:nR]
        x1 -= np.tensordot(beta, WB, 1) @ y[nR:]
        return x1

    def stage_solution(self, X: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """The full stage solution L(t)^{-1} R(t) X (N x d) of one step (for the check)."""
        XK = X[self.K]
        FX, XC, y = self._terms(XK, beta)
        w = self.W0 @ XK + self.Wp @ FX + np.tensordot(beta, self.WG, 1) @ XC
        if y is None:
            return w
        return w - self.Wp @ y[:self.nR] - np.tensordot(beta, self.WB, 1) @ y[self.nR:]

    def check(self, st: "_Stepper", X: np.ndarray, h: float, betas: np.ndarray,
              ts: np.ndarray) -> bool:
        """Conditioning of the (equilibrated) capacitance matrices of all steps, and the first
        step's stage solution for a few combinations of the columns of X against a factorized
        step with the unmodified coefficients (relative difference; two valid fill-reducing
        orderings of the turbine's stage matrix already differ by ~1e-10)."""
        conds = np.ones(1)
        if self.rank:
            Cs = np.array([self.capacitance(b) for b in betas])
            for i in range(Cs.shape[0]):
                r, c = self._equilibrate(Cs[i])
                Cs[i] *= r[:, None] * c[None, :]
            conds = np.linalg.cond(Cs)
        ns = ts.size // betas.shape[0]
        Ed, Ad = st.coeffs.data_at(ts[:ns])
        L, R = st.matrices(h, Ed, Ad)
        Xc = X @ np.random.default_rng(12345).standard_normal((X.shape[1], min(4, X.shape[1])))
        ref = spla.splu(L).solve(np.asarray(R @ Xc))
        st.factorizations += 1
        z = self.stage_solution(Xc, betas[0])
        err = float(np.linalg.norm(z - ref) / max(np.linalg.norm(ref), 1e-300))
        st.lowrank_info.update(check=err, max_capacitance_cond=float(np.max(conds)))
        return bool(err <= _LOWRANK_CHECK_TOL and np.all(np.isfinite(conds))
                    and np.max(conds) < 1e12)


def _settle(coeffs, h: float, t_end: float, lowrank: Optional[bool] = False,
            stepper: Optional["_Stepper"] = None) -> tuple[np.ndarray, int]:
    """_SETTLE_STEPS Radau IIA steps of length h ending at t_end, applied to all differential
    unit vectors (the algebraic columns are irrelevant: a step depends on x0 only via E x0).
    ``stepper``: a Radau stepper to use (and whose low-rank data for h to share).  Returns the
    end values and the number of factorizations."""
    dae = coeffs.dae
    diff = np.flatnonzero(dae.differential)
    X0 = np.zeros((dae.n, diff.size))
    X0[diff, np.arange(diff.size)] = 1.0
    st = _Stepper(coeffs, "radau", lowrank=lowrank) if stepper is None else stepper
    f0 = st.factorizations
    X, _ = st.march(X0, t_end - _SETTLE_STEPS * h, h, _SETTLE_STEPS)
    return X, st.factorizations - f0


def _consistent_basis(coeffs, h: float, t_end: float, dynamic_dim: Optional[int],
                      lowrank: Optional[bool] = False, stepper: Optional["_Stepper"] = None):
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
    stepper = _Stepper(coeffs, method, lowrank=lowrank)
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


# --------------------------------------------------------------------------------------------
@dataclass
class FloquetResult:
    """Floquet modal results; arrays have one entry per dynamic multiplier (length d).

    ``exponents`` are resolved (dominant harmonic moved into the exponent), in rad/s;
    ``frequency_per_rev = Im(eta)/Omega0``, ``real_per_rev = Re(eta)/Omega0``,
    ``frequency_hz = Im(eta)/(2 pi)``, ``damping_ratio = -Re(eta)/|eta|`` (0 for eta = 0).
    Conjugate pairs: both members are kept, ``representative`` marks the member with
    frequency >= 0 (and every real multiplier).  ``eigenvectors[:, i]`` is the Floquet
    eigenvector x(0) (full state); ``periodic_samples[m, :, i]`` is p_i(t_m) on the rows
    ``sample_rows`` with x_i(t) = p_i(t) exp(eta_i t).
    """
    multipliers: np.ndarray
    exponents: np.ndarray
    exponents_principal: np.ndarray
    frequency_per_rev: np.ndarray
    real_per_rev: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    harmonic: np.ndarray
    harmonic_share: np.ndarray
    representative: np.ndarray
    eigenvectors: np.ndarray
    sample_times: np.ndarray
    sample_rows: np.ndarray
    _p_unique: np.ndarray = field(repr=False)
    _n_upper: int = field(repr=False)
    omega: float
    period: float
    method: str
    steps: int
    fast: bool
    blades: int
    n_dynamic: int
    wall_time: float
    timings: dict = field(default_factory=dict)
    #: positions in ``sample_rows`` and weights (on squared amplitudes) of the rows that
    #: decided the dominant harmonic and the normalisation
    observed: Optional[np.ndarray] = field(default=None, repr=False)
    weights: Optional[np.ndarray] = field(default=None, repr=False)

    def recombine(self, columns, Q: np.ndarray) -> None:
        """Replace the modes ``columns`` (members of one cluster of equal exponents, all with
        a positive-frequency upper member or all real) by the combinations ``V Q`` of their
        eigenvectors and periodic samples (in place; the conjugate members follow), then
        normalise them like :func:`periodic_modes`.  Used to turn an arbitrary basis of a
        degenerate eigenspace into one of the symmetry classes."""
        nu = self._n_upper
        cols = [int(c) for c in columns]
        conj = [nu <= c < 2 * nu for c in cols]
        if any(conj) and not all(conj):
            raise ValueError("recombine: mixed upper and conjugate members")
        slot = [c - nu if c >= nu else c for c in cols]              # in _p_unique
        Qe = np.conj(Q) if conj[0] else Q
        P = self._p_unique[:, :, slot] @ Qe
        V = self.eigenvectors[:, cols] @ Q
        w = np.ones(len(self.sample_rows)) if self.weights is None else self.weights
        obs = slice(None) if self.observed is None else self.observed
        nrm = np.sqrt(np.einsum("r,mrk->k", w, np.abs(P[:, obs, :]) ** 2) / P.shape[0])
        nrm[nrm == 0] = 1.0
        P /= nrm
        V /= (np.conj(nrm) if conj[0] else nrm)[None, :]
        self._p_unique[:, :, slot] = P
        self.eigenvectors[:, cols] = V
        for c, s_ in zip(cols, slot):      # the partner members
            if c < nu:
                self.eigenvectors[:, c + nu] = np.conj(self.eigenvectors[:, c])
            elif c < 2 * nu:
                self.eigenvectors[:, c - nu] = np.conj(self.eigenvectors[:, c])
        self.__dict__.pop("_periodic_samples_cache", None)

    @property
    def periodic_samples(self) -> np.ndarray:
        """(M, len(sample_rows), d) complex: p_i(t_m), built on first use and cached
        (conjugate members are the conjugates of their partners); do not modify in place."""
        cached = self.__dict__.get("_periodic_samples_cache")
        if cached is None:
            P, nu = self._p_unique, self._n_upper
            cached = np.concatenate([P[:, :, :nu], np.conj(P[:, :, :nu]), P[:, :, nu:]], axis=2)
            self.__dict__["_periodic_samples_cache"] = cached
        return cached

    def periodic_sample(self, i: int) -> np.ndarray:
        """(M, len(sample_rows)) samples of the periodic eigenvector of mode i."""
        nu = self._n_upper
        if i < nu:
            return self._p_unique[:, :, i]
        if i < 2 * nu:
            return np.conj(self._p_unique[:, :, i - nu])
        return self._p_unique[:, :, i - nu]

    def modes(self, sort: bool = True) -> np.ndarray:
        """Indices of the representative members, sorted by frequency then real part."""
        idx = np.flatnonzero(self.representative)
        if sort:
            idx = idx[np.lexsort((self.real_per_rev[idx], self.frequency_per_rev[idx]))]
        return idx

    def summary(self) -> str:
        lines = [f"Floquet: {self.n_dynamic} multipliers, method={self.method}, "
                 f"steps/period={self.steps}, fast={self.fast}, {self.wall_time * 1e3:.1f} ms",
                 "   freq/rev     real/rev      freq Hz    damping   |lambda|   k  share"]
        for i in self.modes():
            lines.append(f"{self.frequency_per_rev[i]:11.6f} {self.real_per_rev[i]:12.4e} "
                         f"{self.frequency_hz[i]:12.6f} {self.damping_ratio[i]:10.3e} "
                         f"{abs(self.multipliers[i]):10.6f} {self.harmonic[i]:3d} "
                         f"{self.harmonic_share[i]:6.3f}")
        return "\n".join(lines)


def _real_tol(lam: np.ndarray) -> float:
    """Multipliers with |Im mu| below this are treated as real: 1e-7 (relative) covers the
    O(sqrt(eps)) splitting of a defective double multiplier at 1 (free yaw angle with a
    conserved yaw momentum), which would otherwise appear as a spurious tiny frequency."""
    return 1e-7 * max(1.0, float(np.max(np.abs(lam), initial=1.0)))


def _dominant_harmonic(energy: np.ndarray, k: np.ndarray, freq0: float, w0: float,
                       tie: float) -> int:
    """Position in ``k`` (integer harmonics) of the dominant harmonic: the largest ``energy``;
    candidates within 1e-6 (relative) of it tie, and ties (real eigenvectors) prefer the
    non-negative frequency ``freq0 + k w0`` (negative: below ``-tie * w0``), then the
    smallest |frequency|."""
    cand = np.flatnonzero(energy >= energy.max() * (1.0 - 1e-6))
    freqs = freq0 + k[cand] * w0
    best = min(range(cand.size), key=lambda j: (freqs[j] < -tie * w0, abs(freqs[j])))
    return int(cand[best])


def floquet_analysis(dae: LinearPeriodicDAE, method: str = "radau", steps: Optional[int] = None,
                     fast: Optional[bool] = None, samples: int = 128, observed=None,
                     weights=None, coefficients="fourier", harmonics="auto",
                     fourier_tol: float = 1e-10, dynamic_dim: Optional[int] = None,
                     store_all: bool = False, lowrank: Optional[bool] = None) -> FloquetResult:
    """Floquet multipliers, resolved characteristic exponents and periodic eigenvectors.

    observed : indices of the variables used for the dominant-harmonic analysis (default: all
        differential variables); weights : per observed variable (default 1), applied to the
        squared Fourier amplitudes, so that units do not decide.
    lowrank : low-rank stage update (see :func:`monodromy`); None automatic.
    """
    t0 = time.perf_counter()
    mono = monodromy(dae, method=method, steps=steps, fast=fast, coefficients=coefficients,
                     harmonics=harmonics, fourier_tol=fourier_tol, samples=samples,
                     observed=observed, dynamic_dim=dynamic_dim, store_all=store_all,
                     lowrank=lowrank)
    t1 = time.perf_counter()
    T, w0, nb = dae.period, dae.omega, mono.blades
    d = mono.n_dynamic
    mu, V = mono.eig()
    # --- canonical conjugate structure: upper members, their conjugates, real ones
    tol = _real_tol(mu)
    upper = np.flatnonzero(mu.imag > tol)
    real = np.flatnonzero(np.abs(mu.imag) <= tol)
    nlow = int(np.sum(mu.imag < -tol))
    if nlow != upper.size:     # should not happen for a real matrix
        upper = np.flatnonzero(mu.imag > 0)
        real = np.flatnonzero(mu.imag == 0)
    mus = list(mu[upper]) + [complex(np.real(mu[i]), 0.0) for i in real]
    vecs = [V[:, i] for i in upper]
    for i in real:
        v = V[:, i]
        j = np.argmax(np.abs(v))
        vecs.append(np.real(v * np.conj(v[j]) / abs(v[j])))
    mus = np.array(mus, dtype=complex)
    Vc = np.column_stack(vecs).astype(complex) if vecs else np.zeros((V.shape[0], 0), complex)
    nu = upper.size
    # --- samples of x over the full period: x(t + j tau) = mu^j S^j x(t)
    obs_rows = mono.sample_rows
    if observed is None:
        obs_local = np.flatnonzero(dae.differential[obs_rows])
    else:
        pos = {r: i for i, r in enumerate(obs_rows)}
        obs_local = np.array([pos[int(r)] for r in np.asarray(observed, dtype=int)])
    w = np.ones(obs_local.size) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.size != obs_local.size:
        raise ValueError("weights must have one entry per observed variable")
    Xs = np.array(mono.samples)                     # (M/nb, rows, d) real
    Mb = Xs.shape[0]
    Xm = np.empty((Mb * nb, Xs.shape[1], len(mus)), dtype=complex)   # (M, rows, modes)
    np.matmul(Xs, Vc, out=Xm[:Mb])
    if nb > 1:
        Srr = dae.S[obs_rows][:, obs_rows].tocsr()
        Srr.sum_duplicates()
        perm = None
        if Srr.nnz == Srr.shape[0] and np.all(np.diff(Srr.indptr) == 1):
            perm, sgn = Srr.indices, Srr.data          # a signed permutation: gather rows
        else:
            Srr = Srr.toarray()
        for j in range(1, nb):
            prev, cur = Xm[(j - 1) * Mb:j * Mb], Xm[j * Mb:(j + 1) * Mb]
            if perm is not None:
                np.multiply(prev[:, perm, :], sgn[None, :, None], out=cur)
            else:
                np.matmul(Srr, prev, out=cur)
            cur *= mus[None, None, :]
    lam = mus ** nb
    eta0 = np.log(mus) * nb / T                     # e^{eta0 T} = lambda
    t2 = time.perf_counter()
    return periodic_modes(
        eta0, Xm, mono.basis @ Vc, nu, period=T, sample_rows=obs_rows, observed=obs_local,
        weights=w, multipliers=lam, method=method, steps=mono.steps, fast=mono.fast,
        blades=nb, n_dynamic=d, start_time=t0,
        timings={"monodromy": t1 - t0, "eigen": t2 - t1,
                 "factorizations": mono.factorizations, "lowrank": mono.lowrank,
                 "coefficient_evaluations": getattr(mono.coefficients, "evaluations", None),
                 "fourier_harmonics": getattr(mono.coefficients, "harmonics", None),
                 "fourier_error": getattr(mono.coefficients, "error", None)})


def periodic_modes(eta0: np.ndarray, X: np.ndarray, x0: np.ndarray, n_upper: int, *,
                   period: float, sample_rows: np.ndarray, observed: np.ndarray,
                   weights: np.ndarray, multipliers: Optional[np.ndarray] = None,
                   method: str, steps: int, fast: bool, blades: int, n_dynamic: int,
                   start_time: Optional[float] = None, timings: Optional[dict] = None
                   ) -> FloquetResult:
    """A FloquetResult from solutions ``x_i(t) = p_i(t) exp(eta0_i t)`` (p periodic).

    ``X`` (M, len(sample_rows), m): samples x_i(t_m) at ``t_m = m period / M`` over one full
    period (any method: monodromy marching, Hill's method, multi-blade coordinates);
    ``x0`` (n, m): x_i(0) on every state row; the first ``n_upper`` columns are the members
    with a positive imaginary multiplier part (their conjugates are added), the rest real
    ones.  ``observed`` (positions in ``sample_rows``) and ``weights`` (per observed row,
    applied to squared amplitudes) decide the dominant harmonic k, which moves into the
    exponent (eta = eta0 + i k Omega); p is shifted accordingly and normalised (weighted RMS
    over the period 1, largest observed component real positive).  ``X`` is overwritten."""
    T = float(period)
    w0 = 2.0 * math.pi / T
    nu = int(n_upper)
    if start_time is None:
        start_time = time.perf_counter()
    eta0 = np.asarray(eta0, complex)
    lam = np.exp(eta0 * T) if multipliers is None else np.asarray(multipliers, complex)
    obs_local = np.asarray(observed, dtype=int)
    w = np.asarray(weights, dtype=float).ravel()
    M = X.shape[0]
    tm = np.arange(M) * T / M
    P = X
    P *= np.exp(-eta0[None, None, :] * tm[:, None, None])
    # the observed rows as a slice when they are all the sample rows in order (no copies)
    obs_sel = (slice(None) if np.array_equal(obs_local, np.arange(len(sample_rows)))
               else obs_local)
    C = np.fft.fft(P[:, obs_sel, :], axis=0) / M    # (M, obs, modes)
    energy = np.einsum("r,krm->km", w, np.abs(C) ** 2)
    kk = np.fft.fftfreq(M, 1.0 / M).astype(int)
    nm = eta0.size
    harm = np.zeros(nm, dtype=int)
    share = np.zeros(nm)
    for i in range(nm):
        e = energy[:, i]
        harm[i] = kk[_dominant_harmonic(e, kk, eta0[i].imag, w0, tie=1e-12)]
        share[i] = e.max() / max(e.sum(), 1e-300)
    eta = eta0 + 1j * harm * w0
    # build the full list: uppers, their conjugates, reals
    idx_up = np.arange(nu)
    idx_re = np.arange(nu, nm)
    all_eta = np.concatenate([eta[idx_up], np.conj(eta[idx_up]), eta[idx_re]])
    all_eta0 = np.concatenate([eta0[idx_up], np.conj(eta0[idx_up]), eta0[idx_re]])
    all_lam = np.concatenate([lam[idx_up], np.conj(lam[idx_up]), lam[idx_re]])
    all_h = np.concatenate([harm[idx_up], -harm[idx_up], harm[idx_re]])
    all_share = np.concatenate([share[idx_up], share[idx_up], share[idx_re]])
    rep = np.concatenate([eta[idx_up].imag >= 0, eta[idx_up].imag < 0,
                          np.ones(idx_re.size, bool)])
    all_V = np.concatenate([x0[:, idx_up], np.conj(x0[:, idx_up]), x0[:, idx_re]], axis=1)
    Pm = P
    Pm *= np.exp(-1j * harm[None, None, :] * w0 * tm[:, None, None])
    # normalise: weighted RMS of p over the observed rows = 1, largest component real > 0
    Po = Pm[:, obs_sel, :]
    nrm = np.sqrt(np.einsum("r,mrk->k", w, np.abs(Po) ** 2) / M)
    nrm[nrm == 0] = 1.0
    Pm /= nrm
    Po = Pm[:, obs_sel, :]
    flat = np.abs(Po).reshape(-1, nm)
    jmax = np.argmax(flat, axis=0)
    mi, ri = np.unravel_index(jmax, Po.shape[:2])
    big = Po[mi, ri, np.arange(nm)]
    ph = np.where(np.abs(big) > 0, np.conj(big) / np.where(np.abs(big) > 0, np.abs(big), 1.0), 1.0)
    ph[nu:] = np.where(np.real(ph[nu:]) < 0, -1.0, 1.0)     # real eigenvectors stay real
    Pm *= ph[None, None, :]
    scale = ph / nrm
    Vn = all_V * np.concatenate([scale[:nu], np.conj(scale[:nu]), scale[nu:]])[None, :]
    absn = np.abs(all_eta)
    zeta = np.where(absn > 0, -all_eta.real / np.where(absn > 0, absn, 1.0), 0.0)
    t_end = time.perf_counter()
    timings = dict(timings or {})
    wall = t_end - start_time
    if "monodromy" in timings:
        timings["analysis"] = wall - timings["monodromy"]
    return FloquetResult(
        multipliers=all_lam, exponents=all_eta, exponents_principal=all_eta0,
        frequency_per_rev=all_eta.imag / w0, real_per_rev=all_eta.real / w0,
        frequency_hz=all_eta.imag / (2 * math.pi), damping_ratio=zeta, harmonic=all_h,
        harmonic_share=all_share, representative=rep, eigenvectors=Vn, sample_times=tm,
        sample_rows=np.asarray(sample_rows), _p_unique=Pm, _n_upper=nu, omega=w0, period=T,
        method=method, steps=steps, fast=fast, blades=blades, n_dynamic=n_dynamic,
        wall_time=wall, timings=timings, observed=obs_local, weights=w)
