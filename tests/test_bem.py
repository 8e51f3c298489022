"""Blade-element momentum theory and airfoil polars (hawt_core/aero), and ``hawt aero-table``.

References (each test states its tolerance):
* Glauert's optimum rotor (closed form: a, a' and the power coefficient integral
  Cp = 8 / lambda^2 int a' (1 - a) x^3 dx, written in the test; Burton et al., Wind Energy
  Handbook, 2nd ed., section 3.7) and its limit Cp -> 16/27 at a = 1/3 (Betz);
* Buhl's thrust-induction relation (NREL/TP-500-36834, 2005, eq. 20), written in the test;
* the NREL 5-MW definition report (Jonkman et al., NREL/TP-500-38060, 2009, section 7.1:
  "the peak power coefficient of 0.482 occurred at a TSR of 7.55 and a rotor-collective
  blade-pitch angle of 0.0 deg");
* ROSCO's own Cp_Ct_Cq.NREL5MW.txt (CCBlade, shipped with the rosco wheel), read by a
  transliteration of rosco.toolbox.utilities.load_from_txt written here.
"""
from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from hawt_core.aero import BemRotor, HermiteTable, StationPolars, axial_induction
from hawt_core.aero.bem import induction_from_thrust
from hawt_core.analyses.aero_table import aero_table
from hawt_core.io.catalog import load_any, rosco_test_cases
from hawt_core.model import Aerodynamics, Polar

HAWT = Path(sys.executable).parent / "hawt"


def nrel5mw():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_any("nrel5mw")


def rosco_decks() -> Path:
    """The rosco wheel's Examples/Test_Cases (skips without the wheel)."""
    root = rosco_test_cases()
    if root is None:
        pytest.skip("the rosco wheel is not installed")
    return root


def load_from_txt(path):
    """rosco.toolbox.utilities.load_from_txt, transliterated (its module needs WISDEM)."""
    with open(path) as pfile:
        for line in pfile:
            if "Pitch angle" in line:
                pitch = np.array([float(x) for x in pfile.readline().strip().split()])
            if "TSR" in line:
                tsr = np.array([float(x) for x in pfile.readline().strip().split()])
            for word in ("Power", "Thrust", "Torque"):
                if word in line:
                    pfile.readline()
                    table = np.empty((len(tsr), len(pitch)))
                    for i in range(len(tsr)):
                        table[i] = np.array([float(x) for x in pfile.readline().strip().split()])
                    if word == "Power":
                        cp = table
                    elif word == "Thrust":
                        ct = table
                    else:
                        cq = table
    return np.radians(pitch), tsr, cp, ct, cq


# ------------------------------------------------------------------------------ polars
def test_hermite_polar_is_c1_exact_at_knots_and_complex_step_safe():
    """Reference: the table values at the knots (1e-15), PCHIP's no-overshoot property on
    monotone data, one-sided derivatives equal at every knot (C1, 1e-8), the complex-step
    derivative equal to central differences (1e-7)."""
    x = np.array([-0.4, -0.1, 0.0, 0.15, 0.3, 0.8])
    y = np.array([-0.9, -0.3, 0.1, 0.9, 1.2, 0.7])
    h = HermiteTable(x, [y, y ** 2])
    assert np.allclose(h(x)[0], y, atol=1e-15, rtol=0)
    q = np.linspace(-0.4, 0.3, 2001)                   # y increases monotonically here
    v = h(q)[0]
    assert np.all(np.diff(v) >= -1e-15) and v.min() >= y[0] - 1e-15 and v.max() <= y[4] + 1e-15
    step = 1e-30
    for knot in x[1:-1]:
        left = h(knot - 1e-9 + 1j * step)[0].imag / step
        right = h(knot + 1e-9 + 1j * step)[0].imag / step
        assert abs(left - right) < 1e-6 * max(1.0, abs(left))
    q = np.array([-0.33, 0.07, 0.21, 0.5, 1.0, -0.6])  # inside, and beyond both ends
    cs = h(q + 1j * step)[0].imag / step
    d = 1e-6
    cd = (h(q + d)[0] - h(q - d)[0]) / (2 * d)
    assert np.allclose(cs, cd, rtol=1e-7, atol=1e-7)


