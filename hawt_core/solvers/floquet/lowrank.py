"""Low-rank time variation of the stage matrices: one factorization of the mean stage matrix
and a Woodbury update per step, when the harmonics of E(t), A(t) are confined to a few rows
and columns (docs/floquet.md, "Low-rank time variation").
"""

from __future__ import annotations

from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...numerics.woodbury import equilibrate_rows_columns, equilibrated_solve
from .coefficients import FourierCoefficients


# --------------------------------------------------------------------------------------------
# low-rank time variation: one factorization of the mean stage matrix + Woodbury updates
LOWRANK_VAR_TOL = 1e-13      # harmonics below this x the row's largest coefficient: constant

LOWRANK_MAX_FRACTION = 8     # automatic: varying rows + columns <= n / 8

LOWRANK_MIN_N = 64           # automatic: not for smaller systems

LOWRANK_CHECK_TOL = 1e-7     # first step vs a factorized step (relative): gross errors


def varying_cover(coeffs: FourierCoefficients, tol: float, max_size: Optional[int] = None):
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


class LowRankUpdate:
    """One step x1 = out(L(t)^{-1} R(t) x0) with L(t) = L0 + P_Rs a(t) + b(t) P_Cs^T.

    L0, R0: stage and right-hand-side matrices of the mean coefficients (one sparse LU per
    step size).  The harmonics of E(t), A(t) live in the rows R and columns C only, so with
    beta = the Fourier basis at the stage times (constant term excluded),
    a = sum_i beta_i A_i (the rows Rs of the harmonic stage matrices), b = sum_i beta_i B_i
    (their columns Cs, rows Rs removed), R(t) = R0 + P_Rs F(beta) + G(beta) P_C^T.  Woodbury:
    L^{-1} = L0^{-1} - L0^{-1} U (I + V^T L0^{-1} U)^{-1} V^T L0^{-1},  U = [P_Rs, b],
    V^T = [a; P_Cs^T]; every product with L0^{-1} is precomputed, so a step costs one n x n
    by n x d product plus products with the r = |Rs| + |Cs| low-rank directions.

    ``st`` (here and in :meth:`check`): the stepper (hawt_core.solvers.floquet.steppers)
    whose stage matrices are updated; it imports this module, so it is not named here."""

    def __init__(self, st, h: float, R, C, cEv, cAv):
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
        # the blocks of the capacitance differ by many orders of magnitude
        y = equilibrated_solve(self.capacitance(beta), np.vstack([aw, cw]))
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

    def check(self, st, X: np.ndarray, h: float, betas: np.ndarray,
              ts: np.ndarray) -> bool:
        """Conditioning of the (equilibrated) capacitance matrices of all steps, and the first
        step's stage solution for a few combinations of the columns of X against a factorized
        step with the unmodified coefficients (relative difference; two valid fill-reducing
        orderings of the turbine's stage matrix already differ by ~1e-10)."""
        conds = np.ones(1)
        if self.rank:
            Cs = np.array([self.capacitance(b) for b in betas])
            for i in range(Cs.shape[0]):
                r, c = equilibrate_rows_columns(Cs[i])
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
        return bool(err <= LOWRANK_CHECK_TOL and np.all(np.isfinite(conds))
                    and np.max(conds) < 1e12)
