"""Tests of the turbine file format: hawt_core.io.turbine_yaml (loader, validation, writer)."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from hawt_core.io import (
    TurbineFileError,
    TurbineFileWarning,
    default_turbine_path,
    dump_turbine,
    load_turbine,
    turbine_from_dict,
    turbines_equal,
)
from hawt_core.io import turbine_yaml
from hawt_core.model import Beam, Gravity, Hub, Nacelle, Rotor, SectionTable, Turbine

DATA = Path(__file__).parent / "data"
BAD = DATA / "bad_turbines"
BAD_FILES = sorted(BAD.glob("*.yaml"))
DOCS = Path(__file__).resolve().parents[1] / "docs" / "turbine-format.md"


def default_dict() -> dict:
    """The default turbine as a plain dict (to be modified by a test)."""
    return yaml.safe_load(dump_turbine(load_turbine()))


def load_quietly(source):
    """Load with every warning turned into an error (so a test sees unexpected warnings)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_turbine(source)


def test_default_is_table_1_exactly():
    """The shipped default file loads without warnings and holds the paper's Table 1 values."""
    t = load_quietly(None)
    assert t.rotor == Rotor(speed=6.02, blades=2, precone=0.0)
    assert t.hub == Hub(radius=1.8, undersling=0.0, teeter=True, inertia_lateral=50.0,
                        inertia_longitudinal=5.0, teeter_stiffness=0.0, teeter_damping=0.0,
                        mass=0.0)
    assert t.nacelle == Nacelle(yaw_inertia=16599.0, yaw_stiffness=0.0, yaw_damping=0.0,
                                yaw_to_teeter=2.388, shaft_tilt=0.0, yaw_free=True, mass=0.0)
    assert t.blade.length == 8.42 and t.blade.elements == 4
    s = t.blade.sections
    assert s.stations.tolist() == [0.0, 1.0]
    expected = dict(mass=67.5772, i1=5.0, i2=0.0001, i3=4.9999, gj=21.8e3, ei2=4.36e6,
                    ei3=21.8e6)
    for key, value in expected.items():
        assert getattr(s, key).tolist() == [value, value], key
    assert s.ea is None and s.ga2 is None and s.ga3 is None  # inextensible, shear-rigid
    assert s.rigid_directions() == ("ea", "ga2", "ga3")
    assert s.twist is None and s.cg_offset is None and s.tension_offset is None
    assert s.stiffness_6x6 is None and s.mass_6x6 is None
    assert t.tower is None                                   # rigid tower
    assert t.gravity == Gravity(enabled=False, g=9.81)       # "in a vacuum"
    assert "2001-0064" in t.name


def test_default_path_is_package_data():
    """default_turbine_path() points at hawt_core/data/paper_turbine.yaml, and it exists."""
    p = default_turbine_path()
    assert p.name == "paper_turbine.yaml" and p.parent.name == "data" and p.is_file()
    assert turbines_equal(load_turbine(p), load_turbine())


def test_model_defaults_match_default_file():
    """The model dataclasses' defaults (Rotor(), Hub(), Nacelle()) agree with the default file."""
    t = load_turbine()
    assert (t.rotor, t.hub, t.nacelle, t.gravity) == (Rotor(), Hub(), Nacelle(), Gravity())


def test_exponent_without_sign_is_a_number(tmp_path):
    """'4.36e6' and '1e5' (no dot or no sign in the exponent: strings in YAML 1.1, numbers in
    YAML 1.2) are read as floats."""
    assert "ei2: 4.36e6" in default_turbine_path().read_text()  # the file uses this spelling
    assert load_turbine().blade.sections.ei2[0] == 4.36e6
    p = tmp_path / "t.yaml"
    p.write_text(default_turbine_path().read_text().replace("ei3: 21.8e6", "ei3: 1e5"))
    assert load_turbine(p).blade.sections.ei3[0] == 1e5


def test_dict_input_equals_file_input():
    """turbine_from_dict and load_turbine(dict) validate a mapping exactly like a file."""
    d = default_dict()
    assert turbines_equal(turbine_from_dict(d), load_turbine())
    assert turbines_equal(load_turbine(d), load_turbine())
    d["blade"]["length"] = -1.0
    with pytest.raises(TurbineFileError, match=r"<dict>: blade\.length = -1\.0"):
        turbine_from_dict(d)