def test_spanwise_blending_between_airfoils():
    """At an AeroDyn station the coefficients are that station's airfoil's; halfway between
    two stations with different airfoils, the mean of the two (linear in span; exact)."""
    alpha = np.linspace(-1.0, 1.0, 11)
    p0 = Polar("a", alpha, 2 * np.pi * alpha, 0.01 + 0 * alpha, 0 * alpha)
    p1 = Polar("b", alpha, np.pi * alpha, 0.03 + 0 * alpha, -0.1 + 0 * alpha)
    aero = Aerodynamics(stations=np.array([0.0, 0.5, 1.0]), chord=np.ones(3),
                        twist=np.zeros(3), airfoil=np.array([0, 0, 1]), polars=(p0, p1))
    sp = StationPolars(aero, [0.25, 0.5, 0.75, 1.0])
    cl, cd, cm = sp.coefficients(np.full(4, 0.2))
    assert np.allclose(cl, [2 * np.pi * 0.2, 2 * np.pi * 0.2, 1.5 * np.pi * 0.2,
                            np.pi * 0.2], rtol=1e-14)
    assert np.allclose(cd, [0.01, 0.01, 0.02, 0.03], rtol=1e-14)
    assert np.allclose(cm, [0.0, 0.0, -0.05, -0.1], atol=1e-15)


def test_station_polars_evaluate_each_stations_own_airfoils():
    """Reference: each station's two airfoil tables (HermiteTable, tested above) evaluated
    one by one and blended linearly in span by the station's weight, written here.  The
    NREL 5-MW's AeroDyn airfoils (8 polars of different grids, cylinders to DU/NACA
    sections) at 200 stations, angles of attack inside the tables and beyond both ends,
    real and complex (the complex-step derivative too).  Tolerance 1e-13 of the value."""
    aero = nrel5mw().aerodynamics
    stations = np.linspace(0.0, 1.0, 200)
    sp = StationPolars(aero, stations)
    rng = np.random.default_rng(7)
    alpha = rng.uniform(-4.0, 4.0, (3, stations.size))       # rad: past +-pi too
    alpha[0, :5] = [-np.pi, np.pi, 0.0, -3.5, 3.5]
    assert len({np.size(p.alpha) for p in aero.polars}) > 1    # grids of different sizes
    for q in (alpha, alpha + 1e-30j):
        got = np.stack(sp.coefficients(q))
        want = np.empty_like(got)
        for k in range(stations.size):
            c0 = sp.curves[sp.first[k]].table(q[:, k])
            c1 = sp.curves[sp.second[k]].table(q[:, k])
            want[:, :, k] = (1 - sp.weight[k]) * c0 + sp.weight[k] * c1
        scale = np.maximum(1.0, np.abs(want.real))
        assert np.all(np.abs(got.real - want.real) <= 1e-13 * scale)
        assert np.all(np.abs(got.imag - want.imag) <= 1e-13 * np.maximum(1e-30, np.abs(
            want.imag)))


# ------------------------------------------------------------------------------ induction
def buhl_thrust(a, F):
    """Buhl (2005) eq. 20 and momentum theory, written here."""
    return np.where(a <= 0.4, 4 * a * F * (1 - a),
                    8 / 9 + (4 * F - 40 / 9) * a + (50 / 9 - 4 * F) * a ** 2)


def test_axial_induction_satisfies_momentum_with_buhl():
    """For every k and F, the induction a makes the blade element's thrust 4 F k (1 - a)^2
    equal the momentum (a <= 0.4) or Buhl (a > 0.4) thrust; a is continuous at the switch
    (k = 2/3, a = 0.4), and without the correction the classic relation a = k / (1 + k)
    holds. Tolerance 1e-12."""
    k = np.concatenate([np.linspace(0.01, 0.66, 40), np.linspace(0.67, 8.0, 60)])
    for F in (1.0, 0.8, 0.5, 0.2):
        a = axial_induction(k, F)
        assert np.allclose(4 * F * k * (1 - a) ** 2, buhl_thrust(a, F), rtol=1e-12, atol=1e-14)
        low = k <= 2 / 3
        assert np.allclose(a[low], k[low] / (1 + k[low]), rtol=1e-15)
        a_switch = axial_induction(np.array([2 / 3 - 1e-9, 2 / 3 + 1e-9]), F)
        assert abs(a_switch[1] - a_switch[0]) < 1e-6 and abs(a_switch[0] - 0.4) < 1e-8
        # the inverse: the induction of a local thrust coefficient, both branches
        ct = np.linspace(0.01, 0.96 * F + 0.8, 60)
        assert np.allclose(buhl_thrust(induction_from_thrust(ct, F), F), ct, rtol=1e-12,
                           atol=1e-14)


