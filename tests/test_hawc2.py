"""HAWC2 models (issue 35, items 2 and 3, first part): a main body of a HAWC2 model (its
c2_def line and Timoshenko st set, its damping_posdef) as a hawt beam.

Reference: HAWC2's own eigenanalysis of the DTU 10-MW blade alone, clamped, asserted in
DTU's h2lib test suite (h2lib_tests 13.2.2103, test_lin.py::test_sys_eig_with_damping;
tests/data/hawc2/README.md): frequencies 0.610409, 0.930444, 1.739086, 2.762015 Hz and
damping ratios 0.004826, 0.004758, 0.013395, 0.014198.  The comparison is HAWC2 against
hawt, not a self-check: the targets of issue 35 are 1 % in frequency and 10 % in damping.
What remains different: HAWC2 linearizes its 26 bodies of linear Timoshenko elements about
the blade under gravity with its span horizontal; hawt's p-version elements (converged:
6 elements give the same to 1e-5) about the unloaded blade."""
from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.io import TurbineFileError
from hawt_core.io.catalog import load_any
from hawt_core.io.hawc2 import hawc2_body, timoshenko_matrices
from hawt_core.io.hawc2_files import TIMOSHENKO_COLUMNS, read_htc, read_st

HTC = Path(__file__).parent / "data" / "hawc2" / "DTU_10_MW" / "htc" / "DTU_10MW_RWT.htc"
HAWC2_HZ = [0.610409, 0.930444, 1.739086, 2.762015]
HAWC2_ZETA = [0.004826, 0.004758, 0.013395, 0.014198]


def _clamped(beam):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_any("nrel5mw")
    t = replace(t, blade=beam, rotor=replace(t.rotor, speed=0.0, precone=0.0),
                gravity=replace(t.gravity, enabled=False), aerodynamics=None,
                tower_aerodynamics=None)
    return blade_modes(t, rotor_speed=0.0, count=6).modes


def test_dtu10mw_blade_alone_matches_hawc2s_eigenanalysis():
    beam, notes = hawc2_body(HTC, "blade1")
    modes = _clamped(beam)[:4]
    assert [m.family for m in modes] == ["flap", "lag", "flap", "lag"]
    f = np.array([m.frequency_hz for m in modes])
    z = np.array([m.damping_ratio for m in modes])
    np.testing.assert_allclose(f, HAWC2_HZ, rtol=0.01)        # found +0.62 .. +0.69 %
    np.testing.assert_allclose(z, HAWC2_ZETA, rtol=0.10)      # found -5.8 .. +4.9 %
    assert beam.length == pytest.approx(86.3655, abs=1e-9)
    assert any("damping_posdef" in n for n in notes)


def test_the_section_matrices_hold_the_st_files_numbers():
    """Reference: the st file's own columns.  At a section with the elastic, shear and mass
    centres on the c2 point and no structural pitch, K and M are diagonal: EA, k_x G A,
    k_y G A, G I_p, E I_x, E I_y and m, m, m, m (ri_x^2 + ri_y^2), m ri_x^2, m ri_y^2; with
    offsets, the axial-bending coupling is EA times the elastic centre's offset, and the
    static moment m times the mass centre's (1e-12)."""
    st = {k: np.array([v]) for k, v in zip(TIMOSHENKO_COLUMNS, (
        0.0, 500.0, 0.0, 0.0, 0.6, 0.4, 0.0, 0.0, 1e10, 4e9, 0.5, 2.0, 0.8, 0.5, 0.6, 0.3,
        0.0, 0.0, 0.0))}
    K, M = timoshenko_matrices(st)
    np.testing.assert_allclose(np.diag(K[0]), [3e9, 0.5 * 4e9 * 0.3, 0.6 * 4e9 * 0.3,
                                               4e9 * 0.8, 0.5e10, 2e10], rtol=1e-12)
    np.testing.assert_allclose(np.diag(M[0]), [500, 500, 500, 500 * 0.52, 500 * 0.36,
                                               500 * 0.16], rtol=1e-12)
    assert np.count_nonzero(K[0] - np.diag(np.diag(K[0]))) == 0
    st["x_e"], st["y_e"], st["x_cg"], st["y_cg"] = (np.array([v]) for v in (0.1, 0.2,
                                                                             0.3, -0.1))
    K, M = timoshenko_matrices(st)
    assert K[0, 0, 4] == pytest.approx(3e9 * 0.2) and K[0, 0, 5] == pytest.approx(-3e9 * 0.1)
    assert M[0, 3, 1] == pytest.approx(500 * 0.1) and M[0, 3, 2] == pytest.approx(500 * 0.3)