def test_dict_input_accepts_numpy_values():
    """Programmatic dicts may hold numpy arrays and numpy scalars."""
    d = default_dict()
    d["blade"]["sections"]["stations"] = np.array([0.0, 0.5, 1.0])
    d["blade"]["sections"]["ei2"] = np.array([5e6, 4.5e6, 4e6])
    d["blade"]["elements"] = np.int64(3)
    d["rotor"]["speed"] = np.float64(5.0)
    t = turbine_from_dict(d)
    assert t.blade.sections.ei2.tolist() == [5e6, 4.5e6, 4e6]
    assert t.blade.elements == 3 and type(t.blade.elements) is int
    assert t.rotor.speed == 5.0 and type(t.rotor.speed) is float


def test_round_trip_default():
    """dump_turbine -> load gives back an equal model for the default turbine."""
    t = load_turbine()
    text = dump_turbine(t)
    assert turbines_equal(turbine_from_dict(yaml.safe_load(text)), t)


def test_round_trip_rich_file(tmp_path):
    """Round trip of a file using twist, offsets, EA/GA, a flexible tower and gravity; the
    dumped text is also plain YAML readable by yaml.safe_load (e.g. from MCAP metadata)."""
    t = load_quietly(DATA / "three_blade_flexible_tower.yaml")
    assert t.tower is not None and t.tower.elements == 5 and t.gravity.enabled
    s = t.blade.sections
    assert s.ea.tolist() == [5e9] * 3 and s.rigid_directions() == ()
    assert s.tension_offset.tolist() == [[0.01, 0.0]] * 3
    text = dump_turbine(t)
    path = tmp_path / "again.yaml"
    path.write_text(text)
    assert turbines_equal(load_quietly(path), t)
    assert turbines_equal(turbine_from_dict(yaml.safe_load(text)), t)
    assert dump_turbine(load_turbine(path)) == text  # the dump is stable


def test_round_trip_awkward_floats():
    """Values that are not short decimals (e.g. 1/3, pi/7) survive dump -> load bit-exactly."""
    t = load_turbine()
    from dataclasses import replace
    sec = replace(t.blade.sections, twist=np.array([np.pi / 7, -1 / 3]))
    t = replace(t, rotor=replace(t.rotor, speed=2 * np.pi / 3, precone=0.1 + 0.2),
                blade=replace(t.blade, sections=sec))
    assert turbines_equal(turbine_from_dict(yaml.safe_load(dump_turbine(t))), t)


def test_round_trip_full_matrices():
    """Round trip of a section table given by full 6x6 matrices, with .inf marking rigid
    directions; the scalar properties are taken from the matrices' diagonals."""
    K = np.diag([np.inf, 1e9, np.inf, 2e4, 4e6, 2e7])
    K[3, 4] = K[4, 3] = 1e3
    M = np.diag([60.0, 60.0, 60.0, 5.0, 1e-4, 4.9999])
    M[1, 3] = M[3, 1] = 0.5
    d = default_dict()
    d["blade"]["sections"] = {"stations": [0.0, 0.5, 1.0], "stiffness_6x6": K.tolist(),
                              "mass_6x6": [M.tolist(), (0.9 * M).tolist(), (0.8 * M).tolist()]}
    t = turbine_from_dict(d)
    s = t.blade.sections
    assert s.stiffness_6x6.shape == (3, 6, 6) and s.mass_6x6.shape == (3, 6, 6)
    assert s.rigid_directions() == ("ea", "ga3")
    assert s.ea is None and s.ga2.tolist() == [1e9] * 3 and s.ga3 is None
    assert s.gj.tolist() == [2e4] * 3 and s.mass.tolist() == [60.0, 54.0, 48.0]
    text = dump_turbine(t)
    assert ".inf" in text and "gj" not in text  # derived scalars are not repeated
    assert turbines_equal(turbine_from_dict(yaml.safe_load(text)), t)


