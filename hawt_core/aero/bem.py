"""Steady blade-element momentum theory of a rigid rotor in uniform axial wind.

The formulation and its solution are Ning's (A. Ning, "A simple solution method for the blade
element momentum equations with guaranteed convergence", Wind Energy 17, 2014): one residual
in the inflow angle phi per station,

    f(phi) = sin(phi) / (1 - a) - (Vx / Vy) cos(phi) (1 - k')            (Ning eq. 21)

where the axial induction a and k' = a' / (1 + a') follow from phi in closed form: Prandtl's
tip and hub losses F, ``k = sigma' c_n / (4 F sin^2 phi)``, ``a = k / (1 + k)`` up to
a = 0.4 and Buhl's high-induction correction beyond (the thrust coefficient of a fully
turbulent wake state continued from momentum theory's 4 a F (1 - a) with equal value and slope
at a = 0.4; M. L. Buhl, NREL/TP-500-36834, 2005), the propeller-brake branch for phi < 0.
f is continuous in phi on (0, pi/2], where a root exists for a turbine's operating stations, so
a bracketing solve always converges; here all stations and all operating points are solved at
once by vectorized bisection (54 halvings: phi to 1e-16 rad).

Conventions (the rotor frame of the definition reports): Vx = U cos(precone) the wind
component normal to the coned rotor plane, Vy = Omega r cos(precone) the blade section's
speed; the section pitch ``theta = twist + pitch`` positive towards feather (AeroDyn's BlTwist
and BlPitch), so the angle of attack is alpha = phi - theta.  Loads per unit blade length:
N' (normal to the rotor plane) and T' (in the plane, driving the rotor).  Integrated loads use
the trapezoid rule over the stations with zero loads at the hub and tip radii (as CCBlade).
"""
from __future__ import annotations

from dataclasses import dataclass
import numpy as np

from .polars import StationPolars

__all__ = ["BemRotor", "BemSolution", "axial_induction", "momentum_thrust",
           "induction_from_thrust", "prandtl_loss", "quasi_steady_inductions"]

#: Axial induction above which Buhl's correction replaces momentum theory (k = 2/3).
BUHL_INDUCTION = 0.4


def momentum_thrust(a, F=1.0):
    """Local thrust coefficient of an annulus with axial induction a and loss factor F:
    momentum theory 4 a F (1 - a) up to a = 0.4, Buhl's empirical parabola beyond (C1 at
    the switch; complex-step safe: the branch is chosen by the real part)."""
    a = np.asarray(a)
    F = np.asarray(F)
    buhl = 8.0 / 9.0 + (4.0 * F - 40.0 / 9.0) * a + (50.0 / 9.0 - 4.0 * F) * a * a
    return np.where(np.real(a) <= BUHL_INDUCTION, 4.0 * a * F * (1.0 - a), buhl)


def induction_from_thrust(ct, F=1.0):
    """The axial induction a whose momentum_thrust(a, F) is the local thrust coefficient
    ``ct``: a = (1 - sqrt(1 - ct/F)) / 2 up to ct = 0.96 F (a = 0.4), the root of Buhl's
    parabola beyond (complex-step safe)."""
    ct = np.asarray(ct)
    F = np.asarray(F)
    switch = 0.96 * F
    low = 0.5 * (1.0 - np.sqrt(1.0 - np.where(np.real(ct) <= np.real(switch), ct, 0.0) / F))
    qa = 50.0 / 9.0 - 4.0 * F
    qb = 4.0 * F - 40.0 / 9.0
    qc = 8.0 / 9.0 - ct
    disc = qb * qb - 4.0 * qa * qc
    disc = np.where(np.real(disc) > 0, disc, 0.0)
    high = (-qb + np.sqrt(disc)) / (2.0 * qa)
    return np.where(np.real(ct) <= np.real(switch), low, high)


def prandtl_loss(blades, r, tip_radius, hub_radius, sin_phi, tip=True, hub=True):
    """Prandtl's tip and hub loss factor F (product of the two) at radii ``r`` [m] for the
    inflow angle's |sin phi| ``sin_phi`` (rotor frame), complex-step safe (no clipping: for
    r inside (hub, tip) and sin phi > 0 the exponentials are in (0, 1))."""
    F = np.ones_like(sin_phi)
    if tip:
        F = F * (2 / np.pi) * np.arccos(np.exp(-0.5 * blades * (tip_radius - r) / (r * sin_phi)))
    if hub:
        F = F * (2 / np.pi) * np.arccos(np.exp(-0.5 * blades * (r - hub_radius)
                                               / (hub_radius * sin_phi)))
    return F


