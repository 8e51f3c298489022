"""Can the turbine have a steady state at all?  A check that runs before any Newton solve.

A rigid degree of freedom whose generalized force has a nonzero mean over a revolution and
nothing that restores it has no steady state (constant or periodic): a free generator with
no generator torque under the rotor's aerodynamic torque accelerates; a free yaw bearing
without a spring under a mean yaw moment turns.  Newton (and the harmonic balance's
continuation) would search for minutes and fail; this check sees it from the turbine's
starting state in a fraction of a second.

For each rigid coordinate ``q_c`` with its speed row ``r_c`` (hawt_core.rigid.kane: Kane's
equation of that generalized speed) the residual is sampled at the starting state
(``model.initial_guess()``: the rotor in rigid rotation, blades in their own aeroelastic
steady state) at SAMPLES equally spaced times over a revolution (one time for a standing
rotor):

    G = mean_t R_rc          (the unbalanced generalized force: N m for the angles)
    K = mean_t dR_rc / dq_c  (its restoring stiffness, exact by complex step)

No steady state exists near the starting state when ``|G|`` is above round-off and the
restoring stiffness cannot balance it within half a turn, ``|K| pi < |G|``.  A free
generator's K is zero (nothing depends on the drivetrain's angle); a yaw bearing with a
spring, or a teeter hinge (centrifugal stiffness), passes.  The forces are those the
starting state's blade root loads carry (centrifugal and, in wind, aerodynamic: the blades
are in their own aeroelastic steady state, so the free generator's G is the rotor's
aerodynamic torque to 1e-9, tests/test_equilibrium.py); gravity on an unbalanced rotor is
not in them, and its mean over a revolution is zero anyway: the check only refuses, it
never replaces the solvers' own convergence.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["NoEquilibrium", "check_equilibrium_exists", "unbalanced_forces", "SAMPLES"]

#: Times per revolution the mean generalized forces are taken over.
SAMPLES = 12

#: A mean force below this share of the loads' scale (times the rotor radius for moments)
#: is round-off (the steady-state solvers converge to 1e-9 of it).
ROUNDOFF = 1e-8


class NoEquilibrium(ValueError):
    """The turbine as specified has no steady state (a ValueError: bad input, refused up
    front); the message names the field and what would make the problem solvable."""


def unbalanced_forces(model):
    """[(coordinate name, mean force G, mean stiffness K, largest |R| over the samples)]
    of every rigid coordinate, at the starting state."""
    nq, nu = model.nq, model.nu
    if nq == 0 or nu != nq:
        return []
    period = model.period
    times = (np.arange(SAMPLES) * period / SAMPLES if math.isfinite(period)
             else np.zeros(1))
    K = len(times)
    y = np.real(model.initial_guess())
    # one batched residual: a complex step of each coordinate at every time (its real part
    # is the unstepped residual, to O(h^2))
    h = 1e-30
    Y = np.tile(y, (nq * K, 1)).astype(complex)
    for c in range(nq):
        Y[c * K:(c + 1) * K, c] += 1j * h
    R = model.residual(np.zeros_like(Y), Y, np.tile(times, nq)).reshape(nq, K, -1)
    R0 = np.real(R[0])
    out = []
    for c, name in enumerate(model.rigid.coordinates):
        row = nq + c                     # Kane's equation of the c-th generalized speed
        dr = R[c, :, row].imag / h
        out.append((name, float(R0[:, row].mean()), float(dr.mean()),
                    float(np.abs(R0[:, row]).max())))
    return out


def check_equilibrium_exists(model) -> None:
    """Raise NoEquilibrium when a rigid degree of freedom of ``model`` (a TurbineModel) has
    an unbalanced mean generalized force that nothing restores (module docstring); return
    None otherwise (a model without rigid degrees of freedom passes)."""
    if getattr(model, "rigid", None) is None:
        return
    turbine = model.turbine
    radius = float(turbine.hub.radius) + float(turbine.blade.length)
    floor = ROUNDOFF * model.load_scale() * max(radius, 1.0)
    trimmed = getattr(model, "generator_trim", None) is not None
    for name, G, K, peak in unbalanced_forces(model):
        if abs(G) <= max(floor, 1e-6 * peak) or abs(K) * math.pi >= abs(G):
            continue
        if name == "generator_azimuth" and trimmed:
            continue         # the steady state trims the generator torque (solvers/trim.py)
        raise NoEquilibrium(_message(model, name, G, K))


def _where(model) -> str:
    rpm = model.rotor_speed * 30.0 / math.pi
    wind = getattr(model, "wind", None)
    air = f" in {wind.speed:g} m/s wind" if wind is not None else " in a vacuum"
    return (f"at {rpm:.4g} rpm" if model.rotor_speed > 0 else "at standstill") + air


def _message(model, name, G, K) -> str:
    where = _where(model)
    if name == "generator_azimuth":
        controls = getattr(model, "controls", None)
        torque = "with no generator torque" if controls is None else \
            "with the controls' generator torque"
        return (f"drivetrain.generator: 'free' {torque}: the rotor's mean torque {where} is "
                f"{abs(G) / 1e3:.6g} kN m on the low-speed shaft and nothing balances it (a free "
                "drivetrain has no restoring torque), so the rotor cannot turn steadily at "
                "this speed and no steady state exists. For the modes at this operating "
                "point hold the rotor speed (drivetrain.generator: prescribed, as OpenFAST "
                "with GenDOF = False); to let the rotor speed change, simulate it with a "
                "controller (hawt simulate --controller)")
    if name == "yaw":
        k = float(model.turbine.nacelle.yaw_stiffness)
        return (f"nacelle.yaw_free: true with yaw_stiffness {k:g} N m/rad: the mean yaw moment "
                f"on the nacelle {where} is {abs(G) / 1e3:.6g} kN m, and the yaw bearing's spring "
                f"and the loads' own restoring ({-K:.6g} N m/rad in all) cannot hold it within "
                "half a turn, so no steady state exists. Lock the yaw (nacelle.yaw_free: "
                "false) or give a yaw spring (nacelle.yaw_stiffness) of at least "
                f"{abs(G) / math.pi:.3g} N m/rad")
    return (f"{name}: the mean generalized force on this degree of freedom {where} is "
            f"{G:.6g} (N m for an angle) and its restoring stiffness {-K:.6g} cannot balance "
            "it within half a turn, so no steady state exists")