def test_scalar_broadcast():
    """A scalar per-station property, a single [x2, x3] pair and a single 6x6 matrix are the
    same at every station."""
    d = default_dict()
    sec = d["blade"]["sections"]
    sec["stations"] = [0.0, 0.2, 0.7, 1.0]
    sec["ei2"] = [4e6, 3e6, 2e6, 1e6]
    sec["ea"] = 1e9
    sec["cg_offset"] = [0.01, -0.02]
    t = turbine_from_dict(d)
    s = t.blade.sections
    assert s.n_stations == 4
    assert s.mass.tolist() == [67.5772] * 4 and s.gj.tolist() == [21.8e3] * 4
    assert s.ei2.tolist() == [4e6, 3e6, 2e6, 1e6] and s.ea.tolist() == [1e9] * 4
    assert s.cg_offset.shape == (4, 2) and s.cg_offset.tolist() == [[0.01, -0.02]] * 4
    del sec["ei2"], sec["gj"], sec["ei3"], sec["ea"]
    sec["stiffness_6x6"] = np.diag([np.inf, np.inf, np.inf, 1.0, 2.0, 3.0]).tolist()
    s = turbine_from_dict(d).blade.sections
    assert s.stiffness_6x6.shape == (4, 6, 6) and s.ei3.tolist() == [3.0] * 4


def test_minimal_file_defaults():
    """Only the required keys: name = file stem, zero springs/dampers/offsets/masses,
    rigid tower, gravity off; integers in the file are accepted for floats."""
    t = load_quietly(DATA / "minimal_turbine.yaml")
    assert t.name == "minimal_turbine"
    assert t.rotor.precone == 0.0 and t.hub.undersling == 0.0 and t.hub.teeter_stiffness == 0.0
    assert t.nacelle.shaft_tilt == 0.0 and t.nacelle.mass == 0.0 and t.hub.mass == 0.0
    assert t.tower is None and t.gravity == Gravity()
    assert type(t.hub.inertia_lateral) is float
    assert turbines_equal(t.blade, load_turbine().blade)


def test_explicit_rigid_tower_and_null_tower_are_rigid():
    """'tower: {rigid: true}', 'tower: null' and no tower section all mean a rigid tower."""
    d = default_dict()
    for value in ({"rigid": True}, None):
        d["tower"] = value
        assert turbine_from_dict(d).tower is None
    del d["tower"]
    assert turbine_from_dict(d).tower is None


def _expected_fragments(path: Path) -> list:
    first = path.read_text().splitlines()[0]
    assert first.startswith("# expect:"), f"{path.name}: first line must be '# expect: ...'"
    return [f.strip() for f in first.split(":", 1)[1].split("|")]


def test_enough_bad_files():
    """There are at least 15 distinct bad turbine files, each with an expectation line."""
    assert len(BAD_FILES) >= 15
    assert all(_expected_fragments(p) for p in BAD_FILES)


@pytest.mark.parametrize("path", BAD_FILES, ids=[p.stem for p in BAD_FILES])
def test_bad_file_is_rejected_with_a_clear_message(path):
    """Each bad file (one defect each) raises TurbineFileError whose message names the file,
    the field (dotted path) and the offending value, as listed on the file's first line."""
    with pytest.raises(TurbineFileError) as info:
        load_turbine(path)
    message = str(info.value)
    assert str(path) in message and info.value.source == str(path)
    for fragment in _expected_fragments(path):
        assert fragment in message, f"{fragment!r} not in {message!r}"
    assert len(info.value.errors) == 1, f"expected exactly one problem: {message}"


def test_error_is_a_value_error_and_lists_several_problems():
    """Several problems are reported together, first one first, and the error is a ValueError."""
    d = default_dict()
    d["rotor"]["speed"] = "fast"
    d["blade"]["sections"]["gj"] = -1.0
    d["hub"]["colour"] = "red"
    with pytest.raises(ValueError) as info:
        turbine_from_dict(d)
    err = info.value
    assert isinstance(err, TurbineFileError) and len(err.errors) == 3
    assert "3 problems" in str(err)
    assert err.errors[0].startswith("rotor.speed = 'fast': must be a number")  # file order
    assert any(e.startswith("hub.colour: unknown key") for e in err.errors)
    assert any(e.startswith("blade.sections.gj = -1.0: must be > 0") for e in err.errors)


def test_missing_file():
    """A missing file is a TurbineFileError naming the path, not a FileNotFoundError."""
    with pytest.raises(TurbineFileError, match=r"no_such_turbine\.yaml: file not found"):
        load_turbine(DATA / "no_such_turbine.yaml")


