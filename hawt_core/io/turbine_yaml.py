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

import difflib
import math
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Optional

import numpy as np
import yaml

from ..model import (GENERATOR_MODES, Beam, Drivetrain, Gravity, Hub, Nacelle, Rotor,
                     SectionTable, Turbine)

__all__ = [
    "TurbineFileError", "TurbineFileWarning", "load_turbine", "turbine_from_dict",
    "default_turbine_path", "I1_TOLERANCE",
]

#: Relative tolerance on ``I1 = I2 + I3`` before a TurbineFileWarning is issued.
I1_TOLERANCE = 0.01
#: Relative tolerance for the symmetry of a 6x6 section matrix (scaled by its largest entry).
SYMMETRY_TOLERANCE = 1e-9


class TurbineFileError(ValueError):
    """A turbine file (or dict) that cannot be loaded.

    Attributes:
        source: the file path (or ``"<dict>"``) the problem is in.
        errors: list of messages, each ``"<dotted.path> = <value>: <what is allowed>"``.
    """

    def __init__(self, source: str, errors: list):
        self.source = str(source)
        self.errors = list(errors)
        if len(self.errors) == 1:
            text = f"{self.source}: {self.errors[0]}"
        else:
            text = f"{self.source}: {len(self.errors)} problems:\n" + "\n".join(
                f"  - {e}" for e in self.errors)
        super().__init__(text)


class TurbineFileWarning(UserWarning):
    """Legal but doubtful turbine data (e.g. I1 != I2 + I3 beyond 1 %)."""


def default_turbine_path() -> Path:
    """Path of the shipped default turbine file (the paper's Table 1 turbine)."""
    return Path(__file__).resolve().parent.parent / "data" / "paper_turbine.yaml"


# --------------------------------------------------------------------------------------------
# YAML reading: accept 4.36e6 as a float (YAML 1.1 insists on a dot and a signed exponent) and
# refuse duplicate keys (PyYAML silently keeps the last one).

class _Loader(yaml.SafeLoader):
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
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _parse_yaml(text: str, source: str):
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        where = ""
        mark = getattr(exc, "problem_mark", None)
        if mark is not None:
            where = f" at line {mark.line + 1}, column {mark.column + 1}"
        problem = getattr(exc, "problem", None) or str(exc)
        raise TurbineFileError(source, [f"not valid YAML{where}: {problem}"]) from None


# --------------------------------------------------------------------------------------------
# The schema: for each section, its keys and whether they are required.

_TOP = {"name": False, "rotor": True, "hub": True, "nacelle": True, "blade": True,
        "tower": False, "gravity": False, "drivetrain": False}
_DRIVETRAIN = {"stiffness": False, "damping": False, "generator_inertia": False,
               "gearbox_ratio": False, "generator": False}
_ROTOR = {"speed": True, "blades": True, "precone": False}
_HUB = {"radius": True, "undersling": False, "teeter": True, "inertia_lateral": True,
        "inertia_longitudinal": True, "teeter_stiffness": False, "teeter_damping": False,
        "mass": False, "counterweight_mass": False, "counterweight_radius": False}
_NACELLE = {"yaw_inertia": True, "yaw_stiffness": False, "yaw_damping": False,
            "yaw_to_teeter": True, "shaft_tilt": False, "yaw_free": True, "mass": False,
            "cg_offset": False, "inertia_pitch": False, "inertia_roll": False,
            "shaft_height": False, "yaw_bearing_mass": False}
_BEAM = {"length": True, "elements": True, "sections": True}
_TOWER = dict(_BEAM, rigid=False)
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
                 cg_offset=False, tension_offset=False, stiffness_6x6=False, mass_6x6=False,
                 prebend=False, sweep=False)
#: Offsets of a curved reference line, per station [m] (blades only).
LINE_PROPS = ("prebend", "sweep")

_RULES = {
    "> 0": "must be > 0",
    ">= 0": "must be >= 0",
    "finite": "must be a finite number",
    "angle": "must be an angle in radians strictly between -pi/2 and pi/2 "
             "(angles are in radians; did you give degrees?)",
    "twist": "must be an angle in radians between -pi/2 and pi/2 "
             "(angles are in radians; did you give degrees?)",
}


def _rule_ok(x: float, rule: str) -> bool:
    if rule == "> 0":
        return x > 0
    if rule == ">= 0":
        return x >= 0
    if rule == "angle":
        return abs(x) < math.pi / 2
    if rule == "twist":
        return abs(x) <= math.pi / 2
    return True


def _show(value: Any) -> str:
    """A short, readable rendering of an offending value."""
    if isinstance(value, str):
        text = repr(value)
    elif isinstance(value, (float, np.floating)):
        text = repr(float(value))
    elif isinstance(value, np.ndarray):
        text = np.array2string(value, threshold=8)
    else:
        text = repr(value)
    return text if len(text) <= 70 else text[:67] + "..."


