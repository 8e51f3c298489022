"""HAWC2 input files read as text: the ``.htc`` model file (blocks and commands) and the
``_st.dat`` structural property files (sets and subsets of section rows).

An htc file is a tree of ``begin NAME; ... end NAME;`` blocks holding commands ``name
values;``; text after a command's ``;`` is a comment, and so is a line or the rest of a line
from ``;`` on when no command precedes it.  Commands keep their line numbers for messages.
An st file holds numbered sets (``#k`` lines) of subsets (``$j n`` lines followed by n rows
of numbers: 19 columns of a Timoshenko beam, 30 of a fully populated 6x6 one).

Plain text parsing (DTU's ``wetb`` reads these formats too, but brings numba, pandas, h5py,
paramiko and more with it: not worth it for two formats).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

__all__ = ["HtcBlock", "HtcCommand", "read_htc", "read_st", "read_ae", "read_pc",
           "HawcFileError", "TIMOSHENKO_COLUMNS", "FPM_COLUMNS", "model_folder", "read_opt",
           "OPT_COLUMNS", "where"]

#: The columns of a Timoshenko st subset (HAWC2 manual, "Structural data").
TIMOSHENKO_COLUMNS = ("r", "m", "x_cg", "y_cg", "ri_x", "ri_y", "x_sh", "y_sh", "E", "G",
                      "I_x", "I_y", "I_p", "k_x", "k_y", "A", "pitch", "x_e", "y_e")

#: The columns of a fully populated (FPM) st subset: the mass columns, the elastic centre and
#: the principal axes' pitch, then the upper triangle of the 6x6 stiffness row by row
#: (K11, K12, ..., K16, K22, ..., K66) on BECAS's strains (shear x, shear y, axial strain,
#: bending about x, bending about y, twist rate) at the elastic centre, pitched axes.
FPM_COLUMNS = ("r", "m", "x_cg", "y_cg", "ri_x", "ri_y", "pitch", "x_e", "y_e") + tuple(
    f"K{i}{j}" for i in range(1, 7) for j in range(i, 7))


class HawcFileError(ValueError):
    """A HAWC2 file that cannot be read: file, line (or None) and what is wrong."""

    def __init__(self, file: str, line: Optional[int], message: str):
        self.file, self.line, self.message = file, line, message
        super().__init__(f"{file}" + (f", line {line}" if line else "") + f": {message}")


@dataclass
class HtcCommand:
    """One command: its name, values, line and the file it is in (an included file's own,
    through continue_in_file)."""

    name: str
    values: list
    line: int
    file: str = ""

    def numbers(self, file: str = "") -> list:
        try:
            return [float(v) for v in self.values]
        except ValueError:
            raise HawcFileError(self.file or file, self.line,
                                f"{self.name} {' '.join(self.values)}: numbers expected"
                                ) from None


@dataclass
class HtcBlock:
    name: str
    line: int
    commands: list = field(default_factory=list)
    blocks: list = field(default_factory=list)
    file: str = ""

    def command(self, name: str) -> Optional[HtcCommand]:
        """The first command ``name`` of this block (None: absent)."""
        return next((c for c in self.commands if c.name == name), None)

    def all(self, name: str) -> list:
        return [c for c in self.commands if c.name == name]

    def block(self, name: str) -> Optional["HtcBlock"]:
        return next((b for b in self.blocks if b.name == name), None)

    def walk(self):
        """Every block below this one, depth first."""
        for b in self.blocks:
            yield b
            yield from b.walk()


def where(item) -> str:
    """'FILE, line N' of a command or block (its own file, an included one's included)."""
    return f"{Path(item.file).name}, line {item.line}" if item.file else f"line {item.line}"


_TOKEN = re.compile(r'"[^"]*"|[^\s;]+')


def model_folder(htc: Path) -> Path:
    """The folder HAWC2 runs a model from (its relative paths' base): the htc folder's
    parent when the htc file sits in a folder named ``htc``, else the htc file's folder."""
    htc = Path(htc).resolve()
    return htc.parent.parent if htc.parent.name.lower() == "htc" else htc.parent


def _lines(path: Path, base: Path, depth: int = 0) -> list:
    """(file, line number, text) of ``path`` with every ``continue_in_file`` expanded in
    place (paths relative to the model folder ``base``)."""
    if depth > 20:
        raise HawcFileError(str(path), None, "continue_in_file nested more than 20 deep")
    text = _text(path)
    out = []
    for i, raw in enumerate(text, 1):
        tok = _TOKEN.findall(raw.split(";", 1)[0])
        if depth and tok and tok[0].lower() == "exit":
            break                           # an included file returns to its includer
        if tok and tok[0].lower() == "continue_in_file":
            if len(tok) < 2:
                raise HawcFileError(str(path), i, "continue_in_file without a file name")
            target = (base / tok[1].strip('"')).resolve()
            if not target.is_file():
                raise HawcFileError(str(path), i, f"continue_in_file {tok[1]}: not found "
                                                  f"(looked for {target})")
            out += _lines(target, base, depth + 1)
            continue
        out.append((str(path), i, raw))
    return out


def read_htc(path) -> HtcBlock:
    """The htc file's block tree under a root block named ``""`` (``continue_in_file``
    expanded; the commands keep their own file's line numbers)."""
    path = Path(path)
    root = HtcBlock("", 0)
    stack = [root]
    for file, i, raw in _lines(path, model_folder(path)):
        line = raw.split(";", 1)[0]
        tok = _TOKEN.findall(line)
        if not tok or tok[0].startswith(("#", ";")):
            continue
        word = tok[0].lower()
        if word == "begin":
            if len(tok) < 2:
                raise HawcFileError(file, i, "begin without a block name")
            blk = HtcBlock(tok[1].lower(), i, file=file)
            stack[-1].blocks.append(blk)
            stack.append(blk)
        elif word == "end":
            if len(tok) >= 2 and tok[1].lower() == "exit":
                break
            if len(stack) == 1 or (len(tok) >= 2 and tok[1].lower() != stack[-1].name):
                raise HawcFileError(file, i, f"'end {tok[1] if len(tok) > 1 else ''}' "
                                                  f"does not close 'begin {stack[-1].name}' "
                                                  f"(line {stack[-1].line})")
            stack.pop()
        elif word == "exit":
            break
        else:
            stack[-1].commands.append(HtcCommand(word, [t.strip('"') for t in tok[1:]], i,
                                                 file=file))
    if len(stack) > 1:
        raise HawcFileError(stack[-1].file, stack[-1].line, f"'begin {stack[-1].name}' is "
                                                            "never closed")
    return root


def read_st(path, set_no: int, subset_no: int) -> np.ndarray:
    """The rows (n, columns) of subset ``subset_no`` of set ``set_no`` of an st file."""
    path = Path(path)
    text = _text(path)
    current = None
    for i, raw in enumerate(text, 1):
        tok = raw.split()
        if not tok:
            continue
        if tok[0].startswith("#"):
            try:
                current = int(tok[0][1:] or tok[1])
            except (ValueError, IndexError):
                current = None
            continue
        if tok[0].startswith("$") and current == set_no:
            try:
                sub = int(tok[0][1:] or tok[1])
                n = int(tok[1] if tok[0][1:] else tok[2])
            except (ValueError, IndexError):
                raise HawcFileError(str(path), i, f"{raw.strip()!r}: a subset line is "
                                                  "'$number rows'") from None
            if sub != subset_no:
                continue
            rows = []
            for j in range(i, min(i + n, len(text))):
                try:
                    rows.append([float(x) for x in text[j].split()])
                except ValueError:
                    raise HawcFileError(str(path), j + 1, f"set {set_no} subset {subset_no}: "
                                                          "row of numbers expected") from None
            if len(rows) < n or len({len(r) for r in rows}) != 1:
                raise HawcFileError(str(path), i, f"set {set_no} subset {subset_no}: {n} rows "
                                                  "of one width expected")
            return np.array(rows)
    raise HawcFileError(str(path), None, f"set {set_no} subset {subset_no} not found")


def _numbers(text: list, i: int, path: Path, what: str) -> list:
    """The numbers of line ``i`` (0-based) before a ``;`` or ``!`` comment."""
    if i >= len(text):
        raise HawcFileError(str(path), None, f"{what}: the file ends early")
    tok = re.split(r"[;!]", text[i], maxsplit=1)[0].split()
    out = []
    for t in tok:
        try:
            out.append(float(t))
        except ValueError:
            break                       # a name after the numbers (a pc table's airfoil)
    return out


def _text(path: Path) -> list:
    """The lines of ``path`` (HawcFileError naming it when it cannot be read)."""
    try:
        return path.read_text(errors="replace").splitlines()
    except OSError as exc:
        raise HawcFileError(str(path), None, f"cannot be read ({exc})") from None


def _table(text: list, start: int, n: int, path: Path, what: str) -> np.ndarray:
    """``n`` rows of at least four numbers from line ``start`` (0-based) on, the first four
    kept; HawcFileError naming the first short row's line."""
    rows = [_numbers(text, start + j, path, f"{what} row {j + 1}") for j in range(n)]
    bad = next((j for j, r in enumerate(rows) if len(r) < 4), None)
    if bad is not None:
        raise HawcFileError(str(path), start + 1 + bad, f"{what}: four numbers expected")
    return np.array([r[:4] for r in rows])


def read_ae(path, set_no: int) -> np.ndarray:
    """Set ``set_no`` of an ae file: rows (radius [m], chord [m], thickness [%], pc set)."""
    path = Path(path)
    text = _text(path)
    nsets = int(_numbers(text, 0, path, "the number of sets")[0])
    i = 1
    for k in range(1, nsets + 1):
        head = _numbers(text, i, path, f"set {k}'s header")
        if len(head) < 2:
            raise HawcFileError(str(path), i + 1, f"set {k}: 'set rows' expected")
        n = int(head[1])
        rows = _table(text, i + 1, n, path, f"ae set {k} (radius, chord, thickness, pc set)")
        if int(head[0]) == set_no:
            return rows
        i += 1 + n
    raise HawcFileError(str(path), None, f"ae set {set_no} not found ({nsets} sets)")


def read_pc(path, set_no: int) -> list:
    """Set ``set_no`` of a pc file: [(thickness [%], name, rows (n, 4): alpha [deg], cl, cd,
    cm)] in the file's order."""
    path = Path(path)
    text = _text(path)
    nsets = int(_numbers(text, 0, path, "the number of sets")[0])
    i = 1
    for k in range(1, nsets + 1):
        ntab = int(_numbers(text, i, path, f"set {k}'s table count")[0])
        i += 1
        tables = []
        for _ in range(ntab):
            head = _numbers(text, i, path, f"set {k}'s table header")
            if len(head) < 3:
                raise HawcFileError(str(path), i + 1, "a pc table header is 'number rows "
                                                      "thickness [name]'")
            n = int(head[1])
            name = " ".join(text[i].split()[3:])
            rows = _table(text, i + 1, n, path, f"pc set {k} table (alpha, cl, cd, cm)")
            tables.append((head[2], name, rows))
            i += 1 + n
        if k == set_no:
            return tables
    raise HawcFileError(str(path), None, f"pc set {set_no} not found ({nsets} sets)")


#: Columns of HAWCStab2's operational data (``.opt``, ``operation.dat``): the first three
#: are always there, the aerodynamic power and thrust when HAWCStab2 wrote the file.
OPT_COLUMNS = ("wind_speed", "pitch", "rpm", "power_kw", "thrust_kn")


def read_opt(path) -> dict:
    """HAWCStab2's operational data: a first line starting with the number of rows, then
    rows of wind speed [m/s], pitch [deg], rotor speed [rpm] and, in a written ``.opt``,
    aerodynamic power [kW] and thrust [kN].  Returns {column: array} (OPT_COLUMNS, the ones
    present)."""
    path = Path(path)
    text = _text(path)
    n = _numbers(text, 0, path, "the number of rows")
    if not n or n[0] < 1 or n[0] != int(n[0]):
        raise HawcFileError(str(path), 1, "the first line must start with the number of "
                                          "rows")
    rows = [_numbers(text, 1 + j, path, f"row {j + 1}") for j in range(int(n[0]))]
    width = min(len(r) for r in rows)
    if width < 3:
        bad = next(j for j, r in enumerate(rows) if len(r) < 3)
        raise HawcFileError(str(path), bad + 2, "wind speed, pitch and rotor speed expected")
    data = np.array([r[:min(width, 5)] for r in rows])
    return {k: data[:, j] for j, k in enumerate(OPT_COLUMNS[:data.shape[1]])}
