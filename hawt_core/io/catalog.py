"""Where a turbine comes from: a shipped short name, a hawt file, an OpenFAST deck, a HAWC2
model or a WindIO file.

``load_any(spec)`` is what every command and the ROS node take as TURBINE:

- ``None``: the paper's Table 1 turbine (the default);
- a short name of a turbine shipped with hawt (``SHIPPED``: ``paper``, ``nrel5mw``,
  ``iea15mw``, ...; :func:`shipped_turbines` lists them with what they are);
- a path ending in ``.fst``: an OpenFAST deck, imported by :mod:`hawt_core.io.openfast`
  (any OpenFAST version's layout, read by its keys); its warnings are issued as TurbineFileWarning;
- a path ending in ``.htc``: a HAWC2 model, imported by :mod:`hawt_core.io.hawc2_turbine`
  (its st, ae, pc files and operational data beside it), warnings likewise;
- a YAML file whose top-level keys are WindIO's (``windIO_version``, ``assembly``,
  ``components``): a WindIO turbine, imported by :mod:`hawt_core.io.windio` (needs the
  optional ``windio``), warnings likewise;
- any other path: a hawt turbine file (YAML, docs/turbine-format.md).

The shipped NREL 5-MW and IEA 15-MW files were converted by hawt's importer from the decks
the ``rosco`` wheel installs; their header comment names the source and importer version.
"""
from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path
from typing import Optional

from ..model import Turbine
from .turbine_yaml import (TurbineFileError, TurbineFileWarning, check_regular_file,
                           default_turbine_path, load_turbine)

__all__ = ["SHIPPED", "shipped_path", "shipped_turbines", "load_any", "describe", "is_windio",
           "rosco_test_cases", "shipped_controller", "SHIPPED_CONTROLLERS"]

_DATA = Path(__file__).resolve().parent.parent / "data"

#: short name -> file in hawt_core/data
SHIPPED = {
    "paper": "paper_turbine.yaml",
    "three-blade": "three_blade_rotor.yaml",
    "nrel5mw": "nrel5mw.yaml",
    "iea15mw": "iea15mw.yaml",
}


#: The rosco wheel's controller file (DISCON.IN) of each shipped turbine, under its
#: Examples/Test_Cases.
SHIPPED_CONTROLLERS = {
    "nrel5mw": "NREL-5MW/DISCON.IN",
    "iea15mw": "IEA-15-240-RWT/IEA-15-240-RWT-Monopile/IEA-15-240-RWT-Monopile_DISCON.IN",
}


def rosco_test_cases() -> Optional[Path]:
    """The rosco wheel's Examples/Test_Cases folder (complete OpenFAST decks, airfoil polars,
    DISCON.IN and Cp_Ct_Cq files; the wheel installs a top-level ``Examples`` package), or
    None when the wheel is not installed."""
    spec = importlib.util.find_spec("Examples")
    if spec is None or not spec.submodule_search_locations:
        return None
    root = Path(list(spec.submodule_search_locations)[0]) / "Test_Cases"
    return root if root.is_dir() else None


def shipped_controller(name: str) -> Optional[Path]:
    """The DISCON.IN the rosco wheel ships for the shipped turbine ``name``, or None."""
    root = rosco_test_cases()
    if root is None or name not in SHIPPED_CONTROLLERS:
        return None
    return root / SHIPPED_CONTROLLERS[name]


def shipped_path(name: str) -> Path:
    """The file of a shipped turbine; an unknown name raises TurbineFileError listing them."""
    if name not in SHIPPED:
        raise TurbineFileError(name, [f"not a file and not a shipped turbine; shipped: "
                                      f"{', '.join(SHIPPED)} (hawt turbines lists them)"])
    return _DATA / SHIPPED[name] if name != "paper" else default_turbine_path()


def describe(path: Path) -> str:
    """The first header line of a turbine file that says what it is (``# turbine: ...``)."""
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                if not line.startswith("#"):
                    break
                if line.lower().startswith("# turbine:"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return ""


def shipped_turbines() -> list:
    """One dict per shipped turbine: name, file, description, blades, rotor radius [m],
    tower (flexible or rigid), rotor speed [rad/s], elements per blade."""
    out = []
    for name in SHIPPED:
        p = shipped_path(name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TurbineFileWarning)
            t = load_turbine(p)
        out.append({"name": name, "file": str(p), "description": describe(p),
                    "blades": t.rotor.blades,
                    "rotor_radius_m": t.hub.radius + t.blade.length,
                    "tower": "rigid" if t.tower is None else f"flexible, {t.tower.length:g} m",
                    "rotor_speed": t.rotor.speed, "elements": t.blade.elements})
    return out


def load_any(spec=None) -> Turbine:
    """The turbine named by ``spec`` (see the module docstring)."""
    if spec is None:
        return load_turbine(None)
    text = str(spec)
    p = Path(text)
    if not p.exists() and text in SHIPPED:
        return load_turbine(shipped_path(text))
    if p.exists():
        check_regular_file(p)          # a FIFO or a huge file: refused before any reader opens it
    if p.suffix.lower() == ".fst":
        from .openfast import read_openfast
        return _imported(read_openfast(p))
    if p.suffix.lower() == ".htc":
        from .hawc2_turbine import read_hawc2
        return _imported(read_hawc2(p))
    if not p.exists() and "/" not in text and not p.suffix:
        shipped_path(text)                 # raises with the list of shipped names
    if p.suffix.lower() in (".yaml", ".yml") and is_windio(p):
        from .windio import read_windio
        return _imported(read_windio(p))
    return load_turbine(p)


def _imported(result) -> Turbine:
    """The turbine of an ImportResult, its warnings issued as TurbineFileWarning."""
    for w in result.warnings:
        warnings.warn(w, TurbineFileWarning, stacklevel=3)
    return result.turbine


def is_windio(p: Path) -> bool:
    """True when the top-level keys of a YAML file (a cheap look at its first 64 kB) are
    WindIO's."""
    try:
        with open(p, encoding="utf-8", errors="replace") as f:
            head = f.read(65536)
    except OSError:
        return False
    keys = {line.split(":", 1)[0] for line in head.splitlines()
            if line and not line[0].isspace() and ":" in line and not line.startswith("#")}
    return "windIO_version" in keys or {"assembly", "components"} <= keys