def test_empty_file(tmp_path):
    """An empty file is a TurbineFileError naming the path."""
    p = tmp_path / "empty.yaml"
    p.write_text("# nothing here\n")
    with pytest.raises(TurbineFileError, match="empty.yaml: the file is empty"):
        load_turbine(p)


def test_i1_inconsistent_warns():
    """I1 differing from I2 + I3 by more than 1 % gives a TurbineFileWarning naming the
    station, not an error; within 1 % there is no warning."""
    d = default_dict()
    d["blade"]["sections"]["stations"] = [0.0, 0.5, 1.0]
    d["blade"]["sections"]["i1"] = [5.0, 5.2, 5.0]
    with pytest.warns(TurbineFileWarning, match=r"blade\.sections\.i1\[1\] = 5\.2 .* by 4 %"):
        t = turbine_from_dict(d)
    assert t.blade.sections.i1.tolist() == [5.0, 5.2, 5.0]
    d["blade"]["sections"]["i1"] = 5.04  # 0.8 % off: fine
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        turbine_from_dict(d)


def test_scalar_contradicting_matrix_warns():
    """A scalar property given alongside a full 6x6 matrix that disagrees with its diagonal
    warns (the matrix is used)."""
    d = default_dict()
    d["blade"]["sections"]["stiffness_6x6"] = np.diag([np.inf, np.inf, np.inf, 2e4, 4.36e6,
                                                       21.8e6]).tolist()
    with pytest.warns(TurbineFileWarning, match=r"blade\.sections\.gj .* the matrix is used"):
        turbine_from_dict(d)


def test_stiffness_rigid_direction_must_be_decoupled():
    """In a stiffness_6x6, a rigid (.inf) direction must have zeros off the diagonal."""
    K = np.diag([np.inf, 1e9, 1e9, 2e4, 4e6, 2e7])
    K[0, 5] = K[5, 0] = 1.0
    d = default_dict()
    sec = d["blade"]["sections"]
    for key in ("gj", "ei2", "ei3"):
        del sec[key]
    sec["stiffness_6x6"] = K.tolist()
    with pytest.raises(TurbineFileError, match=r"stiffness_6x6\[0\]\[5\] = 1\.0: row and col"):
        turbine_from_dict(d)


def test_programmatic_turbine_round_trip():
    """A Turbine built directly from the model classes dumps and loads back equal."""
    sec = SectionTable(stations=[0.0, 0.4, 1.0], mass=[10.0, 8.0, 6.0], i1=[1.0, 0.8, 0.6],
                       i2=[0.1, 0.08, 0.06], i3=[0.9, 0.72, 0.54], gj=[1e4, 8e3, 6e3],
                       ei2=[1e5, 8e4, 6e4], ei3=[1e6, 8e5, 6e5], ga2=[1e8, 1e8, 1e8])
    t = Turbine(name="built in code", rotor=Rotor(speed=3.0, blades=4), hub=Hub(teeter=False),
                nacelle=Nacelle(yaw_free=False), blade=Beam(length=5.0, sections=sec, elements=3),
                tower=Beam(length=30.0, sections=sec, elements=2),
                gravity=Gravity(enabled=True, g=9.80665))
    back = turbine_from_dict(yaml.safe_load(dump_turbine(t)))
    assert turbines_equal(back, t)
    assert back.blade.sections.rigid_directions() == ("ea", "ga3")


def test_turbines_equal_detects_differences():
    """turbines_equal is exact: a one-ulp change in one station value makes turbines differ."""
    from dataclasses import replace
    t = load_turbine()
    ei2 = t.blade.sections.ei2.copy()
    ei2[1] = np.nextafter(ei2[1], np.inf)
    other = replace(t, blade=replace(t.blade, sections=replace(t.blade.sections, ei2=ei2)))
    assert turbines_equal(t, load_turbine()) and not turbines_equal(t, other)
    assert not turbines_equal(t, t.with_elements(3))


def _doc_examples():
    if not DOCS.exists():
        return []
    return re.findall(r"```yaml\n(.*?)```", DOCS.read_text(), flags=re.S)


def test_documentation_examples_load(tmp_path):
    """Every complete YAML example in docs/turbine-format.md (blocks with a 'rotor:' section)
    loads without errors or warnings."""
    examples = [e for e in _doc_examples() if re.search(r"^rotor:", e, flags=re.M)]
    assert examples, "docs/turbine-format.md has no complete example"
    for k, text in enumerate(examples):
        p = tmp_path / f"doc_example_{k}.yaml"
        p.write_text(text)
        load_quietly(p)


