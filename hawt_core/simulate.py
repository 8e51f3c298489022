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
:mod:`hawt_core.window` (one batched residual evaluation per iteration for the whole window;
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

import csv
import math
import sys
import time
from typing import Callable, Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from .fem.beam import BLOCK_SIZE, ROOT_SIZE
from .jacobian import STEP, ColouredJacobian
from .window import WindowFailure, WindowSolver, midpoint_arguments, step_matrix
from .threads import blas_threads

__all__ = ["Simulator", "SimulationError", "NAMED", "consistent_state", "cmd_simulate",
           "parse_perturb"]

#: Scalar outputs of ``Simulator.named()`` (and the first CSV columns).
NAMED = ("time", "azimuth", "yaw", "yaw_rate", "teeter", "teeter_rate")
#: Names accepted in ``perturb``.
PERTURBABLE = ("yaw", "yaw_rate", "teeter", "teeter_rate")


class SimulationError(RuntimeError):
    """The time integration failed (Newton did not converge, or values became non-finite)."""


# ============================================================================ helpers
def _check_number(field: str, value, minimum=None, positive=False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{field}: {value!r} is not allowed; need a finite number") from None
    if not math.isfinite(v):
        raise ValueError(f"{field}: {value!r} is not allowed; need a finite number")
    if positive and v <= 0:
        raise ValueError(f"{field}: {value!r} is not allowed; need a number > 0")
    if minimum is not None and v < minimum:
        raise ValueError(f"{field}: {value!r} is not allowed; need a number >= {minimum}")
    return v


def _check_perturbation(name, value) -> float:
    """One perturbation: ``name`` in PERTURBABLE, ``value`` a finite number."""
    if name not in PERTURBABLE:
        raise ValueError(f"perturb: unknown name {name!r}; allowed: {', '.join(PERTURBABLE)}")
    return _check_number(f"perturb {name}", value)


def parse_perturb(text: str) -> dict:
    """``"teeter=0.02,yaw_rate=0.01"`` -> dict (names checked against PERTURBABLE)."""
    out = {}
    if text is None or not text.strip():
        return out
    for item in text.split(","):
        if "=" not in item:
            raise ValueError(f"perturb: {item.strip()!r} is not allowed; need NAME=VALUE "
                             f"with NAME in {', '.join(PERTURBABLE)}")
        name, val = (s.strip() for s in item.split("=", 1))
        out[name] = _check_perturbation(name, val)
    return out


class _BladeIndex:
    """Precomputed index arrays of one blade (cheap extraction every step)."""

    def __init__(self, layout, k):
        bl = layout.blade(k)
        self.u = bl.u[1:].ravel()
        self.theta = bl.theta[1:].ravel()
        self.root_force = bl.root_force
        self.root_moment = bl.root_moment


# ============================================================================ initial state
def _blade_rows(model):
    """Row/column index sets of the blades: strain-displacement rows (constraints),
    kinematic rows, and the columns of u, theta, M, V, Omega (all blades)."""
    sd, kin = [], []
    cols = {"u": [], "theta": [], "M": [], "F": [], "VO": []}
    N = model.beam.N
    for k in range(model.n_blades):
        off = model.layout.blade_offset(k)
        kin.append(off + 6 + np.arange(6))
        for e in range(N):
            b = off + ROOT_SIZE + e * BLOCK_SIZE
            sd.append(b + np.arange(6))
            kin.append(b + 12 + np.arange(6))
        bl = model.layout.blade(k)
        cols["u"].append(bl.u[1:].ravel())
        cols["theta"].append(bl.theta[1:].ravel())
        cols["M"].append(bl.M.ravel())
        cols["F"].append(bl.F.ravel())
        cols["VO"].append(np.concatenate([bl.V.ravel(), bl.Omega.ravel()]))
    cols = {key: np.concatenate(v) for key, v in cols.items()}
    return np.concatenate(sd), np.concatenate(kin), cols


def _rigid_speed_map(model, q, t):
    """Matrix A with qdot = A u (the kinematic relation is linear in the speeds)."""
    nu = model.nu
    if nu == 0:
        return np.zeros((model.nq, 0))
    return np.stack([model.rigid.qdot(q, e, t) for e in np.eye(nu)], -1)


def _lin_solve(fun, x0, cols_rows_jac, what, iters=6):
    """Newton on a square sub-system: ``fun(x) -> residual rows``, ``cols_rows_jac(x)`` the
    sparse square Jacobian. The sub-systems used here are linear or nearly so."""
    x = x0.copy()
    r = fun(x)
    scale = max(1.0, np.abs(r).max())
    for _ in range(iters):
        J = sp.csc_matrix(cols_rows_jac(x))
        try:
            dx = spl.splu(J).solve(r)
        except RuntimeError as exc:
            raise SimulationError(f"initial state: singular system in {what} ({exc})") from exc
        x = x - dx
        r = fun(x)
        if np.abs(r).max() <= 1e-12 * scale:
            break
    if not np.all(np.isfinite(x)):
        raise SimulationError(f"initial state: non-finite values in {what}")
    return x


def consistent_state(model, y, ydot, t, theta_rate=None):
    """Make ``y`` consistent with the constraints of the blades, holding the rigid-body
    coordinates and speeds and the blade rotations ``theta``:

    1. positions: the strain-displacement equations (the index-3 constraints, rows without a
       time derivative) are solved for the nodal displacements ``u`` and the section moments
       ``M`` (the axial/shear forces ``F`` are held);
    2. velocities: the time derivative of those equations is solved for ``udot`` (and
       ``Mdot``) given the rotation rates ``theta_rate`` (default: those of ``ydot``; zero for
       a start at rest relative to the hub);
    3. the hat-weighted kinematic equations are solved for the section velocities ``V`` and
       angular velocities ``Omega`` with those ``udot, thetadot`` and the hub's motion.

    Returns ``(y, ydot)``. The remaining algebraic unknowns (``F``, root loads) are not needed
    by the midpoint scheme (it solves them at the first midpoint); they keep their values.
    """
    y = np.array(y, float)
    ydot = np.array(ydot, float)
    sd, kin, cols = _blade_rows(model)
    pos_cols = np.concatenate([cols["u"], cols["M"]])

    def solve_subset(cc, rows, what):
        """Solve the residual rows ``rows`` for the unknowns ``cc`` (the rest held)."""
        def f(x):
            yy = y.copy()
            yy[cc] = x
            return model.residual(ydot, yy, t)[rows]

        def j(x):
            yy = y.copy()
            yy[cc] = x
            return sp.csr_matrix(model.jacobians(ydot, yy, t)[0])[rows][:, cc]

        return _lin_solve(f, y[cc], j, what)

    # 1. positions
    y[pos_cols] = solve_subset(pos_cols, sd, "the position constraints")

    # 2. velocity level: d/dt of the constraint rows = Jy[sd] @ ydot = 0
    Jy, _ = model.jacobians(ydot, y, t)
    Jy = sp.csr_matrix(Jy)[sd]
    if theta_rate is not None:
        ydot[cols["theta"]] = theta_rate
    ydot[cols["F"]] = 0.0
    rhs = -(Jy[:, cols["theta"]] @ ydot[cols["theta"]])
    A = sp.csc_matrix(Jy[:, pos_cols])
    try:
        ydot[pos_cols] = spl.splu(A).solve(rhs)
    except RuntimeError as exc:
        raise SimulationError(f"initial state: singular velocity constraints ({exc})") from exc

    # 3. kinematics -> V, Omega
    vo = cols["VO"]
    nr = model.nq + model.nu
    ydot[:model.nq] = model.rigid.qdot(y[:model.nq], y[model.nq:nr], t)

    y[vo] = solve_subset(vo, kin, "the kinematic equations")
    return y, ydot


def _mode_delta(model, mode, amplitude, blade_signs=None):
    """Real perturbation (n,) of the mode ``mode`` scaled so that the largest blade
    displacement or (blade length x rotation) is ``amplitude`` [m].

    ``mode``: a full state vector (n,), one blade's vector (beam.n,) (applied to every blade
    with ``blade_signs``, default +1: a symmetric mode), or a blade_modes ``Mode`` (its
    ``shape``: nodal displacement and rotation)."""
    n, nb, N = model.n, model.n_blades, model.beam.N
    L = float(model.beam.props.nodes[-1])
    signs = np.ones(nb) if blade_signs is None else np.asarray(blade_signs, float)
    if len(signs) != nb:
        raise ValueError(f"mode_blade_signs: {list(signs)} is not allowed; need {nb} values")
    delta = np.zeros(n, complex)
    if hasattr(mode, "shape") and isinstance(getattr(mode, "shape"), dict):
        shp = mode.shape
        u = np.asarray(shp["displacement"], float)
        th = np.asarray(shp["rotation"], float)
        if u.shape != (N + 1, 3):
            raise ValueError(f"mode: shape has {u.shape[0] - 1} elements; the model has {N}")
        for k in range(nb):
            bl = model.layout.blade(k)
            delta[bl.u[1:].ravel()] = signs[k] * u[1:].ravel()
            delta[bl.theta[1:].ravel()] = signs[k] * th[1:].ravel()
    else:
        x = np.asarray(mode)
        if x.shape == (n,):
            delta[:] = x
        elif x.shape == (model.beam.n,):
            for k in range(nb):
                off = model.layout.blade_offset(k)
                delta[off:off + model.beam.n] = signs[k] * x
        else:
            raise ValueError(f"mode: a vector of length {x.shape} is not allowed; need "
                             f"{n} (turbine state) or {model.beam.n} (one blade)")
    if not np.all(np.isfinite(delta)):
        raise ValueError("mode: the vector has non-finite entries")
    z = np.concatenate([np.concatenate([delta[model.layout.blade(k).u[1:].ravel()],
                                        L * delta[model.layout.blade(k).theta[1:].ravel()]])
                        for k in range(nb)])
    j = int(np.argmax(np.abs(z)))
    if abs(z[j]) == 0:
        raise ValueError("mode: the vector has no blade displacement or rotation")
    c = amplitude / z[j]                      # makes the largest entry real = amplitude
    return np.real(c * delta)


# ============================================================================ simulator
class Simulator:
    """Implicit-midpoint time integration of a TurbineModel.

    ``step_deg``: step in rotor azimuth [deg] (fixed step; ``step_seconds`` overrides it, and
    is needed when the rotor does not spin). ``adaptive=True`` controls the step size by a
    local-error estimate (predictor-corrector difference, Milne's device) against ``rtol``.
    ``perturb``: dict of named rigid DOF perturbations (``yaw``, ``yaw_rate``, ``teeter``
    [rad], ``teeter_rate`` [rad/s], ``teeter_rate`` being d(teeter)/dt). ``mode``,
    ``mode_amplitude`` [m], ``mode_blade_signs``: a mode-shape perturbation (see
    :func:`_mode_delta`). ``y0``: an explicit starting state (made consistent unless
    ``consistent=False``). ``record``: keep time histories for ``history()``/``save()``.

    ``method``: how each step's equations are solved (the time discretization is the same):
    ``"window"`` solves ``window_steps`` steps together (hawt_core.window: one batched
    residual evaluation per iteration for the whole window; several times faster for small
    and medium meshes), ``"step"`` one step at a time with a sparse LU (the fallback when a
    window does not converge, and used for adaptive steps), ``"auto"`` (default) picks
    ``"window"`` for fixed steps and up to WINDOW_MAX_UNKNOWNS unknowns (its matrices are
    dense).
    """

    #: largest number of unknowns for which method="auto" uses the window solver
    WINDOW_MAX_UNKNOWNS = 1500

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
            h = _check_number("step_seconds", step_seconds, positive=True)
        else:
            deg = _check_number("step_deg", step_deg, positive=True)
            if omega <= 0:
                raise ValueError("step_deg: the rotor does not spin; give step_seconds instead")
            h = math.radians(deg) / omega
        self.h = h
        self.adaptive = bool(adaptive)
        self.rtol = _check_number("rtol", rtol, positive=True)
        self.newton_tol = _check_number("newton_tol", newton_tol, positive=True)
        self.max_iter = int(max_iter)
        #: refresh the Jacobian when the Newton contraction rate exceeds this
        self.refresh_contraction = 0.3
        self.record = bool(record)
        t0 = _check_number("t0", t0)

        perturb = dict(perturb or {})
        for name, val in perturb.items():
            _check_perturbation(name, val)
            base = "yaw" if name.startswith("yaw") else "teeter"
            if base not in model.layout:
                raise ValueError(f"perturb: {name!r} is not allowed; this model has no {base} "
                                 f"degree of freedom ({base} locked)")
        mode_amplitude = _check_number("mode_amplitude", mode_amplitude)

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
        self._colour = None
        if hasattr(model, "sparsity"):
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
            y = m.steady_state()
            return y, np.zeros(self.n)
        except ValueError:
            from .periodic import periodic_steady_state
            ss = periodic_steady_state(m, harmonics=harmonics)
            return ss.at(t), ss.rate_at(t)

    def _perturbed(self, y, yd, t, perturb, mode, amplitude, signs):
        m = self.model
        nq, nr = m.nq, m.nq + m.nu
        y = y.copy()
        yd = yd.copy()
        if mode is not None and amplitude != 0:
            d = _mode_delta(m, mode, amplitude, signs)
            y[:nr] += d[:nr]
            _, _, cols = _blade_rows(m)
            y[cols["theta"]] += d[cols["theta"]]
            y[cols["u"]] += d[cols["u"]]          # initial guess; re-solved below
        for name in ("yaw", "teeter"):
            if name in perturb:
                y[m.layout[name]] += float(perturb[name])
        q = y[:nq]
        # rates: the requested coordinate rates, through the linear map qdot = A u
        rates = {"yaw_rate": "yaw", "teeter_rate": "teeter"}
        if any(r in perturb for r in rates):
            A = _rigid_speed_map(m, q, t)
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
        for k in range(m.n_blades):
            bl = m.layout.blade(k)
            for name, s in (("u", R), ("theta", 1.0), ("V", omega * R), ("Omega", omega),
                            ("F", Fs), ("M", Fs * L), ("root_force", Fs),
                            ("root_moment", Fs * L)):
                idx = getattr(bl, name).ravel()
                idx = idx[idx >= 0]
                sc[idx] = max(s, float(np.abs(y[idx]).max()) if len(idx) else s)
        return sc

    # ------------------------------------------------------------------ outputs
    def _init_outputs(self):
        m = self.model
        lay = m.layout
        self._iy = lay["yaw"] if "yaw" in lay else None
        self._it = lay["teeter"] if "teeter" in lay else None
        self._blades = [_BladeIndex(lay, k) for k in range(m.n_blades)]
        self._stations = np.array(m.beam.props.nodes, float)
        self._stations.setflags(write=False)
        self._N = m.beam.N

    def _rates(self):
        m = self.model
        nq, nr = m.nq, m.nq + m.nu
        return np.real(m.rigid.qdot(self.y[:nq], self.y[nq:nr], self.t)) if nq else np.zeros(0)

    def named(self) -> dict:
        """time [s], azimuth [rad, in [0, 2 pi)], yaw [rad], yaw_rate [rad/s], teeter [rad],
        teeter_rate (= d teeter/dt) [rad/s]; locked DOFs report 0."""
        qd = self._rates()
        y = self.y
        az = (self.omega * self.t) % (2 * math.pi)
        out = {"time": self.t, "azimuth": az, "yaw": 0.0, "yaw_rate": 0.0,
               "teeter": 0.0, "teeter_rate": 0.0}
        if self._iy is not None:
            out["yaw"] = float(y[self._iy])
            out["yaw_rate"] = float(qd[self._iy])
        if self._it is not None:
            out["teeter"] = float(y[self._it])
            out["teeter_rate"] = float(qd[self._it])
        return out

    def blade_deflections(self) -> list:
        """Per blade: dict(stations (N+1,) [m], u (N+1,3) [m], theta (N+1,3) (Rodrigues, root
        frame b), root_force (3,) [N], root_moment (3,) [N m] (loads on the hub, frame b))."""
        y = self.y
        out = []
        N = self._N
        for b in self._blades:
            u = np.zeros((N + 1, 3))
            th = np.zeros((N + 1, 3))
            u[1:] = y[b.u].reshape(N, 3)
            th[1:] = y[b.theta].reshape(N, 3)
            out.append({"stations": self._stations, "u": u, "theta": th,
                        "root_force": y[b.root_force].copy(),
                        "root_moment": y[b.root_moment].copy()})
        return out

    def _record(self):
        nm = self.named()
        y = self.y
        row = [nm[k] for k in NAMED]
        parts = [np.array(row)]
        for b in self._blades:
            parts += [y[b.u], y[b.theta], y[b.root_force], y[b.root_moment]]
        self._hist.append(np.concatenate(parts))

    def columns(self) -> list:
        """Names of the history columns (CSV header)."""
        cols = list(NAMED)
        for k in range(len(self._blades)):
            # stored as all u then all theta
            us = [f"blade{k}_node{i}_u{c}" for i in range(1, self._N + 1) for c in (1, 2, 3)]
            ths = [f"blade{k}_node{i}_theta{c}" for i in range(1, self._N + 1) for c in (1, 2, 3)]
            cols += us + ths
            cols += [f"blade{k}_root_force{c}" for c in (1, 2, 3)]
            cols += [f"blade{k}_root_moment{c}" for c in (1, 2, 3)]
        return cols

    def history(self) -> dict:
        """Time histories: dict of arrays: the NAMED scalars, and per blade ``u`` (steps,
        N+1, 3), ``theta`` (steps, N+1, 3), ``root_force``, ``root_moment`` (steps, 3) under
        keys ``blade{k}_u`` etc. (root node rows are zero: clamped)."""
        if not self.record:
            raise ValueError("history: this Simulator was created with record=False")
        H = np.array(self._hist)
        out = {k: H[:, i] for i, k in enumerate(NAMED)}
        c = len(NAMED)
        N = self._N
        for k in range(len(self._blades)):
            for name in ("u", "theta"):
                a = np.zeros((len(H), N + 1, 3))
                a[:, 1:] = H[:, c:c + 3 * N].reshape(-1, N, 3)
                out[f"blade{k}_{name}"] = a
                c += 3 * N
            for name in ("root_force", "root_moment"):
                out[f"blade{k}_{name}"] = H[:, c:c + 3]
                c += 3
        return out

    def save(self, path) -> None:
        """Write the time histories to ``path``: CSV (header row, columns ``columns()``:
        time, azimuth, yaw, yaw_rate, teeter, teeter_rate [s, rad, rad/s], then per blade and
        node u1..u3 [m] and theta1..theta3 (Rodrigues), then the root loads [N, N m]) or NPZ
        (the same columns as arrays, plus ``stations``)."""
        if not self.record:
            raise ValueError("save: this Simulator was created with record=False")
        path = str(path)
        H = np.array(self._hist)
        cols = self.columns()
        if path.lower().endswith(".npz"):
            np.savez(path, stations=self._stations, columns=np.array(cols),
                     **{c: H[:, i] for i, c in enumerate(cols)})
        elif path.lower().endswith(".csv"):
            with open(path, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(cols)
                for row in H:
                    w.writerow([repr(float(v)) for v in row])
        else:
            raise ValueError(f"output: {path!r} is not allowed; need a .csv or .npz file name")

    def summary(self) -> dict:
        sim = self.t - self.t0
        wall = self.wall_seconds
        return {"simulated_seconds": sim, "wall_seconds": wall,
                "real_time_factor": (sim / wall) if wall > 0 else float("inf"),
                "steps": self.steps, "newton_iterations": self.newton_iterations,
                "residual_evaluations": self.residual_evaluations,
                "jacobian_evaluations": self.jacobian_evaluations,
                "factorizations": self.factorizations, "rejected_steps": self.rejected_steps,
                "low_rank_updates": self.low_rank_updates, "method": self.method,
                **({"windows": self._win.windows, "window_steps": self.window_steps,
                    "window_iterations": self._win.iterations,
                    "window_rigid_updates": self._win.updates,
                    "window_failures": self._win.failures,
                    "residual_instants": self._win.residual_instants}
                   if self._win is not None else {}),
                "step_seconds": self.h, "step_deg": math.degrees(self.h * self.omega),
                "unknowns": self.n}

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
            t = np.concatenate([y[self._rc], D @ y[self._kc]])
            y = y - Z @ (Cinv @ t)
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
        cap = np.eye(2 * nr) + np.concatenate([Z[rc], dR @ Z[kc]])
        try:
            Cinv = np.linalg.inv(cap)
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
        """True when the rigid rows and columns of the Jacobian change with the azimuth at
        the starting state (a free yaw: the yaw axis is fixed, the blades turn; gravity;
        tilt), compared at two azimuths 0.3 revolution apart."""
        m = self.model
        if m.nq + m.nu == 0 or getattr(m, "tower", None) is not None \
                or not hasattr(m, "coupling_jacobians"):
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

    def run(self, duration: float, progress: Optional[Callable] = None) -> dict:
        """Integrate for ``duration`` seconds (the last step is shortened to land on it).
        ``progress(fraction, message)`` is called a few times per second. Returns summary()."""
        duration = _check_number("duration", duration, minimum=0.0)
        t_end = self.t + duration
        last = time.perf_counter()
        w_start = self.wall_seconds
        while self.t < t_end - 1e-9 * max(1.0, abs(t_end)):
            # one decision for full and shortened steps: a step that overshoots t_end by
            # round-off counts as full (and keeps the window's step size)
            self._steps_wanted = int(math.floor((t_end - self.t) / self.h
                                                + 1e-9 * max(1.0, abs(t_end))))
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


# ============================================================================ CLI
def _status_line(fraction, message):
    sys.stderr.write(f"\r[{'#' * int(30 * fraction):<30}] {message}   ")
    sys.stderr.flush()
    if fraction >= 1.0:
        sys.stderr.write("\n")


def cmd_simulate(args) -> int:
    import json
    from .assembly import TurbineModel
    from .io import load_turbine
    duration = _check_number("duration", args.duration, minimum=0.0)
    step_deg = _check_number("step-deg", args.step_deg, positive=True)
    perturb = parse_perturb(args.perturb)
    if args.output and not args.output.lower().endswith((".csv", ".npz")):
        raise ValueError(f"output: {args.output!r} is not allowed; need a .csv or .npz file")
    turbine = load_turbine(args.turbine)
    if args.lock_yaw:
        from dataclasses import replace
        turbine = replace(turbine, nacelle=replace(turbine.nacelle, yaw_free=False))
    model = TurbineModel(turbine, elements=args.elements)
    sim = Simulator(model, step_deg=step_deg, perturb=perturb, record=bool(args.output),
                    method=args.method)
    show = (not args.quiet) and sys.stderr.isatty() or args.progress
    summary = sim.run(duration, progress=_status_line if show else None)
    if args.output:
        sim.save(args.output)
        summary["output"] = args.output
    summary["final"] = sim.named()
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"simulated {summary['simulated_seconds']:.4g} s in {summary['wall_seconds']:.3g} s "
              f"(real-time factor {summary['real_time_factor']:.3g}), {summary['steps']} steps, "
              f"{summary['method']} solver, {summary['factorizations']} factorizations")
        fin = summary["final"]
        print("final: " + ", ".join(f"{k} {fin[k]:.6g}" for k in NAMED))
        if args.output:
            print(f"time histories written to {args.output}")
    return 0


def add_arguments(p):
    from .cli import _positive_int, finite_float
    p.add_argument("turbine", nargs="?", default=None, metavar="TURBINE",
                   help="turbine YAML file (default: the paper's Table 1 turbine)")
    p.add_argument("--duration", type=finite_float(), required=True, metavar="S",
                   help="simulated time [s]")
    p.add_argument("--step-deg", type=finite_float(), default=1.0, metavar="DEG",
                   help="time step in rotor azimuth [deg] (default 1)")
    p.add_argument("--elements", "-n", type=_positive_int, default=None, metavar="N",
                   help="finite elements per blade (default: the turbine file's)")
    p.add_argument("--perturb", default=None, metavar="NAME=VALUE,...",
                   help="initial perturbations of yaw, yaw_rate, teeter, teeter_rate "
                        "[rad, rad/s], e.g. teeter=0.02,yaw_rate=0.01")
    p.add_argument("--lock-yaw", action="store_true", help="lock the yaw bearing")
    p.add_argument("--method", choices=("auto", "window", "step"), default="auto",
                   help="Newton organization: 24 steps solved together (window, the default "
                        "for small and medium meshes) or one step at a time (step); the "
                        "results agree to the Newton tolerance")
    p.add_argument("--output", "-o", default=None, metavar="FILE.csv|FILE.npz",
                   help="write the time histories (CSV with a header row, or NPZ)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--progress", action="store_true",
                   help="show the status line even when stderr is not a terminal")
    p.add_argument("--quiet", "-q", action="store_true", help="no status line")

