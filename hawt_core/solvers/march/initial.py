"""Initial states of the time simulation: perturbations of the steady state (named rigid
DOFs, a mode shape) made consistent with the constraints (positions: the strain-
displacement equations; velocities: their time derivative and the kinematic equations).
See docs/simulation.md.
"""

from __future__ import annotations

import re

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from ...fem.beam import BLOCK_SIZE, ROOT_SIZE
from ...numerics.checks import check_perturbation_value

__all__ = ['NAMED', 'PERTURBABLE', 'SimulationError', 'parse_perturb', 'consistent_state']


class SimulationError(RuntimeError):
    """The time integration failed (Newton did not converge, or values became non-finite)."""


#: Scalar outputs of ``Simulator.named()`` (and the first CSV columns).
NAMED = ("time", "azimuth", "yaw", "yaw_rate", "teeter", "teeter_rate")

#: Names accepted in ``perturb``.
PERTURBABLE = ("yaw", "yaw_rate", "teeter", "teeter_rate")


def check_perturbation(name, value) -> float:
    """One perturbation: ``name`` in PERTURBABLE, ``value`` a finite number within
    MAX_PERTURB_ANGLE [rad] (MAX_PERTURB_RATE [rad/s] for a rate)."""
    if name not in PERTURBABLE:
        raise ValueError(f"perturb: unknown name {name!r}; allowed: {', '.join(PERTURBABLE)}")
    return check_perturbation_value(name, value)


def parse_perturb(text: str) -> dict:
    """``"teeter=0.02,yaw_rate=0.01"`` -> ``{"teeter": 0.02, "yaw_rate": 0.01}`` [rad, rad/s].

    Items separated by commas, semicolons or blanks; names from PERTURBABLE, each once;
    values finite numbers within the limits of check_perturbation. ``None`` or blank: no
    perturbation."""
    out = {}
    if text is None:
        return out
    if not isinstance(text, str):
        raise ValueError(f"perturb: {text!r} is not allowed; need a string of NAME=VALUE items")
    for item in re.split(r"[,;\s]+", text.strip()):
        if not item:
            continue
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"perturb: {item!r} is not allowed; need NAME=VALUE "
                             f"with NAME in {', '.join(PERTURBABLE)}")
        if name in out:
            raise ValueError(f"perturb: {name} is given twice in {text!r}; give each name once")
        out[name] = check_perturbation(name, value)
    return out


class BladeIndex:
    """Precomputed index arrays of one blade (cheap extraction every step)."""

    def __init__(self, layout, k):
        bl = layout.blade(k)
        self.u = bl.u[1:].ravel()
        self.theta = bl.theta[1:].ravel()
        self.root_force = bl.root_force
        self.root_moment = bl.root_moment


# ============================================================================ initial state
def blade_rows(model):
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


def rigid_speed_map(model, q, t):
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
    sd, kin, cols = blade_rows(model)
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


def mode_delta(model, mode, amplitude, blade_signs=None):
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
        elif x.shape == (model.blade_size,):
            for k in range(nb):
                off = model.layout.blade_offset(k)
                delta[off:off + model.blade_size] = signs[k] * x
        else:
            raise ValueError(f"mode: a vector of length {x.shape} is not allowed; need "
                             f"{n} (turbine state) or {model.blade_size} (one blade)")
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
