"""The step-by-step solver of the implicit-midpoint simulation (a mixin of the Simulator):
Newton's method per step with a reused sparse LU of the scaled Jacobian, the low-rank
(Woodbury) update of the rigid rows and columns that turn with the azimuth, and the
predictors of the step unknowns (Lagrange and autoregressive extrapolation).
"""

from __future__ import annotations

import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from ...numerics.jacobian import STEP
from ...numerics.woodbury import row_column_capacitance, row_column_correction
from .initial import SimulationError
from .window import midpoint_arguments, step_matrix

__all__ = ['StepSolver']


class StepSolver:
    """One implicit-midpoint step at a time (mixin of
    :class:`~hawt_core.solvers.march.Simulator`)."""

    # ------------------------------------------------------------------ the step
    def _G(self, x, yn, tm, h):
        """Midpoint residual of the step unknowns x = [y_{n+1} | z_{n+1/2}] (n,), or of K
        sets of them (K, n) (same step: one batched residual evaluation)."""
        return self.model.residual(*midpoint_arguments(x, yn, self._di, h), tm)

    def _refresh_jacobian(self, x, yn, tm, h):
        """Exact Newton matrix dG/dx at x (= dR/dydot / h + dR/dy / 2 on differential
        columns, dR/dy on algebraic ones): from the model's structured Jacobians when it has
        them (TurbineModel.jacobians: a few batched calls), else one coloured complex-step
        pass over G itself."""
        w0 = time.perf_counter()
        m = self.model
        if hasattr(m, "jacobians"):
            Jy, Jd = (sp.csc_matrix(J) for J in m.jacobians(*midpoint_arguments(x, yn, self._di,
                                                                                 h), tm))
            J = step_matrix(Jy, Jd, self.diff, h)
        else:
            J = self._colour(lambda xx: self._G(xx, yn, tm, h), x)
        self.jacobian_evaluations += 1
        self._jac_fresh = True
        J = sp.csc_matrix(J)
        if self._rc is not None:
            self._add_snapshot(tm, h, J[:, np.concatenate([self._rc, self._kc])].toarray())
        self._factor(J, h)
        self._refresh_cost = time.perf_counter() - w0
        self._extra_since_refresh = 0.0

    def _maybe_schedule_refresh(self, its):
        """After a step with a reused matrix: schedule a refresh before the next step when
        Newton contracts slowly (theta > refresh_contraction, or more than 4 iterations), or
        when the time spent on iterations beyond those of the first step after the last
        refresh exceeds the cost of a refresh (so that reuse never costs more than about twice
        the optimum). The refresh is the low-rank update of the rigid rows and columns when
        the model has them and the stored factorization still serves well after such an
        update (its first step needed no more iterations than after a full refresh), else a
        full Jacobian."""
        low = self._rc is not None and self._J0 is not None and (
            self._its_after_update is None or self._its_after_refresh is None
            or self._its_after_update <= self._its_after_refresh)
        if self._theta > self.refresh_contraction or its > 4:
            self._pending = "update" if (low and self._theta < 0.5) else "refresh"
            return
        base = min(self._its_fresh, 2) if self._its_fresh is not None else 2
        self._extra_since_refresh += max(0, its - base) * self._iter_cost
        cost = (self._update_cost if self._update_cost else self._refresh_cost / 2) \
            if low else self._refresh_cost
        if self._extra_since_refresh > cost:
            self._pending = "update" if low else "refresh"

    def _solve(self, b):
        """Solve with the stored (scaled) Newton matrix, including the low-rank update of the
        rigid rows and columns (Woodbury) when there is one."""
        y = self._lu.solve(b)
        wb = self._wb
        if wb is not None:
            Z, Cinv, D = wb
            y = row_column_correction(y, Z, Cinv, D, self._rc, self._kc)
        return y

    # ------------------------------------------------------------------ low-rank update
    def _setup_low_rank(self):
        """Index sets of the low-rank update: the rigid unknowns ``rc`` (the first
        ``nq + nu``; their rows and columns vary with the azimuth when the yaw is free) and
        the other columns ``kc`` the rigid rows depend on (the blades' root loads, from the
        model's sparsity pattern)."""
        self._wb = None
        self._J0 = None
        self._rc = self._kc = None
        self._snaps = []
        self.low_rank_updates = 0
        m = self.model
        nr = int(getattr(m, "nq", 0)) + int(getattr(m, "nu", 0))
        if nr == 0 or not hasattr(m, "sparsity") or nr > 16:
            return
        P = sp.csr_matrix(m.sparsity())
        kc = np.unique(P[:nr].indices)
        self._rc = np.arange(nr)
        self._kc = kc[kc >= nr]

    def _low_rank_update(self, x, yn, tm, h):
        """Exact rigid rows and columns of the Newton matrix at x (complex steps of G along
        the rigid unknowns and the columns of the rigid rows: ONE batched residual evaluation
        of ``nq + nu + len(kc)`` instants instead of a full Jacobian), stored as a snapshot;
        see :meth:`_set_woodbury` for how the snapshots update the stored LU."""
        w0 = time.perf_counter()
        cols = np.concatenate([self._rc, self._kc])
        xc = np.tile(x.astype(complex), (len(cols), 1))
        xc[np.arange(len(cols)), cols] += 1j * STEP
        Jc = self._G(xc, yn, tm, h).imag.T / STEP
        self.residual_evaluations += len(cols)
        self._add_snapshot(tm, h, Jc)
        self.low_rank_updates += 1
        self._upd_fresh = True
        self._update_cost = time.perf_counter() - w0
        self._extra_since_refresh = 0.0

    def _add_snapshot(self, tm, h, Jc):
        """Keep the exact rigid rows/columns ``Jc = dG/dx[:, rc + kc]`` (unscaled) at time tm
        (the last two)."""
        self._snaps = [sn for sn in self._snaps[-1:] if sn["h"] == h] + \
            [{"t": tm, "h": h, "J": Jc, "gen": -1}]

    def _set_woodbury(self, t, h):
        """Low-rank update of the stored LU for the step at midpoint time t: the rigid rows
        and columns are replaced by their values linearly extrapolated in time from the last
        two snapshots (exact at a snapshot; they vary with the azimuth when the yaw is free),
        applied by the Woodbury formula
        ``(J0 + U V^T)^-1 = J0^-1 - J0^-1 U (I + V^T J0^-1 U)^-1 V^T J0^-1`` with
        ``U = [dJ[:, rc], E_rc]``, ``V^T = [E_rc^T; dJ[rc, kc]]`` (rank 2 (nq + nu)).
        U and dJ are linear in the snapshot values, so J0^-1 U is formed once per snapshot and
        LU, and each step costs a few small products and a (2 (nq+nu))^2 inverse."""
        self._wb = None
        snaps = [sn for sn in self._snaps if sn["h"] == h]
        if not snaps or self._J0 is None:
            return
        rc, kc = self._rc, self._kc
        nr = len(rc)
        for sn in snaps:
            if sn["gen"] != self.factorizations:         # (re)form against the current LU
                cols = np.concatenate([rc, kc])
                Js = sn["J"] * (self._row[:, None] * self._scale[cols][None, :])
                U = np.zeros((self.n, 2 * nr))
                U[:, :nr] = Js[:, :nr] - self._J0[:, rc].toarray()
                U[rc, nr + np.arange(nr)] = 1.0
                sn["Z"] = self._lu.solve(U)
                sn["dR"] = Js[rc, nr:] - self._J0[rc][:, kc].toarray()
                sn["gen"] = self.factorizations
        b = snaps[-1]
        Z, dR = b["Z"], b["dR"]
        if len(snaps) == 2:
            a = snaps[0]
            span = b["t"] - a["t"]
            if 0 < span <= 60 * h:
                s_ = (t - b["t"]) / span
                Z = Z + s_ * (Z - a["Z"])
                dR = dR + s_ * (dR - a["dR"])
        try:
            Cinv = row_column_capacitance(Z, dR, rc, kc)
        except np.linalg.LinAlgError:
            return
        if np.all(np.isfinite(Cinv)):
            self._wb = (Z, Cinv, dR)

    def _factor(self, J, h):
        J = sp.csc_matrix(J @ sp.diags(self._scale))
        rmax = np.asarray(abs(J).max(axis=1).todense()).ravel()
        rmax[rmax == 0] = 1.0
        self._row = 1.0 / rmax
        J = sp.csc_matrix(sp.diags(self._row) @ J)
        self._J0 = J if self._rc is not None else None
        self._wb = None
        try:
            self._lu = spl.splu(J)
        except RuntimeError as exc:
            raise SimulationError(f"simulation: singular Newton matrix at t = {self.t:.6g} s, "
                                  f"step {self.steps} ({exc})") from exc
        self._lu_h = h
        self.factorizations += 1

    def _predict(self, t1, h, trial=False):
        """Predictor of the step unknowns. Candidates: Lagrange extrapolation of the grid
        values (differential) and of the midpoint values (algebraic) of degree 0, 1, 2, and a
        linear-prediction (autoregressive) extrapolation ``x_{n+1} = sum_k a_k x_{n+1-k}``
        (``AR_ORDER`` coefficients shared by all scaled unknowns, least squares over the last
        ``AR_WINDOW`` steps; exact for up to AR_ORDER / 2 undamped linear modes, which the
        implicit midpoint rule propagates by a fixed rotation per step). The candidate used,
        per group, is the one whose predictions were best over the recent steps (a running
        mean of the scaled error). Quadratic is best for smooth motion; after a teeter release
        the undamped, aliased high mesh frequencies dominate, where linear extrapolation is
        ~2x better than quadratic and the AR predictor ~30x (7e-6 vs 2.4e-4 scaled, N = 4,
        1 degree): then most steps converge in ONE Newton iteration."""
        # all candidates are computed (and scored) on every 8th step and while the errors
        # are unknown; otherwise only the chosen one per group, and with adaptive steps the
        # quadratic one of the differential group (for the error estimate, _error)
        best = {key: self._best_candidate(key) for key in ("d", "a")}
        trial = trial or self.steps % 8 == 0 or None in best.values()
        want = lambda key, k: trial or best[key] == k or (self.adaptive and key == "d"
                                                          and k == 2)
        cands = {"d": [None] * 4, "a": [None] * 4}
        g = self._grid[-3:]
        ts = np.array([a for a, _ in g])
        ys = [b for _, b in g]
        for k in range(min(3, len(ts))):
            if want("d", k):
                cands["d"][k] = _extrapolate(ts[len(ts) - k - 1:], ys[len(ts) - k - 1:], t1)
        if self._mid:
            mids = self._mid[-3:]
            tm = np.array([a for a, _ in mids])
            zs = [b for _, b in mids]
            for k in range(min(3, len(tm))):
                if want("a", k):
                    cands["a"][k] = _extrapolate(tm[len(tm) - k - 1:], zs[len(tm) - k - 1:],
                                                 t1 - h / 2)
        else:
            cands["a"][0] = self._z_init.copy()
        if want("d", 3) or want("a", 3):
            ar = self._ar_predict(h)
            if ar is not None:
                cands["d"][3] = ar[self._di]
                cands["a"][3] = ar[self._ai]
        if not trial and any(cands[key][best[key]] is None for key in ("d", "a")):
            return self._predict(t1, h, trial=True)     # the chosen one is not available
        self._cands = cands
        x = np.empty(self.n)
        for key, idx in (("d", self._di), ("a", self._ai)):
            c = cands[key]
            err = np.array([e if p is not None else np.inf
                            for e, p in zip(self._pred_err[key], c)])
            if np.isfinite(err).any():
                k = int(np.argmin(err))
            else:
                k = max(i for i, p in enumerate(c) if p is not None and i < 3)
            x[idx] = c[k]
        return x

    def _best_candidate(self, key):
        err = np.array(self._pred_err[key])
        return int(np.argmin(err)) if np.isfinite(err).any() else None

    def _ar_predict(self, h):
        """The autoregressive candidate (see :meth:`_predict`), or None without a long enough
        history at this step size."""
        P, M = self.AR_ORDER, self.AR_WINDOW
        K = P + M
        if len(self._xhist) < K or any(hh != h for hh, _ in self._xhist[-K:]):
            return None
        Xh = np.array([x for _, x in self._xhist[-K:]])          # (K, n), oldest first
        S = Xh @ Xh.T
        rk = self._ar_rows                                        # (M, P)
        A = S[rk[:, :, None], rk[:, None, :]].sum(0)
        b = S[rk, self._ar_targets[:, None]].sum(0)
        A[np.diag_indices(P)] += 1e-13 * np.trace(A) / P + 1e-300
        try:
            a = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(a)):
            return None
        return (a @ Xh[::-1][:P]) * self._scale

    def _score_predictors(self, x):
        """Update the running scaled errors of the candidate predictors with the solution."""
        for key, idx in (("d", self._di), ("a", self._ai)):
            sc = self._scale[idx]
            xi = x[idx]
            for k, p in enumerate(self._cands[key]):
                if p is None:
                    continue
                e = float(np.abs((p - xi) / sc).max()) if len(idx) else 0.0
                old = self._pred_err[key][k]
                self._pred_err[key][k] = e if not np.isfinite(old) else 0.8 * old + 0.2 * e

    def _theta_estimate(self, dn0):
        """Contraction rate expected for this step before its second iteration: the LARGEST
        of the last 10 measured ones (a fresh matrix shows only Newton's quadratic term, but
        the reused one soon contracts more slowly, so the minimum would be unsafe), scaled
        up with the size of the first correction, grown by 1.5 per step since the last
        measurement; never more than 3 steps without a measurement."""
        hist, dn_ref, age = self._theta_meas
        if not hist or age >= 3:
            return 1.0
        return min(1.0, max(hist) * max(1.0, dn0 / dn_ref) * 1.5 ** age)

    def _newton(self, yn, tn, h, x):
        """Simplified Newton with the stored factorization. Stopping test (Hairer & Wanner
        IV.8): the scaled increment times theta / (1 - theta) below ``newton_tol``, theta
        being the contraction rate; on the first iteration theta is predicted from the
        previous steps (with a safety factor 2), so a step whose first correction is tiny
        relative to the tolerance is accepted after ONE residual evaluation."""
        tm = tn + 0.5 * h
        tol = self.newton_tol
        sc = self._scale
        dn_old = dn0 = None
        dn = np.inf
        for it in range(self.max_iter):
            w0 = time.perf_counter()
            G = self._G(x, yn, tm, h)
            self.residual_evaluations += 1
            if not np.all(np.isfinite(G)):
                return None, it, np.inf, "non-finite residual"
            dxs = self._solve(self._row * G)
            x = x - dxs * sc
            self.newton_iterations += 1
            dn = float(np.abs(dxs).max())
            self._iter_cost = 0.9 * self._iter_cost + 0.1 * (time.perf_counter() - w0) \
                if self._iter_cost else time.perf_counter() - w0
            if not math.isfinite(dn):
                return None, it, np.inf, "non-finite Newton increment"
            if it == 0:
                dn0 = dn
                theta = self._theta_estimate(dn)
                if theta < 0.5 and 2.0 * theta / (1 - theta) * dn <= tol:
                    self._theta_meas[2] += 1
                    return x, 1, dn, ""
            else:
                theta = dn / dn_old if dn_old > 0 else 0.0
                if theta >= 0.9:
                    return None, it, dn, f"Newton diverging (contraction {theta:.2f})"
                self._theta = max(self._theta, theta)
                if it == 1 and dn0 > 0:
                    hist = (self._theta_meas[0] or [])[-9:] + [max(theta, 1e-16)]
                    self._theta_meas = [hist, dn0, 0]
                if theta / (1 - theta) * dn <= tol:
                    return x, it + 1, dn, ""
            if dn <= 1e-3 * tol or (it >= 3 and dn <= 1e-9):   # round-off floor
                return x, it + 1, dn, ""
            dn_old = dn
        return None, self.max_iter, dn, f"no convergence in {self.max_iter} iterations"

    def _step(self):
        h = self.h
        tn = self.t
        yn = self._grid[-1][1]
        while True:
            t1 = tn + h
            x0 = self._predict(t1, h)
            if self._lu is None or self._lu_h != h or self._pending == "refresh":
                self._refresh_jacobian(x0, yn, tn + h / 2, h)
            elif self._pending == "update":
                self._low_rank_update(x0, yn, tn + h / 2, h)
            self._pending = None
            if self._rc is not None:
                self._set_woodbury(tn + h / 2, h)
            self._theta = 0.0
            x, its, dn, why = self._newton(yn, tn, h, x0)
            if x is not None and self._jac_fresh:
                self._its_fresh = self._its_after_refresh = its
            elif x is not None and self._upd_fresh:
                self._its_fresh = self._its_after_update = its
            elif x is not None:
                self._maybe_schedule_refresh(its)
            if x is None and not self._jac_fresh:
                self.rejected_steps += 1
                self._refresh_jacobian(x0, yn, tn + h / 2, h)
                self._its_fresh = None
                if self._rc is not None:
                    self._set_woodbury(tn + h / 2, h)
                x, its, dn, why = self._newton(yn, tn, h, x0)
            if x is not None:
                if self.adaptive:
                    err = self._error(x)
                    if err > 1.0 and h > 1e-6 * self.h:
                        self.rejected_steps += 1
                        h = h * max(0.2, 0.9 * err ** (-1 / 3))
                        continue
                    fac = min(2.0, max(0.2, 0.9 * max(err, 1e-10) ** (-1 / 3)))
                    self._h_next = h * fac if (fac < 0.9 or fac > 1.3) else h
                break
            if self.adaptive and h > 1e-6 * self.h:
                self.rejected_steps += 1
                h *= 0.25
                continue
            G = self._G(x0, yn, tn + h / 2, h)
            rn = float(np.abs(self._row * G).max()) if np.all(np.isfinite(G)) else float("nan")
            raise SimulationError(
                f"simulation: step {self.steps + 1} from t = {tn:.6g} s (h = {h:.4g} s) failed: "
                f"{why}; scaled residual norm at the predictor {rn:.3e}, Newton increment "
                f"{dn:.3e} (tolerance {self.newton_tol:.1e})")
        self._score_predictors(x)
        self._jac_fresh = self._upd_fresh = False
        self._accept(x, tn, h)


def _extrapolate(ts, ys, t):
    """Lagrange extrapolation of the values ys at times ts to t."""
    k = len(ts)
    if k == 1:
        return ys[0].copy()
    out = np.zeros_like(ys[0])
    for i in range(k):
        li = 1.0
        for j in range(k):
            if j != i:
                li *= (t - ts[j]) / (ts[i] - ts[j])
        out += li * ys[i]
    return out
