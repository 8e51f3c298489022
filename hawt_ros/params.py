"""Parameter and request validation of the hawt node (pure Python: no rclpy import).

Every error is a :class:`ParameterError` (a ``ValueError``) whose text names the parameter, the
offending value and what is allowed, e.g.
``step_deg: -1.0 is not allowed; need a finite number > 0 and <= 30 [deg]``.

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

#: Names the ``perturb`` parameter may set (initial offsets of the rigid-body states).
PERTURB_NAMES = ("yaw", "yaw_rate", "teeter", "teeter_rate")
#: Frames the blade markers may be expressed in.
MARKER_FRAMES = ("nacelle", "hub")
#: Largest element count accepted (simulation and analysis).
MAX_ELEMENTS = 64
#: Largest number of marching steps per period accepted by the analysis requests.
MAX_STEPS = 1_000_000
#: Integration methods of the Floquet analysis (hawt_core.modal.METHODS when available).
try:  # hawt_core is pure NumPy/SciPy: importing it here is cheap and rclpy-free
    from hawt_core.modal import METHODS as ANALYSIS_METHODS  # type: ignore
except Exception:  # pragma: no cover - modal.py not available
    ANALYSIS_METHODS = ("auto", "radau", "paper", "hill")
try:
    from hawt_core.modal import MAX_STEPS as _CORE_MAX_STEPS  # type: ignore
    MAX_STEPS = min(MAX_STEPS, int(_CORE_MAX_STEPS))
except Exception:  # pragma: no cover
    pass
#: Smallest number of steps per period the analysis accepts.
MIN_STEPS = 8


class ParameterError(ValueError):
    """A parameter or request field has a value that is not allowed."""

    def __init__(self, name: str, value: Any, allowed: str):
        self.name, self.value, self.allowed = name, value, allowed
        super().__init__(f"{name}: {value!r} is not allowed; {allowed}")


# ------------------------------------------------------------------------------ parameters
#: name -> (default, description). Types are checked by validate_parameter (the node declares
#: every parameter with dynamic typing so that ``-p step_deg:=1`` (an integer) is accepted
#: where a float is expected).
PARAMETERS: Dict[str, Tuple[Any, str]] = {
    "turbine": ("", "turbine YAML file; '' = the shipped default (the paper's Table 1)"),
    "elements": (0, "beam elements per blade; 0 = the turbine file's value"),
    "step_deg": (5.0, "simulation time step as rotor azimuth increment [deg], > 0 and <= 30"),
    "publish_rate": (20.0, "publishing rate [Hz] (of simulation time when real_time_factor = 0)"),
    "real_time_factor": (1.0, "simulation time / wall-clock time; 0 = as fast as possible, "
                              "stamps in simulation time, /clock published"),
    "record": ("", "MCAP file (or rosbag2 folder) to record every published topic into; "
                   "'' = no recording"),
    "perturb": ("", "initial perturbation, e.g. 'teeter=0.02,yaw_rate=0.01' "
                    f"(names: {', '.join(PERTURB_NAMES)})"),
    "marker_frame": ("nacelle", "frame of the blade markers: 'nacelle' or 'hub'"),
}

#: Parameters that may change while the node runs; all others need a restart.
RUNTIME_CHANGEABLE = ("publish_rate", "real_time_factor", "record", "marker_frame")


@dataclass(frozen=True)
class NodeSettings:
    turbine: str = ""
    elements: int = 0
    step_deg: float = 5.0
    publish_rate: float = 20.0
    real_time_factor: float = 1.0
    record: str = ""
    perturb: Mapping[str, float] = field(default_factory=dict)
    marker_frame: str = "nacelle"

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
    """``"teeter=0.02,yaw_rate=0.01"`` -> ``{"teeter": 0.02, "yaw_rate": 0.01}``.

    Separators: commas, semicolons or blanks. Names from :data:`PERTURB_NAMES`, values finite
    numbers (rad, rad/s)."""
    allowed = (f"need 'name=value' pairs separated by commas with names from "
               f"{', '.join(PERTURB_NAMES)} and finite values, e.g. 'teeter=0.02,yaw_rate=0.01'")
    if text is None:
        return {}
    if not isinstance(text, str):
        raise ParameterError("perturb", text, allowed)
    out: Dict[str, float] = {}
    for item in text.replace(";", ",").replace(" ", ",").split(","):
        item = item.strip()
        if not item:
            continue
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in PERTURB_NAMES:
            raise ParameterError("perturb", text, allowed + f" (bad item {item!r})")
        try:
            x = float(value)
        except ValueError:
            raise ParameterError("perturb", text, allowed + f" (bad value in {item!r})") from None
        if not math.isfinite(x):
            raise ParameterError("perturb", text, allowed + f" (bad value in {item!r})")
        if name in out:
            raise ParameterError("perturb", text, allowed + f" ({name} given twice)")
        out[name] = x
    return out


#: numeric parameters: (lower bound, lower bound allowed, upper bound, what is allowed)
_RANGES = {
    "step_deg": (0.0, False, 30.0, "need a finite number > 0 and <= 30 [deg of rotor azimuth]"),
    "publish_rate": (0.0, False, 1000.0, "need a finite number > 0 and <= 1000 [Hz]"),
    "real_time_factor": (0.0, True, 1000.0, "need a finite number >= 0 and <= 1000 "
                         "(1 = wall clock, 0 = as fast as possible)"),
}


def validate_parameter(name: str, value: Any) -> Any:
    """The checked, normalized value of one node parameter; ParameterError if not allowed."""
    if name == "turbine":
        if value is None:
            return ""
        if not isinstance(value, str):
            raise ParameterError(name, value, "need a file path (string); '' = the default turbine")
        return value.strip()
    if name == "elements":
        allowed = f"need an integer from 1 to {MAX_ELEMENTS}, or 0 = the turbine file's value"
        if not _is_int(value) or not 0 <= value <= MAX_ELEMENTS:
            raise ParameterError(name, value, allowed)
        return int(value)
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
    ``steps`` 0 = the method's default; ``method`` '' = 'auto'."""
    allowed = "need a finite number > 0 [rad/s], or 0 = the turbine's nominal speed"
    if _number("rotor_speed", rotor_speed, allowed) < 0:
        raise ParameterError("rotor_speed", rotor_speed, allowed)
    if float(rotor_speed) > 1000:
        raise ParameterError("rotor_speed", rotor_speed, "need at most 1000 rad/s")
    if not _is_int(elements) or not 0 <= elements <= MAX_ELEMENTS:
        raise ParameterError("elements", elements,
                             f"need an integer from 1 to {MAX_ELEMENTS}, or 0 = the node's default")
    if not _is_int(steps) or not (steps == 0 or MIN_STEPS <= steps <= MAX_STEPS):
        raise ParameterError("steps", steps, f"need an integer from {MIN_STEPS} to {MAX_STEPS}, "
                                             "or 0 = the method's default")
    if not isinstance(method, str) or (method and method not in ANALYSIS_METHODS):
        raise ParameterError("method", method,
                             f"choose one of {', '.join(ANALYSIS_METHODS)}, or '' = {default_method}")
    el = int(elements) if elements else (default_elements or None)
    return AnalysisRequest(elements=el,
                           rotor_speed=float(rotor_speed) if rotor_speed else None,
                           steps=int(steps) if steps else None,
                           method=method or default_method)
