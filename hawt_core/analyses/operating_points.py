"""``operating_points``: the aeroelastic steady state of the rotor at each wind speed under a
variable-speed, pitch-to-feather schedule (region 2: the optimal tip-speed ratio between the
minimum and rated rotor speed at fine pitch; region 3: rated rotor speed, the pitch that holds
rated generator power), from ROSCO's DISCON.IN or given values.

The rotor is axisymmetric here (uniform axial wind, no tilt, shear or gravity): one blade on
the hub spinning at the scheduled speed (assembly/aero_blade.py) stands for each of the B
blades. In region 3 the pitch is found by Brent's method on the generator power, each
evaluation an aeroelastic steady state started from the last.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np
from scipy.optimize import brentq

from ..assembly.aero_blade import AeroelasticBlade
from ..results.operating import OperatingPoints

__all__ = ["operating_points", "at_operating_point", "check_schedule", "scheduled_rotor_speed"]


def check_schedule(s: dict) -> dict:
    """The schedule ``s`` (a copy) once every field is a finite number in its range;
    ValueError naming the field, its value and what is allowed otherwise."""
    s = dict(s)
    need = ("rated_power", "efficiency", "rated_speed", "min_speed", "tsr", "fine_pitch",
            "max_pitch")
    for k in need:
        v = s.get(k)
        if not isinstance(v, (int, float)) or not np.isfinite(v):
            raise ValueError(f"schedule.{k}: {v!r} is not allowed; need a finite number")
    for k in ("rated_power", "efficiency", "rated_speed", "tsr"):
        if not s[k] > 0:
            raise ValueError(f"schedule.{k}: {s[k]!r} is not allowed; need a number > 0")
    if not 0 < s["efficiency"] <= 1:
        raise ValueError(f"schedule.efficiency: {s['efficiency']!r} is not allowed; need a "
                         "fraction from 0 to 1")
    if not 0 <= s["min_speed"] <= s["rated_speed"]:
        raise ValueError(f"schedule.min_speed: {s['min_speed']!r} is not allowed; need 0 <= "
                         f"min_speed <= rated_speed ({s['rated_speed']!r}) [rad/s]")
    if not s["fine_pitch"] < s["max_pitch"]:
        raise ValueError("schedule: fine_pitch must be below max_pitch")
    return s


def operating_points(turbine, wind_speeds, schedule: dict, elements: Optional[int] = None,
                     rho: float = 1.225, progress=None) -> OperatingPoints:
    """One aeroelastic operating point per wind speed [m/s]; ``schedule``: rated_power [W,
    electrical], efficiency [-], rated_speed and min_speed [rad/s], tsr [-], fine_pitch and
    max_pitch [rad, towards feather] (io/discon.py reads them from a DISCON.IN).
    ``elements``: per blade, of the blade's order (default: the turbine file's mesh, which
    for the shipped turbines puts the tip deflection within 2e-4 of converged)."""
    s = check_schedule(schedule)
    winds = np.asarray(wind_speeds, float)
    if winds.ndim != 1 or winds.size < 1 or np.any(~(winds > 0)):
        raise ValueError("wind_speeds: need wind speeds > 0 [m/s]")
    n_el = int(elements or turbine.blade.elements)
    R = turbine.hub.radius + turbine.blade.length
    Bn = turbine.rotor.blades
    points = []
    state = {"y": None}
    solved = {}          # (U, omega, pitch) -> solution: Brent's method asks again for its ends

    def solve(U, omega, pitch):
        key = (float(U), float(omega), float(pitch))
        if key in solved:
            return solved[key]
        t = replace(turbine, rotor=replace(turbine.rotor, speed=omega, pitch=-pitch))
        m = AeroelasticBlade(t, U, elements=n_el, rho=rho)
        y0 = state["y"] if state["y"] is not None and state["y"].size == m.n else None
        y = m.steady_state(y0=y0)
        state["y"] = y
        torque, thrust = m.root_loads(y)
        solved[key] = m, y, Bn * torque * omega, Bn * thrust
        return solved[key]

    for i, U in enumerate(winds):
        solved.clear()
        omega = scheduled_rotor_speed(turbine, U, s)
        pitch = s["fine_pitch"]
        converged, region = True, 2
        try:
            m, y, power, thrust = solve(U, omega, pitch)
            if power * s["efficiency"] > s["rated_power"] * (1 + 1e-9):
                region = 3
                target = s["rated_power"] / s["efficiency"]
                saved = state["y"]

                def excess(p):
                    return solve(U, omega, p)[2] / target - 1.0
                hi = min(s["max_pitch"], s["fine_pitch"] + np.radians(5.0))
                while excess(hi) > 0 and hi < s["max_pitch"]:
                    hi = min(s["max_pitch"], hi + np.radians(5.0))
                state["y"] = saved
                pitch = brentq(excess, s["fine_pitch"], hi, xtol=1e-8)
                m, y, power, thrust = solve(U, omega, pitch)
        except (RuntimeError, ValueError) as exc:                  # Newton or bracket failed
            converged = False
            state["y"] = None
            points.append({"wind_speed": float(U), "rotor_speed_rpm": omega * 30 / np.pi,
                           "pitch_deg": float(np.degrees(pitch)), "aero_power_kw": None,
                           "generator_power_kw": None, "thrust_kn": None, "cp": None,
                           "ct": None, "tip_flap_m": None, "tip_edge_m": None,
                           "converged": False, "region": region, "error": str(exc)[:200]})
            continue
        flap, edge = m.tip_deflection(y)
        q = 0.5 * rho * U * U * np.pi * R * R
        points.append({"wind_speed": float(U), "rotor_speed_rpm": omega * 30 / np.pi,
                       "pitch_deg": float(np.degrees(pitch)), "aero_power_kw": power / 1e3,
                       "generator_power_kw": power * s["efficiency"] / 1e3,
                       "thrust_kn": thrust / 1e3, "cp": power / (q * U), "ct": thrust / q,
                       "tip_flap_m": flap, "tip_edge_m": edge, "converged": converged,
                       "region": region})
        if progress is not None:
            progress((i + 1) / winds.size, f"{U:.3g} m/s")
    return OperatingPoints(turbine=turbine.name, points=points, schedule=s,
                           settings={"elements": n_el,
                                     "order": int(turbine.blade.order),
                                     "density": rho,
                                     "model": "one blade per blade on the spinning hub, BEM "
                                              "(Prandtl, Buhl) at the Gauss points, axial wind"})


def scheduled_rotor_speed(turbine, wind_speed: float, schedule: dict) -> float:
    """The rotor speed [rad/s] of the (checked) ``schedule`` at ``wind_speed`` [m/s]: the
    optimal tip-speed ratio's between the minimum and the rated speed."""
    R = turbine.hub.radius + turbine.blade.length
    return float(np.clip(schedule["tsr"] * float(wind_speed) / R, schedule["min_speed"],
                         schedule["rated_speed"]))


def at_operating_point(turbine, wind_speed: float, schedule: dict, rotor_speed=None,
                       rho: float = 1.225):
    """(turbine, point): ``turbine`` with the rotor speed [rad/s] and pitch of the schedule's
    operating point at ``wind_speed`` [m/s] (``rotor_speed`` given: that speed, the
    schedule's pitch) and that point (operating_points' dict; air density ``rho``
    [kg/m^3]).  ValueError naming the wind when the schedule has no converged point there."""
    U = float(wind_speed)
    point = operating_points(turbine, [U], schedule, rho=rho).points[0]
    if not point["converged"]:
        raise ValueError(f"wind: no operating point at {U:g} m/s under the schedule: "
                         f"{point.get('error')}")
    speed = point["rotor_speed_rpm"] * math.pi / 30 if not rotor_speed else float(rotor_speed)
    return replace(turbine, rotor=replace(turbine.rotor, speed=speed,
                                          pitch=-math.radians(point["pitch_deg"]))), point