def test_the_readers_name_what_is_wrong(tmp_path):
    """An unknown body, an unclosed block and a missing st subset are refused with the
    file (and line) and what is missing."""
    with pytest.raises(TurbineFileError, match="main_body 'blade7' not found.*blade1"):
        hawc2_body(HTC, "blade7")
    bad = tmp_path / "x.htc"
    bad.write_text("begin new_htc_structure;\n  begin main_body;\n    name blade1;\n")
    with pytest.raises(Exception, match="line 2.*never closed"):
        read_htc(bad)
    with pytest.raises(TurbineFileError, match=r"x.htc: .*never closed \(line 2\)"):
        hawc2_body(bad, "blade1")
    st = HTC.parent.parent / "data" / "DTU_10MW_RWT_Blade_st.dat"
    assert read_st(st, 1, 1).shape == (51, 19)
    with pytest.raises(Exception, match="set 1 subset 9 not found"):
        read_st(st, 1, 9)


def test_what_a_body_holds_and_the_beam_does_not_take_is_named(tmp_path):
    """Nothing dropped silently: a concentrated mass, an anisotropic damping and an unknown
    block of the body come back as notes with their lines; nbodies with the mesh used."""
    text = HTC.read_text()
    text = text.replace("name        blade1 ;", "name        blade1 ;\n    concentrated_mass 5 0.0 "
                        "0.0 0.0 100.0 0.0 0.0 0.0 ;\n    damping_aniso 0 0 0 1e-3 1e-3 1e-3 ;"
                        "\n    begin extra_stuff ;\n    end extra_stuff ;", 1)
    d = tmp_path / "DTU_10_MW"
    (d / "htc").mkdir(parents=True)
    (d / "data").mkdir()
    (d / "htc" / "m.htc").write_text(text)
    (d / "data" / "DTU_10MW_RWT_Blade_st.dat").write_text(
        (HTC.parent.parent / "data" / "DTU_10MW_RWT_Blade_st.dat").read_text())
    _, notes = hawc2_body(d / "htc" / "m.htc", "blade1")
    joined = "\n".join(notes)
    assert "concentrated_mass 5 0.0" in joined and "point masses" in joined
    assert "damping_aniso" in joined and "block extra_stuff" in joined
    assert "nbodies 10" in joined and "3 elements of order 6" in joined


IEA_HTC = (Path(__file__).parent / "data" / "hawc2" / "IEA-15-240-RWT-Onshore" / "htc"
           / "IEA_15MW_RWT_Onshore.htc")


def test_iea15mw_blade_from_hawc2_is_the_windio_blade():
    """The IEA 15-MW blade in two formats of the same design: the HAWC2 model's Timoshenko
    st set (h2lib_tests, read through continue_in_file) and windio's WindIO 2.x file (full
    6x6 matrices).  Reference: the WindIO blade's clamped modes at rest, computed on the
    same mesh; tolerance 0.5 % (the noFPM st drops the 6x6's couplings; found 0.02-0.2 %).
    The body's damping_aniso is taken by damping_posdef's rule, and the notes say so."""
    windio = pytest.importorskip("windIO")
    from hawt_core.io.windio import read_windio
    example = Path(windio.__file__).parent / "examples" / "turbine" / "IEA-15-240-RWT.yaml"
    if not example.is_file():
        pytest.skip("windio's IEA 15-MW example is not installed")
    beam, notes = hawc2_body(IEA_HTC, "blade1")
    assert any("damping_aniso" in n and "damping_posdef's rule" in n for n in notes)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = read_windio(example).turbine.blade
    assert beam.length == pytest.approx(ref.length, rel=1e-9)
    got, want = _clamped(beam)[:5], _clamped(ref)[:5]
    assert [m.family for m in got] == [m.family for m in want]
    np.testing.assert_allclose([m.frequency_hz for m in got],
                               [m.frequency_hz for m in want], rtol=5e-3)


