"""Inputs of the node in wind: the wind itself, and an external controller's pitch and
generator-torque commands, which replace the node's controller until they fall silent.

``wind`` (geometry_msgs/Vector3): the wind velocity at hub height [m/s] in the frame
``tower`` (x up along the yaw axis, y lateral, z downwind at zero direction): speed
``hypot(y, z)``, direction ``atan2(-y, z)`` about the yaw axis (aero.wind.Wind's); it holds
until the next message; a vertical component is warned about and ignored (the wind model is
horizontal); out-of-range winds (speed 0.1..100 m/s, from upwind) are rejected (logged).

Topics (subscribed only with ``wind`` > 0): ``pitch_command`` (std_msgs/Float64MultiArray: one
angle for all blades or one per blade [rad, towards feather]) and ``torque_command``
(std_msgs/Float64: generator torque [N m, high-speed shaft]).  Each command holds until
``override_timeout`` seconds of the node's clock pass without a new one; then the node's
controller takes over again (logged), so a crashed external controller cannot leave the
turbine uncontrolled.  Commands outside the actuator limits (the DISCON.IN's pitch range and
rate, torque limit) are clipped by the closed loop and reported (throttled log), never
applied raw; a non-finite or wrongly sized command is rejected (logged) and changes nothing.
"""
from __future__ import annotations

import math
import threading

from geometry_msgs.msg import Vector3
from std_msgs.msg import Float64, Float64MultiArray

from .config import STATE_QOS

__all__ = ["Overrides"]

#: at most one clipping report per this many seconds
CLIP_REPORT_PERIOD = 2.0


class Overrides:
    """Part of :class:`~hawt_ros.node.turbine_node.HawtNode` (with a ClosedLoop as ``sim``)."""

    def _start_overrides(self, callback_group) -> None:
        self._override_lock = threading.Lock()
        self._override_last = {"pitch": None, "torque": None}   # node-clock ns of the last
        self._override_value = {"pitch": None, "torque": None}
        self._last_clip_report = -math.inf
        self.sub_pitch = self.create_subscription(
            Float64MultiArray, "pitch_command", self._on_pitch_command, STATE_QOS,
            callback_group=callback_group)
        self.sub_torque = self.create_subscription(
            Float64, "torque_command", self._on_torque_command, STATE_QOS,
            callback_group=callback_group)
        self._wind_pending = None
        self.sub_wind = self.create_subscription(Vector3, "wind", self._on_wind, STATE_QOS,
                                                 callback_group=callback_group)

    def _on_wind(self, msg) -> None:
        x, y, z = float(msg.x), float(msg.y), float(msg.z)
        speed, direction = math.hypot(y, z), math.atan2(-y, z) + 0.0   # no -0.0
        if not all(math.isfinite(v) for v in (x, y, z)) or not 0.1 <= speed <= 100.0 \
                or not abs(direction) < math.pi / 2:
            self.get_logger().warning(
                f"wind: ({x!r}, {y!r}, {z!r}) m/s rejected; need a finite horizontal wind of "
                "0.1 to 100 m/s from upwind (z > 0) in frame tower (x up, z downwind)")
            return
        if x != 0.0:
            self.get_logger().warning(f"wind: vertical component x = {x:g} m/s ignored (the "
                                      "wind model is horizontal)")
        with self._override_lock:
            self._wind_pending = (speed, direction)

    def _on_pitch_command(self, msg) -> None:
        values = list(msg.data)
        nb = self.n_blades
        if len(values) not in (1, nb) or not all(math.isfinite(v) for v in values):
            self.get_logger().warning(
                f"pitch_command: {values!r} rejected; need 1 or {nb} finite angles [rad]")
            return
        self._set_override("pitch", values[0] if len(values) == 1 else values)

    def _on_torque_command(self, msg) -> None:
        if not math.isfinite(msg.data):
            self.get_logger().warning(f"torque_command: {msg.data!r} rejected; need a finite "
                                      "torque [N m]")
            return
        self._set_override("torque", float(msg.data))

    def _set_override(self, which, value) -> None:
        now = self.get_clock().now().nanoseconds
        with self._override_lock:
            fresh = self._override_value[which] is None
            self._override_value[which] = value
            self._override_last[which] = now
        if fresh:
            self.get_logger().info(f"{which}_command: external {which} in control (released "
                                   f"after {self.settings.override_timeout:g} s of silence)")

    def _apply_overrides(self) -> None:
        """Before a controller step (under the node's lock): apply a new wind, hand the live
        overrides to the closed loop, release the silent ones (clipping is reported after
        the step, _report_clipping)."""
        now = self.get_clock().now().nanoseconds
        timeout_ns = self.settings.override_timeout * 1e9
        released = []
        with self._override_lock:
            wind, self._wind_pending = self._wind_pending, None
        if wind is not None:
            self.sim.set_wind(*wind)
            self.get_logger().info(f"wind: {wind[0]:.4g} m/s, direction "
                                   f"{math.degrees(wind[1]):+.3g} deg (from t = "
                                   f"{self.sim.t:.3f} s)")
        with self._override_lock:
            for which in ("pitch", "torque"):
                last = self._override_last[which]
                if last is None:
                    continue
                if now - last > timeout_ns:
                    self._override_last[which] = self._override_value[which] = None
                    released.append(which)
                    self.sim.clear_override(which)
                else:
                    self.sim.set_override(**{which: self._override_value[which]})
        for which in released:
            self.get_logger().info(f"{which}_command: silent for more than "
                                   f"{self.settings.override_timeout:g} s; the controller "
                                   f"({self.settings.controller}) has the {which} again")

    def _report_clipping(self) -> None:
        clipped = getattr(self.sim, "last_clipped", None)
        if not clipped or self._override_last["pitch"] is None and \
                self._override_last["torque"] is None:
            return
        now = self.get_clock().now().nanoseconds * 1e-9
        if now - self._last_clip_report >= CLIP_REPORT_PERIOD:
            self._last_clip_report = now
            lim = self.sim.limits
            self.get_logger().warning(
                f"command clipped ({', '.join(clipped)}) to the actuator limits: pitch "
                f"{lim.pitch_min:.4g}..{lim.pitch_max:.4g} rad at <= {lim.pitch_rate} rad/s, "
                f"torque 0..{lim.torque_max} N m (counts so far: {self.sim.clipped})")
