"""The turbine file (YAML): loader, validation and writer.

A turbine file describes one turbine in SI units (metres, kilograms, seconds, newtons) with all
angles in RADIANS (rotor speed in rad/s), exactly like :mod:`hawt_core.model`; the format is
documented key by key in ``docs/turbine-format.md``.  The paper's Table 1 turbine ships as
``hawt_core/data/paper_turbine.yaml`` and is the default.

Public API::

    load_turbine(path=None) -> Turbine      # None: the shipped default; also takes a dict
    turbine_from_dict(d, source="<dict>")   # the same validation for an already-parsed mapping
    default_turbine_path() -> pathlib.Path

Every problem found in a file is reported as a :class:`TurbineFileError` (a ``ValueError``) whose
message names the field by its dotted path (``blade.sections.ei2[3]``), the offending value and
what is allowed; all problems found in one pass are listed, the first one first.  Doubtful but
legal data (``I1`` differing from ``I2 + I3`` by more than 1 %, a scalar property contradicting a
full 6x6 matrix) gives a :class:`TurbineFileWarning`.
"""
from __future__ import annotations

import math
import re
import stat
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Optional

import numpy as np
import yaml

from ..numerics.limits import (MAX_BLADES, MAX_ELEMENTS, MAX_ORDER, MAX_FILE_BYTES, MAX_POLAR_ANGLES,
                               MAX_POLARS, MAX_ROTOR_SPEED, MAX_SCALAR_CHARS, MAX_YAML_DEPTH,
                               MAX_YAML_VALUES)
from ..model import (GENERATOR_MODES, PITT_PETERS_SKEW, Aerodynamics, Beam, BeamDamping,
                     Drivetrain, Gravity, Hub, Nacelle, Polar, Rotor, SectionTable, TowerAerodynamics,
                     Turbine)
from .checker import _Checker, _plain, _show, _type_name

__all__ = [
    "TurbineFileError", "TurbineFileWarning", "load_turbine", "turbine_from_dict",
    "default_turbine_path", "I1_TOLERANCE", "check_regular_file", "read_bounded",
]

#: Relative tolerance on ``I1 = I2 + I3`` before a TurbineFileWarning is issued.
I1_TOLERANCE = 0.01


class TurbineFileError(ValueError):
    """A turbine file (or dict) that cannot be loaded (the message shows the first SHOWN
    problems; ``errors`` has them all).

    Attributes:
        source: the file path (or ``"<dict>"``) the problem is in.
        errors: list of messages, each ``"<dotted.path> = <value>: <what is allowed>"``.
    """

    SHOWN = 20

    def __init__(self, source: str, errors: list):
        self.source = str(source)
        self.errors = list(errors)
        if len(self.errors) == 1:
            text = f"{self.source}: {self.errors[0]}"
        else:
            shown = self.errors[:self.SHOWN]
            text = f"{self.source}: {len(self.errors)} problems:\n" + "\n".join(
                f"  - {e}" for e in shown)
            if len(self.errors) > len(shown):
                text += f"\n  ... and {len(self.errors) - len(shown)} more"
        super().__init__(text)


class TurbineFileWarning(UserWarning):
    """Legal but doubtful turbine data (e.g. I1 != I2 + I3 beyond 1 %)."""


def default_turbine_path() -> Path:
    """Path of the shipped default turbine file (the paper's Table 1 turbine)."""
    return Path(__file__).resolve().parent.parent / "data" / "paper_turbine.yaml"


# --------------------------------------------------------------------------------------------
# YAML reading: accept 4.36e6 as a float (YAML 1.1 insists on a dot and a signed exponent) and
# refuse duplicate keys (PyYAML silently keeps the last one).  The parser is libyaml's where
# PyYAML has it (CSafeLoader: a file with airfoil polars parses 5-10x faster); resolution and
# construction, where those rules live, stay in Python either way.

