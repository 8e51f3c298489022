"""Hostile and mistaken input: every file below is refused in well under a second and a few
megabytes, with a message naming the file, the field and the limit; every command line below is
refused with the whole allowed range, the same range the turbine file, the node's parameters and
its service requests state (one validator per quantity, hawt_core.numerics.checks; one set of
limits, hawt_core.numerics.limits, documented in docs/turbine-format.md).

Reference: the limits themselves (each test checks that the message names the limit and that
the refusal is fast and small); tolerances: < 1 s wall time and < 200 MB of Python allocations
(tracemalloc peak) per refused file, the issue's bounds.
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import time
import tracemalloc
from pathlib import Path

import pytest

from hawt_core.io.catalog import load_any
from hawt_core.io.turbine_yaml import (TurbineFileError, _parse_yaml, default_turbine_path,
                                       turbine_from_dict)
from hawt_core.numerics import limits
from hawt_core.numerics.checks import check_rotor_speed, check_step_deg

TIME_LIMIT_S = 1.0
MEMORY_LIMIT_B = 200 * 2**20

PAPER = default_turbine_path().read_text()


def bomb(levels: int = 9) -> str:
    """A billion-laughs YAML fragment: anchors a0..a{levels-1}, each nine of the previous,
    so that *a{levels-1} expands to 9**levels strings."""
    lines = ['x0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for k in range(1, levels):
        lines.append(f"x{k}: &a{k} [" + ",".join([f"*a{k - 1}"] * 9) + "]")
    return "\n".join(lines)


def _with(text: str, key: str, value: str) -> str:
    """The paper's file with the first ``key: ...`` line's value replaced."""
    out, n = re.subn(rf"^(\s*{key}:)\s*[^#\n]*", rf"\g<1> {value}  ", text, count=1, flags=re.M)
    assert n == 1, key
    return out


def _paper_dict() -> dict:
    return _parse_yaml(PAPER, "paper")


def _stations_file(n: int) -> str:
    """The paper's (uniform) blade given at n stations."""
    stations = ", ".join(f"{i / (n - 1):.9g}" for i in range(n))
    out = PAPER.replace("    stations: [0.0, 1.0]", f"    stations: [{stations}]")
    assert out != PAPER
    return out


def _bomb_in(where: str) -> str:
    """The alias bomb (anchors in extra top-level keys: the file is refused before its keys
    are checked) used as the value of ``name``, ``blade.sections.mass`` or ``rotor``."""
    d = {"name": _with(PAPER, "name", "*a8"),
         "mass": PAPER.replace("    mass: 67.5772", "    mass: *a8"),
         "rotor": re.sub(r"^rotor:\n(?:[ \t]+.*\n)+", "rotor: *a8\n", PAPER, count=1,
                         flags=re.M)}[where]
    assert d != PAPER
    return bomb() + "\n" + d


HOSTILE_FILES = {
    # name: (file text or a callable(path) making the file, words the message must contain)
    "alias bomb in name": (lambda: _bomb_in("name"), ["MAX_YAML_VALUES", "alias"]),
    "alias bomb in blade.sections.mass": (lambda: _bomb_in("mass"), ["MAX_YAML_VALUES"]),
    "alias bomb as rotor": (lambda: _bomb_in("rotor"), ["MAX_YAML_VALUES"]),
    "50 MB file": (lambda: PAPER + "\n#" + "x" * 50_000_000 + "\n",
                   ["MAX_FILE_BYTES", "50"]),
    "3 million stations": (lambda: _stations_file(3_000_000), ["MAX_FILE_BYTES"]),
    "20000 stations": (lambda: _stations_file(20_000),
                       ["blade.sections.stations", "20000", "MAX_STATIONS"]),
    "20000 polar angles": (lambda: PAPER + "aerodynamics: {stations: [0, 1], chord: 1, twist: 0, "
                           "airfoil: 0, polars: [{name: a, alpha: [" + ", ".join(
                               f"{i * 1e-4:.4f}" for i in range(20_000)) + "], cl: 0, cd: 0, "
                           "cm: 0}]}\n", ["aerodynamics.polars[0].alpha", "MAX_POLAR_ANGLES"]),
    "100000 elements": (lambda: _with(PAPER, "elements", "100000"),
                        ["blade.elements", "100000", "MAX_ELEMENTS", "512"]),
    "elements 1e30": (lambda: _with(PAPER, "elements", "1e30"),
                      ["blade.elements", "1e+30", "MAX_ELEMENTS"]),
    "400-digit speed": (lambda: _with(PAPER, "speed", "9" * 400),
                        ["rotor.speed", "400 digits"]),
    "speed 1e6 rad/s": (lambda: _with(PAPER, "speed", "1e6"),
                        ["rotor.speed", "MAX_ROTOR_SPEED", "100"]),
    "a million blades": (lambda: _with(PAPER, "blades", "1000000"),
                         ["rotor.blades", "MAX_BLADES"]),
    "nesting 100k deep": (lambda: _with(PAPER, "name", "[" * 100_000 + "]" * 100_000),
                          ["MAX_YAML_DEPTH", "32"]),
    "nesting 40 deep": (lambda: _with(PAPER, "name", "[" * 40 + "]" * 40),
                        ["MAX_YAML_DEPTH"]),
    "a 1 MB name": (lambda: _with(PAPER, "name", "x" * 1_000_000), ["MAX_SCALAR_CHARS"]),
    "100000 unknown keys": (lambda: PAPER + "".join(f"k{i}: 1\n" for i in range(100_000)),
                            ["MAX_YAML_VALUES"]),
    "5000 unknown keys": (lambda: PAPER + "".join(f"k{i}: 1\n" for i in range(5000)),
                          ["unknown key", "k0", "k19", "more"]),
    # legal in size (refused for its content): parsed in full, so timed by its size, not
    # by a limit; the memory bound holds, the time is PyYAML's (about 0.5 s unloaded)
    "values just below MAX_YAML_VALUES": (
        lambda: _with(PAPER, "name", "[" + ", ".join(["1"] * (limits.MAX_YAML_VALUES - 100))
                      + "]"), ["name", "text string"]),
}


