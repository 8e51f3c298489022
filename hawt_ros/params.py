"""Parameter and request validation of the hawt node (pure Python: no rclpy import).

Every error is a :class:`ParameterError` (a ``ValueError``) whose text names the parameter, the
offending value and what is allowed, e.g.
``step_deg: -1.0 is not allowed; need a finite number > 0 and <= 10 [deg of rotor azimuth]``.
The limits are hawt_core.numerics.limits' (the same for the command line, the turbine file,
the parameters and the requests).

Used by :mod:`hawt_ros.node` for its ROS parameters (at start-up and on runtime changes) and
for modal-analysis service/action requests, and by :mod:`hawt_ros.cli` for ``hawt call``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Dict, Mapping, Optional, Tuple

__all__ = [
    "ParameterError", "NodeSettings", "PARAMETERS", "RUNTIME_CHANGEABLE", "parse_perturb",
    "validate_parameter", "settings_from_parameters", "AnalysisRequest", "validate_request",
    "PERTURB_NAMES", "MARKER_FRAMES", "MAX_ELEMENTS", "MAX_STEPS", "ANALYSIS_METHODS",
]

from hawt_core.analyses.modal import MAX_STEPS, MIN_STEPS
from hawt_core.numerics.checks import (STEP_DEG_ALLOWED, check_step_deg, elements_allowed,
                                       rotor_speed_allowed)
from hawt_core.numerics.limits import MAX_ELEMENTS, MAX_STEP_DEG
from hawt_core.analyses.modal import METHODS as ANALYSIS_METHODS
from hawt_core.analyses.modal import validate_request as _validate_analysis
from hawt_core.solvers.march import PERTURBABLE as PERTURB_NAMES
from hawt_core.solvers.march import parse_perturb as _parse_perturb

#: Frames the blade markers may be expressed in.
MARKER_FRAMES = ("nacelle", "hub")


class ParameterError(ValueError):
    """A parameter or request field has a value that is not allowed."""

    def __init__(self, name: str, value: Any, allowed: str):
        self.name, self.value, self.allowed = name, value, allowed
        super().__init__(f"{name}: {value!r} is not allowed; {allowed}")


# ------------------------------------------------------------------------------ parameters
#: what `bash scripts/run.sh` shows: the shipped NREL 5-MW operating in 15 m/s (above rated:
#: ROSCO pitches) at the turbine file's mesh (3 blade elements of order 6: first three blade
#: frequencies within 3e-5 of converged, steady tip deflection within 2e-4), which the node
#: simulates faster than real time on one core (bench/live_default.py, bench/node.py)
DEFAULT_TURBINE = "nrel5mw"
DEFAULT_WIND = 15.0
DEFAULT_ELEMENTS = 0
#: The time step [deg of azimuth].  The implicit midpoint rule shortens a mode's period by
#: (omega h)^2 / 12: at 2 deg the NREL 5-MW's first flap, edge and second flap (3.6, 5.4,
#: 10 per-rev at 12.1 rpm) are simulated 0.13, 0.3, 1.0 % low (at 5 deg: 0.8, 1.9, 6.3 %;
#: at 1 deg: 0.03, 0.07, 0.25 %); the node runs them at 1.24 x real time (5 deg: 1.72, 1 deg:
#: 1.02; bench/node.py --wind-steps, 2 cores)
DEFAULT_STEP_DEG = 2.0

#: name -> (default, description). Types are checked by validate_parameter (the node declares
#: every parameter with dynamic typing so that ``-p step_deg:=1`` (an integer) is accepted
#: where a float is expected).
PARAMETERS: Dict[str, Tuple[Any, str]] = {
    "turbine": (DEFAULT_TURBINE, "turbine YAML file, OpenFAST deck (.fst), HAWC2 model "
                                 "(.htc), WindIO file or shipped name (hawt turbines): "
                                 "default the NREL 5-MW under "
                                 "ROSCO; 'paper' = the paper's Table 1 (in a vacuum); '' = "
                                 "the default"),
    "elements": (DEFAULT_ELEMENTS, "beam elements per blade, of the blade's order; 0 (the "
                                   "default) = the turbine file's mesh (the shipped NREL "
                                   "5-MW: 3 of order 6, converged to 1e-4; the paper's "
                                   "turbine: its Table 2 mesh, 4 of the paper's element)"),
    "step_deg": (DEFAULT_STEP_DEG, "simulation time step as rotor azimuth increment [deg], "
                                   f"> 0 and <= {MAX_STEP_DEG:g} (default 2: the NREL 5-MW's "
                                   "first blade modes simulated within 0.3 %, its second "
                                   "flap 1 % low; 5: faster, 0.8-6 % low; 1: 0.25 %, about "
                                   "real time)"),
    "publish_rate": (20.0, "publishing rate [Hz] (of simulation time when real_time_factor = 0)"),
    "real_time_factor": (1.0, "simulation time / wall-clock time; 0 = as fast as possible, "
                              "stamps in simulation time, /clock published"),
    "record": ("", "MCAP file (or rosbag2 folder) to record every published topic into; "
                   "'' = no recording"),
    "perturb": ("", "initial perturbation, e.g. 'teeter=0.02,yaw_rate=0.01' "
                    f"(names: {', '.join(PERTURB_NAMES)})"),
    "marker_frame": ("nacelle", "frame of the blade markers: 'nacelle' or 'hub'"),
    "wind": (DEFAULT_WIND, "wind at hub height: a steady speed [m/s], or a time series "
                           "'t0:U0,t1:U1,...' [s:m/s] (e.g. '0:15,10:15,10.5:17', a step at "
                           "10 s; 'eog@T' adds the IEC extreme operating gust); the turbine "
                           "operates in it under `controller` (it needs an aerodynamics "
                           "section and a drivetrain, e.g. turbine:=nrel5mw); 0 = in a "
                           "vacuum (the paper's model); left at its default, a turbine "
                           "without aerodynamics (the paper's) runs in a vacuum"),
    "controller": ("rosco", "with wind > 0: 'rosco' (the rosco wheel's DISCON.IN for the "
                            "turbine), 'builtin' (hawt's baseline controller on that schedule) "
                            "or a DISCON.IN path"),
    "override_timeout": (1.0, "with wind > 0: seconds without a pitch_command / "
                              "torque_command after which the controller takes over again"),
}

#: Parameters that may change while the node runs; all others need a restart.
RUNTIME_CHANGEABLE = ("publish_rate", "real_time_factor", "record", "marker_frame",
                      "override_timeout")


@dataclass(frozen=True)
class NodeSettings:
    turbine: str = DEFAULT_TURBINE
    elements: int = DEFAULT_ELEMENTS
    step_deg: float = DEFAULT_STEP_DEG
    publish_rate: float = 20.0
    real_time_factor: float = 1.0
    record: str = ""
    perturb: Mapping[str, float] = field(default_factory=dict)
    marker_frame: str = "nacelle"
    wind: float = DEFAULT_WIND
    controller: str = "rosco"
    #: the wind as a time series (hawt_core.aero.wind.WindSeries), None = steady at
    #: ``wind``; ``wind`` is then its speed at t = 0
    wind_series: Any = None
    override_timeout: float = 1.0

    def replace(self, **kw) -> "NodeSettings":
        return replace(self, **kw)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool))


def _number(name: str, v: Any, allowed: str) -> float:
    if not _is_number(v) or not math.isfinite(float(v)):
        raise ParameterError(name, v, allowed)
    return float(v)


def parse_perturb(text: Any) -> Dict[str, float]:
    """``"teeter=0.02,yaw_rate=0.01"`` -> ``{"teeter": 0.02, "yaw_rate": 0.01}`` (the
    simulator's parser, hawt_core.solvers.march.parse_perturb; its error as a ParameterError)."""
    try:
        return _parse_perturb(text)
    except ValueError as e:
        raise ParameterError("perturb", text,
                             f"need 'name=value' pairs separated by commas with names from "
                             f"{', '.join(PERTURB_NAMES)} and finite values, e.g. "
                             f"'teeter=0.02,yaw_rate=0.01' ({str(e).split(': ', 1)[-1]})") from None


#: numeric parameters: (lower bound, lower bound allowed, upper bound, what is allowed)
_RANGES = {
    "publish_rate": (0.0, False, 1000.0, "need a finite number > 0 and <= 1000 [Hz]"),
    "real_time_factor": (0.0, True, 1000.0, "need a finite number >= 0 and <= 1000 "
                         "(1 = wall clock, 0 = as fast as possible)"),
    "wind": (0.0, True, 100.0, "need a finite number >= 0 and <= 100 [m/s] (0 = in a vacuum), "
             "or a time series 't0:U0,t1:U1,...' [s:m/s]"),
    "override_timeout": (0.0, False, 3600.0, "need a finite number > 0 and <= 3600 [s]"),
}


def validate_parameter(name: str, value: Any) -> Any:
    """The checked, normalized value of one node parameter; ParameterError if not allowed."""
    if name == "turbine":
        if value is None:
            return ""
        if not isinstance(value, str):
            raise ParameterError(name, value, "need a file path or a shipped turbine's name "
                                              "(string); '' = the default turbine")
        return value.strip()
    if name == "elements":
        allowed = f"{elements_allowed()}, or 0 = the turbine file's value"
        if not _is_int(value) or not 0 <= value <= MAX_ELEMENTS:
            raise ParameterError(name, value, allowed)
        return int(value)
    if name == "step_deg":
        if not _is_number(value):
            raise ParameterError(name, value, STEP_DEG_ALLOWED)
        try:
            return check_step_deg(value)
        except ValueError:
            raise ParameterError(name, value, STEP_DEG_ALLOWED) from None
    if name == "wind" and isinstance(value, str):
        from hawt_core.aero.wind import parse_wind_series
        try:
            return parse_wind_series(value.strip(), name)
        except ValueError as exc:
            raise ParameterError(name, value, str(exc).split("; ", 1)[-1]) from None
    if name in _RANGES:
        low, closed, high, allowed = _RANGES[name]
        x = _number(name, value, allowed)
        if not ((low <= x) if closed else (low < x)) or not x <= high:
            raise ParameterError(name, value, allowed)
        return x
    if name == "record":
        if value is None:
            return ""
        if not isinstance(value, str):
            raise ParameterError(name, value, "need a file path (string, e.g. 'run.mcap'); '' = off")
        return value.strip()
    if name == "perturb":
        return parse_perturb(value if value is not None else "")
    if name == "controller":
        if not isinstance(value, str) or not value.strip():
            raise ParameterError(name, value, "need 'rosco', 'builtin' or a DISCON.IN path")
        return value.strip()
    if name == "marker_frame":
        if value not in MARKER_FRAMES:
            raise ParameterError(name, value, f"choose one of {', '.join(MARKER_FRAMES)}")
        return value
    raise ParameterError(name, value, f"unknown parameter; known: {', '.join(PARAMETERS)}")


def settings_from_parameters(values: Mapping[str, Any]) -> NodeSettings:
    """NodeSettings from raw parameter values (missing ones: defaults). Raises
    ParameterError for the first bad one."""
    kw = {}
    for name, (default, _doc) in PARAMETERS.items():
        kw[name] = validate_parameter(name, values.get(name, default))
    if not isinstance(kw["wind"], float):       # a time series: its speed at t = 0 too
        kw["wind_series"] = kw["wind"]
        kw["wind"] = kw["wind"].initial_speed
    return NodeSettings(**kw)


# ---------------------------------------------------------------------- analysis requests
@dataclass(frozen=True)
class AnalysisRequest:
    """Resolved modal-analysis request (None = the analysis' own default)."""

    elements: Optional[int]
    rotor_speed: Optional[float]
    steps: Optional[int]
    method: str

    def as_kwargs(self) -> dict:
        return {"elements": self.elements, "rotor_speed": self.rotor_speed,
                "steps": self.steps, "method": self.method}


def validate_request(rotor_speed: Any = 0.0, elements: Any = 0, steps: Any = 0,
                     method: Any = "", default_elements: Optional[int] = None,
                     default_method: str = "auto") -> AnalysisRequest:
    """Check a ModalAnalysis request (service or action goal).

    Conventions of hawt_msgs/srv/ModalAnalysis: ``rotor_speed`` 0 = the turbine's nominal
    speed (negative, NaN or infinite: rejected); ``elements`` 0 = the node's default;
    ``steps`` 0 = the method's default; ``method`` '' = 'auto'. The limits are the
    analysis' own (hawt_core.analyses.modal.validate_request); the node adds the
    conventions for 0 and '' to what is allowed."""
    allowed = {
        "rotor_speed": f"{rotor_speed_allowed(positive=True)}, or 0 = the turbine's "
                       "nominal speed",
        "elements": f"{elements_allowed()}, or 0 = the node's default",
        "steps": f"need an integer from {MIN_STEPS} to {MAX_STEPS}, or 0 = the method's default",
        "method": f"choose one of {', '.join(ANALYSIS_METHODS)}, or '' = {default_method}"}
    given = {"rotor_speed": rotor_speed, "elements": elements, "steps": steps, "method": method}
    for name, zero_ok in (("rotor_speed", _is_number), ("elements", _is_int), ("steps", _is_int)):
        if not zero_ok(given[name]):
            raise ParameterError(name, given[name], allowed[name])
    if not isinstance(method, str):
        raise ParameterError("method", method, allowed["method"])
    request = AnalysisRequest(elements=int(elements) if elements else (default_elements or None),
                              rotor_speed=float(rotor_speed) if rotor_speed else None,
                              steps=int(steps) if steps else None,
                              method=method or default_method)
    try:
        _validate_analysis(**request.as_kwargs())
    except ValueError as e:
        name = str(e).split(":", 1)[0]
        raise ParameterError(name, given.get(name), allowed.get(name, str(e))) from None
    return request
