"""Time-parallel Newton over a window of implicit-midpoint steps.

The implicit midpoint rule of :mod:`hawt_core.simulate` advances one step by solving
``G_k(x_{k-1}, x_k) = R((y_k - y_{k-1}) / h, midpoint, t_{k-1/2}) = 0`` for the step unknowns
``x_k = [y_k (differential), z_{k-1/2} (algebraic, midpoint values)]``.  With small meshes the
cost of one residual evaluation is NumPy call overhead, not arithmetic (0.19 ms at N = 4, and
0.52 ms for 24 instants in ONE batched call), so step-by-step Newton cannot be made much
faster than a few residual evaluations per step.  This module solves the K steps of a window
TOGETHER:

    G(X) = [G_1(x_0, x_1), ..., G_K(x_{K-1}, x_K)] = 0,     x_0 known,

by a simplified Newton iteration whose matrix is block lower bidiagonal, ``A`` on the
diagonal (dG_k/dx_k) and ``B`` below it (dG_k/dx_{k-1}, differential columns only), frozen
over the window.  With ``S = -A^-1`` applied to all K residual rows at once (one matrix
product), the correction follows from the recurrence

    d_k = -A^-1 G_k + P d_{k-1},    P = -A^-1 B    (d_0 = 0),

one small dense matrix-vector product per step.  Each iteration therefore costs ONE batched
residual evaluation of the K instants plus K cheap products, and converges like step-wise
simplified Newton: three to six iterations per window from a constant start (the first one
is the linearized propagation over the window; the NREL 5-MW in wind with gravity, 12 steps
of 1 deg: 5.6 at newton_tol 1e-8).

The matrices are scaled (rows by their largest entry, unknowns by their characteristic
size) and formed from an exact Jacobian (the *base*), refreshed when the iteration contracts
slowly: ``A^-1`` and ``P`` dense for small systems, a sparse LU of ``A`` (one solve per step)
from SPARSE_FROM unknowns (window_bases.py).  The rows and columns of the rigid-body
coupling vary with the azimuth (the blades turn; the yaw axis and the tower do not): a free
yaw, gravity and tilt turn the rigid unknowns' columns, and a flexible tower's top sees the
turning root loads and moves the turning roots.  Every window then replaces them by their
exact values at the window's start state and centre time (TurbineModel.coupling_jacobians,
two batched calls) through a Woodbury update of the base inverse of rank len(cols) +
len(rows) (2 (nq + nu) on a rigid tower, 2 (nq + nu) + 15 on a flexible one), instead of a
new Jacobian and inverse: on the NREL 5-MW (8 elements, flexible tower, 8 m/s) 3 bases
instead of 11 per 5 s.  (Interpolating them in azimuth from samples at the base state is
exact at that state, but their dependence on the teeter motion then costs more iterations
than the exact values cost to compute.)

The converged window solves exactly the same equations as step-by-step Newton (same
tolerance on the scaled increment), so the two agree to the Newton tolerance; the tests check
it.  The window is a solver choice, not a different time discretization.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .window_bases import DenseBase, SparseBase, WindowFailure


def midpoint_arguments(x, prev, di, h):
    """(ydot, y) arguments of the residual at the midpoint of implicit-midpoint steps of size
    h: ``x`` (n,) or (K, n) the step unknowns (grid values at the steps' ends at the
    differential indices ``di``, algebraic midpoint values elsewhere), ``prev`` the
    differential grid values at the steps' starts ((len(di),) or (K, len(di)))."""
    xd = x[..., di]
    ydot = np.zeros(x.shape, dtype=x.dtype)
    ydot[..., di] = (xd - prev) / h
    ym = x.copy()
    ym[..., di] = 0.5 * (xd + prev)
    return ydot, ym


def step_matrix(Jy, Jd, diff, h):
    """Newton matrix dG/dx of a step of size h from the residual's Jacobians at the midpoint
    arguments: ``dR/dydot / h + dR/dy / 2`` on the differential columns (``diff`` (n,)
    bool), ``dR/dy`` on the algebraic ones. ``Jy``, ``Jd``: dense arrays or sparse
    matrices (the result is of the same kind)."""
    cy = np.where(diff, 0.5, 1.0)
    cd = np.where(diff, 1.0 / h, 0.0)
    if sp.issparse(Jy):
        return Jd @ sp.diags(cd) + Jy @ sp.diags(cy)
    return Jd * cd[None, :] + Jy * cy[None, :]


