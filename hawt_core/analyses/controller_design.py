"""``builtin_gains``: the built-in controller's gains (control/builtin.py) from the turbine's own
aerodynamics and inertia, as Jonkman et al. designed the NREL 5-MW baseline controller
(NREL/TP-500-38060, 2009, section 7; Hansen et al., Risoe-R-1500, 2005):

* region 2: ``k_opt = 1/2 rho pi R_s^2 R^3 Cp(tsr*) / tsr*^3 / N^3`` on the high-speed shaft
  (R the tip radius along the blade, R_s the swept one: the table's definitions), at
  the schedule's tip-speed ratio ``tsr*`` and fine pitch (Cp from the rigid-rotor BEM table,
  analyses/aero_table.py);
* region 3: along the rated-speed, rated-power line the pitch sensitivity ``dP/dtheta`` is
  fitted linearly in pitch, ``dP/dtheta(theta) = dP/dtheta(0) (1 + theta / theta_k)``; the PI
  gains at zero pitch give the speed error a second-order response of natural frequency
  ``w_n`` (0.6 rad/s) and damping ``zeta`` (0.7) with the drivetrain inertia
  ``I = J_rotor + N^2 J_gen``: ``kp = 2 I Omega_r zeta w_n / (N (-dP/dtheta(0)))``,
  ``ki = I Omega_r w_n^2 / (N (-dP/dtheta(0)))``.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..aero.bem import BemRotor
from ..control.builtin import BuiltinGains
from .aero_table import aero_table

__all__ = ["builtin_gains", "rotor_inertia", "pitch_sensitivity"]


def rotor_inertia(turbine, n: int = 2001) -> float:
    """Polar inertia of the rotor about the shaft [kg m^2]: the blades (section mass and
    tip masses at their distance from the shaft, precone included; the sections' own
    inertia about the shaft is neglected, as ElastoDyn does) and the hub's."""
    b = turbine.blade
    S = b.sections
    x = np.linspace(0.0, 1.0, n)
    s = x * b.length
    r = turbine.distance_from_shaft(s)
    m = np.interp(x, S.stations, S.mass)
    rt = float(turbine.distance_from_shaft(b.length))
    blade = float(np.trapezoid(m * r * r, s)) + b.tip_mass * rt * rt
    return turbine.rotor.blades * blade + float(turbine.hub.inertia_longitudinal)


def pitch_sensitivity(turbine, schedule: dict, rho: float = 1.225, winds=None) -> dict:
    """Along region 3 (rated rotor speed, the pitch that gives rated power in the steady
    BEM state) at the wind speeds ``winds`` [m/s] (default 12 to 25 where rated power is
    reached): ``pitch`` [rad] and the frozen-wake ``dp_dtheta`` [W/rad] (inductions held at
    that state, central differences of 0.1 deg), and the linear fit's ``at_zero`` [W/rad]
    and ``theta_k`` [rad]."""
    rotor = BemRotor.from_turbine(turbine)
    R = rotor.tip_radius
    omega = float(schedule["rated_speed"])
    target = float(schedule["rated_power"]) / float(schedule["efficiency"])
    pitch_deg = np.arange(np.degrees(schedule["fine_pitch"]), 30.0 + 1e-9, 0.25)
    if winds is None:
        # the rated wind speed (fine pitch at rated speed gives rated power), then 12..25
        fine = lambda U: rotor.solve(U, omega, float(schedule["fine_pitch"]), rho=rho).power
        lo = 5.0
        rated = brentq(lambda U: fine(U) - target, lo, 25.0, xtol=1e-6) \
            if (fine(lo) - target) * (fine(25.0) - target) < 0 else None
        grid = np.arange(12.0, 25.0 + 1e-9, 1.0)
        winds = grid if rated is None else np.concatenate([[rated], grid[grid > rated + 0.1]])
    winds = np.asarray(winds, float)
    table = aero_table(turbine, omega * R / winds, pitch_deg)
    used, pitches = [], []
    for i, U in enumerate(winds):
        P = 0.5 * rho * np.pi * rotor.swept_radius ** 2 * U ** 3 * table.cp[i]
        cross = np.flatnonzero((P[:-1] - target) * (P[1:] - target) <= 0)
        if P[0] < target * (1 - 1e-6) or cross.size == 0:
            continue                                   # below rated, or out of the grid
        j = int(cross[0])
        f = (P[j] - target) / (P[j] - P[j + 1]) if P[j] != P[j + 1] else 0.0
        used.append(U)
        pitches.append(np.radians(pitch_deg[j] + f * (pitch_deg[j + 1] - pitch_deg[j])))
    if len(pitches) < 2:
        raise ValueError("schedule: rated power is not reached between 12 and 25 m/s at the "
                         "rated rotor speed; no region 3 to design the pitch controller on")
    used, pitches = np.array(used), np.array(pitches)
    sol = rotor.solve(used, omega, pitches, rho=rho)
    d = np.radians(0.1)
    slopes = (rotor.frozen_wake_power(used, omega, pitches + d, sol.a, sol.ap, rho)
              - rotor.frozen_wake_power(used, omega, pitches - d, sol.a, sol.ap, rho)) / (2 * d)
    b, a = np.polyfit(pitches, slopes, 1)
    return {"winds": used, "pitch": pitches, "dp_dtheta": slopes, "at_zero": float(a),
            "theta_k": float(a / b)}


def builtin_gains(turbine, schedule: dict, rho: float = 1.225, natural_frequency: float = 0.6,
                  damping: float = 0.7) -> BuiltinGains:
    """The built-in controller's gains for ``turbine`` under ``schedule`` (the operating-point
    schedule's keys: rated_power [W], efficiency, rated_speed [rad/s, rotor], tsr,
    fine_pitch, max_pitch [rad]; optional max_torque [N m, HSS])."""
    dt = turbine.drivetrain
    if dt is None:
        raise ValueError(f"turbine {turbine.name!r}: no drivetrain section (gearbox ratio, "
                         "generator inertia) to design a controller for")
    N = float(dt.gearbox_ratio)
    tsr = float(schedule["tsr"])
    cp = float(aero_table(turbine, [tsr], [np.degrees(schedule["fine_pitch"])]).cp[0, 0])
    # P = 1/2 rho pi R_swept^2 U^3 Cp with U = Omega R_tip / tsr (the table's definitions)
    rotor = BemRotor.from_turbine(turbine)
    k_rotor = 0.5 * rho * np.pi * rotor.swept_radius ** 2 * rotor.tip_radius ** 3 * cp \
        / tsr ** 3
    sens = pitch_sensitivity(turbine, schedule, rho)
    inertia = rotor_inertia(turbine) + N * N * float(dt.generator_inertia)
    omega = float(schedule["rated_speed"])
    slope = -sens["at_zero"]
    rated_torque = float(schedule["rated_power"]) / (float(schedule["efficiency"]) * omega * N)
    return BuiltinGains(
        k_opt=k_rotor / N ** 3, rated_speed=omega * N,
        rated_power=float(schedule["rated_power"]), efficiency=float(schedule["efficiency"]),
        kp=2 * inertia * omega * damping * natural_frequency / (N * slope),
        ki=inertia * omega * natural_frequency ** 2 / (N * slope),
        theta_k=sens["theta_k"], fine_pitch=float(schedule["fine_pitch"]),
        max_pitch=float(schedule["max_pitch"]),
        max_torque=float(schedule.get("max_torque", 1.1 * rated_torque)))
