"""The constant steady state of a turbine (rigid rotation, no gravity): Newton's method on
R(0, y, 0) = 0 with the ignorable coordinates (a free yaw angle) held."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..numerics.newton import newton
from .equilibrium import check_equilibrium_exists
from .trim import generator_trim

__all__ = ["constant_steady_state", "is_time_invariant_at", "ignorable_columns"]


def is_time_invariant_at(model, y, times=None, tol=1e-9) -> bool:
    """True when ``R(0, y, t)`` stays zero over a revolution (a constant steady state)."""
    if times is None:     # a standing rotor (period infinite) does not change with time
        times = np.linspace(0, model.period, 7)[:-1] if np.isfinite(model.period) else [0.0]
    z = np.zeros(model.n)
    scale = model.load_scale()
    return all(np.abs(model.residual(z, y, t)).max() <= tol * scale for t in times)

def ignorable_columns(J, rtol=1e-12) -> np.ndarray:
    """Columns of dR/dy that vanish (to round-off relative to the largest entry): the
    ignorable coordinates, e.g. a free yaw angle without a spring."""
    colmax = np.abs(sp.csc_matrix(J)).max(axis=0).toarray().ravel()
    return np.flatnonzero(colmax <= rtol * max(colmax.max(initial=0.0), 1e-300))

def constant_steady_state(model, tol=1e-10, check: bool = True) -> np.ndarray:
    """The steady state of a TurbineModel, constant in the rotating frame (no gravity, symmetric
    rotor).

    Ignorable coordinates (a free yaw angle: its column of dR/dy is zero) are held at
    their initial value. Raises ConvergenceError if Newton fails, and ValueError if the
    steady state is periodic rather than constant; NoEquilibrium (a ValueError) up front
    when no steady state can exist (solvers/equilibrium.py; ``check`` False: the caller
    checked).
    """
    trim = generator_trim(model)
    if check:
        check_equilibrium_exists(model)
    z = np.zeros(model.n)
    fun = lambda y: model.residual(z, y, 0.0)
    y0 = model.initial_guess()
    J0 = model.jacobians(z, y0, 0.0)[0]
    # Newton's first step is at y0 again: reuse J0 there
    jac = lambda y: J0 if np.array_equal(y, y0) else model.jacobians(z, y, 0.0)[0]
    ignorable = ignorable_columns(J0)
    border = None
    if trim is not None:
        ignorable, border = trim.border(ignorable, fun, y0)
    y, _ = newton(fun, jac, y0, tol=tol, what="turbine steady state", fixed=ignorable,
                  scale=model.load_scale(), border=border)
    if not is_time_invariant_at(model, y):
        raise ValueError("steady state: this configuration (gravity, tilt or an asymmetric "
                         "rotor) has a periodic steady state, not a constant one; use the "
                         "periodic steady-state solver")
    return y
