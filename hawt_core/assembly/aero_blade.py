"""One blade on the hub spinning in a uniform axial wind, with blade-element momentum loads at
its Gauss points: the first aeroelastic model of a rotor blade (the SpinningBlade of the
blade-modes analysis with aerodynamics), for its steady state.

At each Gauss point of the beam, in the deformed section frame B (the element's section frame,
which carries the pitch, turned by the elastic rotation: twist and bending slopes), the air
velocity relative to the section is

    W = U (1 - a) s3 - a' Omega r t - V

with s3 the shaft axis (the wind's direction, downwind), t = b2 the direction of the blade's
motion, r the distance from the shaft, V the section's velocity (its rotation and its
deformation rates) and a, a' the axial and tangential inductions, two algebraic unknowns per
Gauss point.  In B's chord plane (B2, B3): the inflow angle phi_B = atan2(W3, -W2), the angle
of attack alpha = phi_B + tau (tau the aerodynamic twist, hawt's sign: AeroDyn's -BlTwist;
the pitch is in B), q = rho (W2^2 + W3^2) / 2; lift along (W3, -W2)/|W|, drag along W, the
pitching moment c_m q c^2 about B1, all at the reference line (the aerodynamic centre's offset
is not modelled yet).  The inductions satisfy the momentum balance of their annulus with the
blade's own loads (thrust along s3, driving force along t, per unit annulus radius):

    B N_s3 / cos(precone) = momentum_thrust(a, F) (rho U^2 / 2) 2 pi r
    B T_t r / cos(precone) = 4 a' (1 - a) F rho U Omega pi r^3

with Prandtl's tip and hub loss F of the inflow angle in the rotor frame and Buhl's
high-induction thrust beyond a = 0.4: Ning's BEM equations, here solved together with the
beam (one residual, complex-step Jacobians).  For a rigid blade they are those of
aero/bem.py's BemRotor at the same stations.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..aero.bem import momentum_thrust, prandtl_loss, quasi_steady_inductions
from ..aero.inflow import oye_residuals, oye_steady, oye_time_constants
from ..aero.strip import BladeStrips, inflow_sine
from ..fem.discretization import pointwise_jacobian
from ..model import Turbine
from ..numerics.newton import newton
from ..fem.beam import BLOCK_SIZE, ROOT_F, ROOT_M, U_
from .spinning_blade import SpinningBlade

__all__ = ["AeroelasticBlade", "annulus_mean", "distance_from_shaft"]


def annulus_mean(beam, r, a) -> float:
    """The mean of ``a`` (N, G) over the rotor disk swept by ``beam``'s Gauss points at radii
    ``r`` (N, G, ...) [m]: weights r h w (annulus area per Gauss point), e.g. the rotor's mean
    axial induction for Oye's tau1."""
    w = r[..., 0] * beam.h[:, None] * beam.w[None, :]
    return float(np.sum(np.real(a) * w) / np.sum(w))


def distance_from_shaft(turbine: Turbine, x) -> np.ndarray:
    """Distance [m] from the shaft axis of the points at span ``x`` [m] of the undeformed
    blade (Turbine.distance_from_shaft)."""
    return turbine.distance_from_shaft(x)


