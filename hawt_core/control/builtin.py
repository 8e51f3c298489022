"""hawt's built-in controller for turbines without a DISCON file: the variable-speed,
pitch-to-feather baseline of Jonkman et al. (NREL/TP-500-38060, 2009, section 7).

* Generator speed low-pass filtered (first order, ``corner`` rad/s).
* Torque: region 2, ``k_opt w^2`` (the optimal tip-speed ratio's torque law, on the filtered
  generator speed); region 3 (pitch more than 1 deg above fine pitch, or speed at rated),
  constant power ``P_rated / (efficiency w)``.
* Pitch: a PI controller on the generator-speed error, gain-scheduled by
  ``GK = 1 / (1 + theta / theta_k)`` (the pitch sensitivity dP/dtheta grows linearly with
  pitch), its integral clamped so that the pitch stays between fine and largest pitch (no
  wind-up).

The gains come from the turbine's own aerodynamics (analyses/controller_design.py): the
controller here only runs them.  Units: rad, rad/s (generator: high-speed shaft), N m, W.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .discon import Demands, Measurements

__all__ = ["BuiltinGains", "BuiltinController"]


@dataclass(frozen=True)
class BuiltinGains:
    """``k_opt`` [N m s^2/rad^2, HSS]; ``rated_speed`` [rad/s, HSS]; ``rated_power`` [W,
    electrical]; ``efficiency`` [-]; ``kp`` [s] and ``ki`` [-] of the pitch PI (rad of pitch
    per rad/s of generator-speed error, at zero pitch); ``theta_k`` [rad] (the pitch where
    the gains halve); ``fine_pitch``, ``max_pitch`` [rad]; ``max_torque`` [N m];
    ``corner`` [rad/s] of the speed filter."""

    k_opt: float
    rated_speed: float
    rated_power: float
    efficiency: float
    kp: float
    ki: float
    theta_k: float
    fine_pitch: float
    max_pitch: float
    max_torque: float
    corner: float = 1.570796

    def to_dict(self) -> dict:
        return asdict(self)


class BuiltinController:
    """Runs :class:`BuiltinGains`, one call per controller step ``dt`` [s] (the
    DisconController's interface: ``step(Measurements) -> Demands``, ``close()``)."""

    def __init__(self, gains: BuiltinGains, dt: float, n_blades: int):
        for k, v in gains.to_dict().items():
            if not np.isfinite(v):
                raise ValueError(f"gains.{k}: {v!r} is not allowed; need a finite number")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt: {dt!r} is not allowed; need the controller step > 0 [s]")
        self.gains = gains
        self.dt = float(dt)
        self.n_blades = int(n_blades)
        self._speed = None
        self._integral = 0.0
        self.calls = 0

    def step(self, m: Measurements) -> Demands:
        g = self.gains
        w = float(m.generator_speed)
        pitch_now = float(np.mean(m.pitch))
        gk = 1.0 / (1.0 + max(pitch_now, 0.0) / g.theta_k)   # the gain schedule
        if self._speed is None:                      # the filter starts at the measurement
            self._speed = w
            # the integral that reproduces the starting pitch at zero speed error
            self._integral = (pitch_now - g.fine_pitch) / (gk * g.ki) if g.ki else 0.0
        a = math.exp(-g.corner * self.dt)
        self._speed = a * self._speed + (1.0 - a) * w
        ws = self._speed
        # pitch: gain-scheduled PI on the speed error, integral clamped to the pitch range
        err = ws - g.rated_speed
        self._integral += err * self.dt
        lo = 0.0
        hi = (g.max_pitch - g.fine_pitch) / (gk * g.ki) if g.ki else 0.0
        self._integral = min(max(self._integral, lo), hi)
        pitch = g.fine_pitch + gk * (g.kp * err + g.ki * self._integral)
        pitch = min(max(pitch, g.fine_pitch), g.max_pitch)
        # torque: optimal-tsr law below rated, constant power above
        if pitch > g.fine_pitch + math.radians(1.0) or ws >= g.rated_speed:
            torque = g.rated_power / (g.efficiency * max(ws, 1e-6))
        else:
            torque = g.k_opt * ws * ws
        torque = min(max(torque, 0.0), g.max_torque)
        self.calls += 1
        return Demands(pitch=np.full(self.n_blades, pitch), torque=torque)

    def close(self) -> None:
        """Nothing to release (the DISCON interface's final call)."""
