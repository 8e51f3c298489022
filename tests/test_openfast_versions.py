"""OpenFAST decks of every version in use (issue 35, item 1): every file read by its keys
(hawt_core/io/openfast_keys.py), so decks of the v3.0-and-earlier (Gravity in ElastoDyn), v3.2,
v3.x, v3.5-v4 and v5 layouts come in.

References: decks that describe the same turbine in two layouts must import to the same
turbine, to the numbers' printed digits (the files hold the same numbers): the IEA 15-MW
reference turbine's own deck (IEAWindTask37/IEA-15-240-RWT, v3.5-v4 layout) against the rosco
wheel's (v5, from which the shipped ``iea15mw.yaml`` is made); the NREL 5-MW's blade,
aerodynamics and tower in openfast_toolbox's v3.2 and v3.x decks against the rosco wheel's
NREL-5MW; the AOC 15/50 deck of OpenFAST's Homebrew formula in its v3.0 and v4.0 layouts.
Sources and trimming: tests/data/openfast/README.md.  The key parser's rules are
checked on small files written here."""
from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from hawt_core.io import TurbineFileError, turbines_equal
from hawt_core.io.catalog import load_any
from hawt_core.io.openfast import LATER_KEYS, read_openfast
from hawt_core.io.openfast_keys import KeyedFileError, read_keyed

DATA = Path(__file__).parent / "data" / "openfast"
LIN_V32 = DATA / "NREL5MW" / "5MW_Land_Lin_Rotating" / "Main.fst"
ONSHORE_BD = DATA / "NREL5MW" / "Main_Onshore_OF2_BD.fst"
IEA_V4 = DATA / "IEA15MW" / "IEA-15-240-RWT-Monopile" / "IEA-15-240-RWT-Monopile.fst"
AOC_V30 = DATA / "AOC15_50" / "v3.0" / "homebrew.fst"
AOC_V40 = DATA / "AOC15_50" / "v4.0" / "homebrew.fst"


def _with_torsion_of(turbine, other):
    """``turbine`` with ``other``'s blade torsion and rotary inertia: the rosco wheel's
    decks name a BeamDyn blade, which supplies them (CompElast 1), the older decks do not
    (the importer's warned estimate, a torsionally rigid blade)."""
    sec = replace(turbine.blade.sections, **{k: getattr(other.blade.sections, k)
                                             for k in ("gj", "i1", "i2", "i3")})
    return replace(turbine, blade=replace(turbine.blade, sections=sec))