class _Loader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    pass


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                    |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _construct_mapping(loader, node, deep=False):
    loader.flatten_mapping(node)
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (first given on line {seen[key] + 1})",
                key_node.start_mark)
        seen[key] = key_node.start_mark.line
    return yaml.constructor.SafeConstructor.construct_mapping(loader, node, deep=deep)


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _prescan(text: str, source: str) -> None:
    """Refuse, before anything is built, YAML that would take unbounded time or memory: nesting
    deeper than MAX_YAML_DEPTH, more than MAX_YAML_VALUES values once every alias is expanded
    (the "billion laughs" bomb: a few lines that expand to 10^9 values), a value longer than
    MAX_SCALAR_CHARS.  One pass over libyaml's events, counting each anchored node's expanded
    size once, so the pass itself is linear in the file's length."""
    counts = [0]                          # expanded values under each open collection
    anchors = []                          # the anchor of each open collection
    expanded = {}                         # anchor -> expanded value count
    aliases = False
    for event in yaml.parse(text, Loader=_Loader):
        kind = type(event)
        if kind is yaml.ScalarEvent:
            if len(event.value) > MAX_SCALAR_CHARS:
                raise TurbineFileError(source, [
                    f"line {event.start_mark.line + 1}: a value of {len(event.value)} "
                    f"characters; at most {MAX_SCALAR_CHARS} are allowed (MAX_SCALAR_CHARS)"])
            n = 1
            if event.anchor:
                expanded[event.anchor] = 1
        elif kind is yaml.AliasEvent:
            n = expanded.get(event.anchor, 1)
            aliases = True
        elif kind in (yaml.SequenceStartEvent, yaml.MappingStartEvent):
            if len(counts) > MAX_YAML_DEPTH:
                raise TurbineFileError(source, [
                    f"line {event.start_mark.line + 1}: lists and mappings nested more than "
                    f"{MAX_YAML_DEPTH} deep (MAX_YAML_DEPTH); a turbine file needs 5"])
            counts.append(0)
            anchors.append(event.anchor)
            continue
        elif kind in (yaml.SequenceEndEvent, yaml.MappingEndEvent):
            n = counts.pop()
            anchor = anchors.pop()
            if anchor:
                expanded[anchor] = n
        else:
            continue
        counts[-1] += n
        if counts[-1] > MAX_YAML_VALUES:
            raise TurbineFileError(source, [
                f"line {event.start_mark.line + 1}: more than {MAX_YAML_VALUES} values "
                "(MAX_YAML_VALUES)" + ("; each alias (*name) counts as all the values it "
                                       "stands for: is it an alias bomb?" if aliases else "")])


def _parse_yaml(text: str, source: str):
    try:
        _prescan(text, source)
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        where = ""
        mark = getattr(exc, "problem_mark", None)
        if mark is not None:
            where = f" at line {mark.line + 1}, column {mark.column + 1}"
        problem = getattr(exc, "problem", None) or str(exc)
        if "nesting depth" in problem:     # libyaml's own stop, met before the prescan's
            problem = (f"lists and mappings nested more than {MAX_YAML_DEPTH} deep "
                       "(MAX_YAML_DEPTH); a turbine file needs 5")
        raise TurbineFileError(source, [f"not valid YAML{where}: {problem}"]) from None


# --------------------------------------------------------------------------------------------
# The schema: for each section, its keys and whether they are required.

_TOP = {"name": False, "rotor": True, "hub": True, "nacelle": True, "blade": True,
        "tower": False, "gravity": False, "drivetrain": False, "aerodynamics": False,
        "tower_aerodynamics": False}
_TOWER_AERO = {"stations": True, "diameter": True, "drag": True}
_AERO = {"stations": True, "chord": True, "twist": True, "airfoil": True, "polars": True,
         "ac_prebend": False, "ac_sweep": False, "cant": False, "skew_factor": False,
         "ac_chordwise": False}
_POLAR = {"name": True, "alpha": True, "cl": True, "cd": True, "cm": True,
          "reynolds": False, "thickness": False}
_DRIVETRAIN = {"stiffness": False, "damping": False, "generator_inertia": False,
               "gearbox_ratio": False, "generator": False, "generator_torque_slope": False}
_ROTOR = {"speed": True, "blades": True, "precone": False, "pitch": False}
_HUB = {"radius": True, "undersling": False, "teeter": True, "inertia_lateral": True,
        "inertia_longitudinal": True, "teeter_stiffness": False, "teeter_damping": False,
        "mass": False, "counterweight_mass": False, "counterweight_radius": False}
_NACELLE = {"yaw_inertia": True, "yaw_stiffness": False, "yaw_damping": False,
            "yaw_to_teeter": True, "shaft_tilt": False, "yaw_free": True, "mass": False,
            "cg_offset": False, "inertia_pitch": False, "inertia_roll": False,
            "shaft_height": False, "yaw_bearing_mass": False}