# ------------------------------------------------------------------------------ ideal rotor
def glauert(x):
    """Glauert's optimum rotor at local speed ratio x: (a, a'), from
    x^2 = (1 - a)(4a - 1)^2 / (1 - 3a), a' = (1 - 3a) / (4a - 1), a in (1/4, 1/3)."""
    lo, hi = np.full_like(x, 0.25 + 1e-12), np.full_like(x, 1 / 3 - 1e-15)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g = (1 - mid) * (4 * mid - 1) ** 2 / (1 - 3 * mid) - x * x
        lo, hi = np.where(g < 0, mid, lo), np.where(g < 0, hi, mid)
    a = 0.5 * (lo + hi)
    return a, (1 - 3 * a) / (4 * a - 1)


def ideal_rotor(tsr, stations=300, blades=3, alpha_design=0.1):
    """Glauert's optimum rotor for ``tsr`` (no tip loss, no drag): chord and twist from the
    optimum inductions, a flat-plate polar (cl = 2 pi alpha, exact in the interpolation)."""
    R, Rh = 50.0, 5.0
    u = 0.5 * (1 - np.cos(np.pi * (np.arange(stations) + 0.5) / stations))
    r = Rh + (R - Rh) * u                            # clustered at both ends
    x = tsr * r / R
    a, ap = glauert(x)
    phi = np.arctan((1 - a) / (x * (1 + ap)))
    cl = 2 * np.pi * alpha_design
    chord = 8 * np.pi * r * a * np.sin(phi) ** 2 / ((1 - a) * blades * cl * np.cos(phi))
    twist = phi - alpha_design                       # towards feather
    alpha = np.array([-0.5, 0.5])
    polar = Polar("flat", alpha, 2 * np.pi * alpha, np.zeros(2), np.zeros(2))
    aero = Aerodynamics(stations=(r - Rh) / (R - Rh), chord=chord, twist=-twist,
                        airfoil=np.zeros(stations, int), polars=(polar,))
    polars = StationPolars(aero, aero.stations)
    rotor = BemRotor(blades, r, chord, twist, polars, Rh, R, tip_loss=False, hub_loss=False)
    return rotor, r, a, ap


@pytest.mark.parametrize("tsr", [4.0, 7.0, 10.0])
def test_glauert_optimum_rotor(tsr):
    """hawt's BEM on Glauert's optimum rotor finds the design inductions at every station
    (1e-9) and the power coefficient of Glauert's integral (computed here by fine quadrature;
    2e-3: hawt's trapezoid over 300 stations with zero loads at the ends)."""
    rotor, r, a, ap = ideal_rotor(tsr)
    U = 10.0
    sol = rotor.solve(U, tsr * U / rotor.tip_radius)
    assert np.max(sol.residual) < 1e-12
    assert np.allclose(sol.a, a, atol=1e-9) and np.allclose(sol.ap, ap, atol=1e-9)
    xs = np.linspace(tsr * 5.0 / 50.0, tsr, 200001)
    aa, aap = glauert(xs)
    cp_glauert = 8 / tsr ** 2 * np.trapezoid(aap * (1 - aa) * xs ** 3, xs)
    assert sol.cp == pytest.approx(cp_glauert, rel=2e-3)


def test_ideal_rotor_approaches_betz():
    """At a high tip-speed ratio the optimum rotor's inductions approach a = 1/3, a' = 0 and
    its power coefficient 16/27 (Betz): within 1.5 % at TSR 20 (the remaining wake-rotation
    and hub losses are Glauert's)."""
    rotor, r, a, ap = ideal_rotor(20.0)
    sol = rotor.solve(10.0, 20.0 * 10.0 / rotor.tip_radius)
    outer = r > 0.5 * rotor.tip_radius
    assert np.all(np.abs(sol.a[outer] - 1 / 3) < 2e-3) and np.all(sol.ap[outer] < 2.5e-3)
    assert sol.cp == pytest.approx(16 / 27, rel=0.015)
    assert sol.cp < 16 / 27


