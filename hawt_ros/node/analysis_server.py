"""The modal_analysis service and action of the node: requests checked, analyses run in
worker processes (:mod:`hawt_ros.analysis_workers`), results as hawt_msgs."""
from __future__ import annotations

import threading
import time
from typing import List, Optional

from geometry_msgs.msg import Vector3
from rclpy.action import CancelResponse

from hawt_msgs.action import ModalAnalysis as ModalAnalysisAction
from hawt_msgs.msg import AnalysisSettings, Mode, ModeShape

from ..params import ParameterError, validate_request
from ..analysis_workers import Job
from .config import MAX_BLOCKED

__all__ = ["AnalysisServer"]


class AnalysisServer:
    """Part of :class:`~hawt_ros.node.turbine_node.HawtNode`: the service and action
    callbacks. At most MAX_BLOCKED callbacks wait for analyses at a time (the executor keeps
    free threads for the simulation timer and quick requests)."""

    def _resolve(self, rotor_speed, elements, steps, method):
        return validate_request(rotor_speed=rotor_speed, elements=int(elements),
                                steps=int(steps), method=method,
                                default_elements=self._analysis_elements)

    def _job_kwargs(self, req) -> dict:
        """The analysis of a request: in wind, the aeroelastic one at the operating point of
        the wind the node is in now (its speed and direction, the controller's schedule)."""
        kwargs = req.as_kwargs()
        if self.in_wind:
            # the hub speed now (a wind series or gust moves it away from Wind.speed)
            kwargs.update(wind_speed=float(self.sim.hub_wind(self.sim.t)),
                          wind_direction=float(self.sim.wind.direction),
                          discon=str(self._discon_path))
        return kwargs

    def _settings_msg(self, req=None, result=None) -> AnalysisSettings:
        s = AnalysisSettings()
        rs = (result or {}).get("settings", {}) if result else {}
        s.turbine = str(rs.get("turbine", self.turbine.name))
        s.rotor_speed = float(rs.get("rotor_speed", (req.rotor_speed if req and req.rotor_speed
                                                     else self.omega)))
        s.elements = int(rs.get("elements", (req.elements if req and req.elements
                                             else self._analysis_elements)))
        s.order = int(rs.get("order", self.turbine.blade.order))
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
        job = self.runner.submit(self._job_kwargs(req), shareable=True)
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
            job = self.runner.submit(self._job_kwargs(req), shareable=False)
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