_TOWER = {"length": True, "elements": True, "sections": True, "rigid": False,
          "order": False, "damping": False}
_BEAM = {"length": True, "elements": True, "sections": True, "tip_mass": False,
         "tip_inertia": False, "order": False, "damping": False}
_DAMPING = {"stiffness": False, "mass": False, "modal_percent": False}
#: the mode families a blade's and a tower's modal damping may name
_MODAL_FAMILIES = {"blade": ("flap", "edge"), "tower": ("fore_aft", "side_side")}
_GRAVITY = {"enabled": True, "g": False}
#: Per-station scalar properties: name -> value rule (a key of _RULES).
SCALAR_PROPS = {
    "mass": "> 0", "i1": "> 0", "i2": "> 0", "i3": "> 0",
    "gj": "> 0", "ei2": "> 0", "ei3": "> 0",
    "ea": "> 0", "ga2": "> 0", "ga3": "> 0", "twist": "twist",
}
MASS_PROPS = ("mass", "i1", "i2", "i3")          # replaced by mass_6x6 ...
MASS_DIAGONAL = (0, 3, 4, 5)                     # ... diagonal entries holding them
STIFF_PROPS = ("ea", "ga2", "ga3", "gj", "ei2", "ei3")  # replaced by stiffness_6x6 diagonal
_SECTIONS = dict({"stations": True}, **{k: False for k in SCALAR_PROPS},
                 cg_offset=False, tension_offset=False, shear_offset=False,
                 stiffness_6x6=False, mass_6x6=False,
                 prebend=False, sweep=False)
#: Offsets of a curved reference line, per station [m] (blades only).
LINE_PROPS = ("prebend", "sweep")

# --------------------------------------------------------------------------------------------
# Building the model.

def _section_table(c: _Checker, value: Any, path: str,
                   curved_line: bool = True) -> Optional[SectionTable]:
    d = c.mapping(value, path, _SECTIONS)
    if d is None:
        return None
    n_errors = len(c.errors)
    ns = None
    if "stations" in d:
        st = c.stations(d["stations"], f"{path}.stations")
        ns = None if st is None else len(st)
    has_k = d.get("stiffness_6x6") is not None
    has_m = d.get("mass_6x6") is not None
    K = c.matrices(d["stiffness_6x6"], f"{path}.stiffness_6x6", ns, True) if has_k else None
    M = c.matrices(d["mass_6x6"], f"{path}.mass_6x6", ns, False) if has_m else None

    props = {}
    for key, rule in SCALAR_PROPS.items():
        if d.get(key) is not None:
            props[key] = c.per_station(d[key], f"{path}.{key}", ns, rule)
        elif key in MASS_PROPS and not has_m or key in ("gj", "ei2", "ei3") and not has_k:
            c.error(f"{path}.{key}", "required key is missing (or give the full "
                                     f"{'mass_6x6' if key in MASS_PROPS else 'stiffness_6x6'})")
    for key in ("cg_offset", "tension_offset", "shear_offset"):
        if d.get(key) is not None:
            props[key] = c.pairs(d[key], f"{path}.{key}", ns)
    for key in LINE_PROPS:
        if d.get(key) is None:
            continue
        if not curved_line:
            c.error(f"{path}.{key}", "is not supported here: the tower's reference line is "
                                     "straight (its top carries the nacelle)", d[key])
            continue
        props[key] = c.per_station(d[key], f"{path}.{key}", ns, "finite")
        if props[key] is not None and props[key][0] != 0:
            c.error(f"{path}.{key}[0]", "must be 0: the reference line starts at the blade "
                                        "root (the root point is set by the hub)",
                    props[key][0])
    if has_m and d.get("cg_offset") is not None:
        c.error(f"{path}.cg_offset", "cannot be combined with mass_6x6 (the matrix already "
                                     "holds the mass-centre offset)", d["cg_offset"])
    for key, what in (("tension_offset", "tension"), ("shear_offset", "shear")):
        if has_k and d.get(key) is not None:
            c.error(f"{path}.{key}", "cannot be combined with stiffness_6x6 (the matrix "
                                     f"already holds the {what}-centre offset)", d[key])
    if has_k and has_m and d.get("twist") is not None:
        c.error(f"{path}.twist", "cannot be combined with both stiffness_6x6 and mass_6x6 "
                                 "(give the matrices in the untwisted reference frame)",
                d["twist"])
    if len(c.errors) > n_errors or ns is None:
        return None

    # Fill the scalar properties from the full matrices' diagonals where not given.
    for mats, keys, diag in ((M, MASS_PROPS, MASS_DIAGONAL), (K, STIFF_PROPS, range(6))):
        if mats is None:
            continue
        for key, j in zip(keys, diag):
            derived = mats[:, j, j]
            rigid = not np.all(np.isfinite(derived))
            if key in props:
                given = props[key]
                if rigid or not np.allclose(given, derived, rtol=1e-9, atol=0):
                    c.warnings.append(
                        f"{path}.{key} = {_show(given)} differs from the diagonal "
                        f"[{j}][{j}] of the 6x6 matrix ({_show(derived)}); the matrix is used")
            else:
                props[key] = None if rigid else derived.copy()

    i1, i2, i3 = props["i1"], props["i2"], props["i3"]
    rel = np.abs(i1 - (i2 + i3)) / (i2 + i3)
    if np.any(rel > I1_TOLERANCE):
        k = int(np.argmax(rel))
        c.warnings.append(
            f"{path}.i1[{k}] = {float(i1[k])!r} differs from i2 + i3 = "
            f"{float(i2[k] + i3[k])!r} by "
            f"{100 * rel[k]:.3g} % (more than {100 * I1_TOLERANCE:g} %); for a thin section "
            "I1 = I2 + I3")
    return SectionTable(stations=st, stiffness_6x6=K, mass_6x6=M, **props)