def _type_name(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, Mapping):
        return "a mapping"
    if value is None:
        return "nothing (null)"
    return f"a {type(value).__name__}"


def _plain(value: Any) -> Any:
    """Numpy arrays/scalars (programmatic dicts) -> plain Python lists/numbers."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class _Checker:
    """Walks a parsed turbine mapping, collecting every problem with its dotted path."""

    def __init__(self, source: str):
        self.source = source
        self.errors: list = []
        self.warnings: list = []

    def error(self, path: str, what: str, value: Any = ...):
        if value is ...:
            self.errors.append(f"{path}: {what}")
        else:
            self.errors.append(f"{path} = {_show(value)}: {what}")

    # -- structure ---------------------------------------------------------------------------
    def mapping(self, value: Any, path: str, spec: dict) -> Optional[Mapping]:
        """Check that ``value`` is a mapping with only known keys and all required keys."""
        if not isinstance(value, Mapping):
            self.error(path, f"must be a mapping of keys ({', '.join(spec)}), "
                             f"got {_type_name(value)}", value)
            return None
        for key in value:
            if key not in spec:
                self.unknown_key(f"{path}.{key}" if path else str(key), key, spec)
        for key, required in spec.items():
            if required and key not in value:
                where = f"{path}.{key}" if path else key
                self.error(where, "required key is missing")
        return value

    def unknown_key(self, path: str, key: Any, spec: dict):
        hint = ""
        close = difflib.get_close_matches(str(key), list(spec), n=1, cutoff=0.6)
        if isinstance(key, str) and key.endswith(("_deg", "_rpm", "_degrees")):
            base = key.rsplit("_", 1)[0]
            if base in spec:
                hint = f"; angles and speeds are in radians (rad/s): use '{base}'"
        if not hint and close:
            hint = f"; did you mean '{close[0]}'?"
        self.errors.append(f"{path}: unknown key{hint} (allowed: {', '.join(spec)})")

    # -- scalars -----------------------------------------------------------------------------
    def number(self, d: Mapping, key: str, path: str, rule: str, default: Any = None):
        """A finite float obeying ``rule``, or ``default`` if absent; None on error."""
        p = f"{path}.{key}"
        if key not in d:
            return default
        return self.number_value(_plain(d[key]), p, rule)

    def number_value(self, value: Any, path: str, rule: str, allow_inf: bool = False):
        if not _is_number(value):
            kind = "a single number" if isinstance(value, (list, tuple, Mapping)) else "a number"
            self.error(path, f"must be {kind}, got {_type_name(value)}", value)
            return None
        x = float(value)
        if math.isnan(x) or (math.isinf(x) and not allow_inf):
            self.error(path, "must be a finite number (NaN and infinity are not allowed)", value)
            return None
        if not _rule_ok(x, rule):
            self.error(path, _RULES[rule], value)
            return None
        return x

    def integer(self, d: Mapping, key: str, path: str, minimum: int):
        p = f"{path}.{key}"
        if key not in d:
            return None
        value = _plain(d[key])
        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        if not isinstance(value, int) or isinstance(value, bool):
            self.error(p, f"must be a whole number >= {minimum}, got {_type_name(value)}", value)
            return None
        if value < minimum:
            self.error(p, f"must be a whole number >= {minimum}", value)
            return None
        return value

    def boolean(self, d: Mapping, key: str, path: str, default: Any = None):
        p = f"{path}.{key}"
        if key not in d:
            return default
        value = _plain(d[key])
        if not isinstance(value, bool):
            self.error(p, f"must be true or false, got {_type_name(value)}", value)
            return None
        return value

    # -- station tables ----------------------------------------------------------------------
    def stations(self, value: Any, path: str) -> Optional[np.ndarray]:
        value = _plain(value)
        if not isinstance(value, (list, tuple)):
            self.error(path, "must be a list of spanwise stations (fractions of the length, "
                             f"from 0 to 1), got {_type_name(value)}", value)
            return None
        xs = [self.number_value(_plain(v), f"{path}[{i}]", "finite") for i, v in enumerate(value)]
        if any(x is None for x in xs):
            return None
        ok = True
        if len(xs) < 2:
            self.error(path, "needs at least 2 stations (0 and 1)", value)
            return None
        if xs[0] != 0.0:
            self.error(f"{path}[0]", "the first station must be 0 (the root)", value[0])
            ok = False
        if xs[-1] != 1.0:
            self.error(f"{path}[{len(xs) - 1}]", "the last station must be 1 (the tip)",
                       value[-1])
            ok = False
        for i in range(1, len(xs)):
            if not xs[i] > xs[i - 1]:
                self.error(f"{path}[{i}]", "stations must be strictly increasing "
                                           f"(the previous one is {xs[i - 1]!r})", value[i])
                ok = False
                break
        return np.array(xs) if ok else None

    def per_station(self, value: Any, path: str, ns: Optional[int], rule: str):
        """A number (uniform: broadcast) or one number per station; array (ns,) or None."""
        value = _plain(value)
        if _is_number(value):
            x = self.number_value(value, path, rule)
            return None if x is None or ns is None else np.full(ns, x)
        if not isinstance(value, (list, tuple)):
            self.error(path, f"must be a number (uniform) or a list with one number per "
                             f"station, got {_type_name(value)}", value)
            return None
        xs = [self.number_value(_plain(v), f"{path}[{i}]", rule) for i, v in enumerate(value)]
        if ns is not None and len(xs) != ns:
            self.error(path, f"has {len(xs)} values but there are {ns} stations (give one "
                             "value per station, or a single number for a uniform property)",
                       value)
            return None
        if ns is None or any(x is None for x in xs):
            return None
        return np.array(xs)

    def pairs(self, value: Any, path: str, ns: Optional[int]):
        """``[x2, x3]`` (uniform) or a list of ns ``[x2, x3]`` pairs [m]; array (ns, 2)."""
        value = _plain(value)
        what = "must be one [x2, x3] pair (uniform) or a list of [x2, x3] pairs, one per station"
        if not isinstance(value, (list, tuple)) or len(value) == 0:
            self.error(path, f"{what}, got {_type_name(value)}", value)
            return None
        if all(_is_number(_plain(v)) for v in value):
            if len(value) != 2:
                self.error(path, what, value)
                return None
            xy = [self.number_value(_plain(v), f"{path}[{i}]", "finite")
                  for i, v in enumerate(value)]
            return None if None in xy or ns is None else np.tile(xy, (ns, 1))
        out, ok = [], True
        for i, pair in enumerate(value):
            pair = _plain(pair)
            if not isinstance(pair, (list, tuple)) or len(pair) != 2:
                self.error(f"{path}[{i}]", "must be an [x2, x3] pair of numbers [m]", pair)
                ok = False
                continue
            xy = [self.number_value(_plain(v), f"{path}[{i}][{j}]", "finite")
                  for j, v in enumerate(pair)]
            ok = ok and None not in xy
            out.append(xy)
        if ok and ns is not None and len(out) != ns:
            self.error(path, f"has {len(out)} pairs but there are {ns} stations", value)
            return None
        return np.array(out, dtype=float) if ok and ns is not None else None

    def matrices(self, value: Any, path: str, ns: Optional[int], stiffness: bool):
        """One 6x6 matrix (uniform) or one per station; symmetric positive definite.

        In a stiffness matrix, ``.inf`` on one of the first three diagonal entries (EA, GA2,
        GA3) marks a rigid direction; the rest of that row and column must then be 0.
        """
        value = _plain(value)

        def depth(v):
            v = _plain(v)
            return 1 + depth(v[0]) if isinstance(v, (list, tuple)) and len(v) else 0

        d = depth(value)
        if d == 2:
            mats, single = [value], True
        elif d == 3:
            mats, single = list(value), False
        else:
            self.error(path, "must be one 6x6 matrix (a list of 6 rows of 6 numbers) or a "
                             "list of them, one per station", value)
            return None
        out = []
        for k, mat in enumerate(mats):
            p = path if single else f"{path}[{k}]"
            m = self.matrix(mat, p, stiffness)
            if m is None:
                return None
            out.append(m)
        if not single and ns is not None and len(out) != ns:
            self.error(path, f"has {len(out)} matrices but there are {ns} stations "
                             "(give one per station, or a single matrix for uniform)")
            return None
        if ns is None:
            return None
        arr = np.array(out * ns if single else out)
        if stiffness:
            rigid = ~np.isfinite(np.diagonal(arr, axis1=1, axis2=2))
            for j in range(3):
                if rigid[:, j].any() and not rigid[:, j].all():
                    self.error(path, f"diagonal entry [{j}][{j}] is .inf (rigid) at some "
                                     "stations only: a direction must be rigid at all stations "
                                     "or at none")
                    return None
        return arr

    def matrix(self, mat: Any, path: str, stiffness: bool):
        mat = _plain(mat)
        if not (isinstance(mat, (list, tuple)) and len(mat) == 6
                and all(isinstance(_plain(r), (list, tuple)) and len(_plain(r)) == 6
                        for r in mat)):
            self.error(path, "must be a 6x6 matrix (6 rows of 6 numbers)", mat)
            return None
        a = np.zeros((6, 6))
        for i, row in enumerate(mat):
            for j, v in enumerate(_plain(row)):
                inf_ok = stiffness and i == j and i < 3
                x = self.number_value(_plain(v), f"{path}[{i}][{j}]", "finite", allow_inf=inf_ok)
                if x is None:
                    return None
                if math.isinf(x) and x < 0:
                    self.error(f"{path}[{i}][{j}]", "only +.inf (rigid) is allowed", v)
                    return None
                a[i, j] = x
        rigid = ~np.isfinite(np.diag(a))
        for j in np.flatnonzero(rigid):
            off = [k for k in range(6) if k != j and (a[j, k] != 0 or a[k, j] != 0)]
            if off:
                self.error(f"{path}[{j}][{off[0]}]", f"row and column {j} must be 0 off the "
                                                     "diagonal in a rigid (.inf) direction",
                           a[j, off[0]])
                return None
        flex = ~rigid
        f = a[np.ix_(flex, flex)]
        scale = max(np.max(np.abs(f)), 1e-300)
        finite = np.where(np.isfinite(a), a, 0.0)
        asym = np.abs(finite - finite.T)
        if np.max(asym) > SYMMETRY_TOLERANCE * scale:
            i, j = np.unravel_index(np.argmax(asym), asym.shape)
            self.error(path, f"is not symmetric: [{i}][{j}] = {float(a[i, j])!r} but "
                             f"[{j}][{i}] = {float(a[j, i])!r}")
            return None
        low = float(np.min(np.linalg.eigvalsh(0.5 * (f + f.T))))
        if not low > 0:
            self.error(path, f"is not positive definite (smallest eigenvalue {low:.6g}); a "
                             "section matrix must be symmetric positive definite")
            return None
        return a


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
    for key in ("cg_offset", "tension_offset"):
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
    if has_k and d.get("tension_offset") is not None:
        c.error(f"{path}.tension_offset", "cannot be combined with stiffness_6x6 (the matrix "
                                          "already holds the tension-centre offset)",
                d["tension_offset"])
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
    elements = c.integer(d, "elements", path, 1)
    sections = (_section_table(c, d["sections"], f"{path}.sections", path != "tower")
                if "sections" in d else None)
    if None in (length, elements, sections):
        return None
    return Beam(length=length, sections=sections, elements=elements)


def _vector3(c: _Checker, d: Mapping, key: str, path: str):
    """Three finite numbers (a tuple), (0, 0, 0) when absent; None on error."""
    if key not in d:
        return (0.0, 0.0, 0.0)
    value = _plain(d[key])
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        c.error(f"{path}.{key}", "must be a list of three numbers [x1, x2, x3] in metres", value)
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


def _build(c: _Checker, data: Any, default_name: str) -> Optional[Turbine]:
    if not isinstance(data, Mapping):
        c.errors.append(f"the turbine must be a mapping with the sections {', '.join(_TOP)}; "
                        f"got {_type_name(data)}: {_show(data)}")
        return None
    c.mapping(data, "", _TOP)

    name = data.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        c.error("name", "must be a non-empty text string", name)

    rotor = hub = nacelle = None
    if (r := c.mapping(data["rotor"], "rotor", _ROTOR) if "rotor" in data else None) is not None:
        rotor = dict(speed=c.number(r, "speed", "rotor", "> 0"),
                     blades=c.integer(r, "blades", "rotor", 1),
                     precone=c.number(r, "precone", "rotor", "angle", 0.0))
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
                         gearbox_ratio=c.number(dt, "gearbox_ratio", "drivetrain", "> 0", 1.0))
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

    parts = (rotor, hub, nacelle)
    if c.errors or blade is None or any(p is None or None in p.values() for p in parts):
        return None
    return Turbine(name=name, rotor=Rotor(**rotor), hub=Hub(**hub), nacelle=Nacelle(**nacelle),
                   blade=blade, tower=tower, gravity=gravity, drivetrain=drivetrain)


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


def load_turbine(path=None) -> Turbine:
    """Load a turbine file (YAML). ``None`` loads the shipped default (the paper's Table 1
    turbine); a mapping is validated like a file (see :func:`turbine_from_dict`).

    ``name`` defaults to the file name without extension.
    """
    if isinstance(path, Mapping):
        return turbine_from_dict(path, _stacklevel=3)
    p = default_turbine_path() if path is None else Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TurbineFileError(str(p), ["file not found"]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TurbineFileError(str(p), [f"cannot read the file: {exc}"]) from None
    data = _parse_yaml(text, str(p))
    if data is None:
        raise TurbineFileError(str(p), ["the file is empty"])
    return turbine_from_dict(data, str(p), _default_name=p.stem, _stacklevel=3)
