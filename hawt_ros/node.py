"""The hawt ROS 2 node (console script ``hawt-node``).

Steps the nonlinear turbine simulation (hawt_core Simulator) and publishes

* ``joint_states``       sensor_msgs/JointState: joints ``yaw``, ``teeter``, ``rotor_azimuth``
                         (position, velocity, effort = moments from the blade root loads);
* ``blade_deflections``  hawt_msgs/BladeDeflection, one message per blade per publish;
* ``blade_markers``      visualization_msgs/MarkerArray: each deformed blade as a LINE_STRIP
                         in frame ``nacelle`` (or ``hub``, parameter ``marker_frame``);
* ``/clock``             rosgraph_msgs/Clock, only when ``real_time_factor`` is 0;

and serves the Floquet modal analysis of its turbine as service ``modal_analysis``
(hawt_msgs/srv/ModalAnalysis) and action ``modal_analysis`` (hawt_msgs/action/ModalAnalysis,
progress feedback, cancellable). Analyses run in worker processes (hawt_ros.analysis), so the
simulation timer keeps its cadence. Parameters, frames, time stamps and recording:
docs/ros.md.

    hawt-node --ros-args -p publish_rate:=20.0 -p real_time_factor:=1.0 -p record:=run.mcap
"""
from __future__ import annotations

import math
import os
import shutil
import signal
import sys
import threading
import time
from collections import deque
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Point, Vector3
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from hawt_msgs.action import ModalAnalysis as ModalAnalysisAction
from hawt_msgs.msg import AnalysisSettings, BladeDeflection, Mode, ModeShape
from hawt_msgs.srv import ModalAnalysis as ModalAnalysisSrv

from .analysis import AnalysisRunner, Job
from .backend import load_backend
from .geometry import RotorGeometry
from .params import (PARAMETERS, RUNTIME_CHANGEABLE, ParameterError, settings_from_parameters,
                     validate_parameter, validate_request)

__all__ = ["HawtNode", "main", "JOINT_NAMES", "NODE_NAME"]

NODE_NAME = "hawt"
JOINT_NAMES = ("yaw", "teeter", "rotor_azimuth")
BLADE_COLORS = [(0.85, 0.2, 0.2), (0.2, 0.6, 0.9), (0.3, 0.8, 0.3), (0.9, 0.7, 0.1)]
STATE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)
#: Executor threads; at most MAX_BLOCKED of them wait for analyses at any time, so the
#: simulation timer and quick requests always find a free thread.
EXECUTOR_THREADS = 10
MAX_BLOCKED = 6
#: The live status line (parameter ``status``): refreshed in place every STATUS_TTY_PERIOD s
#: on a terminal, else one plain line every STATUS_PLAIN_PERIOD s.
STATUS_PARAM = "status"
STATUS_TTY_PERIOD = 0.5
STATUS_PLAIN_PERIOD = 5.0
STATUS_DOC = ("live status line on stderr (sim time, real-time factor, teeter, yaw, blade-0 tip "
              "deflection, recording, analyses); default true when stderr is a terminal")


class StartupError(RuntimeError):
    """The node cannot start (bad parameter, unreadable turbine file, ...)."""


def _stderr_is_tty(stream=None) -> bool:
    """Whether ``stream`` (default sys.stderr) is a terminal (False if that cannot be told)."""
    try:
        return bool((sys.stderr if stream is None else stream).isatty())
    except (AttributeError, ValueError, OSError):
        return False


def _validate_status(value):
    """The ``status`` parameter: a bool (ParameterError otherwise)."""
    if isinstance(value, bool):
        return value
    raise ParameterError(STATUS_PARAM, value, "need true or false (default: true when stderr "
                                              "is a terminal)")