def _beam(c: _Checker, value: Any, path: str, spec: dict) -> Optional[Beam]:
    d = c.mapping(value, path, spec)
    if d is None:
        return None
    length = c.number(d, "length", path, "> 0")
    elements = c.integer(d, "elements", path, 1, MAX_ELEMENTS, "MAX_ELEMENTS")
    order = c.integer(d, "order", path, 1, MAX_ORDER, "MAX_ORDER") if "order" in d else 1
    if elements is not None and order is not None and elements * order > MAX_ELEMENTS:
        c.error(f"{path}.order", f"elements x order must be at most {MAX_ELEMENTS} "
                f"(MAX_ELEMENTS: the cells of the mesh); {elements} x {order} is "
                f"{elements * order}", order)
        order = None
    blade = spec is _BEAM                  # prebend, sweep and a tip body: blades only
    sections = (_section_table(c, d["sections"], f"{path}.sections", curved_line=blade)
                if "sections" in d else None)
    tip = {}
    if blade:
        tip["tip_mass"] = c.number(d, "tip_mass", path, ">= 0", 0.0)
        tip["tip_inertia"] = _vector3(c, d, "tip_inertia", path,
                                      "[J1, J2, J3] in kg m^2")
        if tip["tip_inertia"] is not None and any(v < 0 for v in tip["tip_inertia"]):
            c.error(f"{path}.tip_inertia", "every value must be >= 0 [kg m^2]",
                    d["tip_inertia"])
            tip["tip_inertia"] = None
    damping = _damping(c, d["damping"], f"{path}.damping",
                       _MODAL_FAMILIES["blade" if blade else "tower"]) \
        if "damping" in d else None
    if None in (length, elements, sections, order) or None in tip.values() or \
            damping is False:
        return None
    return Beam(length=length, sections=sections, elements=elements, order=order,
                damping=damping, **tip)