def test_documentation_section_snippets_load():
    """Every 'sections:' YAML snippet in docs/turbine-format.md is a valid blade section table."""
    snippets = [e for e in _doc_examples() if e.startswith("sections:")]
    assert snippets, "docs/turbine-format.md has no sections example"
    for text in snippets:
        d = default_dict()
        d["blade"]["sections"] = yaml.load(text, Loader=turbine_yaml._Loader)["sections"]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            t = turbine_from_dict(d)
        assert t.blade.sections.stiffness_6x6 is not None


# ---------------------------------------------------------------------------- aerodynamics
def _aero() -> dict:
    """A small valid aerodynamics block: 3 stations, two polars."""
    foil = lambda name, k: {"name": name, "reynolds": 6e6, "thickness": 0.2 * k,
                            "alpha": [-3.1, -0.1, 0.0, 0.2, 3.1],
                            "cl": [0.0, -0.5, 0.1, 1.2, 0.0], "cd": [0.02, 0.01, 0.008, 0.02, 0.05],
                            "cm": [0.0, -0.05, -0.06, -0.08, 0.0]}
    return {"stations": [0.0, 0.5, 1.0], "chord": [3.0, 2.5, 1.0], "twist": [0.2, 0.05, 0.0],
            "airfoil": [0, 1, 1], "polars": [foil("thick", 2), foil("thin", 1)]}


def test_aerodynamics_round_trip_and_in_vacuum_note(tmp_path, capsys):
    """Reference: the file format (docs/turbine-format.md, aerodynamics): the block reads to
    model.Aerodynamics and writes back to an equal turbine; the structural analyses say
    they run in a vacuum."""
    from hawt_core import cli
    d = default_dict()
    d["aerodynamics"] = _aero()
    t = turbine_from_dict(d)
    a = t.aerodynamics
    assert a.airfoil.tolist() == [0, 1, 1] and a.polars[1].name == "thin"
    assert a.polars[0].thickness == 0.4 and a.polars[0].cm[2] == -0.06
    assert turbines_equal(turbine_from_dict(yaml.safe_load(dump_turbine(t))), t)
    f = tmp_path / "aero.yaml"
    f.write_text(dump_turbine(t))
    assert cli.main(["blade-modes", str(f), "--count", "2"]) == 0
    assert "in a vacuum" in capsys.readouterr().out


@pytest.mark.parametrize("edit,words", [
    (lambda a: a["polars"][0].update(alpha=[-180.0, 0.0, 5.0, 10.0, 180.0]),
     ["aerodynamics.polars[0].alpha", "radians"]),
    (lambda a: a["polars"][1].update(alpha=[0.0, -0.1, 0.2, 0.3, 0.4]),
     ["aerodynamics.polars[1].alpha", "increasing"]),
    (lambda a: a["polars"][0].update(cd=[0.02, -0.01, 0.008, 0.02, 0.05]),
     ["aerodynamics.polars[0].cd[1]", ">= 0"]),
    (lambda a: a["polars"][0].update(cl=[0.0, 1.0]), ["aerodynamics.polars[0].cl", "stations"]),
    (lambda a: a.update(airfoil=[0, 2, 1]), ["aerodynamics.airfoil[1]", "0 to 1"]),
    (lambda a: a.update(chord=[3.0, 0.0, 1.0]), ["aerodynamics.chord[1]", "> 0"]),
    (lambda a: a.update(polars=[]), ["aerodynamics.polars", "at least one"]),
    (lambda a: a.pop("twist"), ["aerodynamics.twist", "required"]),
    (lambda a: a["polars"][0].update(lift=[1.0]), ["aerodynamics.polars[0].lift", "unknown"]),
])
def test_bad_aerodynamics_are_refused_naming_the_key(edit, words):
    """Reference: the loader's contract: an error naming the key, the value and what is
    allowed."""
    d = default_dict()
    d["aerodynamics"] = _aero()
    edit(d["aerodynamics"])
    with pytest.raises(TurbineFileError) as ex:
        turbine_from_dict(d)
    for w in words:
        assert w in str(ex.value), (w, str(ex.value))