def _shipped(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_any(name)


def test_the_iea15mw_reference_deck_is_the_rosco_decks_turbine():
    """The IEA-15-240-RWT repository's own deck (v3.5-v4 layout: ``BldFile1`` keys, no
    NRotors, ModCoupling, RhoInf ...; openfast-io 5 refused it at ``DT_UJac = '99999.0'``)
    imports to exactly the turbine of the rosco wheel's v5 deck (the shipped iea15mw), but
    for the aerodynamics the trimmed copy leaves out (CompAero 0) and the blade's torsion
    (_with_torsion_of: this deck names no BeamDyn blade).  The keys older layouts
    lack are warned by name with the value taken."""
    r = read_openfast(IEA_V4)
    ship = _shipped("iea15mw")
    assert any("no torsional rigidity" in w for w in r.warnings)
    assert turbines_equal(replace(_with_torsion_of(r.turbine, ship), name="x"),
                          replace(ship, name="x", aerodynamics=None, tower_aerodynamics=None))
    missing = [w for w in r.warnings if "missing (an older OpenFAST layout)" in w]
    assert missing and all(any(k in w for k in LATER_KEYS["ElastoDyn"]) for w in missing)


def test_the_nrel5mw_v32_linearization_deck_has_the_rosco_decks_blade_and_aerodynamics():
    """openfast_toolbox's 5MW_Land_Lin_Rotating (OpenFAST v3.2, the MBC3 case of issue 34;
    openfast-io 5 refused it at ``DT_UJac = '1.5'``): its ElastoDyn blade, AeroDyn blade and
    airfoil polars are the NREL 5-MW's, so they equal the shipped nrel5mw's (from the rosco
    v5 deck) exactly (but the blade's torsion: _with_torsion_of); its own settings come in as written: 9 rpm, tower DOFs off (rigid),
    precone -2.5 deg, AeroDyn's AIDrag = False warned as not taken."""
    r = read_openfast(LIN_V32)
    t, ship = r.turbine, _shipped("nrel5mw")
    assert turbines_equal(replace(_with_torsion_of(t, ship), name="x", rotor=ship.rotor,
                                  tower=ship.tower,
                                  drivetrain=ship.drivetrain, nacelle=ship.nacelle,
                                  tower_aerodynamics=ship.tower_aerodynamics,
                                  gravity=ship.gravity),
                          replace(ship, name="x"))
    assert t.rotor.speed == pytest.approx(9.0 * np.pi / 30.0, rel=1e-15)
    assert t.tower is None and np.degrees(t.rotor.precone) == pytest.approx(-2.5)
    assert any("AIDrag = False" in w for w in r.warnings)


def test_the_aoc_deck_in_the_v30_and_v40_layouts_is_one_turbine():
    """OpenFAST's Homebrew formula tests the same AOC 15/50 deck (FAST certification test
    #08) in each release's layout: v3.0.0 (the .fst without an environmental section,
    Gravity in ElastoDyn: OpenFAST's layout before v3.1) and v4.0.0 (Gravity in the .fst,
    MHK).  Reference: the two import to the same turbine, the only difference the gravity
    the decks write (9.80665 and 9.8066); the deck's numbers as read (64.14 rpm, 6 deg
    precone, 1.54 deg pitch, TipRad - HubRad, TowerHt)."""
    old, new = read_openfast(AOC_V30), read_openfast(AOC_V40)
    a, b = old.turbine, new.turbine
    assert a.gravity.g == 9.80665 and b.gravity.g == 9.8066
    assert any("Gravity was ElastoDyn's" in n for n in old.notes)
    assert turbines_equal(replace(a, name="x", gravity=b.gravity), replace(b, name="x"))
    assert a.rotor.speed == pytest.approx(64.14 * np.pi / 30, rel=1e-15)
    assert a.rotor.precone == pytest.approx(np.radians(6.0), rel=1e-15)
    assert a.rotor.pitch == pytest.approx(-np.radians(1.54), rel=1e-15)
    assert a.blade.length == pytest.approx(7.49 - 0.28, rel=1e-15)
    assert a.tower.length == pytest.approx(24.4, rel=1e-15)


def test_a_v3_deck_with_beamdyn_blades_comes_in():
    """openfast_toolbox's Main_Onshore_OF2_BD (OpenFAST v3.x: BeamDyn blade file without
    the modal-damping lines, ElastoDyn without PitchDOF): the BeamDyn blade's first station
    as the file prints it (mass 678.935 kg/m, EA 9.72948e9 N, its mu 1e-3 .. 2.2e-3 s) and
    the same tower as the rosco NREL-5MW's (the same tower file)."""
    r = read_openfast(ONSHORE_BD)
    t, ship = r.turbine, _shipped("nrel5mw")
    assert t.blade.sections.mass[0] == pytest.approx(678.935, rel=1e-12)
    assert t.blade.sections.ea[0] == pytest.approx(9.729480e9, rel=1e-12)
    assert any("mu = 0.001 0.001 0.001 0.0014 0.0022 0.0022 s" in n for n in r.notes)
    for k in ("mass", "ei2", "ei3", "gj"):
        np.testing.assert_array_equal(getattr(t.tower.sections, k),
                                      getattr(ship.tower.sections, k))


def test_the_key_parser_rules(tmp_path):
    """Rules (openfast_keys.py): a value then its key; quoted values with spaces; negative
    numbers are values, not section rules; indexed keys also without parentheses; True /
    False any case; a table's header line is no key; a table read by its column names (a
    trailing comment is no column); a list of quoted names (AFNames)."""
    f = tmp_path / "x.dat"
    f.write_text("\n".join([
        "------- header ------",
        "-2.5          PreCone(1)  - cone",
        '"a b.dat"     SomeFile    - a name with a space',
        "true          Flag        - a flag",
        "3             NRows       - rows",
        "2             NumNames    - names",
        '"n1.dat"      Names       - first',
        '"n2.dat"',
        "-------- table ------",
        "Col1   Col2   Col3   ! Col3 only sometimes",
        "(m)    (-)    (-)",
        "0.0    1.0    2.0",
        "0.5    1.5    2.5",
        "1.0    2.0    3.0",
    ]) + "\n")
    kf = read_keyed(f)
    assert kf.values["PreCone(1)"] == -2.5 and kf.values["PreCone1"] == -2.5
    assert kf.values["SomeFile"] == "a b.dat" and kf.values["Flag"] is True
    assert "Col2" not in kf.values and kf.lines["NRows"] == 5
    tab = kf.table("Col1", "NRows")
    assert tab == {"Col1": [0.0, 0.5, 1.0], "Col2": [1.0, 1.5, 2.0], "Col3": [2.0, 2.5, 3.0]}
    assert kf.strings("Names", "NumNames") == ["n1.dat", "n2.dat"]
    f.write_text(f.read_text().replace("0.5    1.5    2.5", "0.5    1.5"))
    with pytest.raises(KeyedFileError, match=r"line 13.*row 2 of 3"):
        read_keyed(f).table("Col1", "NRows")


def test_a_required_key_missing_is_named(tmp_path):
    """A key the importer needs and no version lacks (ElastoDyn ``TipRad``) removed: refused
    with the file and the key's name, at once."""
    import shutil
    d = tmp_path / "NREL5MW"
    shutil.copytree(DATA / "NREL5MW", d)
    ed = d / "5MW_Land_Lin_Rotating" / "ElastoDyn.dat"
    ed.write_text("\n".join(ln for ln in ed.read_text(errors="replace").splitlines()
                            if " TipRad " not in ln) + "\n")
    with pytest.raises(TurbineFileError, match=r"ElastoDyn.dat: TipRad: required key is "
                                               r"missing"):
        read_openfast(d / "5MW_Land_Lin_Rotating" / "Main.fst")