class WindowSolver:
    """Simplified Newton for a window of K implicit-midpoint steps of ``model``.

    ``scale`` (n,): characteristic size of every unknown (the increments are measured in
    it); ``diff`` (n,) bool: the differential unknowns.  ``tol``: Newton tolerance on the
    scaled increment (Hairer & Wanner's stopping test, as the step-wise solver).
    ``azimuth_updates``: replace the coupling rows and columns at every window's centre
    (needed when they vary with the azimuth: the yaw is free, gravity acts, the tower is
    flexible; pointless otherwise); requires ``model.coupling_jacobians``, which the caller
    checks (Simulator._coupling_varies).
    """

    #: a window is "slow" with a larger contraction rate or more iterations: the base is
    #: refreshed before the next window, or the window halved if the base was fresh
    SLOW_CONTRACTION = 0.1
    SLOW_ITERATIONS = 6
    #: the window doubles (up to its maximum) after this many windows contracting faster
    #: than CALM_CONTRACTION
    CALM_WINDOWS = 4
    CALM_CONTRACTION = 0.03
    #: shortest window (steps)
    MIN_STEPS = 2
    #: systems with at least this many unknowns use the sparse base (window_bases.py)
    SPARSE_FROM = 600

    def __init__(self, model, scale, diff, tol, max_steps=24, max_iter=10,
                 azimuth_updates=True):
        self.model = model
        self.n = int(model.n)
        self.sc = np.asarray(scale, float)
        self.diff = np.asarray(diff, bool)
        self.di = np.flatnonzero(self.diff)
        self.ai = np.flatnonzero(~self.diff)
        self.tol = float(tol)
        self.max_iter = int(max_iter)
        self.azimuth_updates = bool(azimuth_updates)
        self._c0 = None                 # the coupling blocks at the base (update_rigid)
        self.h = None
        #: the frozen matrices (window_bases.DenseBase or SparseBase), set by refresh
        self.base = None
        #: sparse LU and solves instead of dense inverses: from SPARSE_FROM unknowns
        self.sparse = self.n >= self.SPARSE_FROM
        self.base_age = 0
        self.pending_refresh = True
        #: window length (steps) for the next window: adapted between MIN_STEPS and
        #: max_steps. The contraction of the frozen matrices degrades like the square of
        #: the window length where the Jacobian varies along it (e.g. a free yaw turning:
        #: the hub's angular velocity then changes with the azimuth)
        self.max_steps = max(1, int(max_steps))
        self.steps = self.max_steps
        self._calm = 0
        #: ((time, h), coupling) evaluated one window ahead, at the then current state
        self._next_coupling = None
        self._theta_hist = []           # contraction rates of third and later iterations
        self._theta_age = 0             # two-iteration windows since the last such rate
        # statistics
        self.windows = 0
        self.iterations = 0
        self.refreshes = 0
        self.updates = 0
        self.failures = 0
        self.residual_instants = 0

    # ------------------------------------------------------------------ matrices
    def _step_matrices(self, x, yn, tm, h):
        """Exact dG/dx_k (A) and dG/dx_{k-1} on the differential columns (B), sparse."""
        Jy, Jd = self.model.jacobians(*midpoint_arguments(x, yn, self.di, h), tm)
        Jy, Jd = sp.csc_matrix(Jy), sp.csc_matrix(Jd)
        A = step_matrix(Jy, Jd, self.diff, h)
        B = (0.5 * Jy - Jd / h)[:, self.di]
        return sp.csr_matrix(A), sp.csr_matrix(B)

    def refresh(self, x, yn, tm, h):
        """New base: exact step matrices at the step unknowns x (midpoint time tm), scaled
        (rows by their largest entry, unknowns by their size), dense or sparse
        (``self.sparse``, window_bases.py)."""
        A, B = self._step_matrices(x, yn, tm, h)
        As = A @ sp.diags(self.sc)
        if not np.all(np.isfinite(As.data)) or not np.all(np.isfinite(B.data)):
            raise WindowFailure("non-finite Newton matrix")
        rmax = abs(As).max(axis=1).toarray().ravel()
        rmax[rmax == 0] = 1.0
        self.row = 1.0 / rmax
        As = sp.diags(self.row) @ As
        Bs = sp.diags(self.row) @ B @ sp.diags(self.sc[self.di])
        self.base = None                # a failed factorization leaves no stale base
        self.base = (SparseBase(As, Bs, self.di) if self.sparse
                     else DenseBase(As.toarray(), Bs.toarray(), self.di))
        if self.azimuth_updates:        # the coupling blocks the base was formed with
            self._next_coupling = None
            self._c0 = self.model.coupling_jacobians(*midpoint_arguments(x, yn, self.di, h),
                                                     tm)
        self.h = h
        self.base_age = 0
        self.pending_refresh = False
        self.refreshes += 1

    def _coupling(self, x, yn, tm, h, t_next=None):
        """The model's coupling blocks (TurbineModel.coupling_jacobians) at the step unknowns
        x and midpoint time tm; ``t_next``: also at that time (the next window's centre, same
        state: the same two batched calls), kept for the next update."""
        nxt = self._next_coupling
        self._next_coupling = None
        if nxt is not None and nxt[0][1] == h and abs(nxt[0][0] - tm) <= 1e-6 * h:
            return nxt[1]
        ydot, ym = midpoint_arguments(x, yn, self.di, h)
        if t_next is None:
            return self.model.coupling_jacobians(ydot, ym, tm)
        cc = self.model.coupling_jacobians(ydot, ym, np.array([tm, t_next]))
        index = ("cols", "rows", "row_cols")
        self._next_coupling = ((t_next, h), {k: (v if k in index else v[1])
                                             for k, v in cc.items()})
        return {k: (v if k in index else v[0]) for k, v in cc.items()}

    def update_rigid(self, x, yn, tm, h, t_next=None):
        """Replace the coupling rows and columns of the base (the rigid unknowns' columns,
        the tower top's with a flexible tower, the rigid rows and tower-top loads at the root
        loads) by their exact values at the step unknowns x and midpoint time tm: Woodbury
        update of the base inverse and of P, rank len(cols) + len(rows). The update adds the
        change of the coupling's part since the base (the tower's own beam terms in the
        tower-top columns stay the base's). ``t_next``: see _coupling."""
        c = self._coupling(x, yn, tm, h, t_next)
        c0 = self._c0
        cols, rows, kc = c["cols"], c["rows"], c["row_cols"]
        pos = np.searchsorted(self.di, cols)
        if np.any(pos >= len(self.di)) or np.any(self.di[np.minimum(pos, len(self.di) - 1)]
                                                  != cols):
            raise ValueError("window solver: the coupling columns must be differential "
                             "unknowns")
        rs = self.row[:, None] * self.sc[cols][None, :]
        dy, dyd = c["y_cols"] - c0["y_cols"], c["ydot_cols"] - c0["ydot_cols"]
        # the coupling columns are differential: A gets dR/dydot / h + dR/dy / 2, B the
        # rest; the root loads are algebraic (factor 1)
        dAc = (dyd / h + 0.5 * dy) * rs
        dBc = (0.5 * dy - dyd / h) * rs
        dR = (c["y_rows"] - c0["y_rows"]) * (self.row[rows][:, None] * self.sc[kc][None, :])
        self.base.update(dAc, dBc, dR, cols, rows, kc, pos)
        self.updates += 1

    def inverse(self):
        """The current A^-1 (scaled; base and update), dense: for tests and diagnostics."""
        return self.base.inverse()

    def propagator(self):
        """The current P = -A^-1 B (scaled; base and update), dense: tests and diagnostics."""
        return self.base.propagator()

    # ------------------------------------------------------------------ iteration
    def _rates_and_midpoint(self, X, yn, h):
        """(ydot, y) arguments of the residual for the K consecutive step unknowns X (K, n)
        from the grid values yn."""
        di = self.di
        prev = np.empty((X.shape[0], len(di)), dtype=X.dtype)
        prev[0] = yn
        prev[1:] = X[:-1, di]
        return midpoint_arguments(X, prev, di, h)

    def residuals(self, X, yn, t0, h):
        """Residual rows (K, n) of the K steps starting at t0 from the grid values yn."""
        ydot, ym = self._rates_and_midpoint(X, yn, h)
        tm = t0 + (np.arange(X.shape[0]) + 0.5) * h
        self.residual_instants += X.shape[0]
        return self.model.residual(ydot, ym, tm)

    def _correction(self, G):
        """Scaled Newton correction of the whole window: d_k = A^-1 (-G_k - B d_{k-1})
        (window_bases.py)."""
        return self.base.correction(G * (-self.row))

    def solve(self, yn, z0, t0, h, K):
        """Solve the window of K steps from the grid values ``yn`` (differential unknowns at
        t0); ``z0``: starting guess of the algebraic (midpoint) unknowns. Returns X (K, n):
        row k = [y at t0 + (k+1) h | z at t0 + (k + 1/2) h] (in the model's order).
        Raises WindowFailure when the iteration does not converge (nothing is changed)."""
        X = np.empty((K, self.n))
        X[:, self.di] = yn
        X[:, self.ai] = z0
        xc = X[0]
        tc = t0 + 0.5 * K * h
        if self.pending_refresh or self.h != h:
            self.refresh(xc, yn, tc, h)
        elif self.azimuth_updates:
            # the next window (same length) reuses values computed now at its centre
            self.update_rigid(xc, yn, tc, h, t_next=tc + K * h)
        self.base_age += 1
        dn_old = None
        theta = 0.0
        for it in range(self.max_iter):
            G = self.residuals(X, yn, t0, h)
            if not np.all(np.isfinite(G)):
                return self._fail(f"non-finite residual in iteration {it + 1}")
            D = self._correction(G)
            dn = float(np.abs(D).max())
            if not np.isfinite(dn):
                return self._fail(f"non-finite Newton increment in iteration {it + 1}")
            X += D * self.sc
            self.iterations += 1
            if dn <= 1e-3 * self.tol:
                break
            if dn_old is not None:
                th = dn / dn_old if dn_old > 0 else 0.0
                theta = max(theta, th)
                if th >= 0.9:
                    return self._fail(f"Newton diverging (contraction {th:.2f})")
                if it >= 2:
                    self._theta_hist = (self._theta_hist + [th])[-10:]
                    self._theta_age = 0
                    est = th
                else:
                    est = self._first_theta(th)
                # the stopping test of Hairer & Wanner (IV.8) on the scaled increment
                if est < 1.0 and est / (1.0 - est) * dn <= self.tol:
                    self._theta_age += it < 2
                    break
            dn_old = dn
        else:
            return self._fail(f"no convergence in {self.max_iter} iterations "
                              f"(last increment {dn:.3e}, tolerance {self.tol:.1e})")
        self._adapt(it + 1, theta)
        self.windows += 1
        return X

    def _first_theta(self, th):
        """Contraction rate to trust after the second iteration. The first ratio (constant
        start -> linearized propagation over the window) measures how well the frozen
        matrices propagate the motion, and under-estimates the rate of the later
        iterations (e.g. 5e-4 where they contract by 0.1 for small motions), so the estimate
        is the largest rate measured on third or later iterations of the last 10 such
        windows (Hairer & Wanner's device); without one, or when the last is more than 8
        windows old, the window takes a third iteration."""
        if not self._theta_hist or self._theta_age >= 8:
            return 1.0
        return max(th, max(self._theta_hist))

    def _adapt(self, its, theta):
        """Window length and refresh policy after a converged window."""
        if its > self.SLOW_ITERATIONS or theta > self.SLOW_CONTRACTION:
            self._calm = 0
            if self.base_age <= 1:      # slow with a fresh base: the window is too long
                self.steps = max(self.MIN_STEPS, self.steps // 2)
            else:                       # the base is stale
                self.pending_refresh = True
        elif theta < self.CALM_CONTRACTION:
            self._calm += 1
            if self._calm >= self.CALM_WINDOWS and self.steps < self.max_steps:
                self.steps = min(self.max_steps, 2 * self.steps)
                self._calm = 0

    def _fail(self, why):
        self.failures += 1
        self.pending_refresh = True
        self.steps = max(self.MIN_STEPS, self.steps // 2)
        self._calm = 0
        raise WindowFailure(why)