def quasi_steady_inductions(blades, thrust, drive, a, F, r, rho, wind_speed, rotor_speed,
                            cos_cone=1.0):
    """(a_qs, a'_qs): the inductions whose annulus momentum balances the blades' loads, from
    one blade's thrust (along the shaft) and driving force (along its motion) per unit blade
    length [N/m] at radius r [m] (``blades`` equal blades; the blade length along a coned
    axis is the annulus width over cos(precone)), the current axial induction ``a`` (in the
    swirl balance), the loss factor F, density ``rho``, the rotor-normal wind speed and the
    rotor speed [rad/s]:

        momentum_thrust(a_qs, F) rho U^2 / 2 2 pi r = B thrust / cos(precone)
        4 a'_qs (1 - a) F rho U Omega pi r^3 = B drive r / cos(precone)."""
    ann = 2 * np.pi * r * 0.5 * rho * wind_speed * wind_speed
    a_qs = induction_from_thrust(blades * thrust / cos_cone / ann, F)
    ap_qs = blades * drive / cos_cone / (4 * (1 - a) * F * rho * wind_speed * rotor_speed
                                         * np.pi * r * r)
    return a_qs, ap_qs


def axial_induction(k, F, phi_positive=True):
    """Axial induction a from ``k = sigma' c_n / (4 F sin^2 phi)`` (Ning 2014, eqs. 15-17):
    the a for which the blade element's thrust 4 F k (1 - a)^2 equals momentum_thrust(a, F).
    With ``phi_positive`` False (propeller brake): a = k / (k - 1) for k > 1, else 0."""
    k = np.asarray(k)
    F = np.asarray(F)
    with np.errstate(divide="ignore", invalid="ignore"):
        low = k / (1.0 + k)
        g1 = 2.0 * F * k - (10.0 / 9.0 - F)
        g2 = np.maximum(2.0 * F * k - F * (4.0 / 3.0 - F), 1e-300)
        g3 = 2.0 * F * k - (25.0 / 9.0 - 2.0 * F)
        buhl = np.where(np.abs(g3) < 1e-6, 1.0 - 1.0 / (2.0 * np.sqrt(g2)),
                        (g1 - np.sqrt(g2)) / np.where(np.abs(g3) < 1e-6, 1.0, g3))
        brake = np.where(k > 1.0, k / (k - 1.0), 0.0)
    positive = np.where(k <= 2.0 / 3.0, low, buhl)
    return np.where(phi_positive, positive, brake)


@dataclass
class BemSolution:
    """Per operating point (leading axes) and station (last axis): inflow angle ``phi``
    [rad], angle of attack ``alpha`` [rad], inductions ``a``, ``ap``, loss factor ``F``,
    relative speed ``w`` [m/s], loads per unit length ``normal``, ``tangential`` [N/m];
    integrated ``thrust`` [N], ``torque`` [N m], ``power`` [W]; coefficients ``cp``, ``ct``,
    ``cq`` (rotor area and radius of the coned rotor); ``residual``: |f(phi)| at the
    solution (the convergence of each station)."""

    phi: np.ndarray
    alpha: np.ndarray
    a: np.ndarray
    ap: np.ndarray
    F: np.ndarray
    w: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    thrust: np.ndarray
    torque: np.ndarray
    power: np.ndarray
    cp: np.ndarray
    ct: np.ndarray
    cq: np.ndarray
    residual: np.ndarray


