"""Nonlinear time simulation of the turbine: implicit midpoint ("finite elements in time").

The turbine residual ``R(ydot, y, t) = 0`` (hawt_core.assembly.TurbineModel) is an index-3 DAE
when the blades are inextensible and shear-rigid: the section forces are Lagrange multipliers
(``model.differential == False``). One step from ``t_n`` to ``t_{n+1} = t_n + h`` solves

    R( (y_{n+1} - y_n) / h,  (y_n + y_{n+1}) / 2 | z_{n+1/2},  t_n + h/2 ) = 0

for ``x = [y_{n+1} (differential variables), z_{n+1/2} (algebraic variables, midpoint
values)]``: the implicit midpoint rule for the differential part, the algebraic equations and
the constraints imposed at the midpoint. It is symmetric, second order, A-stable with no
numerical damping, conserves quadratic invariants and is free of the spurious (-1)^n modes that
the trapezoidal rule puts on index-3 multipliers (the multipliers are never propagated from one
step to the next). See docs/simulation.md for the choice and the checks.

By default (``method="auto"`` -> ``"window"`` for fixed steps and small and medium meshes)
the steps are solved 24 at a time by the time-parallel simplified Newton of
:mod:`hawt_core.solvers.march.window` (one batched residual evaluation per iteration for the whole window;
6-7x faster at N = 4, docs/simulation.md). The step-by-step solver below is its fallback and
serves adaptive steps and large models.

Step by step (``method="step"``), Newton's method solves each step with a sparse LU
(SuperLU, ``splu``) of
``J = dR/dydot / h + dR/dy / 2`` (differential columns) and ``dR/dy`` (algebraic columns),
scaled by rows and columns. The factorization and the exact (complex-step) Jacobians are reused
over steps and iterations while the Newton contraction is fast; they are refreshed when it
degrades; with the yaw free, the rigid rows and columns (which vary with the azimuth) are
replaced by a low-rank (Woodbury) update instead. The stopping test is on the scaled Newton
increment with the contraction-rate estimate of Hairer & Wanner (IV.8); with the
autoregressive predictor a step costs one or two residual evaluations.

Initial state: the steady state (constant, or periodic by harmonic balance when gravity or tilt
make it periodic), plus perturbations of named rigid DOFs (``perturb={"teeter": 0.02}``) or of
a mode shape, made CONSISTENT with the constraints: positions (the strain-displacement
equations, solved for the displacements and section moments with the rotations held),
velocities (the time derivative of those equations, and the hat-weighted kinematic equations
solved for the section velocities V, Omega). See :func:`consistent_state`.
"""
from __future__ import annotations

import math
import time
from typing import Callable, Optional

import numpy as np

from ...numerics.checks import check_number, check_step_deg
from ...numerics.jacobian import ColouredJacobian
from ...numerics.threads import blas_threads
from ..equilibrium import NoEquilibrium
from ..steady import constant_steady_state
from .initial import (SimulationError, blade_rows, check_perturbation, consistent_state,
                      mode_delta, rigid_speed_map)
from .outputs import SimulationOutputs
from .step_solver import StepSolver
from .window import WindowFailure, WindowSolver

__all__ = ["Simulator", "SimulationError"]


# ============================================================================ simulator
#: A remainder of at most this fraction of a step at the end of a run lengthens the last step
#: instead of becoming a tiny step of its own.
TAIL_STRETCH = 0.01


