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
"""
from __future__ import annotations

import numpy as np

__all__ = ["OYE_K", "oye_time_constants", "oye_rates", "oye_residuals", "oye_steady"]

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