def _damping(c: _Checker, value: Any, path: str, families: tuple):
    """A BeamDamping (None: an empty mapping; False on error): ``stiffness`` mu [s] per
    strain and ``mass`` alpha [1/s] per velocity component (six numbers >= 0 each), or
    ``modal_percent``: % of critical per mode family (1 or 2 values >= 0 and < 100)."""
    n_errors = len(c.errors)
    d = c.mapping(value, path, _DAMPING)
    if d is None:
        return False
    out = {}
    for key, unit in (("stiffness", "s"), ("mass", "1/s")):
        if key not in d:
            continue
        v = _plain(d[key])
        if not isinstance(v, (list, tuple)) or len(v) != 6:
            c.error(f"{path}.{key}", f"must be a list of six numbers >= 0 [{unit}] (per "
                    + ("strain [gamma1, gamma2, gamma3, kappa1, kappa2, kappa3])"
                       if key == "stiffness" else
                       "velocity component [v1, v2, v3, omega1, omega2, omega3])"), v)
            continue
        out[key] = tuple(c.number_value(_plain(x), f"{path}.{key}[{i}]", ">= 0")
                         for i, x in enumerate(v))
    if "modal_percent" in d:
        m = c.mapping(d["modal_percent"], f"{path}.modal_percent",
                      {f: False for f in families})
        modal = {}
        for f in families if m is not None else ():
            if f not in m:
                continue
            v = _plain(m[f])
            v = list(v) if isinstance(v, (list, tuple)) else [v]
            where = f"{path}.modal_percent.{f}"
            if not 1 <= len(v) <= 2:
                c.error(where, "must be one or two numbers (% of critical of the "
                        "family's first modes)", m[f])
                continue
            zs = [c.number_value(_plain(x), f"{where}[{i}]", ">= 0") for i, x in enumerate(v)]
            if any(z is not None and z >= 100 for z in zs):
                c.error(where, "must be below 100 (% of critical)", m[f])
            elif None not in zs:
                modal[f] = tuple(z / 100.0 for z in zs)
        if modal:
            out["modal"] = modal
        if modal and ("stiffness" in out or "mass" in out):
            c.error(path, "give modal_percent or stiffness/mass, not both (the modal ratios "
                    "are turned into stiffness and mass damping on the discretization)")
    if len(c.errors) > n_errors:
        return False
    damping = BeamDamping(**out)
    return damping if damping.enabled else None


def _vector3(c: _Checker, d: Mapping, key: str, path: str,
             what: str = "[x1, x2, x3] in metres"):
    """Three finite numbers (a tuple), (0, 0, 0) when absent; None on error."""
    if key not in d:
        return (0.0, 0.0, 0.0)
    value = _plain(d[key])
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        c.error(f"{path}.{key}", f"must be a list of three numbers {what}", value)
        return None
    out = [c.number_value(_plain(v), f"{path}.{key}[{i}]", "finite") for i, v in enumerate(value)]
    return None if None in out else tuple(out)


def _tower(c: _Checker, value: Any) -> Optional[Beam]:
    if value is None:
        return None
    if isinstance(value, Mapping) and "rigid" in value:
        rigid = c.boolean(value, "rigid", "tower")
        if rigid:
            extra = [k for k in value if k != "rigid"]
            if extra:
                c.error(f"tower.{extra[0]}", "a rigid tower (rigid: true) takes no other keys; "
                                             "remove them or set rigid: false")
            return None
        if rigid is None:
            return None
    return _beam(c, value, "tower", _TOWER)


def _polar(c: _Checker, value: Any, path: str) -> Optional[Polar]:
    n_errors = len(c.errors)
    d = c.mapping(value, path, _POLAR)
    if d is None:
        return None
    name = d.get("name")
    if not isinstance(name, str) or not name.strip():
        c.error(f"{path}.name", "must be a non-empty text string", name)
    raw = _plain(d.get("alpha"))
    alpha = None
    if not isinstance(raw, (list, tuple)):
        if "alpha" in d:
            c.error(f"{path}.alpha", "must be a list of angles of attack [rad]", raw)
    elif c.short_list(raw, f"{path}.alpha", MAX_POLAR_ANGLES, "angles", "MAX_POLAR_ANGLES"):
        alpha = c.per_station(raw, f"{path}.alpha", len(raw), "finite")
    na = None
    if alpha is not None:
        na = len(alpha)
        if na < 2 or np.any(np.diff(alpha) <= 0):
            c.error(f"{path}.alpha", "must be a list of at least 2 angles [rad], strictly "
                                     "increasing", d["alpha"])
        elif alpha[-1] - alpha[0] > 2 * math.pi + 1e-9:
            c.error(f"{path}.alpha", f"spans {alpha[-1] - alpha[0]:.6g} rad: angles are in "
                                     "radians, at most one turn (did you give degrees?)",
                    [d["alpha"][0], d["alpha"][-1]])
    coeffs = {k: c.per_station(d[k], f"{path}.{k}", na, ">= 0" if k == "cd" else "finite")
              for k in ("cl", "cd", "cm") if k in d}
    opt = {"reynolds": c.number(d, "reynolds", path, "> 0"),
           "thickness": c.number(d, "thickness", path, "> 0")}
    if len(c.errors) > n_errors:
        return None
    return Polar(name=name, alpha=alpha, **coeffs, **opt)