# ------------------------------------------------------------------------------ NREL 5-MW
def test_nrel5mw_peak_power_coefficient():
    """The NREL 5-MW's maximum Cp and where it is: 0.482 at TSR 7.55, pitch 0 deg
    (Jonkman et al. 2009, section 7.1; WT_Perf). Tolerances: Cp 1 %, TSR 0.25, pitch 0.5 deg
    (the grid below has steps 0.05 and 0.25 deg)."""
    table = aero_table(nrel5mw(), np.linspace(6.5, 8.5, 41), np.linspace(-2.0, 2.0, 17))
    opt = table.optimum()
    print(f"\nNREL 5-MW: max Cp {opt['cp']:.4f} at TSR {opt['tsr']:.3f}, pitch "
          f"{opt['pitch_deg']:.2f} deg (report: 0.482 at 7.55, 0.0)")
    assert opt["cp"] == pytest.approx(0.482, rel=0.01)
    assert abs(opt["tsr"] - 7.55) <= 0.25 and abs(opt["pitch_deg"]) <= 0.5
    assert np.max(table.residual) < 1e-10


def test_nrel5mw_against_roscos_table(tmp_path):
    """ROSCO's Cp_Ct_Cq.NREL5MW.txt (CCBlade, with 5 deg shaft tilt and a 0.2 shear exponent
    averaged over 8 sectors, which hawt's axisymmetric table has not): the same grid point of
    maximum Cp; Ct within 3 % and Cp within 5 % where the rotor operates (Cp > 0.3, pitch >=
    0; hawt's Cp is 1-4 % higher there, as the tilt alone, cos^3(5 deg), makes 1.1 %). hawt's
    own file, read back by ROSCO's reader (transliterated), holds hawt's numbers (1e-6)."""
    ref = rosco_decks() / "NREL-5MW" / "Cp_Ct_Cq.NREL5MW.txt"
    pitch, tsr, cp, ct, cq = load_from_txt(ref)
    table = aero_table(nrel5mw(), tsr, np.degrees(pitch), wind_speed=11.4)
    i, j = np.unravel_index(np.argmax(cp), cp.shape)
    assert np.unravel_index(np.argmax(table.cp), cp.shape) == (i, j)
    region = (cp > 0.3) & (pitch[None, :] >= 0)      # where the controller runs the rotor
    assert np.max(np.abs(table.ct[region] / ct[region] - 1)) < 0.03
    assert np.max(np.abs(table.cp[region] / cp[region] - 1)) < 0.05
    out = table.save_rosco(tmp_path / "Cp_Ct_Cq.hawt.txt")
    p2, t2, cp2, ct2, cq2 = load_from_txt(out)
    assert np.allclose(np.degrees(p2), table.pitch_deg, atol=1e-9)
    assert np.allclose(t2, table.tsr, atol=1e-12)
    for mine, read in ((table.cp, cp2), (table.ct, ct2), (table.cq, cq2)):
        assert np.allclose(read, mine, atol=1e-6, rtol=0)
    # Cq = Cp / TSR, as the definitions demand (R the coned radius for both)
    cone = np.cos(nrel5mw().rotor.precone)
    assert np.allclose(table.cq * tsr[:, None] * cone, table.cp, rtol=1e-12, atol=1e-15)


def test_aero_table_command_line(tmp_path):
    """`hawt aero-table --json` holds the documented keys indexed [tsr][pitch]; --rosco and
    --plot write their files; a turbine without aerodynamics and a bad grid are one-line
    errors (exit 2)."""
    out = subprocess.run([str(HAWT), "aero-table", "nrel5mw", "--tsr", "4:10:7",
                          "--pitch=-2:6:5", "--json", "--rosco", str(tmp_path / "t.txt"), "--plot",
                          str(tmp_path / "t.png")], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["tsr"] == [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]
    assert data["pitch_deg"] == [-2.0, 0.0, 2.0, 4.0, 6.0]
    for key in ("cp", "ct", "cq"):
        assert np.array(data[key]).shape == (7, 5)
    assert (tmp_path / "t.txt").stat().st_size > 0 and (tmp_path / "t.png").stat().st_size > 0
    for argv, words in ((["paper"], ["no aerodynamics"]),
                        (["nrel5mw", "--tsr", "5:4:3"], ["--tsr", "START <= STOP"]),
                        (["nrel5mw", "--pitch=-90:0:3"], ["--pitch", "-30"])):
        bad = subprocess.run([str(HAWT), "aero-table", *argv], capture_output=True, text=True,
                             timeout=120)
        assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
        for w in words:
            assert w in bad.stderr, bad.stderr
