"""``aero_table``: the rigid rotor's power, thrust and torque coefficients over a grid of
tip-speed ratios and collective pitch angles (blade-element momentum theory, hawt_core.aero.bem),
the surfaces controller tools consume (ROSCO's Cp_Ct_Cq file).

The coefficients of this model do not depend on the wind speed (polars of one Reynolds
number, no compressibility); ``wind_speed`` only sets the dimensional loads behind them and is
written into ROSCO's file.
"""
from __future__ import annotations

import numpy as np

from ..aero.bem import BemRotor
from ..results.aero import AeroTable

__all__ = ["aero_table", "MAX_TSR", "PITCH_RANGE_DEG"]

#: Largest tip-speed ratio of a table (a wind turbine's optimum is 6-10).
MAX_TSR = 30.0
#: Collective pitch range of a table [deg, towards feather].
PITCH_RANGE_DEG = (-30.0, 90.0)


def aero_table(turbine, tsr, pitch_deg, wind_speed: float = 10.0, tip_loss: bool = True,
               hub_loss: bool = True, drag_in_induction: bool = True) -> AeroTable:
    """Cp, Ct, Cq [tsr][pitch] of ``turbine`` (it needs an ``aerodynamics`` section) for the
    tip-speed ratios ``tsr`` (Omega R_tip / U, > 0 and <= MAX_TSR) and collective pitch
    angles ``pitch_deg`` [deg, towards feather, within PITCH_RANGE_DEG] at ``wind_speed``
    [m/s]."""
    tsr = np.atleast_1d(np.asarray(tsr, float))
    pitch_deg = np.atleast_1d(np.asarray(pitch_deg, float))
    if tsr.ndim != 1 or not np.all((tsr > 0) & (tsr <= MAX_TSR)):
        raise ValueError(f"tsr: {tsr.tolist()!r:.80} is not allowed; need tip-speed ratios "
                         f"> 0 and <= {MAX_TSR:g}")
    lo, hi = PITCH_RANGE_DEG
    if pitch_deg.ndim != 1 or not np.all((pitch_deg >= lo) & (pitch_deg <= hi)):
        raise ValueError(f"pitch_deg: {pitch_deg.tolist()!r:.80} is not allowed; need angles "
                         f"from {lo:g} to {hi:g} [deg]")
    if not (np.isfinite(wind_speed) and wind_speed > 0):
        raise ValueError(f"wind_speed: {wind_speed!r} is not allowed; need a number > 0 [m/s]")
    rotor = BemRotor.from_turbine(turbine, tip_loss=tip_loss, hub_loss=hub_loss,
                                  drag_in_induction=drag_in_induction)
    T, P = np.meshgrid(tsr, np.radians(pitch_deg), indexing="ij")
    sol = rotor.solve(wind_speed, T * wind_speed / rotor.tip_radius, P)
    return AeroTable(turbine=turbine.name, tsr=tsr, pitch_deg=pitch_deg, cp=sol.cp,
                     ct=sol.ct, cq=sol.cq, wind_speed=float(wind_speed),
                     residual=np.max(sol.residual, axis=-1),
                     settings={"model": "steady BEM (Ning 2014), Prandtl tip/hub loss, "
                                        "Buhl high-induction correction",
                               "tip_loss": tip_loss, "hub_loss": hub_loss,
                               "drag_in_induction": drag_in_induction,
                               "stations": int(rotor.r.size),
                               "tip_radius_m": rotor.tip_radius,
                               "precone_rad": rotor.precone})