def _aerodynamics(c: _Checker, value: Any) -> Optional[Aerodynamics]:
    path = "aerodynamics"
    n_errors = len(c.errors)
    d = c.mapping(value, path, _AERO)
    if d is None:
        return None
    st = c.stations(d["stations"], f"{path}.stations") if "stations" in d else None
    ns = None if st is None else len(st)
    polars = _plain(d.get("polars"))
    if not isinstance(polars, (list, tuple)) or not polars:
        c.error(f"{path}.polars", "must be a list of airfoil polars (at least one)",
                d.get("polars"))
        polars = []
    if not c.short_list(polars, f"{path}.polars", MAX_POLARS, "polars", "MAX_POLARS"):
        polars = []
    polars = [_polar(c, p, f"{path}.polars[{i}]") for i, p in enumerate(polars)]
    parts = {k: c.per_station(d[k], f"{path}.{k}", ns, rule) for k, rule in
             (("chord", "> 0"), ("twist", "finite"), ("ac_prebend", "finite"),
              ("ac_sweep", "finite"), ("cant", "angle"), ("ac_chordwise", "finite"))
             if k in d}
    skew = c.number(d, "skew_factor", path, ">= 0", PITT_PETERS_SKEW)
    idx = None
    if "airfoil" in d:
        raw = _plain(d["airfoil"])
        raw = raw if isinstance(raw, (list, tuple)) else [raw] * (ns or 1)
        ok = [isinstance(_plain(v), int) and not isinstance(_plain(v), bool)
              and 0 <= _plain(v) < len(polars) for v in raw]
        if not all(ok):
            i = ok.index(False)
            c.error(f"{path}.airfoil[{i}]", f"must be the index (0 to {len(polars) - 1}) of "
                                            "one of aerodynamics.polars", raw[i])
        elif ns is not None and len(raw) != ns:
            c.error(f"{path}.airfoil", f"has {len(raw)} values but there are {ns} stations",
                    raw)
        else:
            idx = np.array(raw, int)
    if len(c.errors) > n_errors or st is None or idx is None \
            or any(p is None for p in polars) or any(v is None for v in parts.values()) \
            or skew is None:
        return None
    return Aerodynamics(stations=st, airfoil=idx, polars=tuple(polars), skew_factor=skew,
                        **parts)


def _tower_aerodynamics(c: _Checker, value: Any) -> Optional[TowerAerodynamics]:
    path = "tower_aerodynamics"
    n_errors = len(c.errors)
    d = c.mapping(value, path, _TOWER_AERO)
    if d is None:
        return None
    st = c.stations(d["stations"], f"{path}.stations") if "stations" in d else None
    ns = None if st is None else len(st)
    parts = {k: c.per_station(d[k], f"{path}.{k}", ns, rule) for k, rule in
             (("diameter", "> 0"), ("drag", ">= 0")) if k in d}
    if len(c.errors) > n_errors or st is None or len(parts) < 2 \
            or any(v is None for v in parts.values()):
        return None
    return TowerAerodynamics(stations=st, **parts)


