"""OpenFAST input files read by their keys, not by line position.

Every OpenFAST input line that sets a value reads ``value  Key  - description`` (a quoted
value may hold spaces).  OpenFAST's own parser looks the key up by name; openfast-io (5.x)
reads by line position in the v5 layout, so a deck of v2.x-v4.x (whose main file lacks
ModCoupling, RhoInf, ConvTol, MaxConvIter, NRotors, ... and whose ElastoDyn file has other
lines) fails at the first moved line.  :func:`read_keyed` collects every ``value key`` pair
of a file with its line number, and :meth:`KeyedFile.table` reads a distributed-property
table by its header's column names (so the FAST v7/v8 blade table with its PitchAxis column
comes in as well as the newer one).

Keys are stored as written (``BlPitch(1)``) and, for indexed keys, also without the
parentheses (``BlPitch1``), the spelling openfast-io's dictionaries use.  Values: ``True`` /
``False`` (any case) -> bool, integers -> int, other numbers -> float, quoted text -> str
(unquoted), anything else -> str (``default``, ``unused``).  Plain text parsing (NumPy for
the BeamDyn matrices).  The files with more than tables of named columns have their own
readers here: :func:`aerodyn_files` (AeroDyn with its airfoil and blade files),
:func:`beamdyn_main` and :func:`beamdyn_blade`.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["KeyedFile", "read_keyed", "KeyedFileError", "aerodyn_files", "beamdyn_main",
           "beamdyn_blade"]

#: A key: a name, optionally indexed ``Name(1)`` or ``Name(1_path)``.
_KEY = re.compile(r"^[A-Za-z][A-Za-z0-9_]*(\([A-Za-z0-9_,]+\))?$")
_INT = re.compile(r"^[+-]?\d+$")
_QUOTED = re.compile(r'^\s*"([^"]*)"\s+(\S+)')


class KeyedFileError(ValueError):
    """A key-based read failed: ``file``, ``line`` (or None) and the message."""

    def __init__(self, file: str, line, message: str):
        self.file, self.line, self.message = file, line, message
        super().__init__(f"{file}" + (f", line {line}" if line else "") + f": {message}")


def _count(kf: "KeyedFile", key: str, minimum: int = 1) -> int:
    """The integer count ``key`` holds (a table's rows, a list's names), at least
    ``minimum``; KeyedFileError naming the file, the key and its line otherwise."""
    value = kf.values.get(key)
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise KeyedFileError(str(kf.path), kf.lines.get(key),
                             f"{key} = {value!r}: need an integer >= {minimum}")
    return value


def _convert(text: str):
    low = text.lower()
    if low in ("true", "t"):
        return True
    if low in ("false", "f"):
        return False
    if _INT.match(text):
        return int(text)
    try:
        return float(text.replace("d", "e").replace("D", "E"))
    except ValueError:
        return text.strip("'")


@dataclass
class KeyedFile:
    """The ``value key`` pairs of one OpenFAST input file (first occurrence of a key wins)."""

    path: Path
    values: dict = field(default_factory=dict)
    #: key -> 1-based line number
    lines: dict = field(default_factory=dict)
    text: list = field(default_factory=list, repr=False)

    def table(self, first_column: str, count_key: str) -> dict:
        """The table whose header line starts with ``first_column`` (column names, then a
        units line in parentheses, then ``values[count_key]`` rows of numbers): ``{column
        name: [floats]}``.  KeyedFileError naming the file and line where it does not hold."""
        file = str(self.path)
        count = _count(self, count_key)
        start = self.lines.get(count_key, 0)
        for i in range(start, len(self.text)):
            names = self.text[i].split("!")[0].split()       # a trailing comment is no column
            if names and names[0] == first_column:
                break
        else:
            raise KeyedFileError(file, None, f"no table header starting with {first_column!r} "
                                             f"after {count_key}")
        row0 = i + 1
        if row0 < len(self.text) and self.text[row0].lstrip().startswith("("):
            row0 += 1                                  # the units line
        cols = {n: [] for n in names}
        for j in range(row0, row0 + count):
            tok = self.text[j].split("!")[0].split() if j < len(self.text) else []
            try:
                nums = [float(t) for t in tok[:len(names)]]
            except ValueError:
                nums = []
            if len(nums) < len(names):
                raise KeyedFileError(file, j + 1, f"table {first_column}...: row {j - row0 + 1}"
                                     f" of {count} ({count_key}) needs {len(names)} numbers "
                                     f"({' '.join(names)}), found {self.text[j].strip()!r}"
                                     if j < len(self.text) else "end of file")
            for n, x in zip(names, nums):
                cols[n].append(x)
        return cols


    def strings(self, key: str, count_key: str) -> list:
        """The ``values[count_key]`` quoted strings starting on ``key``'s line (AeroDyn's
        AFNames: the first one carries the key, the others stand alone on the next lines)."""
        file = str(self.path)
        count = _count(self, count_key)
        if key not in self.lines:
            raise KeyedFileError(file, None, f"{key}: {count} names ({count_key}) needed "
                                             "from its line on, the key is missing")
        out = []
        for j in range(self.lines[key] - 1, len(self.text)):
            m = re.match(r'\s*"([^"]*)"', self.text[j])
            if not m:
                break
            out.append(m.group(1))
            if len(out) == count:
                return out
        raise KeyedFileError(file, self.lines[key], f"{key}: {count_key} = {count} names "
                                                    f"needed, found {len(out)}")

    def polar_tables(self, columns: dict) -> list:
        """AeroDyn airfoil tables (AirfoilInfo files of any version): one dict per table with
        its scalars (Re, UserProp, InclUAdata, ...; the file's RelThickness) and the columns
        ``{name: 1-based column}`` (AeroDyn's InCol_*) of its NumAlf rows, comment lines
        (``!``) skipped."""
        file = str(self.path)
        tables, current = [], {}
        j = 0
        while j < len(self.text):
            tok = self.text[j].split()
            if len(tok) >= 2 and tok[1] == "NumAlf":
                try:
                    n = int(tok[0])
                except ValueError:
                    raise KeyedFileError(file, j + 1, f"NumAlf = {tok[0]!r}: need an "
                                                      "integer") from None
                rows, j = [], j + 1
                while len(rows) < n and j < len(self.text):
                    line = self.text[j].split("!")[0].split()
                    j += 1
                    if not line:
                        continue
                    try:
                        rows.append([float(x) for x in line])
                    except ValueError:
                        raise KeyedFileError(file, j, f"airfoil table row {len(rows) + 1} of "
                                                      f"{n} (NumAlf): not numbers") from None
                if len(rows) < n:
                    raise KeyedFileError(file, j, f"airfoil table: {n} rows (NumAlf) needed, "
                                                  f"found {len(rows)}")
                width = min(len(r) for r in rows)
                table = dict(current)
                for name, col in columns.items():
                    if col and col > width:
                        raise KeyedFileError(file, j, f"airfoil table: column {col} for "
                                                      f"{name} but the rows have {width}")
                    if col:
                        table[name] = [r[col - 1] for r in rows]
                if "RelThickness" in self.values:
                    table.setdefault("RelThickness", self.values["RelThickness"])
                tables.append(table)
                current = {}
                continue
            if len(tok) >= 2 and _KEY.match(tok[1]) and not tok[0].startswith("!"):
                current[tok[1]] = _convert(tok[0].strip('"'))
            j += 1
        if not tables:
            raise KeyedFileError(file, None, "no airfoil table (NumAlf) found")
        return tables


def read_keyed(path) -> KeyedFile:
    """Every ``value key`` pair of the OpenFAST input file ``path`` (see the module)."""
    path = Path(path)
    try:
        text = path.read_text(errors="replace").splitlines()
    except OSError as exc:
        raise KeyedFileError(str(path), None, f"cannot be read ({exc})") from None
    out = KeyedFile(path=path, text=text)
    for i, line in enumerate(text, 1):
        m = _QUOTED.match(line)
        if m:
            value, key = m.group(1), m.group(2)
        else:
            tok = line.split()
            # section rules (-----, =====), comments and units lines; not negative numbers
            if len(tok) < 2 or tok[0].startswith(("--", "==", "!", "(")):
                continue
            value, key = _convert(tok[0]), tok[1]
        if not _KEY.match(key) or key in out.values:
            continue
        if not m and _KEY.match(str(tok[0])) and len(tok) > 2 and _KEY.match(tok[2]):
            continue                # a table's header (column names), not a value and key
        out.values[key] = value
        out.lines[key] = i
        bare = key.replace("(", "").replace(")", "")
        if bare != key:
            out.values.setdefault(bare, value)
            out.lines.setdefault(bare, i)
    return out


# ------------------------------------------------------------ the files with tables
def aerodyn_files(kf: KeyedFile) -> tuple:
    """AeroDyn (v14-era AeroDyn15 to v5) read by its keys: the main file's scalars, its
    airfoil files (AFNames, each read by keys: AirfoilInfo tables) and the first blade's
    file (the NumBlNds table by its column names): (the AeroDyn dictionary with AFNames and
    af_data, the blade's), as openfast-io's readers fill them."""
    ad = dict(kf.values)
    base = kf.path.parent
    names = kf.strings("AFNames", "NumAFfiles")
    ad["AFNames"] = [os.path.abspath(base / n) for n in names]
    cols = {"Alpha": ad.get("InCol_Alfa", 1), "Cl": ad.get("InCol_Cl", 2),
            "Cd": ad.get("InCol_Cd", 3), "Cm": ad.get("InCol_Cm", 0)}
    ad["af_data"] = []
    for path in ad["AFNames"]:
        if not Path(path).is_file():
            raise KeyedFileError(str(kf.path), kf.lines.get("AFNames"),
                                 f"airfoil file {path!r} not found")
        tables = read_keyed(path).polar_tables(cols)
        for tab in tables:          # AirfoilInfo's Re is in millions (openfast-io's: not)
            if isinstance(tab.get("Re"), (int, float)) and not isinstance(tab["Re"], bool):
                tab["Re"] = 1e6 * tab["Re"]
        ad["af_data"].append(tables)
    blade = ad.get("ADBlFile1")
    if not isinstance(blade, str):
        raise KeyedFileError(str(kf.path), kf.lines.get("ADBlFile(1)"),
                             f"ADBlFile(1) = {blade!r}: need the blade file's name")
    if isinstance(ad.get("NumTwrNds"), int) and ad["NumTwrNds"] > 0:
        ad.update(kf.table("TwrElev", "NumTwrNds"))       # the tower's drag table
    bkf = read_keyed(base / blade)
    bl = dict(bkf.values)
    bl.update(bkf.table("BlSpn", "NumBlNds"))
    return ad, bl


def _numeric_rows(kf: KeyedFile, start: int):
    """(line number, [floats]) of the lines from ``start`` (0-based) on whose every token
    (before a ``!`` comment) is a number."""
    for j in range(start, len(kf.text)):
        tok = kf.text[j].split("!")[0].split()
        try:
            yield j + 1, [float(t) for t in tok] if tok else None
        except ValueError:
            yield j + 1, None


def beamdyn_main(kf: KeyedFile) -> dict:
    """BeamDyn's main file by its keys: the scalars, and ``members`` (per member its key
    points kp_xr, kp_yr, kp_zr, initial_twist: the ``member  count`` line, the column names
    and units, count rows), as openfast-io's dictionary."""
    bd = dict(kf.values)
    file = str(kf.path)
    total = _count(kf, "member_total")
    j = kf.lines.get("kp_total", kf.lines["member_total"])
    members = []
    while len(members) < total and j < len(kf.text):
        tok = kf.text[j].split()
        j += 1
        if len(tok) >= 2 and tok[0].isdigit() and tok[1].isdigit():
            n = int(tok[1])
            while j < len(kf.text) and not kf.text[j].split()[:1] == ["kp_xr"]:
                j += 1
            j += 2                                   # the names and units lines
            rows = [r for _, r in zip(range(n), _numeric_rows(kf, j))]
            if len(rows) < n or any(r is None or len(r) < 4 for _, r in rows):
                raise KeyedFileError(file, j, f"member {len(members) + 1}: {n} key points "
                                              "(kp_xr kp_yr kp_zr initial_twist) needed")
            cols = np.array([r[:4] for _, r in rows])
            members.append(dict(zip(("kp_xr", "kp_yr", "kp_zr", "initial_twist"),
                                    (c.tolist() for c in cols.T))))
            j += n
    if len(members) < total:
        raise KeyedFileError(file, kf.lines.get("member_total"),
                             f"member_total = {total}: found {len(members)} member tables")
    bd["members"] = members
    return bd


def beamdyn_blade(kf: KeyedFile) -> dict:
    """BeamDyn's blade file by its keys: station_total, damp_type, mu1..mu6 (the row under
    their names), and per station eta, the 6x6 stiffness and the 6x6 mass matrices (the
    numeric rows after the DISTRIBUTED PROPERTIES rule), as openfast-io's dictionary."""
    bl = dict(kf.values)
    file = str(kf.path)
    n = _count(kf, "station_total", 2)
    for j, line in enumerate(kf.text):
        if line.split()[:1] == ["mu1"]:
            for ln, row in _numeric_rows(kf, j + 1):
                if row:
                    if len(row) < 6:
                        raise KeyedFileError(file, ln, "mu1 .. mu6: six numbers needed")
                    bl.update({f"mu{i + 1}": row[i] for i in range(6)})
                    break
            break
    start = next((j for j, line in enumerate(kf.text) if "DISTRIBUTED" in line.upper()
                  and line.lstrip().startswith("-")), None)
    if start is None:
        raise KeyedFileError(file, None, "no DISTRIBUTED PROPERTIES section")
    rows = [(ln, r) for ln, r in _numeric_rows(kf, start + 1) if r]
    need = 13 * n
    if len(rows) < need:
        raise KeyedFileError(file, rows[-1][0] if rows else start + 1,
                             f"station_total = {n}: {need} numeric rows (eta, 6 stiffness, 6 "
                             f"mass rows per station) needed, found {len(rows)}")
    eta, K, M = [], [], []
    for i in range(n):
        block = rows[13 * i:13 * (i + 1)]
        bad = [ln for k, (ln, r) in enumerate(block) if len(r) != (1 if k == 0 else 6)]
        if bad:
            raise KeyedFileError(file, bad[0], f"station {i + 1}: one number (eta) then 12 "
                                               "rows of six expected")
        eta.append(block[0][1][0])
        K.append([r for _, r in block[1:7]])
        M.append([r for _, r in block[7:13]])
    bl.update(radial_stations=np.array(eta), beam_stiff=np.array(K),
              beam_inertia=np.array(M))
    return bl