def test_dtu10mw_aerodynamics_from_the_ae_and_pc_files():
    """The aero block (ae_sets, ae and pc files, the linked body's c2_def twist).
    References: the ae file's own chord column (exact); a station whose thickness is a pc
    table's (24.1 %) has exactly that table; a thickness between two tables has the
    linear interpolation between them (closed form at a shared angle, 1e-12); the twist is
    the c2_def twist at the root (-14.5 deg); HAWC2's model options named as not taken."""
    from hawt_core.io.hawc2 import hawc2_aerodynamics, thickness_polar
    from hawt_core.io.hawc2_files import read_ae, read_pc
    data = HTC.parent.parent / "data"
    aero, notes = hawc2_aerodynamics(HTC)
    ae = read_ae(data / "DTU_10MW_RWT_ae.dat", 1)
    np.testing.assert_array_equal(aero.chord, ae[:, 1])
    assert aero.stations[0] == 0.0 and aero.stations[-1] == 1.0
    assert np.degrees(aero.twist[0]) == pytest.approx(-14.5, abs=1e-12)
    tables = read_pc(data / "DTU_10MW_RWT_pc.dat", 1)
    tip = aero.polars[aero.airfoil[-1]]
    t241 = next(r for t, _, r in tables if t == 24.1)
    assert ae[-1, 2] == 24.1
    np.testing.assert_array_equal(tip.cl, t241[:, 1])
    np.testing.assert_allclose(np.degrees(tip.alpha), t241[:, 0], rtol=1e-14, atol=1e-12)
    t301 = next(r for t, _, r in tables if t == 30.1)
    alpha, cl, cd, cm = thickness_polar(tables, 27.1)
    k = int(np.flatnonzero(alpha == 0.0)[0])
    mid = 0.5 * (np.interp(0.0, t241[:, 0], t241[:, 1]) + np.interp(0.0, t301[:, 0], t301[:, 1]))
    assert cl[k] == pytest.approx(mid, rel=1e-12)
    assert any("dynstall_method" in n and "not taken" in n for n in notes)
    # the quarter chord (HAWC2's aerodynamic centre) a quarter chord ahead of the c2 line:
    # at the root 5.38 / 4; the aerodynamic nodes on the c2 line (its root point: 0, 0)
    assert aero.ac_chordwise[0] == pytest.approx(5.38 / 4, rel=1e-12)
    assert aero.ac_sweep[0] == 0.0 and aero.ac_prebend[0] == 0.0