def _build(c: _Checker, data: Any, default_name: str) -> Optional[Turbine]:
    if not isinstance(data, Mapping):
        c.add(lambda: f"the turbine must be a mapping with the sections {', '.join(_TOP)}; "
                      f"got {_type_name(data)}: {_show(data)}")
        return None
    c.mapping(data, "", _TOP)

    name = data.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        c.error("name", "must be a non-empty text string", name)

    rotor = hub = nacelle = None
    if (r := c.mapping(data["rotor"], "rotor", _ROTOR) if "rotor" in data else None) is not None:
        rotor = dict(speed=c.number(r, "speed", "rotor", "> 0"),
                     blades=c.integer(r, "blades", "rotor", 1, MAX_BLADES, "MAX_BLADES"),
                     precone=c.number(r, "precone", "rotor", "angle", 0.0),
                     pitch=c.number(r, "pitch", "rotor", "twist", 0.0))
        if rotor["speed"] is not None and rotor["speed"] > MAX_ROTOR_SPEED:
            c.error("rotor.speed", f"must be > 0 and <= {MAX_ROTOR_SPEED:g} [rad/s] "
                                   "(MAX_ROTOR_SPEED); speeds are in rad/s", r["speed"])
            rotor["speed"] = None
    if (h := c.mapping(data["hub"], "hub", _HUB) if "hub" in data else None) is not None:
        hub = dict(radius=c.number(h, "radius", "hub", ">= 0"),
                   undersling=c.number(h, "undersling", "hub", "finite", 0.0),
                   teeter=c.boolean(h, "teeter", "hub"),
                   # a rigid hub may be a point mass with inertia about the shaft only
                   # (ElastoDyn's hub); a teetering one needs its lateral inertia
                   inertia_lateral=c.number(h, "inertia_lateral", "hub",
                                            ">= 0" if h.get("teeter") is False else "> 0"),
                   inertia_longitudinal=c.number(h, "inertia_longitudinal", "hub", "> 0"),
                   teeter_stiffness=c.number(h, "teeter_stiffness", "hub", ">= 0", 0.0),
                   teeter_damping=c.number(h, "teeter_damping", "hub", ">= 0", 0.0),
                   mass=c.number(h, "mass", "hub", ">= 0", 0.0),
                   counterweight_mass=c.number(h, "counterweight_mass", "hub", ">= 0", 0.0),
                   counterweight_radius=c.number(h, "counterweight_radius", "hub", ">= 0",
                                                 0.0))
    if (n := c.mapping(data["nacelle"], "nacelle", _NACELLE)
            if "nacelle" in data else None) is not None:
        nacelle = dict(yaw_inertia=c.number(n, "yaw_inertia", "nacelle", "> 0"),
                       yaw_stiffness=c.number(n, "yaw_stiffness", "nacelle", ">= 0", 0.0),
                       yaw_damping=c.number(n, "yaw_damping", "nacelle", ">= 0", 0.0),
                       yaw_to_teeter=c.number(n, "yaw_to_teeter", "nacelle", "finite"),
                       shaft_tilt=c.number(n, "shaft_tilt", "nacelle", "angle", 0.0),
                       yaw_free=c.boolean(n, "yaw_free", "nacelle"),
                       mass=c.number(n, "mass", "nacelle", ">= 0", 0.0),
                       cg_offset=_vector3(c, n, "cg_offset", "nacelle"),
                       inertia_pitch=c.number(n, "inertia_pitch", "nacelle", ">= 0", 0.0),
                       inertia_roll=c.number(n, "inertia_roll", "nacelle", ">= 0", 0.0),
                       shaft_height=c.number(n, "shaft_height", "nacelle", "finite", 0.0),
                       yaw_bearing_mass=c.number(n, "yaw_bearing_mass", "nacelle", ">= 0",
                                                 0.0))
    blade = _beam(c, data["blade"], "blade", _BEAM) if "blade" in data else None
    tower = _tower(c, data.get("tower"))
    gravity = Gravity()
    if data.get("gravity") is not None:
        g = c.mapping(data["gravity"], "gravity", _GRAVITY)
        if g is not None:
            enabled = c.boolean(g, "enabled", "gravity")
            acc = c.number(g, "g", "gravity", "> 0", 9.81)
            if None not in (enabled, acc):
                gravity = Gravity(enabled=enabled, g=acc)

    drivetrain = None
    if data.get("drivetrain") is not None:
        dt = c.mapping(data["drivetrain"], "drivetrain", _DRIVETRAIN)
        if dt is not None:
            n_errors = len(c.errors)
            gen = dt.get("generator", "prescribed")
            if gen not in GENERATOR_MODES:
                c.error("drivetrain.generator", f"must be one of {', '.join(GENERATOR_MODES)}",
                        gen)
            parts = dict(stiffness=c.number(dt, "stiffness", "drivetrain", "> 0"),
                         damping=c.number(dt, "damping", "drivetrain", ">= 0", 0.0),
                         generator_inertia=c.number(dt, "generator_inertia", "drivetrain",
                                                    ">= 0", 0.0),
                         gearbox_ratio=c.number(dt, "gearbox_ratio", "drivetrain", "> 0", 1.0),
                         generator_torque_slope=c.number(dt, "generator_torque_slope",
                                                         "drivetrain", "finite", 0.0))
            if parts["generator_torque_slope"] and gen != "free":
                c.error("drivetrain.generator_torque_slope", "is the slope of a free "
                        "generator's torque law: needs generator: free",
                        parts["generator_torque_slope"])
            if len(c.errors) == n_errors:
                if parts["stiffness"] is None and gen == "prescribed":
                    c.error("drivetrain", "a rigid shaft (no stiffness) with a prescribed "
                                          "generator is the default: leave drivetrain out, or "
                                          "give a stiffness or generator: free")
                else:
                    drivetrain = Drivetrain(generator=gen, **parts)

    if hub and nacelle and None not in (hub["inertia_lateral"], nacelle["yaw_inertia"]) \
            and nacelle["yaw_inertia"] < hub["inertia_lateral"]:
        c.error("nacelle.yaw_inertia", "must be >= hub.inertia_lateral "
                                       f"({hub['inertia_lateral']!r}): it includes the hub",
                nacelle["yaw_inertia"])

    aero = _aerodynamics(c, data["aerodynamics"]) if data.get("aerodynamics") is not None \
        else None
    tower_aero = None
    if data.get("tower_aerodynamics") is not None:
        tower_aero = _tower_aerodynamics(c, data["tower_aerodynamics"])
        if "tower" not in data:
            c.error("tower_aerodynamics", "needs a flexible tower (a tower section): the drag "
                                          "of a rigid tower would load nothing",
                    "(no tower section)")

    parts = (rotor, hub, nacelle)
    if c.errors or blade is None or any(p is None or None in p.values() for p in parts):
        return None
    return Turbine(name=name, rotor=Rotor(**rotor), hub=Hub(**hub), nacelle=Nacelle(**nacelle),
                   blade=blade, tower=tower, gravity=gravity, drivetrain=drivetrain,
                   aerodynamics=aero, tower_aerodynamics=tower_aero)