def _time_msg(ns: int) -> TimeMsg:
    return TimeMsg(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def _wrap_pi(a: float) -> float:
    """Angle in [-pi, pi) (the yaw bearing is a continuous joint)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def _finite(*arrays) -> bool:
    for a in arrays:
        if not np.all(np.isfinite(np.asarray(a, dtype=float))):
            return False
    return True


class HawtNode(Node):
    """See the module docstring and docs/ros.md."""

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
        self.declare_parameter(STATUS_PARAM, _stderr_is_tty(),
                               ParameterDescriptor(description=STATUS_DOC, dynamic_typing=True))
        try:
            self.status_enabled = _validate_status(self.get_parameter(STATUS_PARAM).value)
        except ParameterError as exc:
            raise StartupError(f"parameter {exc}") from None
        self._warn_unknown_overrides()

        # ---------------------------------------------------------------- model
        from hawt_core.assembly import TurbineModel
        from hawt_core.io import TurbineFileError, load_turbine

        path = self.settings.turbine or None
        try:
            self.turbine = load_turbine(path)
        except TurbineFileError as exc:
            raise StartupError(f"parameter turbine: {path!r}: {exc}") from None
        except OSError as exc:
            raise StartupError(f"parameter turbine: {path!r} cannot be read: {exc}") from None
        if path is None:
            from hawt_core.io import default_turbine_path
            self.turbine_path = str(default_turbine_path())
        else:
            self.turbine_path = str(Path(path).resolve())
        try:
            self.model = TurbineModel(self.turbine, elements=self.settings.elements or None)
        except (ValueError, NotImplementedError) as exc:
            raise StartupError(f"turbine {self.turbine_path}: {exc}") from None
        self.omega = float(self.model.rotor_speed)
        if self.omega <= 0:
            raise StartupError(f"turbine {self.turbine_path}: rotor speed {self.omega} rad/s; "
                               "the simulation needs a spinning rotor (speed > 0)")
        self.dt = math.radians(self.settings.step_deg) / self.omega
        self.geometry = RotorGeometry(self.model.rigid)
        self.n_blades = int(self.model.n_blades)
        self._analysis_elements = int(self.model.beam.N)

        sim_be = load_backend("simulate")
        self.sim_source = sim_be.source
        self._SimulationError = sim_be.SimulationError
        try:   # no time histories: the node runs for hours
            self.sim = sim_be.Simulator(self.model, step_deg=self.settings.step_deg,
                                        perturb=dict(self.settings.perturb), record=False)
        except Exception as exc:  # noqa: BLE001
            raise StartupError(f"simulation set-up failed: {type(exc).__name__}: {exc}") from None

        # ---------------------------------------------------------------- interfaces
        self._sim_group = MutuallyExclusiveCallbackGroup()
        self._srv_group = ReentrantCallbackGroup()
        self.pub_joints = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.pub_blades = self.create_publisher(BladeDeflection, "blade_deflections", STATE_QOS)
        self.pub_markers = self.create_publisher(MarkerArray, "blade_markers", STATE_QOS)
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
            f"turbine '{self.turbine.name}' ({self.turbine_path}), {self.model.beam.N} elements "
            f"per blade, {self.n_blades} blades, rotor speed {self.omega:.4g} rad/s; "
            f"simulation: {self.sim_source}, step {s.step_deg:g} deg = {self.dt * 1e3:.3f} ms; "
            f"publishing at {s.publish_rate:g} Hz, real_time_factor {s.real_time_factor:g}"
            + (" (stamps in simulation time, /clock published)" if s.real_time_factor == 0 else "")
            + (f"; recording to {self.record_path}" if self.recorder else ""))

    # ================================================================== helpers
    def _publishers_list(self):
        pubs = [self.pub_joints, self.pub_blades, self.pub_markers]
        if self.pub_clock is not None:
            pubs.append(self.pub_clock)
        return pubs

    def _warn_unknown_overrides(self) -> None:
        overrides = getattr(self, "_parameter_overrides", {}) or {}
        known = set(PARAMETERS) | {STATUS_PARAM, "use_sim_time",
                                   "start_type_description_service"}
        unknown = sorted(n for n in overrides if n not in known and not n.startswith("qos_overrides"))
        if unknown:
            self.get_logger().warning(
                f"unknown parameter(s) ignored: {', '.join(unknown)}; known: {', '.join(PARAMETERS)}")

    def _check_step_rate(self) -> None:
        """Every publish is a new simulation instant: warn when the simulation cannot provide
        publish_rate of them (real_time_factor / step time)."""
        s = self.settings
        if s.real_time_factor > 0 and s.publish_rate > s.real_time_factor / self.dt * (1 + 1e-9):
            self.get_logger().warning(
                f"publish_rate {s.publish_rate:g} Hz exceeds the rate of new simulation instants "
                f"real_time_factor / step = {s.real_time_factor / self.dt:.3g} Hz: publishing "
                "will be at most that (raise real_time_factor or lower step_deg)")

    def _timer_period(self) -> float:
        if self.settings.real_time_factor == 0:
            return 0.002                       # as fast as possible: short ticks
        return 1.0 / self.settings.publish_rate

    def _start_recording(self, path: str) -> None:
        from .mcap_io import BagWriter

        p = Path(path).expanduser()
        if p.exists() and (p.is_file() or any(p.iterdir())):
            raise ValueError(f"{p} exists; choose a new file name (recordings are never overwritten)")
        try:
            turbine_yaml = Path(self.turbine_path).read_text()
        except OSError:
            turbine_yaml = None
        s = self.settings
        settings = {"node": self.get_fully_qualified_name(), "turbine": self.turbine_path,
                    "elements": self.model.beam.N, "step_deg": s.step_deg,
                    "publish_rate": s.publish_rate, "real_time_factor": s.real_time_factor,
                    "perturb": dict(s.perturb), "marker_frame": s.marker_frame,
                    "simulation": self.sim_source}
        self.recorder = BagWriter(p, turbine_yaml=turbine_yaml, settings=settings)
        for pub in self._publishers_list():
            from .mcap_io import type_name_of
            self.recorder.add_topic(pub.topic_name, type_name_of(pub.msg_type), qos=STATE_QOS)
        self.record_path = str(p)

    def _stop_recording(self, failure: Optional[str] = None) -> None:
        """Drop the recorder and clear ``record_path`` and ``settings.record`` (so setting
        ``record`` again starts a new recording). Normally finalize the file and log it; with
        ``failure`` (a write failed) log that and close the file quietly."""
        rec, path = self.recorder, self.record_path
        self.recorder = None
        self.record_path = ""
        if self.settings.record:
            self.settings = self.settings.replace(record="")
        if rec is None:
            return
        if failure is not None:
            self.get_logger().error(f"recording to {path} failed ({failure}); recording stopped")
            try:
                rec.close()
            except Exception:  # noqa: BLE001
                pass
            return
        try:
            rec.close()
            self.get_logger().info(f"recording finalized: {path} ({rec.message_count} messages)")
        except Exception as exc:  # noqa: BLE001
            self.get_logger().error(f"closing the recording {path} failed: {exc}")

    def _emit(self, pub, msg, stamp_ns: int) -> None:
        """Publish ``msg``; when recording, serialize once, publish those bytes and record them."""
        rec = self.recorder
        if rec is None:
            pub.publish(msg)
            return
        from .mcap_io import serialize, type_name_of

        type_name = type_name_of(msg)
        data = serialize(msg, type_name)
        pub.publish(data)
        try:
            rec.write_serialized(pub.topic_name, type_name, data, log_time=stamp_ns)
        except Exception as exc:  # noqa: BLE001 - recording problems never stop the node
            self._stop_recording(failure=str(exc))

    def _fail(self, reason: str) -> None:
        self._failed = reason
        self.get_logger().error(f"simulation stopped: {reason}. The node keeps running "
                                "(services stay available); restart it to simulate again.")
        if self.recorder is not None:
            try:
                self.recorder.flush()
            except Exception:  # noqa: BLE001
                pass

    # ================================================================== simulation
    def _step(self) -> bool:
        try:
            self.sim.step()
        except Exception as exc:  # noqa: BLE001 - SimulationError or anything else
            kind = "simulation error" if isinstance(exc, self._SimulationError) else \
                f"unexpected {type(exc).__name__}"
            self._fail(f"{kind} at t = {self.sim.t:.6f} s: {exc}")
            return False
        self.steps += 1
        if not math.isfinite(float(self.sim.t)):
            self._fail(f"simulation time became {self.sim.t}")
            return False
        return True

    def _tick(self) -> None:
        with self._lock:
            if self._stopping or self._failed:
                return
            if self.settings.real_time_factor > 0:
                self._tick_real_time(self.settings.real_time_factor)
            else:
                self._tick_fast()

    def _tick_real_time(self, rtf: float) -> None:
        now = self.get_clock().now().nanoseconds
        if self._anchor is None:
            self._anchor = (now, float(self.sim.t))
        wall0, sim0 = self._anchor
        target = sim0 + rtf * (now - wall0) * 1e-9
        period = 1.0 / self.settings.publish_rate
        deadline = time.monotonic() + min(0.7 * period, 0.5)
        behind = False
        while self.sim.t + 0.5 * self.dt <= target:
            if time.monotonic() > deadline:
                behind = True
                break
            if not self._step():
                return
        if behind and (target - self.sim.t) / rtf > 2 * period:
            # cannot keep up: restart the mapping sim time -> wall time from here
            self._lag_events += 1
            achieved = (self.sim.t - sim0) / max((now - wall0) * 1e-9, 1e-9)
            if time.monotonic() - self._last_lag_warn > 10.0:
                self._last_lag_warn = time.monotonic()
                self.get_logger().warning(
                    f"simulation slower than real_time_factor {rtf:g}: achieved {achieved:.3g} "
                    f"(step {self.dt * 1e3:.2f} ms of simulation time); stamps follow the "
                    "achieved pace (lower real_time_factor or raise step_deg)")
            self._anchor = (now, float(self.sim.t))
            wall0, sim0 = self._anchor
        if self._last_pub_t is not None and self.sim.t <= self._last_pub_t:
            return                              # nothing new to publish
        stamp = wall0 + int(round((self.sim.t - sim0) / rtf * 1e9))
        self._publish_state(stamp)

    def _tick_fast(self) -> None:
        period = 1.0 / self.settings.publish_rate
        deadline = time.monotonic() + 0.02
        advanced = False
        while time.monotonic() < deadline:
            if not self._step():
                break
            advanced = True
            if self.sim.t >= self._next_pub_t - 1e-12:
                stamp = int(round(self.sim.t * 1e9))
                self._publish_clock(stamp)
                if not self._publish_state(stamp):
                    return
                while self._next_pub_t <= self.sim.t + 1e-12:
                    self._next_pub_t += period
        if advanced and not self._failed:
            self._publish_clock(int(round(self.sim.t * 1e9)))

    def _publish_clock(self, stamp_ns: int) -> None:
        if self.pub_clock is None or self._last_clock_t == stamp_ns:
            return
        self._last_clock_t = stamp_ns
        self._emit(self.pub_clock, Clock(clock=_time_msg(stamp_ns)), stamp_ns)

    def _publish_state(self, stamp_ns: int) -> bool:
        """Publish every topic for the current simulation instant with one stamp."""
        if stamp_ns <= self._last_stamp_ns:
            stamp_ns = self._last_stamp_ns + 1          # strictly increasing stamps
        t = float(self.sim.t)
        try:
            named = self.sim.named()
            defl = self.sim.blade_deflections()
            azimuth = float(named["azimuth"])
            yaw, teeter = float(named["yaw"]), float(named["teeter"])
            yaw_rate, teeter_rate = float(named["yaw_rate"]), float(named["teeter_rate"])
            stations = np.array([d["stations"] for d in defl], float)
            disp = np.array([d["u"] for d in defl], float)
            rot = np.array([d["theta"] for d in defl], float)
            rf = np.array([d["root_force"] for d in defl], float)
            rm = np.array([d["root_moment"] for d in defl], float)
            frames = self.geometry.frames(named, t)
            loads = self.geometry.loads(named, t, rf, rm, frames)
            points = self.geometry.blade_points(named, t, stations, disp,
                                                self.settings.marker_frame, frames)
        except Exception as exc:  # noqa: BLE001
            self._fail(f"reading the simulation state at t = {t:.6f} s failed: "
                       f"{type(exc).__name__}: {exc}")
            return False
        values = [t, azimuth, yaw, teeter, yaw_rate, teeter_rate, *loads]
        if not _finite(values, stations, disp, rot, rf, rm, points):
            self._fail(f"non-finite simulation state at t = {t:.6f} s (nothing published)")
            return False
        stamp = _time_msg(stamp_ns)

        js = JointState()
        js.header = Header(stamp=stamp, frame_id="")
        js.name = list(JOINT_NAMES)
        js.position = [_wrap_pi(yaw), teeter, azimuth % (2 * math.pi)]
        js.velocity = [yaw_rate, teeter_rate, self.omega]
        js.effort = [float(x) for x in loads]
        self._emit(self.pub_joints, js, stamp_ns)

        for k in range(self.n_blades):
            m = BladeDeflection()
            m.header = Header(stamp=stamp, frame_id=f"blade_{k}_root")
            m.blade = k
            m.span = stations[k].tolist()
            m.displacement = [Vector3(x=a, y=b, z=c) for a, b, c in disp[k].tolist()]
            m.rotation = [Vector3(x=a, y=b, z=c) for a, b, c in rot[k].tolist()]
            m.root_force = Vector3(x=rf[k, 0], y=rf[k, 1], z=rf[k, 2])
            m.root_moment = Vector3(x=rm[k, 0], y=rm[k, 1], z=rm[k, 2])
            self._emit(self.pub_blades, m, stamp_ns)

        ma = MarkerArray()
        width = 0.02 * float(self.turbine.blade.length)
        for k in range(self.n_blades):
            mk = Marker()
            mk.header = Header(stamp=stamp, frame_id=self.settings.marker_frame)
            mk.ns = "blades"
            mk.id = k
            mk.type = Marker.LINE_STRIP
            mk.action = Marker.ADD
            mk.pose.orientation.w = 1.0
            mk.scale.x = width
            r, g, b = BLADE_COLORS[k % len(BLADE_COLORS)]
            mk.color = ColorRGBA(r=r, g=g, b=b, a=1.0)
            mk.points = [Point(x=a, y=bb, z=c) for a, bb, c in points[k].tolist()]
            ma.markers.append(mk)
        self._emit(self.pub_markers, ma, stamp_ns)

        self._last_stamp_ns = stamp_ns
        self._last_pub_t = t
        self.published += 1
        self.last_state = (time.monotonic(), t, yaw, teeter, float(disp[0, -1, 2]),
                           float(disp[0, -1, 1]))
        return True

    # ================================================================== parameters
    def _on_set_parameters(self, params: List[Parameter]) -> SetParametersResult:
        changes = {}
        status = None
        for p in params:
            if p.name == STATUS_PARAM:
                try:
                    status = _validate_status(p.value)
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

    # ================================================================== modal analysis
    def _resolve(self, rotor_speed, elements, steps, method):
        return validate_request(rotor_speed=rotor_speed, elements=int(elements),
                                steps=int(steps), method=method,
                                default_elements=self._analysis_elements)

    def _settings_msg(self, req=None, result=None) -> AnalysisSettings:
        s = AnalysisSettings()
        rs = (result or {}).get("settings", {}) if result else {}
        s.turbine = str(rs.get("turbine", self.turbine.name))
        s.rotor_speed = float(rs.get("rotor_speed", (req.rotor_speed if req and req.rotor_speed
                                                     else self.omega)))
        s.elements = int(rs.get("elements", (req.elements if req and req.elements
                                             else self._analysis_elements)))
        steps = rs.get("steps", req.steps if req else None)
        if steps is None:
            try:
                from hawt_core.analyses.modal import DEFAULT_STEPS
                steps = DEFAULT_STEPS.get(req.method if req else "auto", 0)
            except Exception:  # noqa: BLE001
                steps = 0
        s.steps = int(steps)
        s.method = str(rs.get("method", req.method if req else "auto"))
        return s

    @staticmethod
    def _mode_msgs(result) -> List[Mode]:
        out = []
        for m in result["modes"]:
            msg = Mode()
            msg.family = m["family"]
            msg.symmetry = m["symmetry"] or ""
            msg.index = max(0, min(int(m["index"]), 65535))
            msg.frequency_per_rev = float(m["frequency_per_rev"])
            msg.real_per_rev = float(m["real_per_rev"])
            msg.frequency_hz = float(m["frequency_hz"])
            msg.damping_ratio = float(m["damping_ratio"])
            msg.fixed_frame_per_rev = float(m.get("fixed_frame_per_rev", 0.0))
            msg.fixed_frame_hz = float(m.get("fixed_frame_hz", 0.0))
            msg.fixed_frame_damping_ratio = float(m.get("fixed_frame_damping_ratio", 0.0))
            msg.whirl = str(m.get("whirl", ""))
            sh = m.get("shape")
            if sh:
                shape = ModeShape()
                shape.blades = int(sh["blades"])
                shape.span = [float(x) for x in sh["span"]]
                for field in ("displacement_real", "displacement_imag",
                              "rotation_real", "rotation_imag"):
                    setattr(shape, field, [Vector3(x=a, y=b, z=c) for a, b, c in sh[field]])
                for field in ("yaw_real", "yaw_imag", "teeter_real", "teeter_imag"):
                    setattr(shape, field, float(sh[field]))
                msg.shape = shape
            out.append(msg)
        return out

    def _fill(self, out, job: Optional[Job], req, error: Optional[str] = None):
        """Fill a service response / action result."""
        if error is not None:
            out.success = False
            out.message = error
            out.settings = self._settings_msg(req)
            out.compute_time = 0.0
            return out
        if job.status == "ok":
            res = job.result
            out.success = True
            out.modes = self._mode_msgs(res)
            out.settings = self._settings_msg(req, res)
            out.compute_time = float(res.get("compute_time", job.wall_time) or 0.0)
            extra = (f"; {res['unresolved']} mesh modes above the temporal resolution not shown"
                     if res.get("unresolved") else "")
            out.message = f"{len(out.modes)} modes{extra}" + (" (cached result)" if job.cached else "")
        else:
            out.success = False
            out.message = f"{job.status}: {job.message}".strip()
            out.settings = self._settings_msg(req)
            out.compute_time = float(job.wall_time)
        return out

    def _count_served(self) -> None:
        with self._blocked_lock:
            self.analyses_served += 1

    @property
    def analyses_waiting(self) -> int:
        """Service/action callbacks waiting for an analysis right now."""
        return self._blocked

    def _enter_blocking(self) -> bool:
        with self._blocked_lock:
            if self._blocked >= MAX_BLOCKED:
                return False
            self._blocked += 1
            return True

    def _leave_blocking(self) -> None:
        with self._blocked_lock:
            self._blocked -= 1

    def _on_service(self, request, response):
        t0 = time.monotonic()
        try:
            req = self._resolve(request.rotor_speed, request.elements, request.steps, request.method)
        except ParameterError as exc:
            self.get_logger().warning(f"modal_analysis request rejected: {exc}")
            return self._fill(response, None, None, error=f"invalid request: {exc}")
        job = self.runner.submit(req.as_kwargs(), shareable=True)
        if not job.done():
            if not self._enter_blocking():
                return self._fill(response, None, req, error=(
                    f"busy: {MAX_BLOCKED} analysis requests are already waiting; retry later "
                    "(or use the modal_analysis action)"))
            try:
                while not job.wait(0.2):
                    if self._stopping:
                        return self._fill(response, None, req, error="the node is shutting down")
            finally:
                self._leave_blocking()
        self._fill(response, job, req)
        if response.success:
            self._count_served()
        self.get_logger().info(f"modal_analysis service: {response.message} "
                               f"({time.monotonic() - t0:.2f} s)")
        return response

    def _on_action_cancel(self, goal_handle) -> CancelResponse:
        job = self._goal_jobs.get(bytes(goal_handle.goal_id.uuid))
        if job is not None:
            job.cancel()
        return CancelResponse.ACCEPT

    def _on_action_execute(self, goal_handle):
        goal = goal_handle.request
        result = ModalAnalysisAction.Result()
        try:
            req = self._resolve(goal.rotor_speed, goal.elements, goal.steps, goal.method)
        except ParameterError as exc:
            goal_handle.abort()
            return self._fill(result, None, None, error=f"invalid request: {exc}")
        if not self._enter_blocking():
            goal_handle.abort()
            return self._fill(result, None, req, error=f"busy: {MAX_BLOCKED} analysis requests "
                                                       "are already waiting; retry later")
        key = bytes(goal_handle.goal_id.uuid)
        progress: List[tuple] = []
        plock = threading.Lock()

        def on_progress(fraction, stage):
            with plock:
                progress.append((fraction, stage))

        try:
            job = self.runner.submit(req.as_kwargs(), shareable=False)
            self._goal_jobs[key] = job
            job.add_progress_callback(on_progress)
            if job.cached:
                on_progress(1.0, "done (cached result)")
            sent = False
            while True:
                finished = job.wait(0.05)
                with plock:
                    items, progress[:] = list(progress), []
                for fraction, stage in items:
                    fb = ModalAnalysisAction.Feedback(progress=float(fraction), stage=str(stage))
                    goal_handle.publish_feedback(fb)
                    sent = True
                if finished:
                    break
                if goal_handle.is_cancel_requested or self._stopping:
                    job.cancel()
            if not sent:
                goal_handle.publish_feedback(ModalAnalysisAction.Feedback(progress=1.0, stage="done"))
        finally:
            self._goal_jobs.pop(key, None)
            self._leave_blocking()
        self._fill(result, job, req)
        if job.status == "cancelled" and goal_handle.is_cancel_requested:
            result.modes = []
            goal_handle.canceled()
        elif job.status == "ok":
            goal_handle.succeed()
            self._count_served()
        else:
            goal_handle.abort()
        self.get_logger().info(f"modal_analysis action: {result.message}")
        return result

    # ================================================================== shutdown
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


# ====================================================================== status line
def _num(x, fmt: str, missing: str = "--") -> str:
    """``format(x, fmt)``, or ``missing`` when x is None or not finite (never 'nan')."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return missing
    if not math.isfinite(x):
        return missing
    text = format(x, fmt)
    return format(0.0, fmt) if float(text) == 0 else text   # no '-0.0'


class StatusLine:
    """The node's live status on stderr (parameter ``status``), e.g.

    ``hawt | t 12.35 s | rtf 1.00 | teeter +0.42 deg | yaw +0.00 deg | tip flap +41.3 mm,
    lag -2.1 mm | rec hawt-20261124-010203.mcap 1024 msgs | analyses 1``

    A daemon thread samples the node every STATUS_TTY_PERIOD s; on a terminal it redraws the
    line in place (``\\r``, cleared to the end of the line, cut to the terminal width), else it
    writes a plain line every STATUS_PLAIN_PERIOD s. The real-time factor is simulation time
    advanced / wall time elapsed over the last ~2 s (terminal) or the last period (plain).
    It only reads attributes the node replaces whole (no lock), and a write that fails or
    blocks never holds up the node: :meth:`close` waits at most ``timeout`` s for the thread.
    """

    def __init__(self, node: "HawtNode", stream=None, tty: Optional[bool] = None):
        self.node = node
        self.stream = stream if stream is not None else sys.stderr
        if tty is None:
            tty = _stderr_is_tty(self.stream)
        self.tty = tty
        self.period = STATUS_TTY_PERIOD if tty else STATUS_PLAIN_PERIOD
        self.window = 2.0 if tty else STATUS_PLAIN_PERIOD
        self._samples: deque = deque()          # (monotonic, sim t) of published instants
        self._pending = False                   # a redrawn line without its newline
        self._broken = False
        self._stop = threading.Event()
        self._write_lock = threading.Lock()
        self._thread: Optional[threading.Thread] = None

    # ------------------------------------------------------------------ content
    def _sample(self) -> None:
        st = self.node.last_state
        if st is None:
            return
        mono, t = st[0], st[1]
        if not self._samples or mono > self._samples[-1][0]:
            self._samples.append((mono, t))
        horizon = time.monotonic() - self.window - self.period
        while len(self._samples) > 2 and self._samples[1][0] < horizon:
            self._samples.popleft()

    def real_time_factor(self, now: Optional[float] = None) -> Optional[float]:
        """Simulation time / wall time over the sampled window (None before two samples).
        When nothing new has been published for over a second, the window extends to now (a
        stalled simulation heads to 0 instead of showing its last pace)."""
        if len(self._samples) < 2:
            return None
        (m0, t0), (m1, t1) = self._samples[0], self._samples[-1]
        now = time.monotonic() if now is None else now
        if now - m1 > 1.0:
            m1 = now
        if m1 - m0 < 0.2:
            return None
        return (t1 - t0) / (m1 - m0)

    def line(self) -> str:
        node = self.node
        st = node.last_state
        parts = ["hawt"]
        if st is None:
            parts.append("t -- s (starting)")
        else:
            _, t, yaw, teeter, flap, lag = st
            parts += [f"t {_num(t, '.2f')} s",
                      f"rtf {_num(self.real_time_factor(), '.2f')}",
                      f"teeter {_num(math.degrees(teeter), '+.2f')} deg",
                      f"yaw {_num(math.degrees(_wrap_pi(yaw)), '+.2f')} deg",
                      f"tip flap {_num(flap * 1e3, '+.1f')} mm, lag {_num(lag * 1e3, '+.1f')} mm"]
        rec = node.recorder
        if rec is not None:
            parts.append(f"rec {Path(node.record_path).name} {rec.message_count} msgs")
        else:
            parts.append("rec off")
        waiting = node.analyses_waiting
        parts.append(f"analyses {node.analyses_served}" + (f" (+{waiting} running)"
                                                          if waiting else ""))
        if node._failed:
            parts.append("SIMULATION STOPPED")
        return " | ".join(parts)

    # ------------------------------------------------------------------ output
    def _write(self, text: str) -> None:
        if self._broken:
            return
        try:
            with self._write_lock:
                self.stream.write(text)
                self.stream.flush()
        except (OSError, ValueError):           # closed or broken stderr: stop quietly
            self._broken = True

    def show(self) -> None:
        """Write the status once (redraw in place on a terminal)."""
        text = self.line()
        if self.tty:
            width = shutil.get_terminal_size((120, 24)).columns - 1
            if width > 10 and len(text) > width:
                text = text[:width - 1] + "~"
            self._write("\r\x1b[K" + text)
            self._pending = True
        else:
            self._write(text + "\n")

    def end_line(self) -> None:
        """Terminate a redrawn line (before other output, at the end)."""
        if self._pending:
            self._pending = False
            self._write("\n")

    def _run(self) -> None:
        next_show = time.monotonic() + (self.period if not self.tty else 0.0)
        while not self._stop.wait(STATUS_TTY_PERIOD):
            try:
                self._sample()
                if not self.node.status_enabled:
                    self.end_line()
                    continue
                now = time.monotonic()
                if now >= next_show:
                    next_show = now + self.period - 0.05
                    self.show()
            except Exception:  # noqa: BLE001 - the status line never takes the node down
                pass

    def start(self) -> "StatusLine":
        self._thread = threading.Thread(target=self._run, name="hawt-status", daemon=True)
        self._thread.start()
        return self

    def close(self, timeout: float = 1.0) -> None:
        """Stop the thread; on a terminal keep the last line visible (final redraw + newline)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        if self._pending and self.node.status_enabled and not self._broken:
            try:
                self._sample()
                self.show()
            except Exception:  # noqa: BLE001
                pass
        self.end_line()


def _log_format_for_tty() -> None:
    """On a terminal, start every rcutils log line with 'carriage return, clear line' so a log
    message replaces the status line being redrawn instead of being appended to it (the next
    redraw then starts on a fresh line). Only when the user has not chosen a format."""
    if _stderr_is_tty() and "RCUTILS_CONSOLE_OUTPUT_FORMAT" not in os.environ:
        os.environ["RCUTILS_CONSOLE_OUTPUT_FORMAT"] = \
            "\r\x1b[K[{severity}] [{time}] [{name}]: {message}"


# ====================================================================== entry point
USAGE = """usage: hawt-node [-h] [--ros-args -p NAME:=VALUE ...]

ROS 2 node of hawt: simulates the turbine, publishes joint_states, blade_deflections,
blade_markers (and /clock when real_time_factor is 0), serves the modal_analysis service
and action. Parameters (see docs/ros.md):
"""


def _usage() -> str:
    lines = [USAGE]
    for name, (default, doc) in PARAMETERS.items():
        flag = "" if name in RUNTIME_CHANGEABLE else " [restart to change]"
        lines.append(f"  {name} (default {default!r}){flag}\n      {doc}")
    lines.append(f"  {STATUS_PARAM} (default: {_stderr_is_tty()!r} here)\n      {STATUS_DOC}; "
                 f"redrawn every {STATUS_TTY_PERIOD:g} s on a terminal, else a line every "
                 f"{STATUS_PLAIN_PERIOD:g} s")
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    args = list(sys.argv if argv is None else argv)
    # before anything calls into rcl/rcutils (remove_ros_args does): rcutils reads its log
    # format once, at its first use
    _log_format_for_tty()
    from rclpy.utilities import remove_ros_args

    rest = remove_ros_args(args)[1:]
    if any(a in ("-h", "--help") for a in rest):
        sys.stdout.write(_usage())
        return 0
    if rest:
        sys.stderr.write(f"hawt-node: unexpected arguments {rest}; parameters go after "
                         "--ros-args as -p name:=value\n" + _usage())
        return 2

    stop = threading.Event()
    received = []

    def on_signal(signum, _frame):
        received.append(signum)
        stop.set()

    # `kill -USR1 <pid>` prints every thread's Python stack to stderr (diagnosing a hang)
    import faulthandler
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    # Start the analysis forkserver before any DDS thread exists.
    AnalysisRunner.prepare_forkserver()
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    node = None
    executor = None
    status = None
    try:
        try:
            node = HawtNode()
        except StartupError as exc:
            sys.stderr.write(f"hawt-node: {exc}\n")
            return 2
        executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
        executor.add_node(node)

        def spin():
            try:
                executor.spin()
            except (ExternalShutdownException, KeyboardInterrupt):
                pass
            finally:
                stop.set()

        spinner = threading.Thread(target=spin, name="hawt-executor", daemon=True)
        spinner.start()
        status = StatusLine(node).start()
        while not stop.wait(0.5):
            pass
        status.close()
        if received:
            node.get_logger().info(f"signal {signal.Signals(received[0]).name}: shutting down")
    finally:
        if status is not None:
            status.close()
        if node is not None:
            node.shutdown()
        if executor is not None:
            executor.shutdown(timeout_sec=2.0)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for s, h in old.items():
            signal.signal(s, h)
    # Everything is finalized (recording closed by node.shutdown, writers closed below).
    # Leave without running the interpreter's teardown: middleware threads that are still
    # joinable while C++ static destructors run make libstdc++ call std::terminate (an abort,
    # status -6, seen under load); os._exit skips that race.
    from .mcap_io import close_all_writers
    close_all_writers()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())
