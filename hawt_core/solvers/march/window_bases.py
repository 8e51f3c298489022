"""The window solver's frozen matrices (its *base*) and their coupling updates, dense or sparse.

Both hold the scaled step matrices of one instant, ``A = dG_k/dx_k`` and ``B = dG_k/dx_{k-1}``
(differential columns), and give the window's simplified-Newton correction

    d_k = A^-1 (-G_k - B d_{k-1}),     k = 1..K,  d_0 = 0,

for the scaled residuals of K consecutive steps, with A and B changed by the rigid-body
coupling's update (WindowSolver.update_rigid): ``A = A0 + U V^T``, ``U = [dAc, E_rows]``,
``V^T = [E_cols^T; dR at the columns kc]`` and ``B = B0 + dBc E_pos^T``.

* :class:`DenseBase`: A0's dense inverse and the propagator ``P0 = -A0^-1 B0``, the update
  kept factored (``A^-1 = A0^-1 - ZC W``, ``P = P0 + U' V'^T``): the K residuals go through
  A^-1 in ONE matrix product and the recurrence ``d_k = a_k + P d_{k-1}`` costs a dense
  matrix-vector product per step. Cheapest for small systems (a few hundred unknowns), where
  NumPy's call overhead, not arithmetic, sets the cost; windows of one step without updates
  use A0's LU alone.
* :class:`SparseBase`: A0's sparse LU (SuperLU) and B0 sparse; each step one triangular solve
  pair, one sparse product and the Woodbury correction ``y0 - ZC [y0[cols]; dR y0[kc]]``.
  The base costs a sparse factorization (3 ms at 1204 unknowns) instead of a dense inverse
  and P0 (about 200 ms), and a correction of 12 steps 1.2 ms instead of 5.3.

Both give the same corrections to round-off (tests/test_simulate.py).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...numerics.woodbury import row_column_capacitance


class WindowFailure(RuntimeError):
    """The window iteration did not converge, or its frozen matrices are singular or not
    finite (the caller refreshes the base or falls back to single steps)."""


class DenseBase:
    """Dense frozen matrices: ``A0`` (n, n), ``B0`` (n, nd) scaled; ``di`` the differential
    unknowns (B's columns, the recurrence's rows)."""

    def __init__(self, A0: np.ndarray, B0: np.ndarray, di: np.ndarray):
        self.A0, self.B0, self.di = A0, B0, di
        self._lu = None
        self.Ainv0 = self.P0 = self.P0d = None
        self._lowrank = None

    def ensure_inverse(self):
        """A0's inverse and P0 = -A0^-1 B0, formed on first need (windows of more than one
        step, or coupling updates). LAPACK's getrf + getri (scipy.linalg.inv), not the LU's
        solve against the identity: 1.6x faster (31 vs 50 ms at 650 unknowns, one thread)."""
        if self.Ainv0 is not None:
            return
        try:
            Ainv = sla.inv(self.A0, check_finite=False)
        except (ValueError, sla.LinAlgError) as exc:
            raise WindowFailure(f"singular Newton matrix ({exc})") from exc
        if not np.all(np.isfinite(Ainv)):
            raise WindowFailure("singular Newton matrix")
        self.Ainv0, self.P0 = Ainv, -Ainv @ self.B0
        self.P0d = np.ascontiguousarray(self.P0[self.di])

    def _lu0(self):
        if self._lu is None:
            try:
                self._lu = sla.lu_factor(self.A0, check_finite=False)
            except (ValueError, sla.LinAlgError) as exc:
                raise WindowFailure(f"singular Newton matrix ({exc})") from exc
        return self._lu

    def update(self, dAc, dBc, dR, cols, rows, kc, pos):
        """Replace the coupling: A = A0 + dAc E_cols^T + E_rows dR E_kc^T, B = B0 + dBc
        E_pos^T (the previous update is dropped)."""
        self.ensure_inverse()
        Ainv0, P0 = self.Ainv0, self.P0
        p = len(cols)
        AU = Ainv0 @ np.concatenate([dAc, dBc], axis=1)                      # one product
        Z = np.concatenate([AU[:, :p], Ainv0[:, rows]], axis=1)               # A0^-1 U
        W = np.concatenate([Ainv0[cols], dR @ Ainv0[kc]], axis=0)             # V^T A0^-1
        try:
            ZC = Z @ row_column_capacitance(Z, dR, cols, kc)
        except np.linalg.LinAlgError as exc:
            raise WindowFailure(f"singular rigid-body update ({exc})") from exc
        # A^-1 = A0^-1 - ZC W, kept factored; P = -A^-1 B: P = P0 + ZC W B0 - A^-1 dBc
        # E_pos^T, where W B0 = -[P0[cols]; dR P0[kc]] (P0 = -A0^-1 B0): a rank
        # len(cols) + len(rows) + len(pos) update of P0
        Y = AU[:, p:] - ZC @ (W @ dBc)                                        # A^-1 dBc
        WB = -np.concatenate([P0[cols], dR @ P0[kc]], axis=0)
        Vt = np.zeros((WB.shape[0] + p, len(self.di)))
        Vt[:WB.shape[0]] = WB
        Vt[WB.shape[0] + np.arange(p), pos] = 1.0
        U = np.concatenate([ZC, -Y], axis=1)
        if not all(np.all(np.isfinite(a)) for a in (ZC, W, U, Vt)):
            raise WindowFailure("non-finite rigid-body update")
        self._lowrank = (ZC, W, U, np.ascontiguousarray(U[self.di]), Vt)

    def correction(self, Gs: np.ndarray) -> np.ndarray:
        """d_k (K, n) for the scaled negative residuals ``Gs`` (K, n) (rows already
        multiplied by -row scale). The recurrence runs on the differential part only (P's
        rows there, contiguous); the other rows follow in one product."""
        if self.Ainv0 is None and Gs.shape[0] == 1:     # one step: the LU alone
            return sla.lu_solve(self._lu0(), Gs.T).T
        self.ensure_inverse()
        D = Gs @ self.Ainv0.T
        lr = self._lowrank
        if lr is not None:
            ZC, W, U, Ud, Vt = lr
            D -= (Gs @ W.T) @ ZC.T
        Dd = D[:, self.di]
        P0d = self.P0d
        for k in range(1, D.shape[0]):
            Dd[k] += P0d @ Dd[k - 1]
            if lr is not None:
                Dd[k] += Ud @ (Vt @ Dd[k - 1])
        D[1:] += Dd[:-1] @ self.P0.T
        if lr is not None:
            D[1:] += (Dd[:-1] @ Vt.T) @ U.T
        return D

    def inverse(self) -> np.ndarray:
        """The current A^-1 (dense; tests and diagnostics)."""
        self.ensure_inverse()
        if self._lowrank is None:
            return self.Ainv0
        ZC, W = self._lowrank[:2]
        return self.Ainv0 - ZC @ W

    def propagator(self) -> np.ndarray:
        """The current P = -A^-1 B (dense; tests and diagnostics)."""
        self.ensure_inverse()
        if self._lowrank is None:
            return self.P0
        U, Vt = self._lowrank[2], self._lowrank[4]
        return self.P0 + U @ Vt


class SparseBase:
    """Sparse frozen matrices (``A0``, ``B0`` scipy sparse, scaled): A0's SuperLU
    factorization (COLAMD ordering: the least fill of SciPy's orderings on the turbine's
    step matrix, 92 k entries in L + U at 1204 unknowns)."""

    def __init__(self, A0, B0, di: np.ndarray):
        self.A0 = sp.csc_matrix(A0)
        self.B0 = sp.csr_matrix(B0)
        self.di = di
        try:
            self._lu = spla.splu(self.A0, permc_spec="COLAMD")
        except RuntimeError as exc:            # SuperLU: "Factor is exactly singular"
            raise WindowFailure(f"singular Newton matrix ({exc})") from exc
        self._lowrank = None

    def update(self, dAc, dBc, dR, cols, rows, kc, pos):
        """As DenseBase.update: Z = A0^-1 U by one multi-column solve."""
        n = self.A0.shape[0]
        E = np.zeros((n, len(rows)))
        E[rows, np.arange(len(rows))] = 1.0
        Z = self._lu.solve(np.concatenate([dAc, E], axis=1))
        try:
            ZC = Z @ row_column_capacitance(Z, dR, cols, kc)
        except np.linalg.LinAlgError as exc:
            raise WindowFailure(f"singular rigid-body update ({exc})") from exc
        if not (np.all(np.isfinite(ZC)) and np.all(np.isfinite(dBc))):
            raise WindowFailure("non-finite rigid-body update")
        self._lowrank = (ZC, dR, cols, kc, dBc, pos)

    def _solve(self, b):
        """A^-1 b (vector or columns) with the update."""
        y = self._lu.solve(b)
        lr = self._lowrank
        if lr is not None:
            ZC, dR, cols, kc = lr[:4]
            y = y - ZC @ np.concatenate([y[cols], dR @ y[kc]])
        return y

    def correction(self, Gs: np.ndarray) -> np.ndarray:
        """d_k (K, n) for the scaled negative residuals ``Gs`` (K, n): K solves in turn."""
        D = np.empty_like(Gs)
        lr = self._lowrank
        di = self.di
        for k in range(Gs.shape[0]):
            rhs = Gs[k]
            if k:
                dk = D[k - 1, di]
                rhs = rhs - self.B0 @ dk
                if lr is not None:
                    rhs -= lr[4] @ dk[lr[5]]
            D[k] = self._solve(rhs)
        return D

    def inverse(self) -> np.ndarray:
        return self._solve(np.eye(self.A0.shape[0]))

    def propagator(self) -> np.ndarray:
        B = self.B0.toarray()
        lr = self._lowrank
        if lr is not None:
            B[:, lr[5]] += lr[4]
        return -self._solve(B)
