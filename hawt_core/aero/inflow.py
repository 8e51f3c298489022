"""Dynamic inflow: the induced velocity lags its quasi-steady (momentum) value, Oye's model.

Oye's filter of the quasi-steady induced velocity W_qs (Snel & Schepers, ECN-C--94-107, 1995;
M. O. L. Hansen, Aerodynamics of Wind Turbines, 3rd ed., section 10.1):

    W_int + tau1 dW_int/dt = W_qs + k tau1 dW_qs/dt,      W + tau2 dW/dt = W_int,

    tau1 = 1.1 R / ((1 - 1.3 min(a, 0.5)) U0),   tau2 = (0.39 - 0.26 (r / R)^2) tau1,   k = 0.6

(R the rotor radius, U0 the free wind speed, a the rotor's mean axial induction, r the
station's radius).  A step in W_qs makes W_int jump by k of the step at once and creep the
rest with tau1; W follows W_int with tau2.  In the residual the derivative of W_qs (an
algebraic function of the motion) must not appear, so the first filter is written for
z = W_int - k W_qs (tau1 held constant over the step):

    tau1 dz/dt + z = (1 - k) W_qs,     tau2 dW/dt + W = z + k W_qs.

z and W (per station and per induced-velocity component) are the differential unknowns.
Plain arithmetic: complex-step safe.

Skewed wake (yawed or tilted inflow): the wake convects with the wind's component in the
rotor plane, so the downwind half of the disk sits nearer the skewed vortex cylinder and sees
more induced velocity than the upwind half.  Pitt and Peters' correction (D. M. Pitt and
D. A. Peters, Vertica 5, 1981; Coleman's cylindrical-wake result; AeroDyn v15's
SkewRedistr_Mod = 1, with its default constant 15 pi / 32 "recommended by R. R. Damiani"):

    a_skew = a (1 + K (r / R) tan(chi / 2) cos psi),    chi = (1 + 0.6 a) chi0,

chi0 the angle between the wind and the shaft axis, psi the blade's azimuth from the most
downwind position (the blade along the in-plane wind), r / R the station's distance from the
shaft over the tip's.  tan(chi / 2) cos psi is written through sin(chi0) cos(psi) and
sin^2(chi0), both smooth in the wind and the rotor's attitude, so that axial flow (chi0 = 0,
psi undefined) is an ordinary point of the residual and of its complex-step Jacobian.
"""
from __future__ import annotations

import numpy as np

__all__ = ["OYE_K", "oye_time_constants", "oye_rates", "oye_residuals", "oye_steady",
           "skew_angles", "skewed_wake_factor"]

#: Oye's weight of the fast part of the response.
OYE_K = 0.6


def oye_time_constants(rotor_radius, wind_speed, mean_induction, r):
    """(tau1, tau2) [s] of Oye's model: tau1 for the rotor, tau2 per station radius r."""
    a = np.minimum(mean_induction, 0.5)
    tau1 = 1.1 * rotor_radius / ((1.0 - 1.3 * a) * wind_speed)
    tau2 = (0.39 - 0.26 * (np.asarray(r) / rotor_radius) ** 2) * tau1
    return tau1, tau2


def oye_rates(z, W, W_qs, tau1, tau2, k: float = OYE_K):
    """(dz/dt, dW/dt) of the two filter states given the quasi-steady value W_qs."""
    dz = ((1.0 - k) * W_qs - z) / tau1
    dW = (z + k * W_qs - W) / tau2
    return dz, dW


def oye_residuals(z, W, z_rate, W_rate, W_qs, tau1, tau2, k: float = OYE_K):
    """(row_z, row_W): the two filters as residual rows of a DAE (no division by the time
    constants), tau1 z' + z - (1 - k) W_qs and tau2 W' + W - z - k W_qs; zero when the rates
    are oye_rates'."""
    return (tau1 * z_rate + z - (1.0 - k) * W_qs,
            tau2 * W_rate + W - z - k * W_qs)


def oye_steady(W_qs, k: float = OYE_K):
    """The states (z, W) in steady flow: W = W_qs, z = (1 - k) W_qs."""
    W_qs = np.asarray(W_qs)
    return (1.0 - k) * W_qs, W_qs


def skew_angles(wind, s3):
    """(sin(chi0) cos(psi), sin^2(chi0)) of the wind ``wind`` (..., 3) seen by a blade whose
    root frame has the blade axis b1 = e1 and the shaft axis ``s3`` (..., 3) (unit; both in
    root components): chi0 the wind's angle from s3, psi the blade's azimuth from the in-plane
    wind's direction, measured in the rotor plane (b1's component normal to s3).  Both are
    polynomial-and-root expressions free of |w_inplane|: complex-step safe at axial flow."""
    normal = np.sum(wind * s3, axis=-1)
    inplane = wind - normal[..., None] * s3
    speed2 = np.sum(wind * wind, axis=-1)
    # b1's in-plane part b1 - (b1 . s3) s3 has length sqrt(1 - s3_1^2); its dot product
    # with the in-plane wind is the in-plane wind's first component
    along = inplane[..., 0] / np.sqrt((1.0 - s3[..., 0] ** 2) * speed2)
    return along, np.sum(inplane * inplane, axis=-1) / speed2


def skewed_wake_factor(sin_cos, sin2, a, radius_ratio, constant):
    """Pitt and Peters' 1 + K (r / R) tan(chi / 2) cos(psi), chi = (1 + 0.6 a) chi0, from
    skew_angles' ``sin_cos`` = sin(chi0) cos(psi) and ``sin2`` = sin^2(chi0), the axial
    induction ``a``, ``radius_ratio`` r / R and the constant K (broadcasting).  The ratio
    tan(c chi0 / 2) / sin(chi0) is even in chi0; below sin^2(chi0) = 1e-8 its series
    c / 2 + sin^2 (c / 12 + c^3 / 24) (error ~1e-16) replaces the 0 / 0."""
    c = 1.0 + 0.6 * a
    small = np.real(sin2) < 1e-8
    x2 = np.where(small, 0.25, sin2)
    x = np.sqrt(x2)
    exact = np.tan(0.5 * c * np.arcsin(x)) / x
    series = 0.5 * c + sin2 * (c / 12.0 + c ** 3 / 24.0)
    return 1.0 + constant * radius_ratio * np.where(small, series, exact) * sin_cos
