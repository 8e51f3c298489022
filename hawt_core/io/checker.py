"""The validating reader of plain YAML data (hawt_core.io.turbine_yaml uses it): a
``_Checker`` collects every problem as ``path: what`` messages naming the key, the value and
what is allowed, instead of stopping at the first.
"""
from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from typing import Any, Callable, Optional

import numpy as np

from ..numerics.checks import short_repr
from ..numerics.limits import MAX_STATIONS

#: Most problems collected from one file (a hostile file may have millions); the rest are
#: summarized in one line.
MAX_MESSAGES = 50

#: Relative tolerance for the symmetry of a 6x6 section matrix (scaled by its largest entry).
SYMMETRY_TOLERANCE = 1e-9


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
    """A short, readable rendering of an offending value (bounded work for any value)."""
    text = short_repr(value)
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

    def add(self, message: Callable[[], str]):
        """Record the problem ``message()`` builds; past MAX_MESSAGES, note once that there
        are more (and build no further messages)."""
        if len(self.errors) < MAX_MESSAGES:
            self.errors.append(message())
        elif len(self.errors) == MAX_MESSAGES:
            self.errors.append(f"(more problems not listed: hawt stops after {MAX_MESSAGES})")

    def error(self, path: str, what: str, value: Any = ...):
        self.add(lambda: f"{path}: {what}" if value is ... else
                 f"{path} = {_show(value)}: {what}")

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
        def message():
            hint = ""
            close = difflib.get_close_matches(str(key), list(spec), n=1, cutoff=0.6)
            if isinstance(key, str) and key.endswith(("_deg", "_rpm", "_degrees")):
                base = key.rsplit("_", 1)[0]
                if base in spec:
                    hint = f"; angles and speeds are in radians (rad/s): use '{base}'"
            if not hint and close:
                hint = f"; did you mean '{close[0]}'?"
            return f"{path}: unknown key{hint} (allowed: {', '.join(spec)})"
        self.add(message)

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
        try:
            x = float(value)
        except OverflowError:                  # an integer of hundreds of digits
            self.error(path, f"must be a finite number (this integer has "
                             f"{len(str(abs(value)))} digits)", value)
            return None
        if math.isnan(x) or (math.isinf(x) and not allow_inf):
            self.error(path, "must be a finite number (NaN and infinity are not allowed)", value)
            return None
        if not _rule_ok(x, rule):
            self.error(path, _RULES[rule], value)
            return None
        return x

    def integer(self, d: Mapping, key: str, path: str, minimum: int,
                maximum: Optional[int] = None, limit: str = ""):
        """A whole number from ``minimum`` to ``maximum`` (the limit named ``limit``)."""
        p = f"{path}.{key}"
        if key not in d:
            return None
        value = given = _plain(d[key])
        need = f"a whole number >= {minimum}" if maximum is None else \
            f"a whole number from {minimum} to {maximum}" + (f" ({limit})" if limit else "")
        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        if not isinstance(value, int) or isinstance(value, bool):
            self.error(p, f"must be {need}, got {_type_name(value)}", value)
            return None
        if value < minimum or maximum is not None and value > maximum:
            self.error(p, f"must be {need}", given)
            return None
        return value

    def short_list(self, value: list, path: str, limit: int = MAX_STATIONS,
                   what: str = "values", name: str = "MAX_STATIONS") -> bool:
        """False (with an error) when a list is longer than ``limit``: checked before any
        per-entry work."""
        if len(value) > limit:
            self.error(path, f"has {len(value)} {what}; at most {limit} are allowed ({name})")
            return False
        return True

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
        if not self.short_list(value, path, what="stations"):
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
        if ns is not None and len(value) != ns:       # before any per-entry work
            self.error(path, f"has {len(value)} values but there are {ns} stations (give one "
                             "value per station, or a single number for a uniform property)",
                       value)
            return None
        if not self.short_list(value, path):
            return None
        xs = [self.number_value(_plain(v), f"{path}[{i}]", rule) for i, v in enumerate(value)]
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
        if not self.short_list(value, path, what="pairs"):
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
            if not self.short_list(value, path, what="matrices"):
                return None
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
