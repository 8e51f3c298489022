"""``closed_loop``: a turbine in a steady (or time-varying) wind under a controller, started at
its operating point: what ``hawt simulate --controller`` and the ROS 2 node run.

The controller is ROSCO through its DISCON library (control/discon.py) with a DISCON.IN, or
hawt's built-in baseline controller (control/builtin.py) with gains designed from the
turbine's aerodynamics (analyses/controller_design.py) on the schedule (the DISCON.IN's, or
given values).  The initial rotor speed and pitch are the schedule's operating point at the
initial wind speed (analyses/operating_points.py).
"""
from __future__ import annotations

from typing import Optional

from ..control.builtin import BuiltinController
from ..control.discon import DisconController
from ..control.loop import ActuatorLimits, ClosedLoop
from ..io.discon import discon_schedule, read_discon
from .controller_design import builtin_gains
from .operating_points import at_operating_point

__all__ = ["closed_loop", "CONTROLLERS"]

#: the controllers by name ("rosco": the DISCON library with its DISCON.IN)
CONTROLLERS = ("rosco", "builtin")


def closed_loop(turbine, wind, controller: str = "rosco", discon=None,
                schedule: Optional[dict] = None, dt: float = 0.05,
                elements: Optional[int] = None, inflow: str = "oye",
                airfoil: str = "quasi-steady", step_deg: float = 1.0, method: str = "auto",
                record: bool = True, operating_point: bool = True) -> ClosedLoop:
    """The ClosedLoop of ``turbine`` in ``wind`` (aero.wind.Wind) under ``controller``
    ("rosco" or "builtin"); ``discon``: the DISCON.IN (needed for ROSCO; for the built-in
    controller its schedule and actuator limits are used when given); ``schedule``: the
    operating-point schedule (io.discon.discon_schedule's keys; default the DISCON.IN's);
    ``operating_point`` False keeps the turbine's own rotor speed and pitch."""
    if controller not in CONTROLLERS:
        raise ValueError(f"controller: {controller!r} is not allowed; choose one of "
                         f"{', '.join(CONTROLLERS)}")
    if controller == "rosco" and discon is None:
        raise ValueError("controller: 'rosco' needs its DISCON.IN (discon=...)")
    if schedule is None:
        if discon is None:
            raise ValueError("schedule: needed without a DISCON.IN (rated_power, rated_speed, "
                             "tsr, ...)")
        schedule = discon_schedule(discon)
    limits = ActuatorLimits.from_discon(read_discon(discon) if discon is not None else {})
    if operating_point:
        turbine = at_operating_point(turbine, float(wind.hub_speed(0.0)), schedule)[0]
    nb = int(turbine.rotor.blades)
    ctrl = DisconController(discon, dt, nb) if controller == "rosco" else \
        BuiltinController(builtin_gains(turbine, schedule), dt, nb)
    try:
        return ClosedLoop(turbine, wind, ctrl, dt=dt, efficiency=schedule["efficiency"],
                          limits=limits, elements=elements, inflow=inflow, airfoil=airfoil,
                          step_deg=step_deg, method=method, record=record)
    except BaseException:
        ctrl.close()
        raise
