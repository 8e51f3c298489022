"""Unsteady attached-flow airfoil (hawt_core/aero/unsteady.py): the indicial states, and the
flutter of Theodorsen's typical section (a pitch-plunge airfoil on springs).

References, written in the test:
* Wagner's function in Jones's approximation phi(s) = 1 - 0.165 e^{-0.0455 s} - 0.335 e^{-0.3 s}
  (the step response, integrated here with DOP853) and Theodorsen's function
  C(k) = H1(k) / (H1(k) + i H0(k)) (Hankel functions of the second kind, scipy.special);
* the exact flutter point of the typical section: Theodorsen's frequency-domain equations
  solved by the V-g determinant iteration (Hodges & Pierce, Introduction to Structural Dynamics
  and Aeroelasticity, 2nd ed., section 5.3) for the section of their example: mu = 20,
  r^2 = 6/25, sigma = omega_h / omega_alpha = 2/5, x_alpha = 1/10, a = -1/5.
The test couples hawt's loads and state equations to the two springs and finds where the
linearized system (complex-step Jacobians of hawt's functions) first has an eigenvalue with a
positive real part.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import hankel2

from hawt_core.aero.unsteady import (JONES, QUASI_STEADY, downwash_34, thin_airfoil_loads)

# Hodges & Pierce's typical section (b = 1 m, rho = 1 kg/m^3, omega_alpha = 1 rad/s)
MU, R2, SIGMA, X_ALPHA, A = 20.0, 6.0 / 25.0, 0.4, 0.1, -0.2
B, RHO, W_ALPHA = 1.0, 1.0, 1.0
MASS = MU * np.pi * RHO * B ** 2
S_ALPHA = MASS * X_ALPHA * B
I_ALPHA = MASS * R2 * B ** 2
K_H = MASS * (SIGMA * W_ALPHA) ** 2
K_ALPHA = I_ALPHA * W_ALPHA ** 2


def theodorsen(k):
    k = np.asarray(k, float)
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return h1 / (h1 + 1j * h0)


def test_indicial_states_give_wagners_step_response():
    """A unit step of w34 from rest: w_eff(s) = phi(s) (DOP853, rtol 1e-10), and the states'
    frequency response is Jones's C(k) (1e-12), within 2.5 % of Theodorsen's exact C(k)
    for k in [0.01, 2] (the approximation's own accuracy)."""
    U, b = 3.0, 0.7

    def rhs(t, x):
        return JONES.rates(x, 1.0, U, b)

    s = np.linspace(0.0, 60.0, 61)
    sol = solve_ivp(rhs, (0.0, s[-1] * b / U), np.zeros(2), t_eval=s * b / U,
                    method="DOP853", rtol=1e-11, atol=1e-13)
    w = JONES.effective_downwash(sol.y.T, 1.0, U, b)
    assert np.allclose(w, JONES.indicial(s), rtol=1e-9, atol=1e-10)
    assert np.allclose(JONES.indicial(s), 1 - 0.165 * np.exp(-0.0455 * s)
                       - 0.335 * np.exp(-0.3 * s), rtol=1e-15)
    k = np.linspace(0.01, 2.0, 200)
    omega = k * U / b
    # harmonic response of the states: x = w34 / (i omega + b_i U / b)
    x = np.stack([1.0 / (1j * omega + bi * U / b) for bi in JONES.b], axis=-1)
    c_states = JONES.effective_downwash(x, 1.0, U, b)
    assert np.allclose(c_states, JONES.transfer(k), rtol=1e-12)
    assert np.max(np.abs(JONES.transfer(k) / theodorsen(k) - 1)) < 0.025


# ------------------------------------------------------------------ typical section
def section_residual(lag, U):
    """R(zdot, z) of the typical section with hawt's aerodynamics; z = (h, alpha, h', alpha',
    lag states)."""
    def R(zd, z):
        h, al, hd, ald = z[0], z[1], z[2], z[3]
        x = z[4:]
        w34 = downwash_34(U, al, hd, ald, B, A)
        w_eff = lag.effective_downwash(x, w34, U, B)
        lift, moment = thin_airfoil_loads(RHO, U, B, A, zd[2], ald, zd[3], w_eff)
        return np.concatenate([
            [zd[0] - hd, zd[1] - ald,
             MASS * zd[2] + S_ALPHA * zd[3] + K_H * h + lift,
             S_ALPHA * zd[2] + I_ALPHA * zd[3] + K_ALPHA * al - moment],
            zd[4:] - lag.rates(x, w34, U, B)])
    return R


def section_eigenvalues(lag, U):
    """Eigenvalues of the linearization of section_residual (complex-step Jacobians)."""
    n = 4 + lag.states
    R = section_residual(lag, U)
    z0 = np.zeros(n, complex)
    E = np.zeros((n, n))
    J = np.zeros((n, n))
    step = 1e-30
    for j in range(n):
        e = np.zeros(n, complex)
        e[j] = 1j * step
        E[:, j] = R(e, z0).imag / step
        J[:, j] = R(z0, e).imag / step
    return sl.eigvals(-J, E)


def hawt_flutter(lag):
    """The lowest speed at which an eigenvalue's real part crosses zero, and its frequency."""
    def growth(U):
        return np.max(section_eigenvalues(lag, U).real)
    speeds = np.linspace(0.5, 4.0, 36)
    g = [growth(U) for U in speeds]
    i = next(i for i in range(len(g)) if g[i] > 0)
    U_f = brentq(growth, speeds[i - 1], speeds[i], xtol=1e-12)
    lam = section_eigenvalues(lag, U_f)
    return U_f, abs(lam[np.argmax(lam.real)].imag)


def exact_flutter(C):
    """Theodorsen's equations in the frequency domain, V-g method: for each reduced frequency
    k the eigenvalues X = (1 + i g) (omega_alpha / omega)^2 of the flutter determinant;
    flutter where the largest artificial damping g crosses zero."""
    Ms = np.array([[MASS, S_ALPHA], [S_ALPHA, I_ALPHA]])
    Ks = np.diag([K_H, K_ALPHA])

    def aero(k):
        # loads / omega^2 for h = hbar e^{i w t}, alpha = abar e^{i w t}, U = w b / k
        c = C(k)
        nc = np.pi * RHO * B ** 2
        # w34 / omega = (U/omega) alpha + i h + i b (1/2 - a) alpha, U / omega = b / k
        w_h = 1j
        w_a = B / k + 1j * B * (0.5 - A)
        circ = 2 * np.pi * RHO * (B / k) * B * c           # 2 pi rho U b C / omega
        lift = np.array([nc * (-1.0) + circ * w_h,
                         nc * (1j * B / k + B * A) + circ * w_a])
        moment = np.array([nc * (-B * A) + circ * B * (A + 0.5) * w_h,
                           nc * (-1j * B / k * B * (0.5 - A) + B ** 2 * (0.125 + A ** 2))
                           + circ * B * (A + 0.5) * w_a])
        # structure: (-Ms + Ks X) q = [-L, M] / omega^2
        return np.array([-lift, moment])

    def branches(k):
        X = sl.eigvals(Ms + aero(k), Ks)
        return X

    def g_max(k):
        X = branches(k)
        return np.max(X.imag / X.real)

    ks = np.linspace(2.0, 0.05, 400)
    g = [g_max(k) for k in ks]
    i = next(i for i in range(len(g)) if g[i] > 0)
    k_f = brentq(g_max, ks[i], ks[i - 1], xtol=1e-14)
    X = branches(k_f)
    x = X[np.argmax(X.imag / X.real)]
    omega = W_ALPHA / np.sqrt(x.real)
    return omega * B / k_f, omega


def test_quasi_steady_flutter_equals_the_frequency_domain_with_c_one():
    """C(k) = 1: hawt's time-domain system and the frequency-domain determinant are the same
    equations, so their flutter points agree to the root-finders' tolerance (1e-7)."""
    U_h, w_h = hawt_flutter(QUASI_STEADY)
    U_e, w_e = exact_flutter(lambda k: 1.0 + 0j)
    print(f"\nquasi-steady flutter: hawt U/(b w_a) {U_h:.6f}, omega/w_a {w_h:.6f}; "
          f"frequency domain {U_e:.6f}, {w_e:.6f}")
    assert U_h == pytest.approx(U_e, rel=1e-7) and w_h == pytest.approx(w_e, rel=1e-7)


def test_typical_section_flutter_against_theodorsen():
    """Jones's two states: hawt's flutter point equals the frequency-domain one with Jones's
    C(k) (the state-space realization is exact: 1e-7), and Theodorsen's exact solution
    (Hankel functions) within 1 % in speed and frequency (the approximation of C(k)).
    Hodges & Pierce (Fig. 5.7) read U_F / (b omega_alpha) of about 2.17."""
    U_h, w_h = hawt_flutter(JONES)
    U_j, w_j = exact_flutter(lambda k: complex(JONES.transfer(k)))
    U_t, w_t = exact_flutter(lambda k: complex(theodorsen(k)))
    print(f"\nflutter U/(b w_a), omega/w_a: hawt (Jones states) {U_h:.5f}, {w_h:.5f}; "
          f"V-g with Jones's C {U_j:.5f}, {w_j:.5f}; Theodorsen exact {U_t:.5f}, {w_t:.5f}")
    assert U_h == pytest.approx(U_j, rel=1e-7) and w_h == pytest.approx(w_j, rel=1e-7)
    assert U_h == pytest.approx(U_t, rel=0.01) and w_h == pytest.approx(w_t, rel=0.01)
    assert 2.0 < U_t < 2.35
