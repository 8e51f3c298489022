"""A cantilever wing in a uniform stream (hawt_core/assembly/wing.py): hawt's beam elements with
strip-theory unsteady aerodynamics at their Gauss points, on Goland's wing (span 6.096 m, chord
1.8288 m, elastic axis at 33 % chord, mass centre at 43 %, m = 35.71 kg/m, I_alpha = 8.64 kg m,
EI = 9.77e6 N m^2, GJ = 0.99e6 N m^2, air density 1.02 kg/m^3: the data of GXBeam's Goland
example).

References, written in the test:
* the torsional divergence speed of a uniform cantilever in strip theory (closed form):
  U_D = sqrt(pi^2 GJ / (2 rho L^2 c e a0)), e the aerodynamic centre's distance ahead of the
  elastic axis;
* an independent discretization of the same continuum problem: a Rayleigh-Ritz model
  (polynomial bending and torsion shapes, converged in the test) with Theodorsen's strip loads
  in the frequency domain, solved by the V-g determinant iteration, with Jones's C(k) (the
  same aerodynamics as hawt's states: the flutter points must agree to the discretization
  error) and with Theodorsen's exact C(k) (Hankel functions).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.optimize import brentq
from scipy.special import hankel2

from hawt_core.aero.unsteady import JONES
from hawt_core.assembly.wing import WingModel
from hawt_core.model import Beam, SectionTable

SPAN, CHORD = 6.096, 1.8288
MASS, I_EA = 35.71, 8.64
EI, GJ = 9.77e6, 0.99e6
RHO = 1.02
D_CG = (0.43 - 0.33) * CHORD           # mass centre aft of the elastic axis [m]
A_AXIS = 0.33 * 2 - 1                   # elastic axis aft of mid-chord [semi-chords]
B = CHORD / 2
FLUTTER_BAND = 200.0                    # rad/s: the bending-torsion modes that flutter


def goland(N, lag=JONES):
    sec = SectionTable.uniform(mass=MASS, i1=I_EA - MASS * D_CG ** 2, i2=1e-6, i3=1e-6,
                               gj=GJ, ei2=EI, ei3=1e3 * EI, cg_offset=[-D_CG, 0.0])
    return WingModel(Beam(SPAN, sec, N), CHORD, A_AXIS, rho=RHO, lag=lag)


def hawt_flutter(model):
    def growth(U):
        lam = model.eigenvalues(U)
        lam = lam[(np.abs(lam.imag) > 1e-3) & (np.abs(lam.imag) < FLUTTER_BAND)]
        return np.max(lam.real)
    U = brentq(growth, 120.0, 180.0, xtol=1e-6)
    lam = model.eigenvalues(U)
    lam = lam[(np.abs(lam.imag) > 1e-3) & (np.abs(lam.imag) < FLUTTER_BAND)]
    return U, abs(lam[np.argmax(lam.real)].imag)


def test_divergence_speed_closed_form():
    """The real eigenvalue that crosses zero (static torsional divergence) does so at
    U_D = sqrt(pi^2 GJ / (2 rho L^2 c e a0)) = 276.9 m/s: within 1e-3 at N = 32, converging at
    second order (N = 16, 32). A wrong moment arm or sign of the circulatory moment moves it
    (or removes it)."""
    e = B * (A_AXIS + 0.5)
    exact = np.sqrt(np.pi ** 2 * GJ / (2 * RHO * SPAN ** 2 * CHORD * e * 2 * np.pi))
    found = []
    for N in (16, 32):
        m = goland(N)

        def static(U):
            lam = m.eigenvalues(U)
            real = lam[np.abs(lam.imag) < 1e-9]
            return np.max(real.real)
        found.append(brentq(static, 0.8 * exact, 1.2 * exact, xtol=1e-8))
    err = np.abs(np.array(found) / exact - 1)
    print(f"\ndivergence: {found} vs {exact:.4f} m/s")
    assert err[-1] < 1e-3 and 1.7 < np.log2(err[0] / err[1]) < 2.3


# ------------------------------------------------------------------ Rayleigh-Ritz reference
def theodorsen(k):
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return h1 / (h1 + 1j * h0)


def ritz_flutter(C, n_bend=6, n_twist=6):
    """Flutter speed and frequency of the Ritz model (shapes (y/L)^2.. for the plunge h,
    (y/L)^1.. for the pitch alpha) with strip loads L, M of Theodorsen's theory, V-g method."""
    x, w = np.polynomial.legendre.leggauss(40)
    y = 0.5 * SPAN * (x + 1)
    w = 0.5 * SPAN * w
    s = y / SPAN
    ph = np.array([s ** (i + 2) for i in range(n_bend)])                 # h shapes
    ph2 = np.array([(i + 2) * (i + 1) * s ** i / SPAN ** 2 for i in range(n_bend)])
    ps = np.array([s ** (j + 1) for j in range(n_twist)])                # alpha shapes
    ps1 = np.array([(j + 1) * s ** j / SPAN for j in range(n_twist)])
    G = lambda f, g: (f * w) @ g.T
    Mhh, Mha, Maa = G(ph, ph), G(ph, ps), G(ps, ps)
    Ms = np.block([[MASS * Mhh, MASS * D_CG * Mha], [MASS * D_CG * Mha.T, I_EA * Maa]])
    Ks = np.block([[EI * G(ph2, ph2), np.zeros((n_bend, n_twist))],
                   [np.zeros((n_twist, n_bend)), GJ * G(ps1, ps1)]])
    a = A_AXIS

    def aero(k):
        c = C(k)
        nc = np.pi * RHO * B ** 2
        w_h, w_a = 1j, B / k + 1j * B * (0.5 - a)           # w34 / omega per unit h, alpha
        circ = 2 * np.pi * RHO * (B / k) * B * c
        l_h, l_a = nc * (-1.0) + circ * w_h, nc * (1j * B / k + B * a) + circ * w_a
        m_h = nc * (-B * a) + circ * B * (a + 0.5) * w_h
        m_a = nc * (-1j * B / k * B * (0.5 - a) + B ** 2 * (0.125 + a ** 2)) \
            + circ * B * (a + 0.5) * w_a
        # generalized loads / omega^2: -L on the h shapes, M on the alpha shapes
        return np.block([[-l_h * Mhh, -l_a * Mha], [m_h * Mha.T, m_a * Maa]])

    def g_max(k):
        X = sl.eigvals(Ms + aero(k), Ks)
        X = X[1 / np.sqrt(np.abs(X.real)) < FLUTTER_BAND]
        return np.max(X.imag / X.real)

    ks = np.linspace(1.5, 0.05, 300)
    g = [g_max(k) for k in ks]
    i = next(i for i in range(len(g)) if g[i] > 0)
    k_f = brentq(g_max, ks[i], ks[i - 1], xtol=1e-14)
    X = sl.eigvals(Ms + aero(k_f), Ks)
    X = X[1 / np.sqrt(np.abs(X.real)) < FLUTTER_BAND]
    x = X[np.argmax(X.imag / X.real)]
    omega = 1 / np.sqrt(x.real)
    return omega * B / k_f, omega