class Simulator(StepSolver, SimulationOutputs):
    """Implicit-midpoint time integration of a TurbineModel.

    ``step_deg``: step in rotor azimuth [deg] (fixed step; ``step_seconds`` overrides it, and
    is needed when the rotor does not spin). ``adaptive=True`` controls the step size by a
    local-error estimate (predictor-corrector difference, Milne's device) against ``rtol``.
    ``perturb``: dict of named rigid DOF perturbations (``yaw``, ``yaw_rate``, ``teeter``
    [rad], ``teeter_rate`` [rad/s], ``teeter_rate`` being d(teeter)/dt). ``mode``,
    ``mode_amplitude`` [m], ``mode_blade_signs``: a mode-shape perturbation (see
    :func:`mode_delta`). ``y0``: an explicit starting state (made consistent unless
    ``consistent=False``). ``record``: keep time histories for ``history()``/``save()``.

    ``method``: how each step's equations are solved (the time discretization is the same):
    ``"window"`` solves ``window_steps`` steps together (hawt_core.window: one batched
    residual evaluation per iteration for the whole window; several times faster for small
    and medium meshes), ``"step"`` one step at a time with a sparse LU (the fallback when a
    window does not converge, and used for adaptive steps), ``"auto"`` (default) picks
    ``"window"`` for fixed steps and up to WINDOW_MAX_UNKNOWNS unknowns.
    """

    #: largest number of unknowns for which method="auto" uses the window solver. From 600
    #: unknowns its base is a sparse LU (window_bases.py), so size does not cost it dense
    #: n x n matrices; it stays the faster of the two where measured (NREL 5-MW, flexible
    #: tower, frozen wake, 1 deg steps: RTF 2.72 vs 2.11 at 2068 unknowns, 1.41 vs 1.07 at
    #: 3796). The bound only keeps the coupling updates' n x r blocks small.
    WINDOW_MAX_UNKNOWNS = 20000

    #: coefficients and least-squares window (steps) of the autoregressive predictor
    AR_ORDER, AR_WINDOW = 8, 8

    def __init__(self, model, step_deg: float = 1.0, perturb: Optional[dict] = None,
                 y0=None, *, mode=None, mode_amplitude: float = 0.0, mode_blade_signs=None,
                 step_seconds: Optional[float] = None, t0: float = 0.0,
                 adaptive: bool = False, rtol: float = 1e-4, newton_tol: float = 1e-8,
                 max_iter: int = 8, record: bool = True, consistent: bool = True,
                 harmonics: int = 6, method: str = "auto", window_steps: int = 24):
        self.model = model
        self.n = model.n
        self.diff = np.asarray(model.differential, bool)
        self.alg = ~self.diff
        omega = float(getattr(model, "rotor_speed", 0.0))
        self.omega = omega
        if step_seconds is not None:
            h = check_number("step_seconds", step_seconds, positive=True)
        else:
            deg = check_step_deg(step_deg)
            if omega <= 0:
                raise ValueError("step_deg: the rotor does not spin; give step_seconds instead")
            h = math.radians(deg) / omega
        self.h = h
        self.adaptive = bool(adaptive)
        self.rtol = check_number("rtol", rtol, positive=True)
        self.newton_tol = check_number("newton_tol", newton_tol, positive=True)
        self.max_iter = int(max_iter)
        #: refresh the Jacobian when the Newton contraction rate exceeds this
        self.refresh_contraction = 0.3
        self.record = bool(record)
        t0 = check_number("t0", t0)

        perturb = dict(perturb or {})
        for name, val in perturb.items():
            check_perturbation(name, val)
            base = "yaw" if name.startswith("yaw") else "teeter"
            if base not in model.layout:
                raise ValueError(f"perturb: {name!r} is not allowed; this model has no {base} "
                                 f"degree of freedom ({base} locked)")
        mode_amplitude = check_number("mode_amplitude", mode_amplitude)

        # ---------------------------------------------------------------- initial state
        if y0 is None:
            y, yd = self._steady_at(t0, harmonics)
        else:
            y = np.array(y0, float)
            if y.shape != (self.n,):
                raise ValueError(f"y0: shape {y.shape} is not allowed; need ({self.n},)")
            if not np.all(np.isfinite(y)):
                raise ValueError("y0: non-finite values are not allowed")
            yd = np.zeros(self.n)
        self.y_base = y.copy()
        changed = bool(perturb) or (mode is not None and mode_amplitude != 0)
        if changed or (y0 is not None and consistent):
            y, yd = self._perturbed(y, yd, t0, perturb, mode, mode_amplitude, mode_blade_signs)
        self.t0 = t0
        self.t = t0
        self.y = y                      # full state at t (algebraic part: see _alg_at)
        self.steps = 0
        self.newton_iterations = 0
        self.factorizations = 0
        self.jacobian_evaluations = 0
        self.residual_evaluations = 0
        self.rejected_steps = 0
        self.wall_seconds = 0.0
        # histories of grid values (differential) and midpoint values (algebraic)
        self._grid = [(t0, y[self.diff].copy())]
        self._mid = []                   # (t_mid, z)
        self._z_init = y[self.alg].copy()
        self._scale = self._variable_scales(y)
        self._lu = None
        self._lu_h = None
        self._jac_fresh = False
        # the coloured complex step serves models without structured Jacobians only
        # (step_solver.py); colouring a large pattern costs seconds, so not otherwise
        self._colour = None
        if hasattr(model, "sparsity") and not hasattr(model, "jacobians"):
            self._colour = ColouredJacobian(model.sparsity())
        self._di = np.flatnonzero(self.diff)
        self._ai = np.flatnonzero(self.alg)
        #: running scaled errors of the degree-0/1/2 predictors (differential, algebraic)
        self._pred_err = {"d": [np.inf] * 4, "a": [np.inf] * 4}
        self._xhist = []                 # (h, scaled step unknowns) of the last steps
        P, M = self.AR_ORDER, self.AR_WINDOW
        self._ar_targets = np.arange(P, P + M)
        self._ar_rows = self._ar_targets[:, None] - 1 - np.arange(P)[None, :]
        self._cands = None
        #: last measured contraction [theta, first correction of that step, steps since]
        self._theta_meas = [None, 1.0, 0]
        self._theta = 0.0
        self._iter_cost = 0.0            # wall time of one Newton iteration (running mean)
        self._refresh_cost = 0.0         # wall time of the last Jacobian + factorization
        self._extra_since_refresh = 0.0  # time spent on extra iterations since then
        self._its_fresh = None           # iterations of the first step after a refresh
        self._pending = None             # "update" or "refresh" before the next step
        self._upd_fresh = False
        self._update_cost = 0.0
        self._its_after_update = self._its_after_refresh = None
        self._setup_low_rank()
        self._setup_window(method, window_steps)
        self._init_outputs()
        if self.record:
            self._hist = []
            self._record()

    # ------------------------------------------------------------------ initial state
    def _steady_at(self, t, harmonics):
        m = self.model
        try:
            y = constant_steady_state(m)
            return y, np.zeros(self.n)
        except NoEquilibrium:
            raise
        except ValueError:
            from ..periodic import periodic_steady_state
            ss = periodic_steady_state(m, harmonics=harmonics)
            return ss.at(t), ss.rate_at(t)

    def _perturbed(self, y, yd, t, perturb, mode, amplitude, signs):
        m = self.model
        nq, nr = m.nq, m.nq + m.nu
        y = y.copy()
        yd = yd.copy()
        if mode is not None and amplitude != 0:
            d = mode_delta(m, mode, amplitude, signs)
            y[:nr] += d[:nr]
            _, _, cols = blade_rows(m)
            y[cols["theta"]] += d[cols["theta"]]
            y[cols["u"]] += d[cols["u"]]          # initial guess; re-solved below
        for name in ("yaw", "teeter"):
            if name in perturb:
                y[m.layout[name]] += float(perturb[name])
        q = y[:nq]
        # rates: the requested coordinate rates, through the linear map qdot = A u
        rates = {"yaw_rate": "yaw", "teeter_rate": "teeter"}
        if any(r in perturb for r in rates):
            A = rigid_speed_map(m, q, t)
            qd = A @ y[nq:nr]
            for r, c in rates.items():
                if r in perturb:
                    qd[m.layout[c]] += float(perturb[r])
            y[nq:nr] = np.linalg.lstsq(A, qd, rcond=None)[0]
        # (the blades' rotation rates: the base state's, those of yd)
        return consistent_state(m, y, yd, t)

    def _variable_scales(self, y):
        """Characteristic magnitude of every unknown (for the Newton and error norms)."""
        m = self.model
        omega = self.omega if self.omega > 0 else 1.0
        L = float(m.beam.props.nodes[-1])
        R = L + float(getattr(m.turbine.hub, "radius", 0.0))
        mass = float(np.sum(m.beam.h * m.beam.mass_per_length))
        g = float(m.turbine.gravity.g) if m.gravity else 0.0
        Fs = mass * (omega ** 2 * R + g) + 1.0
        sc = np.ones(self.n)
        sc[m.nq:m.nq + m.nu] = omega
        beams = [(m.layout.blade(k), R, Fs, L) for k in range(m.n_blades)]
        if m.layout.has_tower:
            # the tower carries the rotor and its own weight: forces of 1e6 N in a multi-MW
            # turbine, whose round-off (1e-10 N) a unit scale would take for a Newton
            # increment far above the tolerance (Newton then "diverges" at the floor)
            H = float(m.tower.props.nodes[-1])
            Ft = m.n_blades * Fs + float(np.sum(m.tower.h * m.tower.mass_per_length)) * g + 1.0
            beams.append((m.layout.tower(), H, Ft, H))
        for bl, length, force, arm in beams:
            for name, s in (("u", length), ("theta", 1.0), ("V", omega * R),
                            ("Omega", omega), ("F", force), ("M", force * arm),
                            ("root_force", force), ("root_moment", force * arm)):
                idx = getattr(bl, name).ravel()
                idx = idx[idx >= 0]
                sc[idx] = max(s, float(np.abs(y[idx]).max()) if len(idx) else s)
        return sc

    def step(self) -> None:
        """Advance one step. Raises SimulationError on failure (the state is unchanged)."""
        w0 = time.perf_counter()
        try:
            with blas_threads():        # many small dense solves: one thread is fastest
                if self.method == "window":
                    self._window_step()
                else:
                    self._step()
        finally:
            self.wall_seconds += time.perf_counter() - w0

    def _accept(self, x, tn, h):
        """Take the converged step unknowns x of the step from tn to tn + h."""
        self._check_finite(x, tn + h)
        self._commit(tn, h, x[self.diff].copy(), x[self.alg].copy(), x / self._scale)

    def _check_finite(self, x, t1):
        if not np.all(np.isfinite(x)):
            raise SimulationError(f"simulation: non-finite state at step {self.steps + 1}, "
                                  f"t = {t1:.6g} s")

    def _commit(self, tn, h, xd, za, xs, y=None):
        """Histories (for the predictors and the algebraic values at grid times), time,
        state, record, for the step from tn to tn + h with grid values xd (differential),
        midpoint values za (algebraic), scaled unknowns xs; ``y``: the full state at
        tn + h when already known."""
        t1 = tn + h
        self._xhist.append((h, xs))
        if len(self._xhist) > self.AR_ORDER + self.AR_WINDOW:
            del self._xhist[0]
        self._grid.append((t1, xd))
        self._mid.append((tn + h / 2, za))
        if len(self._grid) > 4:
            del self._grid[0]
            del self._mid[0]
        self.t = t1
        self.steps += 1
        if y is None:
            y = np.empty(self.n)
            y[self.diff] = xd
            y[self.alg] = self._alg_at(t1)
        self.y = y
        if self.adaptive:
            self.h = self._h_next
        if self.record:
            self._record()

    # ------------------------------------------------------------------ window solver
    def _setup_window(self, method, window_steps):
        if method not in ("auto", "window", "step"):
            raise ValueError(f"method: {method!r} is not allowed; need 'auto', 'window' or "
                             f"'step'")
        if isinstance(window_steps, bool) or not isinstance(window_steps, (int, np.integer)) \
                or window_steps < 1:
            raise ValueError(f"window_steps: {window_steps!r} is not allowed; need an integer "
                             f">= 1")
        usable = hasattr(self.model, "jacobians") and not self.adaptive
        if method == "window" and not usable:
            raise ValueError("method: 'window' is not allowed with adaptive steps or a model "
                             "without structured Jacobians; use 'step'")
        if method == "auto":
            method = "window" if usable and self.n <= self.WINDOW_MAX_UNKNOWNS else "step"
        self.method = method
        self.window_steps = int(window_steps)
        self._buffer = []                # solved steps not yet taken: (h, x)
        self._steps_wanted = None        # full steps left in run() (windows never overshoot)
        self._sequential_left = 0        # single steps to take after a failed window
        self._win = None
        if method == "window":
            self._win = WindowSolver(self.model, self._scale, self.diff, self.newton_tol,
                                     max_steps=self.window_steps,
                                     azimuth_updates=self._coupling_varies())

    def _coupling_varies(self) -> bool:
        """True when the coupling rows and columns of the Jacobian (TurbineModel.
        coupling_jacobians) change with the azimuth at the starting state (a free yaw: the
        yaw axis is fixed, the blades turn; gravity; tilt; a flexible tower: the tower top
        sees the blades' root loads and moves their roots, both turning with the rotor),
        compared at two azimuths 0.3 revolution apart."""
        m = self.model
        if not hasattr(m, "coupling_jacobians") or (
                m.nq + m.nu == 0 and getattr(m, "tower", None) is None):
            return False
        z = np.zeros(self.n)
        dt = 0.3 * (m.period if np.isfinite(m.period) else 1.0)
        c = m.coupling_jacobians(z, self.y_base, self.t0 + np.array([0.0, dt]))
        for key in ("y_cols", "ydot_cols", "y_rows"):
            a, b = c[key]
            big = max(np.abs(a).max(initial=0.0), 1e-300)
            if np.abs(a - b).max(initial=0.0) > 1e-9 * big:
                return True
        return False

    def _window_step(self):
        """Take the next step from the window buffer, solving a new window when it is empty
        (or was solved with another step size); single steps after a window failed."""
        h = self.h
        if self._buffer and self._buffer[0][0] != h:     # another step size: solve anew
            self._buffer = []
        if self._steps_wanted == 0:      # run()'s shortened last step: keep the window's base
            self._step()
            return
        if not self._buffer and self._sequential_left == 0:
            K = self._win.steps if self._steps_wanted is None else \
                max(1, min(self._win.steps, self._steps_wanted))
            self._solve_window(K, h)
        if not self._buffer:
            self._sequential_left = max(0, self._sequential_left - 1)
            self._step()
            return
        self._commit(self.t, *self._buffer.pop(0))

    def _solve_window(self, K, h):
        win = self._win
        yn = self._grid[-1][1]
        z0 = self._mid[-1][1] if self._mid else self._z_init
        before = win.refreshes
        X = None
        for attempt in range(2):
            try:
                X = win.solve(yn, z0, self.t, h, K)
                break
            except WindowFailure:
                if win.refreshes > before and attempt == 0:
                    break               # failed with a fresh base: single steps instead
        self.jacobian_evaluations += win.refreshes - before
        self.factorizations += win.refreshes - before
        if X is None:
            self.rejected_steps += 1
            self._sequential_left = K
            return
        self._check_finite(X, self.t + K * h)
        # everything the K steps will need, vectorized: grid and midpoint values, scaled
        # unknowns, and the full states (algebraic values at the grid times extrapolated
        # linearly from the last two midpoint values, as _alg_at does)
        Xd, Xa = X[:, self._di], X[:, self._ai]
        Za = np.concatenate([z0[None], Xa]) if self._mid else np.concatenate([Xa[:1], Xa])
        tm_prev = self._mid[-1][0] if self._mid else self.t - h / 2
        span = np.full(K, h)
        span[0] = self.t + h / 2 - tm_prev
        Y = np.empty((K, self.n))
        Y[:, self._di] = Xd
        Y[:, self._ai] = Xa + (Xa - Za[:-1]) * (0.5 * h / span)[:, None]
        Xs = X / self._scale
        self._buffer = [(h, Xd[k], Xa[k], Xs[k], Y[k]) for k in range(K)]

    def _error(self, x):
        """Local error estimate (Milne): the quadratic extrapolation of the grid values (the
        degree-2 candidate of :meth:`_predict`, whichever candidate started Newton) and the
        midpoint corrector differ by about 25x the midpoint rule's local error; 0 without
        three grid values."""
        x2 = self._cands["d"][2]
        if x2 is None:
            return 0.0
        d = self.diff
        sc = self._scale[d]
        e = (x[d] - x2) / 25.0
        w = self.rtol * (sc * 1e-3 + np.abs(x[d]))
        return float(np.sqrt(np.mean((e / w) ** 2)))

    def _alg_at(self, t):
        """Algebraic unknowns at a grid time: linear extrapolation of the last two midpoint
        values (second order)."""
        if len(self._mid) >= 2:
            (ta, za), (tb, zb) = self._mid[-2], self._mid[-1]
            return zb + (zb - za) * (t - tb) / (tb - ta)
        return self._mid[-1][1].copy()

    def advance(self, steps: int) -> None:
        """Take exactly ``steps`` steps of the current size, no window reaching beyond them
        (a controller changes the inputs after them: nothing may be solved ahead)."""
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
            raise ValueError(f"steps: {steps!r} is not allowed; need an integer >= 0")
        try:
            for i in range(steps):
                self._steps_wanted = steps - i
                self.step()
        finally:
            self._steps_wanted = None
        self._buffer = []

    def run(self, duration: float, progress: Optional[Callable] = None) -> dict:
        """Integrate for ``duration`` seconds (the last step is shortened to land on it, or
        lengthened by up to TAIL_STRETCH of a step).
        ``progress(fraction, message)`` is called a few times per second. Returns summary()."""
        duration = check_number("duration", duration, minimum=0.0)
        t_end = self.t + duration
        last = time.perf_counter()
        w_start = self.wall_seconds
        while self.t < t_end - 1e-9 * max(1.0, abs(t_end)):
            # one decision for full and shortened steps: a step that overshoots t_end by
            # round-off counts as full (and keeps the window's step size)
            self._steps_wanted = int(math.floor((t_end - self.t) / self.h
                                                + 1e-9 * max(1.0, abs(t_end))))
            if self._steps_wanted == 1 and t_end - self.t < (1 + TAIL_STRETCH) * self.h:
                # a remainder below TAIL_STRETCH steps joins the last step (a step of a
                # millionth of h is ill-conditioned: the DAE's algebraic rows scale as 1/h)
                self._steps_wanted = 0
            if self._steps_wanted == 0:
                keep = self.h
                self.h = t_end - self.t
                self.step()
                self.h = keep if not self.adaptive else max(self.h, keep)
            else:
                self.step()
            if progress is not None and time.perf_counter() - last > 0.25:
                last = time.perf_counter()
                el = self.wall_seconds - w_start
                done = duration - (t_end - self.t)
                rtf = done / el if el > 0 else float("inf")
                progress(min(1.0, done / duration) if duration > 0 else 1.0,
                         f"t = {self.t:.3f} s / {t_end:.3f} s, RTF {rtf:.2f}, "
                         f"steps {self.steps}")
        self._steps_wanted = None
        if progress is not None:
            progress(1.0, f"t = {self.t:.3f} s done")
        return self.summary()
