"""Unsteady airfoil aerodynamics in attached flow: Theodorsen's thin-airfoil loads with the
circulatory lag (Wagner's indicial function) as two differential states per section.

For a section of semi-chord b moving with speed U, plunging h (positive down) and pitching
alpha (nose up) about an axis a semi-chords aft of mid-chord, thin-airfoil theory gives
(Theodorsen 1935; Bisplinghoff, Ashley & Halfman 1955, ch. 5)

    L   = pi rho b^2 (h'' + U alpha' - b a alpha'') + 2 pi rho U b w_eff
    M_a = pi rho b^2 (b a h'' - U b (1/2 - a) alpha' - b^2 (1/8 + a^2) alpha'')
          + 2 pi rho U b^2 (a + 1/2) w_eff

(lift up, moment about the axis nose up): the first parts are the non-circulatory (added
mass) loads, w_eff the circulatory "effective" downwash.  In steady flow w_eff equals the
downwash at the three-quarter chord, w34 = U alpha + h' + b (1/2 - a) alpha'; in unsteady flow
it lags w34 as Wagner's function says.  R. T. Jones's approximation of Wagner's function,
phi(s) = 1 - A1 exp(-b1 s) - A2 exp(-b2 s) in semi-chords travelled s = U t / b, makes it two
first-order states per section,

    x_i' = -(b_i U / b) x_i + w34,       w_eff = (1 - A1 - A2) w34 + (U / b)(A1 b1 x1 + A2 b2 x2),

whose frequency response is Jones's approximation of Theodorsen's function,
C(k) ~ 1 - A1 i k / (i k + b1) - A2 i k / (i k + b2) (reduced frequency k = omega b / U).
All functions are plain arithmetic on NumPy arrays (any shape: one value per section), so
they accept complex arguments: the complex-step derivative is exact.  ``quasi_steady``
(A1 = A2 = 0) is the limit C(k) = 1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["IndicialLag", "JONES", "QUASI_STEADY", "added_mass_loads", "downwash_34",
           "thin_airfoil_loads"]


@dataclass(frozen=True)
class IndicialLag:
    """The circulatory lag phi(s) = 1 - sum A_i exp(-b_i s) as len(A) states per section."""

    A: tuple = (0.165, 0.335)
    b: tuple = (0.0455, 0.3)
    name: str = "Jones (1938) approximation of Wagner's function"

    @property
    def states(self) -> int:
        return len(self.A)

    def rates(self, x, w34, speed, semichord):
        """x' (..., states) from the states x (..., states), the three-quarter-chord
        downwash w34 [m/s] (...), the speed U [m/s] and the semi-chord b [m]."""
        rate = np.asarray(speed) / np.asarray(semichord)
        out = [-(bi * rate) * x[..., i] + w34 for i, bi in enumerate(self.b)]
        return np.stack(out, axis=-1) if out else np.zeros(np.shape(x))

    def effective_downwash(self, x, w34, speed, semichord):
        """w_eff [m/s]: the downwash the circulatory lift responds to."""
        rate = np.asarray(speed) / np.asarray(semichord)
        w = (1.0 - sum(self.A)) * w34
        for i, (ai, bi) in enumerate(zip(self.A, self.b)):
            w = w + rate * ai * bi * x[..., i]
        return w

    def transfer(self, k):
        """The approximation of Theodorsen's C(k) at reduced frequencies k (complex)."""
        k = np.asarray(k, dtype=complex)
        c = np.ones_like(k)
        for ai, bi in zip(self.A, self.b):
            c = c - ai * 1j * k / (1j * k + bi)
        return c

    def indicial(self, s):
        """phi(s), the lift's response to a unit step of w34 after s semi-chords."""
        s = np.asarray(s, float)
        return 1.0 - sum(ai * np.exp(-bi * s) for ai, bi in zip(self.A, self.b))


#: Jones's two-state approximation of Wagner's function (R. T. Jones, NACA Report 681, 1940).
JONES = IndicialLag()
#: No lag: C(k) = 1 (quasi-steady circulatory lift; the added-mass loads remain).
QUASI_STEADY = IndicialLag(A=(), b=(), name="quasi-steady (C = 1)")


def downwash_34(speed, alpha, h_rate, alpha_rate, semichord, a):
    """Downwash at the three-quarter chord [m/s]: U alpha + h' + b (1/2 - a) alpha'."""
    return speed * alpha + h_rate + semichord * (0.5 - a) * alpha_rate


def added_mass_loads(rho, speed, semichord, a, normal_rate, alpha_rate, alpha_acc):
    """Theodorsen's non-circulatory lift [N/m] (up) and moment about the axis at ``a``
    [N m/m] (nose up) per unit span, written with ``normal_rate`` = h'' + U alpha' [m/s^2]:
    the rate of change of the air's velocity normal to the chord (upwards) relative to the
    section as the section sees it, which is what a rotating blade's section frame gives
    (on a straight wing the two terms are apart):

        L_nc = pi rho b^2 (h'' + U alpha' - b a alpha'')
        M_nc = pi rho b^2 (b a (h'' + U alpha') - U b alpha' / 2 - b^2 (1/8 + a^2) alpha'')

    (the moment's U alpha' terms, -U b (1/2 - a) alpha' in Theodorsen's form, regrouped)."""
    b = semichord
    nc = np.pi * rho * b * b
    lift = nc * (normal_rate - b * a * alpha_acc)
    moment = nc * (b * a * normal_rate - 0.5 * speed * b * alpha_rate
                   - b * b * (0.125 + a * a) * alpha_acc)
    return lift, moment


def thin_airfoil_loads(rho, speed, semichord, a, h_acc, alpha_rate, alpha_acc, w_eff,
                       lift_slope=2.0 * np.pi):
    """Lift [N/m] (up) and moment about the axis at ``a`` [N m/m] (nose up) per unit span
    from Theodorsen's thin-airfoil theory with the circulatory part driven by ``w_eff``;
    ``lift_slope`` [1/rad] replaces thin-airfoil theory's 2 pi in the circulatory part."""
    b = semichord
    # Theodorsen's form as published (added_mass_loads regroups it for rotating sections;
    # the wing path keeps this one, so the two check each other: tests/test_rotor_aero_states)
    nc = np.pi * rho * b * b
    circulatory = lift_slope * rho * speed * b * w_eff
    lift = nc * (h_acc + speed * alpha_rate - b * a * alpha_acc) + circulatory
    moment = nc * (b * a * h_acc - speed * b * (0.5 - a) * alpha_rate
                   - b * b * (0.125 + a * a) * alpha_acc) + b * (a + 0.5) * circulatory
    return lift, moment