def turbine_from_dict(d: Mapping, source: str = "<dict>", *, _default_name: str = "unnamed",
                      _stacklevel: int = 2) -> Turbine:
    """Validate a parsed turbine mapping (same keys as the file) and build the Turbine.

    Raises TurbineFileError listing every problem found; warns TurbineFileWarning for doubtful
    but legal data.
    """
    c = _Checker(source)
    turbine = _build(c, d, _default_name)
    if c.errors or turbine is None:
        raise TurbineFileError(source, c.errors or ["invalid turbine description"])
    for w in c.warnings:
        warnings.warn(f"{source}: {w}", TurbineFileWarning, stacklevel=_stacklevel)
    return turbine


def check_regular_file(p: Path, max_bytes: int = MAX_FILE_BYTES) -> None:
    """Refuse what is not a regular file of at most ``max_bytes`` (MAX_FILE_BYTES) before it
    is opened: opening a FIFO blocks until a writer comes, a device never ends."""
    try:
        st = p.stat()
    except FileNotFoundError:
        raise TurbineFileError(str(p), ["file not found"]) from None
    except OSError as exc:
        raise TurbineFileError(str(p), [f"cannot read the file: {exc}"]) from None
    if stat.S_ISDIR(st.st_mode):
        raise TurbineFileError(str(p), ["is a folder, not a turbine file"])
    if not stat.S_ISREG(st.st_mode):
        raise TurbineFileError(str(p), ["is not a regular file (a FIFO, socket or device); "
                                        "give a turbine file"])
    if st.st_size > max_bytes:
        raise TurbineFileError(str(p), [f"the file has {st.st_size} bytes; at most "
                                        f"{max_bytes} are allowed (MAX_FILE_BYTES)"])


def read_bounded(p: Path, max_bytes: int = MAX_FILE_BYTES) -> str:
    """The text (UTF-8) of a regular file of at most ``max_bytes``; TurbineFileError else."""
    check_regular_file(p, max_bytes)
    try:
        parts, size = [], 0
        with open(p, "rb") as f:              # in pieces: the file may grow after stat()
            while size <= max_bytes and (piece := f.read(1 << 20)):
                parts.append(piece)
                size += len(piece)
        raw = b"".join(parts)
        if len(raw) > max_bytes:
            raise TurbineFileError(str(p), [f"the file has more than {max_bytes} bytes "
                                            "(MAX_FILE_BYTES)"])
        return raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise TurbineFileError(str(p), [f"cannot read the file: {exc}"]) from None


def load_turbine(path=None) -> Turbine:
    """Load a turbine file (YAML). ``None`` loads the shipped default (the paper's Table 1
    turbine); a mapping is validated like a file (see :func:`turbine_from_dict`).

    ``name`` defaults to the file name without extension.
    """
    if isinstance(path, Mapping):
        return turbine_from_dict(path, _stacklevel=3)
    p = default_turbine_path() if path is None else Path(path)
    data = _parse_yaml(read_bounded(p), str(p))
    if data is None:
        raise TurbineFileError(str(p), ["the file is empty"])
    return turbine_from_dict(data, str(p), _default_name=p.stem, _stacklevel=3)
