"""One blade clamped to a hub spinning at constant speed: the model of the blade-modes
analysis (the symmetric modes of the paper's Table 2).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..fem.discretization import beam_elements, pointwise_jacobian
from ..model import Turbine
from ..numerics.checks import check_elements, check_rotor_speed
from ..numerics.newton import newton
from ..rigid import RigidSystem

__all__ = ['SpinningBlade']


class SpinningBlade:
    """One blade clamped at radius ``hub_radius`` on a hub spinning at ``rotor_speed``.

    Unknowns and residual rows are those of BeamElements (one beam). The root motion (root
    frame b, constant) is the rigid system's (hawt_core.rigid) for blade 0 with the yaw locked
    and the hub rigid: ``v = e Omega0 b2``, ``omega = Omega0 (sin(beta) b1 + cos(beta) b3)``
    with the precone beta (the coned blade spins about the shaft, not about its own b3, which
    lowers its centrifugal stiffening); undersling and tilt do not change it.
    """

    def __init__(self, turbine: Turbine, elements: Optional[int] = None,
                 rotor_speed: Optional[float] = None):
        from dataclasses import replace
        self.turbine = turbine
        self.rotor_speed = check_rotor_speed(turbine.rotor.speed if rotor_speed is None
                                             else rotor_speed)
        n_el = check_elements(turbine.blade.elements if elements is None else elements)
        self.beam = beam_elements(turbine.blade, n_el, pitch=turbine.rotor.pitch)
        self.n = self.beam.n
        clamped = replace(turbine, rotor=replace(turbine.rotor, speed=self.rotor_speed),
                          hub=replace(turbine.hub, teeter=False, counterweight_mass=0.0),
                          nacelle=replace(turbine.nacelle, yaw_free=False), tower=None,
                          gravity=replace(turbine.gravity, enabled=False), drivetrain=None)
        v, w = RigidSystem(clamped).root_motion(np.zeros(0), np.zeros(0), 0.0)
        self.v, self.w = np.real(v[0]).astype(float), np.real(w[0]).astype(float)
        self._pointwise = pointwise_jacobian(self.beam)
        self.differential = self.beam.differential

    def residual(self, ydot, y, t=0.0):
        """Beam residual (n,) of the blade whose root moves with the hub's steady motion
        (root velocity v [m/s], angular velocity w [rad/s], root frame b); ``t`` unused (the
        motion is steady)."""
        return self.beam.residual(ydot[None], y[None], self.v[None], self.w[None])[0]

    def jacobians(self, ydot, y, t=0.0):
        """Exact (complex-step) dR/dy and dR/dydot, sparse (n, n), from steps of the
        Gauss-point integrands (fem/beam_jacobian.py)."""
        D = self._pointwise.directions
        V, W = np.broadcast_to(self.v, (D, 3)), np.broadcast_to(self.w, (D, 3))
        fun = lambda Yd, Y, cap: self.beam.residual(Yd, Y, V, W, capture=cap)  # noqa: E731
        return (self._pointwise.matrix(fun, ydot, y),
                self._pointwise.matrix(fun, ydot, y, rates=True))

    def steady_state(self) -> np.ndarray:
        """Steady deflected state (n,) of the spinning blade (Newton from the rigid-body
        state: V = v + w x r, Omega = w in the section frames)."""
        z = np.zeros(self.n)
        y, _ = newton(lambda y: self.residual(z, y), lambda y: self.jacobians(z, y)[0],
                      self.beam.rigid_body_state(self.v, self.w), what="blade steady state")
        return y