#: cases parsed in full (legal in size): their wall time is PyYAML's, not a limit's
UNTIMED = {"values just below MAX_YAML_VALUES"}


@pytest.mark.parametrize("case", list(HOSTILE_FILES))
def test_hostile_file_refused_fast_and_small(tmp_path, case):
    make, words = HOSTILE_FILES[case]
    path = tmp_path / "hostile.yaml"
    path.write_text(make())
    t0 = time.perf_counter()
    with pytest.raises(TurbineFileError) as info:
        load_any(path)
    elapsed = time.perf_counter() - t0
    tracemalloc.start()                 # again, for the memory (tracemalloc slows it down)
    try:
        with pytest.raises(TurbineFileError):
            load_any(path)
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    msg = str(info.value)
    assert str(path) in msg
    for w in words:
        assert w in msg, (w, msg[:500])
    assert len(msg) < 5000, len(msg)
    if case not in UNTIMED:
        assert elapsed < TIME_LIMIT_S, (case, elapsed)
    assert peak < MEMORY_LIMIT_B, (case, peak / 2**20)


def test_non_regular_files_refused(tmp_path):
    """A FIFO (opening it would block until a writer comes) and a folder: refused before they
    are opened, by every reader load_any dispatches to (hawt, OpenFAST, WindIO)."""
    fifo = tmp_path / "turbine.yaml"
    os.mkfifo(fifo)
    deck = tmp_path / "deck.fst"
    os.mkfifo(deck)
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    for p, words in ((fifo, ["not a regular file"]), (deck, ["not a regular file"]),
                     (folder, ["folder"])):
        t0 = time.perf_counter()
        with pytest.raises(TurbineFileError, match=re.escape(str(p))) as info:
            load_any(p)
        assert time.perf_counter() - t0 < TIME_LIMIT_S
        for w in words:
            assert w in str(info.value)


def test_legal_files_still_load():
    """The limits refuse nothing real: the shipped turbines (the IEA 15-MW file with its 56
    polars is the largest) load."""
    for name in ("paper", "three-blade", "nrel5mw", "iea15mw"):
        with contextlib.suppress(Warning):
            t = load_any(name)
        assert t.blade.elements <= limits.MAX_ELEMENTS


def test_the_limits_are_at_their_edges(tmp_path):
    """Exactly at a limit is allowed, one beyond is refused (elements, blades, rotor speed;
    nesting depth through the file)."""
    d = _paper_dict()
    d["blade"]["elements"] = limits.MAX_ELEMENTS
    assert turbine_from_dict(d).blade.elements == limits.MAX_ELEMENTS
    d["blade"]["elements"] = limits.MAX_ELEMENTS + 1
    with pytest.raises(TurbineFileError, match="MAX_ELEMENTS"):
        turbine_from_dict(d)
    d = _paper_dict()
    d["rotor"]["speed"] = limits.MAX_ROTOR_SPEED
    assert turbine_from_dict(d).rotor.speed == limits.MAX_ROTOR_SPEED
    d["rotor"]["speed"] = limits.MAX_ROTOR_SPEED * 1.001
    with pytest.raises(TurbineFileError, match="MAX_ROTOR_SPEED"):
        turbine_from_dict(d)
    ok = tmp_path / "ok.yaml"      # depth MAX_YAML_DEPTH in all: the top mapping + the rest
    ok.write_text("name: x\nextra: " + "[" * (limits.MAX_YAML_DEPTH - 1)
                  + "]" * (limits.MAX_YAML_DEPTH - 1) + "\n")
    with pytest.raises(TurbineFileError) as info:
        load_any(ok)
    assert "MAX_YAML_DEPTH" not in str(info.value)    # refused for its content, not depth
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: x\nextra: " + "[" * limits.MAX_YAML_DEPTH
                    + "]" * limits.MAX_YAML_DEPTH + "\n")
    with pytest.raises(TurbineFileError, match="MAX_YAML_DEPTH"):
        load_any(deep)


