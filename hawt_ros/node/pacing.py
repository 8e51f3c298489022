"""Pacing the simulation: steps to keep simulation time at real_time_factor x wall time
(stamps in wall-clock time), or as fast as possible (stamps in simulation time, /clock)."""
from __future__ import annotations

import math
import time

__all__ = ["Pacing"]


class Pacing:
    """Part of :class:`~hawt_ros.node.turbine_node.HawtNode`: the timer callback and the
    steps it takes."""

    def _check_step_rate(self) -> None:
        """Every publish is a new simulation instant: warn when the simulation cannot provide
        publish_rate of them (real_time_factor / step time)."""
        s = self.settings
        if s.real_time_factor > 0 and s.publish_rate > s.real_time_factor / self.dt * (1 + 1e-9):
            if not self._parameter_given("publish_rate"):
                # the default rate: not the user's request, only a fact
                self.get_logger().info(
                    f"publishing at {s.real_time_factor / self.dt:.3g} Hz, the rate of new "
                    f"simulation instants (real_time_factor / step; publish_rate "
                    f"{s.publish_rate:g} Hz at its default)")
                return
            self.get_logger().warning(
                f"publish_rate {s.publish_rate:g} Hz exceeds the rate of new simulation instants "
                f"real_time_factor / step = {s.real_time_factor / self.dt:.3g} Hz: publishing "
                "will be at most that (raise real_time_factor or lower step_deg)")

    def _timer_period(self) -> float:
        if self.settings.real_time_factor == 0:
            return 0.002                       # as fast as possible: short ticks
        return 1.0 / self.settings.publish_rate

    def _step(self) -> bool:
        try:
            if self.in_wind:
                self._apply_overrides()
            self.sim.step()
            if self.in_wind:
                self._report_clipping()
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