def test_iea15mw_fpm_st_set_is_the_timoshenko_blade(tmp_path):
    """``fpm 1``: the fully populated 6x6 st set (BECAS's strains at the elastic centre,
    principal axes) of the IEA 15-MW blade against the same blade's Timoshenko st set
    (h2lib_tests, both unchanged): two forms of one cross-section analysis, independent
    inputs (the FPM's shear-torsion couplings against the Timoshenko set's shear centre).
    References and tolerances: at every station the section's torsion and flap stiffness at
    the c2 point within 1 % and edge stiffness within 3 % (found 0.9 %, 0.2 %, 2.7 %), the
    shear-twist couplings within 5 % of sqrt(GA GJ) (found 3.7 %; the couplings reach 12
    and 58 % of it); the first seven clamped modes within
    0.3 % (found 0.2 %)."""
    import shutil
    from hawt_core.io.hawc2 import fpm_matrices
    from hawt_core.io.hawc2_files import FPM_COLUMNS
    d = tmp_path / "m"
    shutil.copytree(IEA_HTC.parents[2], d)
    bodies = d / "IEA-15-240-RWT" / "IEA_15MW_RWT_WTG_bodies_noFPM.htc"
    bodies.write_text(bodies.read_text().replace("_Blade_st_noFPM.st;", "_Blade_st_FPM.st;")
                      .replace("FPM 0;", "FPM 1;"))
    fpm, _ = hawc2_body(d / IEA_HTC.relative_to(IEA_HTC.parents[2]), "blade1")
    tim, _ = hawc2_body(IEA_HTC, "blade1")
    st_dir = IEA_HTC.parents[2] / "IEA-15-240-RWT"
    a = read_st(st_dir / "IEA_15MW_RWT_Blade_st_noFPM.st", 1, 1)
    b = read_st(st_dir / "IEA_15MW_RWT_Blade_st_FPM.st", 1, 1)
    Ka, _ = timoshenko_matrices({k: a[:, j] for j, k in enumerate(TIMOSHENKO_COLUMNS)})
    Kb, _ = fpm_matrices({k: b[:, j] for j, k in enumerate(FPM_COLUMNS)})
    for i, tol in ((3, 0.01), (4, 0.01), (5, 0.03)):
        np.testing.assert_allclose(Kb[:, i, i], Ka[:, i, i], rtol=tol)
    for i in (1, 2):           # shear-twist couplings, on the scale sqrt(GA GJ)
        scale = np.sqrt(Ka[:, i, i] * Ka[:, 3, 3])
        assert np.all(np.abs(Kb[:, i, 3] - Ka[:, i, 3]) < 0.05 * scale)
    got, want = _clamped(fpm)[:7], _clamped(tim)[:7]
    assert [m.family for m in got] == [m.family for m in want]
    np.testing.assert_allclose([m.frequency_hz for m in got],
                               [m.frequency_hz for m in want], rtol=3e-3)


def test_elastic_and_mass_centres_sit_where_the_windio_blade_has_them():
    """The HAWC2 st set's offsets (x_e, y_e, x_cg, y_cg, in the twisted c2 frame, relative to
    the c2_def line at the half chord) against the same design's WindIO 6x6 (IEC section
    frame, relative to the pitch-axis reference line): in hawt's untwisted blade frame, the
    reference line plus the elastic centre (-K[0,5]/K[0,0], K[0,4]/K[0,0]) and plus the mass
    centre must land at the same points.  The two reference lines lie up to 1 m apart (the
    c2 line's sweep and the chordwise step from the pitch axis), so a flipped offset or twist
    sign in either reader moves a centre by up to 1 m; tolerance 5 cm (found 2.6 cm: the
    design releases)."""
    windio = pytest.importorskip("windIO")
    from hawt_core.fem.sections import reference_line
    from hawt_core.io.windio import read_windio
    example = Path(windio.__file__).parent / "examples" / "turbine" / "IEA-15-240-RWT.yaml"
    if not example.is_file():
        pytest.skip("windio's IEA 15-MW example is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = read_windio(example).turbine.blade
    beam, _ = hawc2_body(IEA_HTC, "blade1")
    s = np.linspace(0.05, 0.95, 10)

    def centres(b):
        sec = b.sections

        def at(A, i, j):
            return np.interp(s, sec.stations, A[:, i, j])
        K, M = sec.stiffness_6x6, sec.mass_6x6
        line = reference_line(sec, b.length, s * b.length)[:, 1:]
        ec = np.stack([-at(K, 0, 5) / at(K, 0, 0), at(K, 0, 4) / at(K, 0, 0)], -1)
        cg = np.stack([at(M, 2, 3), -at(M, 1, 3)], -1) / at(M, 0, 0)[:, None]
        return line, line + ec, line + cg

    (l1, e1, c1), (l2, e2, c2) = centres(beam), centres(ref)
    assert np.abs(l1 - l2).max() > 0.5                  # the lines differ: a real check
    np.testing.assert_allclose(e1, e2, atol=0.05)
    np.testing.assert_allclose(c1, c2, atol=0.05)