def test_programmatic_dict_with_huge_values():
    """A dict built in Python (no YAML limits apply): a million-entry list and a huge integer
    are refused with a short message (bounded rendering of the value)."""
    d = _paper_dict()
    d["blade"]["sections"]["mass"] = [1.0] * 1_000_000
    d["name"] = "y" * 10**6
    t0 = time.perf_counter()
    with pytest.raises(TurbineFileError) as info:
        turbine_from_dict(d)
    assert time.perf_counter() - t0 < TIME_LIMIT_S
    msg = str(info.value)
    assert "blade.sections.mass" in msg and len(msg) < 2000


# ------------------------------------------------------------------------ command line
def _cli(*argv) -> tuple:
    from hawt_core.cli import main
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(list(argv))
    return code, err.getvalue()


@pytest.mark.parametrize("argv, words", [
    (["simulate", "--duration", "1", "--perturb", "teeter=1e9"],
     ["teeter", "1e9", "-1 to 1 [rad]"]),
    (["simulate", "--duration", "1", "--perturb", "teeter_rate=5"],
     ["teeter_rate", "-2 to 2 [rad/s]"]),
    (["simulate", "--duration", "1", "--perturb", "teeter=0.02,teeter=0.03"],
     ["teeter", "twice"]),
    (["simulate", "--duration", "1", "--step-deg", "1000"], ["--step-deg", "<= 10"]),
    (["simulate", "--duration", "1", "--elements", "100000"], ["--elements", "1 to 512"]),
    (["campbell", "--speeds", "6:6:3"], ["--speeds", "START (6) < STOP"]),
    (["campbell", "--speeds", "1:200:3"], ["--speeds", "<= 100"]),
    (["modes", "--rotor-speed", "-1"], ["--rotor-speed", ">= 0 and <= 100 [rad/s]"]),
    (["modes", "--rotor-speed", "1e6"], ["--rotor-speed", ">= 0 and <= 100 [rad/s]"]),
    (["modes", "--steps", "0"], ["--steps", "from 8 to 1000000"]),
    (["modes", "--steps", "1"], ["--steps", "from 8 to 1000000"]),
    (["modes", "--elements", "0"], ["--elements", "from 1 to 512"]),
    (["blade-modes", "--elements", "1e30"], ["--elements", "from 1 to 512"]),
])
def test_command_line_refused_with_the_allowed_range(argv, words):
    t0 = time.perf_counter()
    code, err = _cli(*argv)
    assert time.perf_counter() - t0 < TIME_LIMIT_S
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)


def test_one_range_per_quantity_at_every_entry_point():
    """The rotor speed's and the step's allowed ranges read the same from the command line,
    the turbine file, the node's parameters and its service requests (one validator each)."""
    from hawt_ros.params import ParameterError, validate_parameter, validate_request
    top = f"<= {limits.MAX_ROTOR_SPEED:g}"
    _, cli = _cli("modes", "--rotor-speed", "1e6")
    d = _paper_dict()
    d["rotor"]["speed"] = 1e6
    with pytest.raises(TurbineFileError) as file_err:
        turbine_from_dict(d)
    with pytest.raises(ParameterError) as request:
        validate_request(rotor_speed=1e6)
    with pytest.raises(ValueError) as core:
        check_rotor_speed(1e6)
    for text in (cli, str(file_err.value), str(request.value), str(core.value)):
        assert top in text and "rad/s" in text, text
    step = f"<= {limits.MAX_STEP_DEG:g}"
    _, cli = _cli("simulate", "--duration", "1", "--step-deg", "30")
    with pytest.raises(ParameterError) as param:
        validate_parameter("step_deg", 30.0)
    with pytest.raises(ValueError) as core:
        check_step_deg(30.0)
    for text in (cli, str(param.value), str(core.value)):
        assert step in text, text
    assert validate_parameter("step_deg", limits.MAX_STEP_DEG) == limits.MAX_STEP_DEG
    # elements: the same maximum for the command line, the file and the node
    with pytest.raises(ParameterError, match=f"1 to {limits.MAX_ELEMENTS}"):
        validate_parameter("elements", limits.MAX_ELEMENTS + 1)
    with pytest.raises(ParameterError, match=f"1 to {limits.MAX_ELEMENTS}"):
        validate_request(elements=limits.MAX_ELEMENTS + 1)
    # a perturbation beyond the limits: refused by the node's parameter as by the CLI
    with pytest.raises(ParameterError, match=r"-1 to 1 \[rad\]"):
        validate_parameter("perturb", "teeter=1e9")


def test_limits_are_documented():
    """docs/turbine-format.md lists every limit with its value (the table is checked, not
    trusted)."""
    doc = (Path(__file__).resolve().parent.parent / "docs" / "turbine-format.md").read_text()
    section = doc.split("## Limits", 1)[1]
    for name, (value, unit, _what) in limits.LIMITS.items():
        row = [line for line in section.splitlines() if f"`{name}`" in line]
        assert row, name
        assert f"{value:g}" in row[0].replace(",", "").replace(" ", "") or \
            str(value) in row[0].replace(",", ""), (name, row[0])