class BemRotor:
    """A rigid rotor for blade-element momentum theory.

    ``blades``: B; ``r`` [m]: station radii along the blade from the rotor axis, increasing,
    strictly between ``hub_radius`` and ``tip_radius`` [m]; ``chord`` [m]; ``twist`` [rad],
    positive towards feather; ``polars``: a StationPolars for these stations (or any object
    with ``coefficients(alpha) -> (cl, cd, cm)``); ``precone`` [rad]; ``tip_loss``,
    ``hub_loss``: Prandtl's factors; ``drag_in_induction``: use c_d in the induction
    equations (CCBlade's default; AeroDyn's AIDrag/TIDrag).
    """

    def __init__(self, blades: int, r, chord, twist, polars, hub_radius: float,
                 tip_radius: float, precone: float = 0.0, tip_loss: bool = True,
                 hub_loss: bool = True, drag_in_induction: bool = True):
        self.B = int(blades)
        self.r = np.asarray(r, float)
        self.chord = np.asarray(chord, float)
        self.twist = np.asarray(twist, float)
        self.polars = polars
        self.hub_radius = float(hub_radius)
        self.tip_radius = float(tip_radius)
        self.precone = float(precone)
        self.tip_loss, self.hub_loss = bool(tip_loss), bool(hub_loss)
        self.drag_in_induction = bool(drag_in_induction)
        if np.any(self.r <= self.hub_radius) or np.any(self.r >= self.tip_radius) \
                or np.any(np.diff(self.r) <= 0):
            raise ValueError("BemRotor: stations must increase strictly between the hub and "
                             "tip radii")
        self.sigma = self.B * self.chord / (2.0 * np.pi * self.r)     # local solidity
        self.swept_radius = self.tip_radius * np.cos(self.precone)

    @classmethod
    def from_turbine(cls, turbine, **options) -> "BemRotor":
        """The rotor of a Turbine with an ``aerodynamics`` description: its AeroDyn stations
        strictly inside the blade (the root and tip stations carry no load), twist in the
        feather-positive sign (minus hawt's), hub radius + blade length as tip radius."""
        aero = turbine.aerodynamics
        if aero is None:
            raise ValueError(f"turbine {turbine.name!r} has no aerodynamics section (airfoil "
                             "polars, chord, twist); import an OpenFAST deck or add one")
        L, rh = turbine.blade.length, turbine.hub.radius
        s = np.asarray(aero.stations, float)
        inner = (s > 1e-9) & (s < 1.0 - 1e-9)
        r = rh + s[inner] * L
        if rh <= 0:
            raise ValueError(f"turbine {turbine.name!r}: hub.radius = {rh!r}; the hub-loss "
                             "model needs a hub radius > 0")
        return cls(turbine.rotor.blades, r, np.asarray(aero.chord)[inner],
                   -np.asarray(aero.twist)[inner], StationPolars(aero, s[inner]),
                   rh, rh + L, precone=turbine.rotor.precone, **options)

    # ------------------------------------------------------------------ the residual
    def _state(self, phi, vx, vy, pitch):
        """Everything that follows from phi: (f(phi), a, ap, F, alpha, cn, ct) with the full
        drag (cn, ct) for the loads."""
        B, r = self.B, self.r
        sphi, cphi = np.sin(phi), np.cos(phi)
        alpha = phi - (self.twist + pitch)
        cl, cd, _ = self.polars.coefficients(alpha)
        cn = cl * cphi + cd * sphi
        ct = cl * sphi - cd * cphi
        cdi = cd if self.drag_in_induction else 0.0
        cn_i = cl * cphi + cdi * sphi
        ct_i = cl * sphi - cdi * cphi
        F = np.ones_like(phi)
        abs_s = np.maximum(np.abs(sphi), 1e-12)
        if self.tip_loss:
            f = 0.5 * B * (self.tip_radius - r) / (r * abs_s)
            F = F * (2.0 / np.pi) * np.arccos(np.clip(np.exp(-f), 0.0, 1.0))
        if self.hub_loss:
            f = 0.5 * B * (r - self.hub_radius) / (self.hub_radius * abs_s)
            F = F * (2.0 / np.pi) * np.arccos(np.clip(np.exp(-f), 0.0, 1.0))
        F = np.maximum(F, 1e-12)
        k = self.sigma * cn_i / (4.0 * F * sphi * sphi)
        kp = self.sigma * ct_i / (4.0 * F * sphi * cphi)
        a = axial_induction(k, F, phi > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ap = kp / (1.0 - kp)
            f = sphi / (1.0 - a) - vx / vy * cphi * (1.0 - kp)
        return f, a, ap, F, alpha, cn, ct

    def solve(self, wind_speed, rotor_speed, pitch=0.0, rho: float = 1.225,
              iterations: int = 54) -> BemSolution:
        """The steady BEM solution at the operating points given by broadcasting
        ``wind_speed`` [m/s] (> 0), ``rotor_speed`` [rad/s] (> 0) and ``pitch`` [rad,
        towards feather]; ``rho`` [kg/m^3].  Every station of every point is solved (the
        bracket with a sign change among (0, pi/2], (-pi/4, 0), (pi/2, pi) is searched,
        Ning's order)."""
        U, Om, th = np.broadcast_arrays(*(np.asarray(v, float) for v in
                                          (wind_speed, rotor_speed, pitch)))
        if np.any(~(U > 0)) or np.any(~(Om > 0)):
            raise ValueError("BEM: wind speed and rotor speed must be > 0")
        shape = U.shape + self.r.shape
        cpc = np.cos(self.precone)
        vx = np.broadcast_to((U * cpc)[..., None], shape)
        vy = np.broadcast_to(Om[..., None] * self.r * cpc, shape)
        pitch_ = np.broadcast_to(th[..., None], shape)
        eps = 1e-6
        brackets = ((eps, np.pi / 2), (-np.pi / 4, -eps), (np.pi / 2, np.pi - eps))
        lo = np.full(shape, np.nan)
        hi = np.full(shape, np.nan)
        for b0, b1 in brackets:
            f0 = self._state(np.full(shape, b0), vx, vy, pitch_)[0]
            f1 = self._state(np.full(shape, b1), vx, vy, pitch_)[0]
            take = np.isnan(lo) & (np.sign(f0) != np.sign(f1)) & np.isfinite(f0 * f1)
            lo = np.where(take, b0, lo)
            hi = np.where(take, b1, hi)
        found = ~np.isnan(lo)
        lo = np.where(found, lo, eps)
        hi = np.where(found, hi, np.pi / 2)
        f_lo = self._state(lo, vx, vy, pitch_)[0]
        for _ in range(int(iterations)):
            mid = 0.5 * (lo + hi)
            f_mid = self._state(mid, vx, vy, pitch_)[0]
            left = np.sign(f_mid) == np.sign(f_lo)
            lo = np.where(left, mid, lo)
            f_lo = np.where(left, f_mid, f_lo)
            hi = np.where(left, hi, mid)
        phi = 0.5 * (lo + hi)
        f, a, ap, F, alpha, cn, ct = self._state(phi, vx, vy, pitch_)
        w2 = (vx * (1.0 - a)) ** 2 + (vy * (1.0 + ap)) ** 2
        q = 0.5 * rho * w2 * self.chord
        normal, tangential = cn * q, ct * q
        residual = np.where(found, np.abs(f), np.inf)
        thrust = self._rotor_total(normal)
        torque = self._rotor_total(tangential, moment=True)
        power = torque * Om
        R = self.swept_radius
        qa = 0.5 * rho * U * U * np.pi * R * R
        return BemSolution(phi=phi, alpha=alpha, a=a, ap=ap, F=F, w=np.sqrt(w2),
                           normal=normal, tangential=tangential, thrust=thrust,
                           torque=torque, power=power, cp=power / (qa * U), ct=thrust / qa,
                           cq=torque / (qa * R), residual=residual)

    def frozen_wake_power(self, wind_speed, rotor_speed, pitch, a, ap, rho: float = 1.225):
        """Aerodynamic power [W] with the inductions ``a``, ``ap`` (stations on the last axis,
        e.g. a BemSolution's) held: the loads of the blade elements at the inflow angle they
        give, no momentum balance (the wake frozen: what the rotor feels in the seconds
        before its inflow adapts, the sensitivity a pitch controller is designed on)."""
        U, Om, th = (np.asarray(v, float)[..., None] for v in (wind_speed, rotor_speed, pitch))
        cpc = np.cos(self.precone)
        vx, vy = U * cpc * (1.0 - a), Om * self.r * cpc * (1.0 + ap)
        phi = np.arctan2(vx, vy)
        cl, cd, _ = self.polars.coefficients(phi - (self.twist + th))
        tangential = (cl * np.sin(phi) - cd * np.cos(phi)) * 0.5 * rho * (vx * vx + vy * vy) \
            * self.chord
        return self._rotor_total(tangential, moment=True) * Om[..., 0]

    def _rotor_total(self, load, moment: bool = False):
        """The rotor's total of a load per unit length [N/m] (stations on the last axis):
        B x its integral over the span (x cos precone), times the radius with ``moment``
        (a torque), with zero load at the hub and tip radii (trapezoid rule)."""
        rr = np.concatenate(([self.hub_radius], self.r, [self.tip_radius]))
        pad = [(0, 0)] * (np.ndim(load) - 1) + [(1, 1)]
        f = np.pad(load, pad) * np.cos(self.precone)
        return self.B * np.trapezoid(f * rr if moment else f, rr, axis=-1)

    def tip_speed_ratio(self, wind_speed, rotor_speed):
        """Omega R_tip / U (R_tip: the blade tip's distance along the blade from the axis, as
        OpenFAST's and ROSCO's tables use)."""
        return np.asarray(rotor_speed) * self.tip_radius / np.asarray(wind_speed)
