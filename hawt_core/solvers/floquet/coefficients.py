"""Linear periodic descriptor systems ``E(t) x' = A(t) x`` and their coefficients: evaluated
directly at every time, or as truncated Fourier series on the union sparsity pattern
(docs/floquet.md, "Coefficients").
"""

from __future__ import annotations

import math
import warnings
from typing import Callable, Optional, Sequence

import numpy as np
import scipy.sparse as sp

__all__ = ['LinearPeriodicDAE', 'FourierCoefficients', 'DirectCoefficients']


# --------------------------------------------------------------------------------------------
# sparse patterns and coefficient providers
class _Pattern:
    """A fixed sparsity pattern (CSC order) of an n x n matrix."""

    def __init__(self, n: int, keys: np.ndarray, unique: bool = False):
        self.n = n
        keys = np.asarray(keys, dtype=np.int64)                    # key = col * n + row
        self.keys = keys if unique else np.unique(keys)
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
        """(keys, values) of ``mat``'s stored entries, keys sorted and distinct (CSC order,
        duplicates summed)."""
        m = _as_sparse(mat, n).tocsc()
        m.sum_duplicates()                      # canonical: sorted rows in every column
        cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(m.indptr))
        return cols * n + m.indices.astype(np.int64), m.data

    @classmethod
    def union(cls, n: int, key_arrays) -> "_Pattern":
        """The union of key arrays: marked in a boolean array of the n x n positions (one
        scatter per array; the samples' patterns differ slightly, so pairwise unions or one
        sort of all keys cost seconds at 3000 unknowns), or sorted together when n x n is
        too large to mark."""
        key_arrays = list(key_arrays)
        if n * n <= 200_000_000:
            mark = np.zeros(n * n, bool)
            for k in key_arrays:
                mark[k] = True
            return cls(n, np.flatnonzero(mark).astype(np.int64), unique=True)
        return cls(n, np.concatenate(key_arrays) if key_arrays else np.zeros(0, np.int64))

    def data_of(self, mat, keyed=None) -> Optional[np.ndarray]:
        """Values of ``mat`` on this pattern; None if ``mat`` has nonzeros outside it.
        ``keyed``: ``(keys, vals)`` of ``mat`` from :meth:`keys_of`, when known."""
        keys, vals = self.keys_of(mat, self.n) if keyed is None else keyed
        if keys.size == self.nnz and np.array_equal(keys, self.keys):
            return np.real(vals).astype(float)          # the same pattern, same order
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
            raise PatternChanged()
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


class PatternChanged(Exception):
    pass


class FourierCoefficients:
    """Truncated Fourier series of E(t), A(t) on their union sparsity patterns.

    The data arrays of the sparse matrices sampled at N equally spaced times are transformed
    by a real DFT and truncated at K = (N - 1) // 2 harmonics (for even N the Nyquist term is
    dropped); the series reproduces any trigonometric polynomial of degree < N / 2 exactly.  ``error`` is the largest relative deviation from a direct evaluation at
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
            """((keys, values) of E(t), (keys, values) of A(t)), each time evaluated once."""
            key = round(float(t) / T, 15)
            if key not in cache:
                cache[key] = (_Pattern.keys_of(dae.E(float(t)), n),
                              _Pattern.keys_of(dae.A(float(t)), n))
            return cache[key]

        if harmonics == "auto":
            # nested grids (every sample is reused at the next level): 5, 15, then doubling
            # (30, 60, 120): the series of an aeroelastic linearization decays only
            # algebraically (C1 airfoil tables), so tripling overshoots (NREL 5-MW at 25 m/s,
            # 48 elements: 2.6e-8 at 15 samples, 7.4e-9 at 29, 45 taken with tripling)
            levels = []
            N = 5
            while (N - 1) // 2 <= max_harmonics:
                levels.append(N)
                N *= 3 if N == 5 else 2
        else:
            K = int(harmonics)
            if K < 0:
                raise ValueError("harmonics must be >= 0")
            levels = [2 * K + 1]
        for li, N in enumerate(levels):
            ts = T * np.arange(N) / N
            mats = [sample(t) for t in ts]
            # check times: points of the next grid (f N samples), i.e. not on this grid
            f = levels[li + 1] // N if li + 1 < len(levels) else 3
            tc = T * (f * np.array([0, N // 3, (2 * N) // 3, N - 1]) + 1) / (f * N)
            chk = [sample(t) for t in tc]
            self.pE = _Pattern.union(n, [m[0][0] for m in mats + chk])
            self.pA = _Pattern.union(n, [m[1][0] for m in mats + chk])
            self._fit(np.array([self.pE.data_of(None, m[0]) for m in mats]),
                      np.array([self.pA.data_of(None, m[1]) for m in mats]), N)
            Ec, Ac = self.data_at(tc)
            Ed = np.array([self.pE.data_of(None, m[0]) for m in chk])
            Ad = np.array([self.pA.data_of(None, m[1]) for m in chk])
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
        """Rows: [a0, a1..aK, b1..bK] with f = a0 + sum a_k cos(k w t) + b_k sin(k w t),
        from the N equally spaced samples D (N, nnz) by a real FFT (its round-off on
        time-invariant entries is what the defective double zero of a free yaw splits by:
        a DFT by one matrix product, faster, split it by 1.7e-6 instead of 3.3e-7 per-rev,
        tests/test_multiblade.py)."""
        F = np.fft.rfft(D, axis=0) / N
        return np.vstack([F[0].real[None, :], 2.0 * F[1:K + 1].real, -2.0 * F[1:K + 1].imag])

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
