"""The wing case file (YAML): a cantilever wing in a uniform stream for ``hawt flutter``.

    wing:
      name: Goland wing
      span: 6.096            # [m]
      chord: 1.8288          # [m]
      elastic_axis: 0.33     # fraction of the chord from the leading edge
      density: 1.02          # [kg/m^3]
      lift_slope: 6.2832     # [1/rad], optional (2 pi)
      elements: 16
      sections:              # as a blade's (docs/turbine-format.md): b2 towards the leading edge
        stations: [0.0, 1.0]
        mass: 35.71
        ...

Problems are TurbineFileErrors naming the key, the value and what is allowed, as for turbine
files (the same bounded reader and limits).
"""
from __future__ import annotations

import warnings
from pathlib import Path

from ..model import Beam, Wing
from ..numerics.limits import MAX_ELEMENTS
from .checker import _Checker
from .turbine_yaml import (TurbineFileError, TurbineFileWarning, _parse_yaml, _section_table,
                           read_bounded)

__all__ = ["load_wing", "wing_from_dict", "is_wing_file"]

_WING = {"name": False, "span": True, "chord": True, "elastic_axis": True, "density": False,
         "lift_slope": False, "elements": True, "sections": True}


def wing_from_dict(d, source: str = "<dict>") -> Wing:
    c = _Checker(source)
    top = c.mapping(d, "", {"wing": True})
    w = c.mapping(top["wing"], "wing", _WING) if top is not None and "wing" in top else None
    if w is None:
        raise TurbineFileError(source, c.errors or ["a wing file needs a 'wing' mapping"])
    span = c.number(w, "span", "wing", "> 0")
    chord = c.number(w, "chord", "wing", "> 0")
    axis = c.number(w, "elastic_axis", "wing", ">= 0")
    if axis is not None and axis > 1:
        c.error("wing.elastic_axis", "must be a fraction of the chord from 0 (leading edge) "
                                     "to 1 (trailing edge)", axis)
    density = c.number(w, "density", "wing", "> 0", 1.225)
    slope = c.number(w, "lift_slope", "wing", "> 0", 6.283185307179586)
    elements = c.integer(w, "elements", "wing", 1, MAX_ELEMENTS, "MAX_ELEMENTS")
    sections = _section_table(c, w["sections"], "wing.sections", curved_line=False) \
        if "sections" in w else None
    name = w.get("name", Path(source).stem)
    if not isinstance(name, str) or not name.strip():
        c.error("wing.name", "must be a non-empty text string", name)
    if c.errors or None in (span, chord, axis, density, slope, elements, sections):
        raise TurbineFileError(source, c.errors or ["invalid wing description"])
    for message in c.warnings:
        warnings.warn(f"{source}: {message}", TurbineFileWarning, stacklevel=3)
    return Wing(name=name, beam=Beam(span, sections, elements), chord=chord,
                elastic_axis=axis, density=density, lift_slope=slope)


def load_wing(path) -> Wing:
    p = Path(path)
    data = _parse_yaml(read_bounded(p), str(p))
    return wing_from_dict(data, str(p))


def is_wing_file(path) -> bool:
    """True when the file's first top-level key is ``wing`` (a cheap look at 4 kB)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            head = f.read(4096)
    except OSError:
        return False
    for line in head.splitlines():
        if line.strip() and not line.startswith("#") and not line[0].isspace():
            return line.split(":", 1)[0].strip() == "wing"
    return False
