"""The hawt node: parameters, the turbine model and simulation, its interfaces; the
publishing, pacing, recording and modal-analysis parts are mixed in from their modules."""
from __future__ import annotations

import math
import threading
from pathlib import Path
from typing import Dict, List, Optional

from rclpy.action import ActionServer, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from visualization_msgs.msg import MarkerArray

from hawt_msgs.action import ModalAnalysis as ModalAnalysisAction
from hawt_msgs.msg import BladeDeflection, RotorState
from hawt_msgs.srv import ModalAnalysis as ModalAnalysisSrv

from ..backend import load_backend
from ..geometry import RotorGeometry
from ..params import (DEFAULT_TURBINE, PARAMETERS, RUNTIME_CHANGEABLE, ParameterError,
                      settings_from_parameters, validate_parameter)
from .analysis_server import AnalysisServer
from ..analysis_workers import AnalysisRunner, Job
from .config import (NODE_NAME, STATE_QOS, STATUS_DOC, STATUS_PARAM, StartupError,
                     stream_is_tty, validate_status)
from .overrides import Overrides
from .pacing import Pacing
from .publishers import StatePublisher
from .recording import Recording

__all__ = ["HawtNode"]


class HawtNode(Pacing, StatePublisher, Recording, AnalysisServer, Overrides, Node):
    """The hawt ROS 2 node (see :mod:`hawt_ros.node` and docs/ros.md)."""

    def __init__(self, **node_kwargs):
        super().__init__(NODE_NAME, **node_kwargs)
        self._lock = threading.RLock()        # simulation state, timer, recorder
        self._stopping = False
        self._failed: Optional[str] = None
        self._blocked = 0
        self._blocked_lock = threading.Lock()
        self._goal_jobs: Dict[bytes, Job] = {}
        self.analyses_served = 0              # successful service/action answers
        # last published instant for the status line: (monotonic, sim t, yaw, teeter,
        # blade-0 tip flap, blade-0 tip lead-lag) [s, s, rad, rad, m, m]; replaced whole
        self.last_state: Optional[tuple] = None
        # in wind: (wind [m/s], rotor [rpm], generator power [kW], blade-0 pitch [deg])
        self.last_rotor: Optional[tuple] = None
        self.status_enabled = False

        # ---------------------------------------------------------------- parameters
        values = {}
        for name, (default, doc) in PARAMETERS.items():
            desc = ParameterDescriptor(description=doc, dynamic_typing=True,
                                       read_only=False)
            self.declare_parameter(name, default, desc)
            values[name] = self.get_parameter(name).value
        try:
            self.settings = settings_from_parameters(values)
        except ParameterError as exc:
            raise StartupError(f"parameter {exc}") from None
        self.declare_parameter(STATUS_PARAM, stream_is_tty(),
                               ParameterDescriptor(description=STATUS_DOC, dynamic_typing=True))
        try:
            self.status_enabled = validate_status(self.get_parameter(STATUS_PARAM).value)
        except ParameterError as exc:
            raise StartupError(f"parameter {exc}") from None
        self._warn_unknown_overrides()

        # ---------------------------------------------------------------- model
        from hawt_core.io import TurbineFileError
        from hawt_core.io.catalog import SHIPPED, load_any, shipped_path

        path = self.settings.turbine or DEFAULT_TURBINE
        try:
            self.turbine = load_any(path)
        except TurbineFileError as exc:
            raise StartupError(f"parameter turbine: {path!r}: {exc}") from None
        except OSError as exc:
            raise StartupError(f"parameter turbine: {path!r} cannot be read: {exc}") from None
        if path in SHIPPED and not Path(path).exists():
            self.turbine_path = str(shipped_path(path))
        else:
            self.turbine_path = str(Path(path).resolve())
        #: the turbine operates in wind under a controller (the closed loop is ``sim``)
        self.in_wind = self.settings.wind > 0
        if self.in_wind and self.turbine.aerodynamics is None:
            if self._parameter_given("wind"):
                raise StartupError(
                    f"parameter wind: {self.settings.wind:g} m/s needs a turbine with an "
                    f"aerodynamics section; turbine '{self.turbine.name}' ({self.turbine_path})"
                    " has none (wind:=0.0 simulates it in a vacuum)")
            # the default wind, on a turbine that cannot feel it: the paper's model
            self.get_logger().info(
                f"turbine '{self.turbine.name}' has no aerodynamics section: in a vacuum "
                f"(the default wind {self.settings.wind:g} m/s does not apply)")
            self.settings = self.settings.replace(wind=0.0)
            self.in_wind = False
        if self.in_wind:
            self._build_closed_loop(path)
        else:
            self._build_simulation()
        self.omega = float(self.model.rotor_speed)
        self.geometry = RotorGeometry(self.model.rigid)
        self.n_blades = int(self.model.n_blades)
        self._analysis_elements = int(self.model.beam.elements)

        # ---------------------------------------------------------------- interfaces
        self._sim_group = MutuallyExclusiveCallbackGroup()
        self._srv_group = ReentrantCallbackGroup()
        self.pub_joints = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.pub_blades = self.create_publisher(BladeDeflection, "blade_deflections", STATE_QOS)
        self.pub_markers = self.create_publisher(MarkerArray, "blade_markers", STATE_QOS)
        self.pub_rotor = None
        if self.in_wind:
            self.pub_rotor = self.create_publisher(RotorState, "rotor_state", STATE_QOS)
            self._start_overrides(MutuallyExclusiveCallbackGroup())
        self.pub_clock = None
        if self.settings.real_time_factor == 0:
            self.pub_clock = self.create_publisher(Clock, "/clock", STATE_QOS)

        self.runner = AnalysisRunner(self.turbine, logger=self.get_logger().info)
        self.srv = self.create_service(ModalAnalysisSrv, "modal_analysis", self._on_service,
                                       callback_group=self._srv_group)
        self.action = ActionServer(self, ModalAnalysisAction, "modal_analysis",
                                   execute_callback=self._on_action_execute,
                                   goal_callback=lambda goal: GoalResponse.ACCEPT,
                                   cancel_callback=self._on_action_cancel,
                                   callback_group=self._srv_group)

        # ---------------------------------------------------------------- recording
        self.recorder = None
        self.record_path = ""
        if self.settings.record:
            try:
                self._start_recording(self.settings.record)
            except (OSError, ValueError) as exc:
                raise StartupError(f"parameter record: {self.settings.record!r}: {exc}") from None

        # ---------------------------------------------------------------- timing
        self._anchor = None                   # (wall ns, sim t) for real_time_factor > 0
        self._last_stamp_ns = -1
        self._last_pub_t = None
        self._next_pub_t = 0.0
        self._last_clock_t = None
        self._lag_events = 0
        self._last_lag_warn = 0.0
        self.published = 0
        self.steps = 0
        self._timer = self.create_timer(self._timer_period(), self._tick,
                                        callback_group=self._sim_group)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        s = self.settings
        self._check_step_rate()
        self.get_logger().info(
            f"turbine '{self.turbine.name}' ({self.turbine_path}), "
            f"{self.turbine.blade.mesh_text(self.model.beam.elements)} per blade, "
            f"{self.n_blades} blades, rotor speed {self.omega:.4g} rad/s; "
            f"simulation: {self.sim_source}, step {s.step_deg:g} deg = {self.dt * 1e3:.3f} ms; "
            f"publishing at {s.publish_rate:g} Hz, real_time_factor {s.real_time_factor:g}"
            + (" (stamps in simulation time, /clock published)" if s.real_time_factor == 0 else "")
            + (f"; recording to {self.record_path}" if self.recorder else ""))

    def _build_simulation(self) -> None:
        """The paper's model in a vacuum: TurbineModel and Simulator (or the fake backend)."""
        from hawt_core.assembly import TurbineModel

        self.get_logger().info(
            f"turbine '{self.turbine.name}' read; building its model "
            f"({self.turbine.blade.mesh_text(self.settings.elements)} per blade) and "
            "the steady state (Ctrl-C stops)")
        try:
            self.model = TurbineModel(self.turbine, elements=self.settings.elements or None)
        except (ValueError, NotImplementedError) as exc:
            raise StartupError(f"turbine {self.turbine_path}: {exc}") from None
        omega = float(self.model.rotor_speed)
        if omega <= 0:
            raise StartupError(f"turbine {self.turbine_path}: rotor speed {omega} rad/s; "
                               "the simulation needs a spinning rotor (speed > 0)")
        self.dt = math.radians(self.settings.step_deg) / omega
        sim_be = load_backend("simulate")
        self.sim_source = sim_be.source
        self._SimulationError = sim_be.SimulationError
        try:   # no time histories: the node runs for hours
            self.sim = sim_be.Simulator(self.model, step_deg=self.settings.step_deg,
                                        perturb=dict(self.settings.perturb), record=False)
        except Exception as exc:  # noqa: BLE001
            raise StartupError(f"simulation set-up failed: {type(exc).__name__}: {exc}") from None

    def _build_closed_loop(self, spec) -> None:
        """The turbine operating in the steady wind ``wind`` under ``controller``, from the
        schedule's operating point (hawt_core.analyses.closed_loop); one simulation step of
        the node is one controller step."""
        from hawt_core.aero.wind import Wind
        from hawt_core.analyses.closed_loop import closed_loop
        from hawt_core.io.catalog import shipped_controller
        from hawt_core.solvers.march import SimulationError
        s = self.settings
        name = s.controller
        discon = shipped_controller(spec or "") if name in ("rosco", "builtin") else name
        if discon is None:
            raise StartupError(f"parameter controller: {name!r}: the rosco wheel ships no "
                               f"DISCON.IN for turbine {self.turbine_path}; give a DISCON.IN "
                               "path")
        self._discon_path = discon
        if s.perturb:
            raise StartupError("parameter perturb: not used with wind > 0 (the turbine starts "
                               "at its operating point)")
        self.get_logger().info(
            f"turbine '{self.turbine.name}' read; finding its operating point at {s.wind:g} m/s "
            f"and starting it under {name} ({self.turbine.blade.mesh_text(s.elements)} per "
            "blade; Ctrl-C stops)")
        try:
            wind = s.wind_series.for_turbine(self.turbine) if s.wind_series else \
                Wind(float(s.wind))
            self.sim = closed_loop(self.turbine, wind,
                                   "builtin" if name == "builtin" else "rosco",
                                   discon=discon, elements=s.elements or None,
                                   step_deg=s.step_deg, record=False)
        except Exception as exc:  # noqa: BLE001
            raise StartupError(f"closed-loop set-up failed: {type(exc).__name__}: {exc}") \
                from None
        self.model = self.sim.model
        self.dt = self.sim.dt
        later = [] if not s.wind_series else [
            f"{u:g} m/s at {t:g} s" for t, u in s.wind_series.points[1:]]
        if s.wind_series and s.wind_series.gust_start is not None:
            later.append(f"an extreme operating gust of {wind.gust.amplitude:.3g} m/s at "
                         f"{s.wind_series.gust_start:g} s")
        series = f" (then {', '.join(later)})" if later else ""
        self.sim_source = (f"closed loop in {s.wind:g} m/s wind{series} under {name} "
                           f"({discon})")
        self._SimulationError = SimulationError

    def _parameter_given(self, name: str) -> bool:
        """Whether ``name`` was set on the command line or in a launch file (not defaulted)."""
        return name in (getattr(self, "_parameter_overrides", {}) or {})

    def _warn_unknown_overrides(self) -> None:
        overrides = getattr(self, "_parameter_overrides", {}) or {}
        known = set(PARAMETERS) | {STATUS_PARAM, "use_sim_time",
                                   "start_type_description_service"}
        unknown = sorted(n for n in overrides if n not in known and not n.startswith("qos_overrides"))
        if unknown:
            self.get_logger().warning(
                f"unknown parameter(s) ignored: {', '.join(unknown)}; known: {', '.join(PARAMETERS)}")

    def _fail(self, reason: str) -> None:
        self._failed = reason
        self.get_logger().error(f"simulation stopped: {reason}. The node keeps running "
                                "(services stay available); restart it to simulate again.")
        if self.recorder is not None:
            try:
                self.recorder.flush()
            except Exception:  # noqa: BLE001
                pass

    def _on_set_parameters(self, params: List[Parameter]) -> SetParametersResult:
        changes = {}
        status = None
        for p in params:
            if p.name == STATUS_PARAM:
                try:
                    status = validate_status(p.value)
                except ParameterError as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
                continue
            if p.name not in PARAMETERS:
                continue                                  # use_sim_time etc.: rclpy's business
            try:
                value = validate_parameter(p.name, p.value)
            except ParameterError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
            if p.name not in RUNTIME_CHANGEABLE:
                if value == getattr(self.settings, p.name):
                    continue
                return SetParametersResult(
                    successful=False,
                    reason=f"{p.name}: changing it needs a restart of the node (the turbine model "
                           f"and simulation are built at start-up); runtime-changeable: "
                           f"{', '.join(RUNTIME_CHANGEABLE)}")
            changes[p.name] = value
        if "real_time_factor" in changes:
            old, new = self.settings.real_time_factor, changes["real_time_factor"]
            if (old == 0) != (new == 0):
                return SetParametersResult(
                    successful=False,
                    reason=f"real_time_factor: {new!r} needs a restart of the node: switching "
                           f"between 0 (simulation-time stamps, /clock) and > 0 (wall-clock "
                           f"stamps) would make time jump; current value {old!r}")
        if status is not None and status != self.status_enabled:
            self.status_enabled = status
            self.get_logger().info(f"parameters changed: status={status!r}")
        if not changes:
            return SetParametersResult(successful=True)
        with self._lock:
            new = changes.get("record")
            if new is not None and (str(Path(new).expanduser()) if new else "") != self.record_path:
                if new:
                    if self.recorder is not None:
                        return SetParametersResult(
                            successful=False,
                            reason=f"record: already recording to {self.record_path}; set record "
                                   "to '' first to finalize it")
                    try:
                        self._start_recording(new)
                    except (OSError, ValueError) as exc:
                        return SetParametersResult(successful=False, reason=f"record: {new!r}: {exc}")
                else:
                    self._stop_recording()
            self.settings = self.settings.replace(**changes)
            if "publish_rate" in changes or "real_time_factor" in changes:
                self._check_step_rate()
                self._anchor = None
                self._timer.timer_period_ns = int(self._timer_period() * 1e9)
                self._timer.reset()
        self.get_logger().info("parameters changed: " + ", ".join(f"{k}={v!r}"
                                                                 for k, v in changes.items()))
        return SetParametersResult(successful=True)

    def shutdown(self) -> None:
        """Stop stepping, cancel analyses, finalize the recording (idempotent)."""
        self._stopping = True
        try:
            self._timer.cancel()
        except Exception:  # noqa: BLE001
            pass
        self.runner.shutdown()
        with self._lock:
            self._stop_recording()
            close = getattr(self.sim, "close", None)     # a controller's final call
            if close is not None:
                try:
                    close()
                except Exception as exc:  # noqa: BLE001 - shutting down: report, go on
                    self.get_logger().warning(f"controller close failed: {exc}")