class AeroelasticBlade:
    """Blade 0 of ``turbine`` (with its ``aerodynamics``) clamped on the hub spinning at
    ``rotor_speed`` [rad/s] (default the turbine's) in a uniform axial wind ``wind_speed``
    [m/s] of density ``rho``; ``elements`` per blade; ``tip_loss``, ``hub_loss``: Prandtl's.

    Unknowns: ``[beam (12 + 18 N) | a (N G) | a' (N G)]``; the structural unknowns and rows
    are SpinningBlade's, the induction rows the momentum balances above.
    """

    INFLOW = ("quasi-steady", "oye")

    def __init__(self, turbine: Turbine, wind_speed: float, elements: Optional[int] = None,
                 rotor_speed: Optional[float] = None, rho: float = 1.225,
                 tip_loss: bool = True, hub_loss: bool = True, inflow: str = "quasi-steady"):
        aero = turbine.aerodynamics
        if aero is None:
            raise ValueError(f"turbine {turbine.name!r} has no aerodynamics section")
        if not wind_speed > 0:
            raise ValueError(f"wind_speed: {wind_speed!r} is not allowed; need a number > 0")
        if inflow not in self.INFLOW:
            raise ValueError(f"inflow: {inflow!r} is not allowed; choose one of "
                             f"{', '.join(self.INFLOW)}")
        self.inflow = inflow
        self.blade = SpinningBlade(turbine, elements, rotor_speed)
        self.beam = self.blade.beam
        self.omega = self.blade.rotor_speed
        self.U = float(wind_speed)
        self.rho = float(rho)
        self.B = int(turbine.rotor.blades)
        self.tip_loss, self.hub_loss = bool(tip_loss), bool(hub_loss)
        L, e = turbine.blade.length, turbine.hub.radius
        beta = turbine.rotor.precone
        self.cos_cone = float(np.cos(beta))
        xg = self.beam.xg                                   # (N, G) span coordinate [m]
        # element section frames (pitch; a curved line's turn) in b: the unknowns are in
        # components of b turned by the elastic rotation, the airfoil lives in these frames
        self.strips = BladeStrips(aero, xg / L, self.beam.props.element_frames(), rho)
        self.r = distance_from_shaft(turbine, xg)[:, :, None]
        #: the root point relative to the shaft axis in the root frame b: e a1 (unconed)
        self.root_lever = e * np.array([np.cos(beta), 0.0, -np.sin(beta)])
        self.hub_r = float(distance_from_shaft(turbine, 0.0))
        self.tip_r = float(distance_from_shaft(turbine, L))
        # shaft axis and direction of motion in the root frame b (precone about b2)
        self.axes = np.array([[np.sin(beta), 0.0, np.cos(beta)], [0.0, 1.0, 0.0]])
        N, G = xg.shape
        self.n_beam = self.beam.n
        self.n_stations = N * G
        #: induction unknowns per Gauss point: (a, a') algebraic, or with Oye's dynamic
        #: inflow (a, a', z_a, z_t) differential (the filters' outputs and first stages)
        self.n_ind = 2 if inflow == "quasi-steady" else 4
        self.n = self.n_beam + self.n_ind * N * G
        self.differential = np.concatenate([self.beam.differential,
                                            np.full(self.n_ind * N * G, inflow == "oye")])
        self.rotor_radius = float(e + L)
        self.set_inflow_time_constant(0.3)
        self._pointwise = pointwise_jacobian(self.beam, self.n_ind)

    # ------------------------------------------------------------------ residual
    def set_inflow_time_constant(self, mean_induction: float) -> None:
        """Oye's tau1 (held constant, as AeroDyn's DBEMT_Mod 1) from the rotor's mean axial
        induction, and tau2 per Gauss point [s]."""
        tau1, tau2 = oye_time_constants(self.rotor_radius, self.U, mean_induction,
                                        self.r / self.cos_cone)
        self.tau1, self.tau2 = float(tau1), tau2

    def _split(self, y):
        B = y.shape[0]
        N, G = self.beam.xg.shape
        ind = y[:, self.n_beam:].reshape(B, self.n_ind, N, G).transpose(1, 2, 3, 0)
        return ind                                                   # (n_ind, N, G, B)

    def residual(self, yd, y, t=0.0, details: Optional[dict] = None, capture=None):
        """R (B, n) or (n,); ``details``: filled with the Gauss-point arrays (N, G, B) of the
        aerodynamics (alpha, phi, a, ap, loads) when given; ``capture``: the beam's
        (BeamElements.residual)."""
        one = np.ndim(y) == 1
        yd, y = np.atleast_2d(yd), np.atleast_2d(y)
        B = y.shape[0]
        ind = self._split(y)
        a, ap = ind[0], ind[1]
        rows = {}
        U, Om = self.U, self.omega

        strips = self.strips

        def loads(sec):
            s3 = strips.to_section(sec["wind"][..., 0, :])                    # (N, G, B, 3)
            tt = strips.to_section(sec["wind"][..., 1, :])
            V = strips.to_section(sec["V"])
            air = U * (1.0 - a)[..., None] * s3 - (ap * Om * self.r)[..., None] * tt
            W = air - V
            force, moment, aero = strips.loads(W)
            # thrust (along s3) and driving force (along t) per unit blade length
            thrust = np.sum(force * s3, axis=-1)
            drive = np.sum(force * tt, axis=-1)
            # the inflow angle in the rotor frame for Prandtl's factors
            sphi = inflow_sine(W, s3, tt)
            r = self.r
            F = prandtl_loss(self.B, r, self.tip_r, self.hub_r, sphi, self.tip_loss,
                             self.hub_loss)
            ann = 2 * np.pi * r * 0.5 * self.rho * U * U                # momentum scale
            if self.inflow == "quasi-steady":
                rows["a"] = (self.B * thrust / self.cos_cone - momentum_thrust(a, F) * ann) / ann
                rows["ap"] = (self.B * drive * r / self.cos_cone
                              - 4 * ap * (1 - a) * F * self.rho * U * Om * np.pi * r ** 3
                              ) / ann / r
            else:
                # the quasi-steady inductions of the blade's loads, filtered (Oye)
                a_qs, ap_qs = quasi_steady_inductions(self.B, thrust, drive, a, F, r,
                                                      self.rho, U, Om, self.cos_cone)
                rows["qs"] = (a_qs, ap_qs)
            if details is not None:
                details.update(a=a, ap=ap, F=F, thrust=thrust, drive=drive, **aero)
            return strips.from_section(force), strips.from_section(moment)

        v = np.broadcast_to(self.blade.v, (B, 3))
        wv = np.broadcast_to(self.blade.w, (B, 3))
        axes = np.broadcast_to(self.axes, (B, 2, 3))
        r_beam = self.beam.residual(yd[:, :self.n_beam], y[:, :self.n_beam], v, wv,
                                    wind=axes, section_loads=loads, capture=capture)
        flat = lambda x: x.transpose(2, 0, 1).reshape(B, -1)
        if self.inflow == "quasi-steady":
            extra = np.concatenate([flat(rows["a"]), flat(rows["ap"])], axis=1)
        else:
            rates = self._split(yd)
            # the filters of a and of a': rows of (a, a', z_a, z_t), the unknowns' order
            (za, Wa), (zt, Wt) = (oye_residuals(ind[2 + j], ind[j], rates[2 + j], rates[j], q,
                                                self.tau1, self.tau2)
                                  for j, q in enumerate(rows["qs"]))
            extra = np.concatenate([flat(r) for r in (Wa, Wt, za, zt)], axis=1)
        out = np.concatenate([r_beam, extra], axis=1)
        return out[0] if one else out

    def root_loads(self, y):
        """(shaft torque [N m], thrust [N]) of this blade through its root: the root force
        and moment about the shaft axis (the inertial loads of steady rotation have no
        moment about it and no component along it)."""
        F0, M0 = y[ROOT_F], y[ROOT_M]
        s3 = self.axes[0]
        torque = np.dot(M0 + np.cross(self.root_lever, F0), s3)
        return float(torque), float(np.dot(F0, s3))

    def inductions(self, y):
        """(a, a') (N, G): the axial and tangential inductions at the Gauss points of the
        state ``y``."""
        N, G = self.beam.xg.shape
        ind = y[self.n_beam:self.n_beam + 2 * N * G].reshape(2, N, G)
        return ind[0].copy(), ind[1].copy()

    def tip_deflection(self, y):
        """(flap along b3, edge along b2) [m] of the tip in the root frame."""
        u = y[self.n_beam - BLOCK_SIZE:self.n_beam][U_]          # the last node's u
        return float(u[2]), float(u[1])

    def jacobian(self, y):
        """dR/dy (n, n) at ydot = 0, sparse, exact by complex step: one batched residual
        evaluation of the Gauss-point integrands' steps (fem/beam_jacobian.py; the induction
        rows are pointwise too)."""
        return self._pointwise.matrix(lambda Yd, Y, cap: self.residual(Yd, Y, capture=cap),
                                      np.zeros(self.n), y)

    def dense_jacobian(self, y):
        """dR/dy (n, n) dense by complex step, every column (the reference of
        :meth:`jacobian`)."""
        n = self.n
        h = 1e-30
        Y = np.broadcast_to(y, (n, n)) + 1j * h * np.eye(n)
        return self.residual(np.zeros((n, n)), Y).imag.T / h

    def steady_state(self, a0=0.3, ap0=0.0, y0=None):
        """The aeroelastic steady state (n,): Newton from ``y0`` (e.g. a neighbouring
        operating point's state), else from the rigid spinning blade with uniform inductions
        (a0, ap0)."""
        z = np.zeros(self.n)
        inductions = [np.full(self.n_stations, a0), np.full(self.n_stations, ap0)]
        if self.inflow == "oye":
            inductions += [oye_steady(inductions[0])[0], oye_steady(inductions[1])[0]]
        # the tolerance's scale: the residual of the rigid, unloaded blade (a warm start's
        # small first residual would ask for less than the round-off of the root rows)
        cold = np.concatenate([self.beam.rigid_body_state(self.blade.v, self.blade.w),
                               *inductions])
        r_cold = np.abs(self.residual(z, cold))
        # per row: the beam's rows in newtons (their rigid-blade imbalance), the induction
        # rows dimensionless (1: inductions to the tolerance itself)
        scale = np.ones(self.n)
        scale[:self.n_beam] = max(1.0, np.max(r_cold[:self.n_beam]))
        if y0 is None:
            y0 = np.concatenate([self.blade.steady_state(), *inductions])
        y, _ = newton(lambda y: self.residual(z, y), self.jacobian, y0, scale=scale,
                      what="aeroelastic blade steady state", reuse_jacobian=True)
        if self.inflow == "oye":        # tau1 from this state's mean induction (area-weighted)
            a = y[self.n_beam:self.n_beam + self.n_stations].reshape(self.beam.xg.shape)
            self.set_inflow_time_constant(annulus_mean(self.beam, self.r, a))
        return y