def test_goland_wing_flutter_against_a_ritz_solution():
    """Jones's C(k) in both: hawt's flutter point (N = 32) equals the converged Ritz model's
    (6 and 7 shapes per field agree to 1e-6) within 0.3 % in speed and frequency, and hawt
    converges (N = 16 to 32 changes the speed by < 0.1 %). The exact Theodorsen C(k) in the
    Ritz model moves the flutter speed by less than 1 % (the approximation's effect).
    Published strip/lifting-line values for this wing, with their own aerodynamic models:
    141 m/s, 69.8 rad/s (Palacios & Epureanu 2011), 140 m/s, 69.0 rad/s (GXBeam's example)."""
    r6 = ritz_flutter(lambda k: complex(JONES.transfer(k)), 6, 6)
    r7 = ritz_flutter(lambda k: complex(JONES.transfer(k)), 7, 7)
    assert abs(r6[0] / r7[0] - 1) < 1e-6 and abs(r6[1] / r7[1] - 1) < 1e-6
    exact = ritz_flutter(lambda k: complex(theodorsen(k)), 7, 7)
    h16 = hawt_flutter(goland(16))
    h32 = hawt_flutter(goland(32))
    print(f"\nGoland flutter U [m/s], omega [rad/s]: hawt N=16 {h16[0]:.3f} {h16[1]:.3f}, "
          f"N=32 {h32[0]:.3f} {h32[1]:.3f}; Ritz (Jones) {r7[0]:.3f} {r7[1]:.3f}; "
          f"Ritz (Theodorsen) {exact[0]:.3f} {exact[1]:.3f}")
    assert h32[0] == pytest.approx(r7[0], rel=3e-3) and h32[1] == pytest.approx(r7[1], rel=3e-3)
    assert abs(h16[0] / h32[0] - 1) < 1e-3
    assert abs(exact[0] / r7[0] - 1) < 0.01


def test_flutter_command_and_wing_file(tmp_path):
    """`hawt flutter goland --json`: the shipped Goland case gives the flutter point of the
    model above (the same equations: 1e-6) and the divergence speed of the closed form (1e-3);
    a bad wing file names the key; a turbine is refused with the reason (exit 2, one line)."""
    import json
    import subprocess
    import sys
    from pathlib import Path
    hawt = Path(sys.executable).parent / "hawt"
    out = subprocess.run([str(hawt), "flutter", "goland", "--speeds", "100:300:11", "--json",
                          "--plot", str(tmp_path / "f.png")], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    ref = hawt_flutter(goland(16))
    assert data["flutter_speed"] == pytest.approx(ref[0], rel=1e-5)
    assert data["flutter_frequency_rad_s"] == pytest.approx(ref[1], rel=1e-5)
    e = B * (A_AXIS + 0.5)
    U_D = np.sqrt(np.pi ** 2 * GJ / (2 * RHO * SPAN ** 2 * CHORD * e * 2 * np.pi))
    assert data["divergence_speed"] == pytest.approx(U_D, rel=1e-3)
    assert (tmp_path / "f.png").stat().st_size > 0
    text = (Path(__file__).resolve().parents[1] / "hawt_core" / "data"
            / "goland_wing.yaml").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("elastic_axis: 0.33", "elastic_axis: 1.5"))
    for argv, words in (([str(bad)], ["wing.elastic_axis", "1.5"]),
                        (["nrel5mw"], ["not a wing file"]),
                        (["goland", "--speeds", "200:100:3"], ["--speeds"])):
        r = subprocess.run([str(hawt), "flutter", *argv], capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        for w in words:
            assert w in r.stderr, r.stderr
