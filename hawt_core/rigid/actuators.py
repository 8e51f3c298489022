"""The turbine's actuators as known functions of time: blade pitch bearings and the generator.

A controller (hawt_core.control) commands them once per controller step; between two calls
each command is ramped linearly from its value at the call to the commanded value one step
later (a first-order hold with one step of delay: the pitch stays continuous and its rate
finite, so every simulation step sees smooth inputs, and the residual stays a smooth function
of the unknowns: the inputs depend on time only).

Signs and units: blade pitch ``beta_k`` [rad] as ElastoDyn's BlPitch and ROSCO's, positive
towards feather (the leading edge turning into the wind), i.e. MINUS hawt's structural
``Rotor.pitch``; generator torque [N m] on the high-speed shaft, positive against the
generator's rotation (ROSCO's ``avrSWAP(47)``).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["ControlInputs"]


class _Ramp:
    """A value (array) ramped linearly from ``start`` at ``t0`` to ``end`` at ``t1``, held
    before and after."""

    def __init__(self, value):
        v = np.array(value, float)
        self.t0, self.t1, self.start, self.end = 0.0, 0.0, v, v.copy()

    def value(self, t):
        """(t.shape + value.shape) values and rates at times ``t`` (any shape)."""
        t = np.asarray(t, float)
        if self.t1 <= self.t0:
            v = np.broadcast_to(self.end, t.shape + self.end.shape)
            return v, np.zeros_like(v)
        f = np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)[(...,) + (None,) *
                                                                  self.end.ndim]
        inside = ((t > self.t0) & (t < self.t1))[(...,) + (None,) * self.end.ndim]
        rate = (self.end - self.start) / (self.t1 - self.t0)
        return self.start + f * (self.end - self.start), np.where(inside, rate, 0.0) + 0 * f

    def command(self, t0, t1, target):
        now = self.value(t0)[0].copy()
        self.t0, self.t1, self.start, self.end = float(t0), float(t1), now, \
            np.array(target, float).reshape(self.end.shape)


class ControlInputs:
    """Pitch of each blade and generator torque, known functions of time.

    ``n_blades``; ``pitch`` [rad, towards feather] of every blade (a number or one per blade);
    ``torque`` [N m, high-speed shaft].  :meth:`command` starts a ramp; :meth:`pitch` and
    :meth:`generator_torque` evaluate at any array of times (the time-parallel simulation asks
    for many instants at once)."""

    def __init__(self, n_blades: int, pitch=0.0, torque: float = 0.0):
        self.n_blades = int(n_blades)
        #: counts the commands (the rigid system's kinematics cache keys on it)
        self.version = 0
        #: False once driving a turbine whose generator is held at the rotor speed (no
        #: torque can act: RigidSystem.set_controls)
        self.torque_allowed = True
        self._pitch = _Ramp(self._check_pitch(pitch))
        self._torque = _Ramp(self._check_torque(torque))

    def _check_pitch(self, pitch) -> np.ndarray:
        p = np.broadcast_to(np.asarray(pitch, float), (self.n_blades,)) \
            if np.ndim(pitch) == 0 else np.asarray(pitch, float)
        if p.shape != (self.n_blades,) or not np.all(np.isfinite(p)):
            raise ValueError(f"pitch: {np.asarray(pitch).tolist()!r} is not allowed; need one "
                             f"finite angle [rad] or {self.n_blades} (one per blade)")
        if np.any(np.abs(p) > math.pi / 2):
            raise ValueError(f"pitch: {p.tolist()!r} is not allowed; need angles within "
                             "+-pi/2 rad")
        return p.copy()

    @staticmethod
    def _check_torque(torque) -> float:
        if not np.isfinite(torque):
            raise ValueError(f"torque: {torque!r} is not allowed; need a finite number [N m]")
        return float(torque)

    def hold_torque(self, torque: float) -> None:
        """Hold the generator torque at ``torque`` [N m, HSS] from now on (a trim's update)."""
        self._torque = _Ramp(self._check_torque(torque))
        self.version += 1

    def command(self, t0: float, t1: float, pitch=None, torque=None) -> None:
        """Ramp from the values at ``t0`` to ``pitch`` (one or one per blade) and ``torque``
        at ``t1`` > ``t0`` [s] (None: hold)."""
        if not t1 > t0:
            raise ValueError(f"command: t1 = {t1!r} must be after t0 = {t0!r} [s]")
        self.version += 1
        if pitch is not None:
            self._pitch.command(t0, t1, self._check_pitch(pitch))
        if torque is not None:
            if not self.torque_allowed and torque != 0:
                raise ValueError(f"torque: {torque!r} is not allowed; this turbine's generator "
                                 "is held at the rotor speed (drivetrain.generator: "
                                 "prescribed), so only 0 is")
            self._torque.command(t0, t1, self._check_torque(torque))

    def pitch(self, t):
        """(beta, beta_dot): pitch [rad] and pitch rate [rad/s] of each blade, (t.shape + (Nb,))."""
        return self._pitch.value(t)

    def generator_torque(self, t):
        """Generator torque [N m] (high-speed shaft) at times t (t.shape)."""
        return self._torque.value(t)[0]
