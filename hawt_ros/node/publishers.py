"""Publishing one simulation instant: joint states, blade deflections, blade markers, in wind
the rotor state, and /clock, each serialized once when recording (the same bytes are
published and recorded)."""
from __future__ import annotations

import math
import time

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Point, Vector3
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from hawt_msgs.msg import BladeDeflection, RotorState

from ..bag import serialize, type_name_of
from .config import BLADE_COLORS, JOINT_NAMES, wrap_pi

__all__ = ["StatePublisher", "time_msg"]


def time_msg(ns: int) -> TimeMsg:
    """builtin_interfaces/Time of integer nanoseconds."""
    return TimeMsg(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def _finite(*arrays) -> bool:
    for a in arrays:
        if not np.all(np.isfinite(np.asarray(a, dtype=float))):
            return False
    return True


class StatePublisher:
    """Part of :class:`~hawt_ros.node.turbine_node.HawtNode`: its publishers and what one
    published instant holds (never a non-finite value: the simulation is stopped instead)."""

    def _publishers_list(self):
        pubs = [self.pub_joints, self.pub_blades, self.pub_markers]
        if self.pub_rotor is not None:
            pubs.append(self.pub_rotor)
        if self.pub_clock is not None:
            pubs.append(self.pub_clock)
        return pubs

    def _emit(self, pub, msg, stamp_ns: int) -> None:
        """Publish ``msg``; when recording, serialize once, publish those bytes and record them."""
        rec = self.recorder
        if rec is None:
            pub.publish(msg)
            return
        type_name = type_name_of(msg)
        data = serialize(msg, type_name)
        pub.publish(data)
        try:
            rec.write_serialized(pub.topic_name, type_name, data, log_time=stamp_ns)
        except Exception as exc:  # noqa: BLE001 - recording problems never stop the node
            self._stop_recording(failure=str(exc))

    def _publish_clock(self, stamp_ns: int) -> None:
        if self.pub_clock is None or self._last_clock_t == stamp_ns:
            return
        self._last_clock_t = stamp_ns
        self._emit(self.pub_clock, Clock(clock=time_msg(stamp_ns)), stamp_ns)

    def _drive_joints(self, js, t, named, root_moments) -> None:
        """In wind: ``blade_<k>_pitch`` (pitch [rad, towards feather], its rate, the root
        moment about the pitch axis b1 [N m]) and ``generator`` (azimuth of the high-speed
        shaft [rad], its speed [rad/s], the generator torque [N m])."""
        loop = self.sim
        beta, rate = loop.inputs.pitch(t)
        for k in range(self.n_blades):
            js.name.append(f"blade_{k}_pitch")
            js.position.append(float(beta[k]))
            js.velocity.append(float(rate[k]))
            js.effort.append(float(root_moments[k, 0]))
        N = loop.gearbox
        angle = N * (loop.omega0 * t + float(named.get("generator_azimuth", 0.0)))
        js.name.append("generator")
        js.position.append(angle % (2 * math.pi))
        js.velocity.append(float(loop.speeds()[1]))
        js.effort.append(float(loop.inputs.generator_torque(t)))

    def _rotor_state_msg(self, header) -> RotorState:
        """In wind: the closed loop's rotor state (ClosedLoop.rotor_state) as a message."""
        r = self.sim.rotor_state()
        top = r["tower_top_displacement"]
        fa, ss = r["tower_top_acceleration"]
        msg = RotorState(
            header=header, wind_speed=float(r["wind_speed"]),
            wind_direction=float(r["wind_direction"]), rotor_speed=float(r["rotor_speed"]),
            generator_speed=float(r["generator_speed"]),
            generator_torque=float(r["generator_torque"]),
            mechanical_power=float(r["mechanical_power"]),
            electrical_power=float(r["electrical_power"]),
            pitch=[float(x) for x in r["pitch"]],
            root_out_of_plane_moment=[float(x) for x in r["root_out_of_plane_moment"]],
            pitch_override=bool(r["pitch_override"]),
            torque_override=bool(r["torque_override"]), controller=self.settings.controller,
            tower_top_displacement=Vector3(x=float(top[0]), y=float(top[1]), z=float(top[2])),
            tower_top_acceleration_fore_aft=float(fa),
            tower_top_acceleration_side_side=float(ss),
            aerodynamic_force=[Vector3(x=a, y=b, z=c) for a, b, c in
                               np.asarray(r["aerodynamic_force"], float).tolist()],
            aerodynamic_moment=[Vector3(x=a, y=b, z=c) for a, b, c in
                                np.asarray(r["aerodynamic_moment"], float).tolist()],
            aerodynamic_thrust=float(r["aerodynamic_thrust"]),
            aerodynamic_torque=float(r["aerodynamic_torque"]))
        values = [msg.wind_speed, msg.wind_direction, msg.rotor_speed, msg.generator_speed,
                  msg.generator_torque, msg.mechanical_power, msg.electrical_power, *msg.pitch,
                  *msg.root_out_of_plane_moment, *top, fa, ss, msg.aerodynamic_thrust,
                  msg.aerodynamic_torque]
        if not _finite(values, r["aerodynamic_force"], r["aerodynamic_moment"]):
            raise ValueError("non-finite rotor state")
        return msg

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
            line = np.array([d["positions"] for d in defl], float)
            disp = np.array([d["u"] for d in defl], float)
            rot = np.array([d["theta"] for d in defl], float)
            rf = np.array([d["root_force"] for d in defl], float)
            rm = np.array([d["root_moment"] for d in defl], float)
            frames = self.geometry.frames(named, t)
            loads = self.geometry.loads(named, t, rf, rm, frames)
            points = self.geometry.blade_points(named, t, line, disp,
                                                self.settings.marker_frame, frames)
        except Exception as exc:  # noqa: BLE001
            self._fail(f"reading the simulation state at t = {t:.6f} s failed: "
                       f"{type(exc).__name__}: {exc}")
            return False
        values = [t, azimuth, yaw, teeter, yaw_rate, teeter_rate, *loads]
        if not _finite(values, stations, disp, rot, rf, rm, points):
            self._fail(f"non-finite simulation state at t = {t:.6f} s (nothing published)")
            return False
        stamp = time_msg(stamp_ns)
        rotor = None
        if self.in_wind:
            try:
                rotor = self._rotor_state_msg(Header(stamp=stamp, frame_id="tower"))
            except Exception as exc:  # noqa: BLE001 - never publish NaN: stop instead
                self._fail(f"reading the rotor state at t = {t:.6f} s failed: "
                           f"{type(exc).__name__}: {exc} (nothing published)")
                return False

        js = JointState()
        js.header = Header(stamp=stamp, frame_id="")
        js.name = list(JOINT_NAMES)
        js.position = [wrap_pi(yaw), teeter, azimuth % (2 * math.pi)]
        # the rotor's actual speed where the simulation has a free one (ClosedLoop.named)
        js.velocity = [yaw_rate, teeter_rate, float(named.get("rotor_speed", self.omega))]
        js.effort = [float(x) for x in loads]
        if self.in_wind:
            self._drive_joints(js, t, named, rm)
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
        if rotor is not None:
            self._emit(self.pub_rotor, rotor, stamp_ns)

        self._last_stamp_ns = stamp_ns
        self._last_pub_t = t
        self.published += 1
        if self.in_wind:
            r = self.sim.last()
            self.last_rotor = (r["wind_speed"], r["rotor_speed_rpm"], r["generator_power_kw"],
                               r["pitch1_deg"])
        self.last_state = (time.monotonic(), t, yaw, teeter, float(disp[0, -1, 2]),
                           float(disp[0, -1, 1]))
        return True
