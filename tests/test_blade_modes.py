"""Blade modes (hawt_core/blade_modes.py), its plot and the `hawt blade-modes` CLI.

References: the paper's Table 2 (Patil, Lee & Hodges, AIAA 2001-0064) and the
variant-discretization column of docs/theory.md (shared), Wright et al. (1982) for rotating
beams, closed-form steady tension and the rotating-torsion formula.  No reference value here
is an output of hawt itself.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hawt_core import cli
from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.assembly import SpinningBlade
from hawt_core.fem.energy import frequency_bound
from hawt_core.model import Beam, Hub, Nacelle, Rotor, SectionTable, Turbine
from mesh_study import mesh_study, richardson
from paper_tables import TABLE2, TABLE2_PRINTED

M, L, OMEGA0, E_HUB = 67.5772, 8.42, 6.02, 1.8
TABLE1 = dict(mass=M, i1=5.0, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6, ei3=21.8e6)


def paper(elements=4, **over):
    sec = SectionTable.uniform(**{**TABLE1, **over})
    return Turbine("paper", Rotor(), Hub(), Nacelle(), Beam(L, sec, elements))


def first_two(result):
    fams = {}
    for m in result.modes:
        fams.setdefault(m.family, []).append(m.frequency_per_rev)
    return {f: np.array(v[:2]) for f, v in fams.items()}


# ---------------------------------------------------------------------------- Table 2
# the symmetric modes of Table 2 (tests/paper_tables.py): 1st and 2nd of each family
PAPER_N4 = {fam: tuple(TABLE2[(fam, "symmetric", k)][2] for k in (1, 2))
            for fam in ("flap", "torsion", "lag")}
PAPER_PRINTED = {N: {fam: tuple(TABLE2_PRINTED[(fam, "symmetric", k)][N - 2] for k in (1, 2))
                     for fam in ("flap", "torsion", "lag")} for N in (2, 3)}
# docs/theory.md, "variant" column (the discretization implemented), per-rev
VARIANT = {2: {"flap": (2.4333, 24.087), "torsion": (2.3252, 7.4010), "lag": (4.8041, 52.081)},
           3: {"flap": (2.4366, 17.405), "torsion": (2.2986, 6.8423), "lag": (4.7703, 37.644)},
           4: {"flap": (2.4346, 15.5477), "torsion": (2.2893, 6.5732),
               "lag": (4.7520, 33.5993)}}
# Printed N = 2, 3 entries the variant does not reproduce within one unit of the last
# printed digit (docs/VALIDATION.md): the paper's 2nd lead-lag at N = 2 and N = 3.
EXCEPTIONS = {(2, "lag", 1), (3, "lag", 1)}


def test_table2_four_elements_within_0p2_percent():
    """Reference: the paper's Table 2, N = 4 symmetric modes (1st/2nd flap 2.4347, 15.5465;
    torsion 2.2896, 6.5738; lead-lag 4.7523, 33.5731 per-rev).  Tolerance 0.2 % (worst
    observed 0.078 %, 2nd lead-lag)."""
    got = first_two(blade_modes(paper(), 4))
    for fam, ref in PAPER_N4.items():
        assert np.all(np.abs(got[fam] / np.array(ref) - 1) < 2e-3), (fam, got[fam])


@pytest.mark.parametrize("N", [2, 3, 4])
def test_table2_variant_column_and_printed_digits(N):
    """References: docs/theory.md's variant column (5 significant digits: tolerance half a
    unit of the last digit + 1e-6 relative) and, for N = 2, 3, the paper's printed values to
    one unit of the last printed digit (the paper's rounding is inconsistent: 2.3252 printed
    2.32, 4.8041 printed 4.81).  Exceptions, documented in docs/VALIDATION.md: 2nd lead-lag
    52.07 (N = 2; variant 52.081, +0.011) and 37.61 (N = 3; variant 37.644, +0.034), checked
    at 0.1 % instead."""
    got = first_two(blade_modes(paper(), N))
    for fam, ref in VARIANT[N].items():
        for k in range(2):
            digits = len(f"{ref[k]:.5g}".split(".")[1]) if "." in f"{ref[k]:.5g}" else 0
            tol = 0.5 * 10.0 ** -digits + 1e-6 * ref[k]
            assert abs(got[fam][k] - ref[k]) <= tol, (N, fam, k, got[fam][k], ref[k])
    for fam, printed in PAPER_PRINTED.get(N, {}).items():
        for k, text in enumerate(printed):
            value = float(text)
            if (N, fam, k) in EXCEPTIONS:
                assert abs(got[fam][k] / value - 1) < 1e-3, (N, fam, k, got[fam][k])
                assert abs(got[fam][k] - value) > 10.0 ** -len(text.split(".")[1])
            else:
                unit = 10.0 ** -len(text.split(".")[1])
                assert abs(got[fam][k] - value) <= unit, (N, fam, k, got[fam][k], value)


def test_steady_root_tension():
    """Reference: F0 = m Omega0^2 (e l + l^2/2) = 123930.9 N (Table 1), other root loads 0.
    Tolerance 1e-9 relative (Newton tolerance)."""
    ref = M * OMEGA0 ** 2 * (E_HUB * L + L ** 2 / 2)
    assert abs(ref - 123930.9) < 0.05
    for N in (2, 4, 16):
        F = blade_modes(paper(), N).root_force
        assert abs(F[0] / ref - 1) < 1e-9
        assert np.all(np.abs(F[1:]) < 1e-6 * ref)


# ---------------------------------------------------------------------------- rotating beams
@pytest.mark.parametrize("lam, ref", [(0.0, (3.5160, 22.0345, 61.6972)),
                                      (12.0, (13.1702, 37.6031, 79.6145))])
def test_rotating_uniform_cantilever_flap_wright(lam, ref):
    """Reference: Wright et al. (1982) / Hodges & Rutkowski (1981): flap frequencies of a
    uniform rotating cantilever, no hub offset, omega sqrt(m l^4/EI) at lambda = Omega
    sqrt(m l^4/EI) = 0: 3.5160, 22.0345, 61.6972 and 12: 13.1702, 37.6031, 79.6145.
    Rotary inertia i2 = i3 = 1e-6 (negligible) and I1 = I2 + I3: with the Table 1 I1 = 5 the
    spin couples the flap slope rate to torsion (gyroscopic term ~ (I1 + I2 - I3) Omega) and
    the converged 1st flap at lambda = 12 moves to 13.1728 (+2e-4), which is physics, not an
    error.  Tolerance: Richardson (N = 8, 16, 32)
    within 2e-4 relative (the table gives 5-6 digits); order 2 +- 0.3 for the 2nd and 3rd
    modes (at lambda = 12 the 1st mode's error changes sign between N = 8 and 32, so its
    ratio is no order estimate)."""
    ei = TABLE1["ei2"]
    scale = math.sqrt(ei / (M * L ** 4))
    sec = SectionTable.uniform(**{**TABLE1, "i1": 2e-6, "i2": 1e-6, "i3": 1e-6})
    T = Turbine("rot", Rotor(speed=lam * scale), Hub(radius=0.0), Nacelle(), Beam(L, sec, 4))
    f = mesh_study(T, "flap", 3) / scale
    e = np.abs(f / np.array(ref) - 1)
    order = np.log2(e[:-1, 1:] / e[1:, 1:])
    assert np.all(np.abs(order - 2) < 0.3), order
    rich = richardson(*f)
    assert np.all(np.abs(rich / np.array(ref) - 1) < 2e-4), rich / np.array(ref) - 1


@pytest.mark.parametrize("lam, ref", [(0.0, (3.5160, 22.0345, 61.6972)),
                                      (12.0, (13.1702, 37.6031, 79.6145))])
def test_rotating_uniform_cantilever_flap_wright_p_version(lam, ref):
    """The same reference (Wright et al. 1982), the p-version (fem/spectral.py) without
    extrapolation: order 4 with 4 elements (16 cells, the unknowns of 16 paper elements,
    which are 1e-3 off in the 3rd mode) within 5e-5 of the table's digits, and its error
    falling from 2 to 4 elements by more than 2^(2 p - 2) = 64 in the 3rd mode (at
    lambda = 0; the table's 5-6 digits end the comparison beyond that)."""
    ei = TABLE1["ei2"]
    scale = math.sqrt(ei / (M * L ** 4))
    sec = SectionTable.uniform(**{**TABLE1, "i1": 2e-6, "i2": 1e-6, "i3": 1e-6})

    def flap(n, order):
        T = Turbine("rot", Rotor(speed=lam * scale), Hub(radius=0.0), Nacelle(),
                    Beam(L, sec, n, order=order))
        r = blade_modes(T, n, method="dense", count=30)
        return np.array([m.frequency_rad_s for m in r.modes if m.family == "flap"][:3]) / scale
    e4 = np.abs(flap(4, 4) / np.array(ref) - 1)
    assert np.all(e4 < 5e-5), e4
    if lam == 0.0:
        e2 = np.abs(flap(2, 4) / np.array(ref) - 1)
        assert e2[2] / max(e4[2], 1e-7) > 64, (e2, e4)
    paper = np.abs(flap(16, 1) / np.array(ref) - 1)
    assert paper[2] > 5e-4, paper


def test_rotating_torsion_on_the_hub():
    """Reference: omega^2 = omega_NR^2 + Omega^2 (I3 - I2)/I1 with omega_NR,k =
    (2k-1) pi/(2l) sqrt(GJ/I1) (docs/theory.md), for a thin section (I1 = I2 + I3 with the
    flap-axis inertia I2 = 1e-4 negligible; a sizeable I2 adds a Coriolis coupling
    ~ 2 I2 Omega to the flap slope rate and moves the 1st torsion by ~4e-4 for I2 = 1),
    hub radius 1.8 m, Omega = 10 rad/s.  Tolerance: Richardson (N = 8, 16, 32) within 1e-4
    relative (worst observed ~1e-7)."""
    i1, i2, i3, gj, om = 5.0, 1e-4, 4.9999, TABLE1["gj"], 10.0
    sec = SectionTable.uniform(**{**TABLE1, "i1": i1, "i2": i2, "i3": i3})
    T = Turbine("tor", Rotor(speed=om), Hub(radius=E_HUB), Nacelle(), Beam(L, sec, 4))
    f = mesh_study(T, "torsion", 2)
    w_nr = (2 * np.arange(1, 3) - 1) * np.pi / (2 * L) * np.sqrt(gj / i1)
    exact = np.sqrt(w_nr ** 2 + om ** 2 * (i3 - i2) / i1)
    e = np.abs(f / exact - 1)
    assert np.all(np.abs(np.log2(e[:-1] / e[1:]) - 2) < 0.3)
    rich = richardson(*f)
    assert np.all(np.abs(rich / exact - 1) < 1e-4), rich / exact - 1
    assert np.all(f[-1] > w_nr)    # stiffened, not softened


# ---------------------------------------------------------------------------- mode selection
@pytest.mark.parametrize("N, flexible, per_element", [
    (8, {}, 3), (32, {}, 3), (8, {"ea": 1e9}, 4), (8, {"ea": 1e9, "ga2": 3e8, "ga3": 3e8}, 6)])
def test_every_finite_mode_is_kept_and_no_spurious_one(N, flexible, per_element):
    """Reference: the number of degrees of freedom of the discrete blade: 3 per element for
    the inextensible, shear-rigid blade (flap, lag, torsion), +1 with finite EA, +2 more with
    finite GA2, GA3 (exact count).  All frequencies are oscillatory (|Re| < 1e-6 |lam|: the
    undamped blade is conservative) and below 2x the element-level bound; in particular the
    spurious +-6e6 per-rev pair that QZ returns at N = 32 is gone."""
    r = blade_modes(paper(N, **flexible), N, method="dense")
    assert len(r.modes) == per_element * N
    lam = np.array([m.eigenvalue for m in r.modes])
    assert np.all(np.abs(lam.real) < 1e-6 * np.abs(lam))
    bound = frequency_bound(SpinningBlade(paper(N, **flexible), N).beam.props)
    assert np.abs(lam).max() < 2 * bound
    fams = {m.family for m in r.modes}
    assert {"flap", "lag", "torsion"} <= fams
    if "ea" in flexible:
        assert "axial" in fams


def test_sparse_path_equals_dense_where_they_overlap():
    """Reference: the dense (deflation + QZ) result at N = 32 (n = 588): the sparse
    shift-invert path's lowest 30 modes have the same frequencies (1e-7 relative), families
    and indices.  ``method='auto'`` picks sparse above 600 unknowns (N = 64)."""
    T = paper(32)
    d = blade_modes(T, 32, method="dense")
    s = blade_modes(T, 32, method="sparse", count=30)
    assert len(s.modes) == 30
    fd, fs = d.frequencies()[:30], s.frequencies()
    assert np.allclose(fs, fd, rtol=1e-7, atol=0)
    assert [(m.family, m.index) for m in s.modes] == [(m.family, m.index) for m in d.modes[:30]]
    auto = blade_modes(paper(64), 64, count=12)
    assert auto.settings["method"] == "sparse" and len(auto.modes) == 12
    # the converged 1st flap at N = 64 is close to N = 32's (O(h^2))
    assert abs(auto.modes[1].frequency_per_rev / d.modes[1].frequency_per_rev - 1) < 1e-3


# ---------------------------------------------------------------------------- arguments
@pytest.mark.parametrize("kw, field", [({"elements": 0}, "elements"),
                                       ({"elements": -3}, "elements"),
                                       ({"elements": 2.5}, "elements"),
                                       ({"rotor_speed": -1.0}, "rotor_speed"),
                                       ({"rotor_speed": float("nan")}, "rotor_speed"),
                                       ({"count": 0}, "count"),
                                       ({"method": "qr"}, "method")])
def test_bad_arguments_name_the_field(kw, field):
    """Reference: the error message contract (field, value, what is allowed)."""
    with pytest.raises(ValueError) as err:
        blade_modes(paper(), **kw)
    msg = str(err.value)
    assert msg.startswith(field + ":") and "allowed" in msg


def test_plot_writes_a_png(tmp_path):
    """Reference: PNG file signature; one subplot per mode."""
    path = tmp_path / "modes.png"
    blade_modes(paper(), 4).plot(path, count=4)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert path.stat().st_size > 10_000


# ---------------------------------------------------------------------------- CLI
def test_cli_json(capsys):
    """Reference: the JSON contract of `hawt blade-modes --json` (keys, sorted frequencies,
    families) and the paper's N = 4 first flap (0.2 %)."""
    assert cli.main(["blade-modes", "--elements", "4", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    modes = out["modes"]
    assert len(modes) == 12
    freqs = [m["frequency_per_rev"] for m in modes]
    assert freqs == sorted(freqs)
    for m in modes:
        assert set(m) >= {"family", "index", "frequency_per_rev", "frequency_hz",
                          "damping_ratio", "shape"}
        assert m["family"] in ("flap", "lag", "torsion", "axial", "shear")
        assert abs(m["frequency_hz"] * 2 * math.pi / OMEGA0 - m["frequency_per_rev"]) < 1e-9
    flap1 = [m for m in modes if m["family"] == "flap"][0]
    assert abs(flap1["frequency_per_rev"] / PAPER_N4["flap"][0] - 1) < 2e-3
    assert out["settings"]["elements"] == 4 and out["settings"]["rotor_speed"] == OMEGA0


def test_cli_table_plot_and_rotor_speed(tmp_path, capsys):
    """Reference: at rotor speed 0 the per-rev column is empty and the JSON per-rev is null;
    the table lists the modes; --plot writes a PNG."""
    png = tmp_path / "m.png"
    assert cli.main(["blade-modes", "-n", "3", "--rotor-speed", "0", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "flap 1" in out and png.exists()
    assert cli.main(["blade-modes", "-n", "2", "--rotor-speed", "0", "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    assert all(m["frequency_per_rev"] is None for m in modes)


@pytest.mark.parametrize("argv, words", [
    (["blade-modes", "/no/such/turbine.yaml"], "not found"),
    (["blade-modes", "--elements", "0"], "elements"),
    (["blade-modes", "--elements", "two"], "elements"),
    (["blade-modes", "--rotor-speed", "-2"], "rotor-speed"),
    (["blade-modes", "--rotor-speed", "nan"], "rotor-speed"),
    (["no-such-command"], "invalid choice")])
def test_cli_errors_are_one_line_exit_2(argv, words, capsys):
    """Reference: the CLI contract: one line on stderr naming the problem, exit status 2."""
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err


def test_cli_bad_turbine_file(tmp_path, capsys):
    """Reference: a malformed turbine file gives one line and exit 2."""
    bad = tmp_path / "bad.yaml"
    bad.write_text("blade: [1, 2\n")
    assert cli.main(["blade-modes", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_cli_help_lists_blade_modes(capsys):
    """Reference: `hawt --help` explains each registered subcommand."""
    with pytest.raises(SystemExit) as ex:
        cli.main(["--help"])
    assert ex.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    for name, entry in cli.COMMANDS.items():
        assert name in out and " ".join(entry["help"].split()) in out


@pytest.mark.parametrize("order", [1, 4], ids=["paper-element", "p-version"])
@pytest.mark.parametrize("offset", [(0.12, 0.0), (0.0, 0.09), (0.07, -0.05)],
                         ids=["chordwise", "flapwise", "both"])
def test_root_loads_of_a_spinning_blade_with_a_mass_centre_offset(offset, order):
    """Closed form (rigid-body statics of the spinning blade): a stiff uniform blade (Table 1
    mass, EI and GJ x 1e5) whose mass centre is offset by (x2, x3) from the reference line,
    root at e from the shaft, spinning at Omega about b3; each element's mass m dx at
    (e + x) b1 + x2 b2 + x3 b3 needs the centripetal force -m dx Omega^2 ((e + x) b1 + x2 b2),
    so the loads the blade exerts on the hub are
        F0 = m Omega^2 ((e L + L^2 / 2) b1 + x2 L b2),
        M0 = m Omega^2 (-x2 x3 L b1 + x3 (e L + L^2 / 2) b2 - x2 e L b3)   (about the
    root point; the sections' own principal inertias about b3 add nothing).
    In the beam equations these come from the V x P and Omega x H terms of the moment
    balance (a sign error there moves M0 by the L^2 / 2 part, 400 % here).  Tolerance 1e-4
    relative to |M0| (the stiff blade's deflection moves the moment arms by ~1e-6)."""
    x2, x3 = offset
    sec = dict(TABLE1)
    for k in ("gj", "ei2", "ei3"):
        sec[k] = sec[k] * 1e5
    T = paper()
    T = Turbine("offset", T.rotor, T.hub, T.nacelle, Beam(L, SectionTable(
        stations=[0.0, 1.0], **{k: [v, v] for k, v in sec.items()},
        cg_offset=[[x2, x3], [x2, x3]]), 4, order=order))
    model = SpinningBlade(T, 4)
    y = model.steady_state()
    F0, M0 = y[0:3], y[3:6]
    W2 = OMEGA0 ** 2
    F_ref = M * W2 * np.array([E_HUB * L + L ** 2 / 2, x2 * L, 0.0])
    M_ref = M * W2 * np.array([-x2 * x3 * L, x3 * (E_HUB * L + L ** 2 / 2), -x2 * E_HUB * L])
    np.testing.assert_allclose(F0, F_ref, atol=1e-6 * np.abs(F_ref).max())
    np.testing.assert_allclose(M0, M_ref, atol=1e-4 * np.abs(M_ref).max())


@pytest.mark.parametrize("order", [1, 4], ids=["paper-element", "p-version"])
def test_root_moment_of_a_blade_under_gravity_with_a_mass_centre_offset(order):
    """Closed form (statics): a stiff uniform cantilever at rest under a gravity vector g with
    components on all three root axes, mass centre offset xi = (0, x2, x3): the loads it exerts
    on its clamp are F0 = m L g and M0 = m L (L/2 b1 + xi) x g; the xi x g part is the gravity
    moment of the offset (a sign error there flips the torsion moment).  Tolerance 1e-6
    relative (Newton, deflection ~1e-7 of the arms).  The paper's element (6 elements) and
    the p-version (2 elements of order 4), Jacobian by dense complex step."""
    from hawt_core.numerics.newton import newton
    from hawt_core.fem.discretization import beam_elements
    x2, x3 = 0.15, -0.08
    sec = dict(TABLE1)
    for k in ("gj", "ei2", "ei3"):
        sec[k] = sec[k] * 1e6
    table = SectionTable(stations=[0.0, 1.0], **{k: [v, v] for k, v in sec.items()},
                         cg_offset=[[x2, x3], [x2, x3]])
    beam = beam_elements(Beam(L, table, 6 if order == 1 else 2, order=order))
    g = np.array([[-3.0, 4.0, -8.5]])
    z3 = np.zeros((1, 3))
    zero = np.zeros(beam.n)
    f = lambda y: beam.residual(zero[None], y[None], z3, z3, g)[0]      # noqa: E731

    def jac(y):
        h = 1e-30
        steps = y[None, :] + 1j * h * np.eye(beam.n)
        return np.array([f(row).imag / h for row in steps]).T
    y, _ = newton(f, jac, np.zeros(beam.n), tol=1e-13, what="statics")
    F_ref = M * L * g[0]
    M_ref = M * L * np.cross(np.array([L / 2, x2, x3]), g[0])
    np.testing.assert_allclose(y[0:3], F_ref, rtol=1e-9, atol=1e-9 * np.abs(F_ref).max())
    np.testing.assert_allclose(y[3:6], M_ref, atol=1e-6 * np.abs(M_ref).max())
