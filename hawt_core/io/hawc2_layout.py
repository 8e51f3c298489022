"""Where the main bodies of a HAWC2 model are: the ``orientation`` block's base and relative
placements turned into each body's frame and origin in HAWC2's global frame, and the
``constraint`` block's joints.

HAWC2's global frame (HAWC2 manual, "Coordinate systems"): z down (gravity along +z), y the
mean wind direction (downwind), x = y x z (lateral).  A main body's coordinates are its
``c2_def`` points; its frame is placed by

- ``base``: ``body``/``mbdy``, ``inipos`` (where its node 1 is, global) and
  ``body_eulerang``/``mbdy_eulerang`` (angles in degrees about x, then the turned y, then
  the turned z, relative to the global frame);
- ``relative``: ``body1``/``mbdy1`` NAME NODE and ``body2``/``mbdy2`` NAME NODE (node 1, a
  c2_def section number or ``last``): body2's node sits on body1's node, and body2's frame
  is body1's turned by every ``body2_eulerang``/``mbdy2_eulerang`` line in turn (each about
  the axes the previous lines left).

So a frame R (columns: the body's axes in global coordinates) of body2 is
``R1 Rx(a1) Ry(b1) Rz(c1) Rx(a2) ...``: for the DTU 10-MW the shaft's z then points upwind
and 5 deg up (its tilt), the hub's z along the blade coned 2.5 deg upwind (its cone).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from .hawc2_files import HawcFileError, HtcBlock

__all__ = ["BodyPlace", "Joint", "ModelLayout", "model_layout", "c2_sections", "rot_xyz",
           "body_blocks"]


def rot_xyz(angles_deg) -> np.ndarray:
    """The frame turned about x, then the turned y, then the turned z by ``angles_deg``:
    Rx(a) Ry(b) Rz(c) (columns: the new axes in the old frame)."""
    a, b, c = np.radians(np.asarray(angles_deg, float))
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rx @ ry @ rz


def _command(block: HtcBlock, *names):
    """The first of the commands ``names`` (HAWC2's body/mbdy spellings) in ``block``."""
    return next((c for n in names for c in block.all(n)), None)


def c2_sections(body: HtcBlock, name: str, file: str) -> np.ndarray:
    """The body's c2_def sections (n, 4): x, y, z [m] in its own coordinates and twist [deg]."""
    c2 = body.block("c2_def")
    if c2 is None:
        raise HawcFileError(body.file or file, body.line, f"main_body {name}: no c2_def")
    secs = [c.numbers(file) for c in c2.all("sec")]
    if len(secs) < 2 or any(len(s) < 5 for s in secs):
        raise HawcFileError(c2.file or file, c2.line, f"main_body {name}: c2_def needs two "
                                                      "or more 'sec NR x y z twist' lines")
    return np.array([s[1:5] for s in secs])


@dataclass
class BodyPlace:
    """One main body: its data block (a ``copy_main_body`` resolved to the body copied),
    c2_def sections, frame ``R`` (columns: its x, y, z in global coordinates), ``origin``
    [m, global] and the body it was placed on (None for the base)."""

    name: str
    block: HtcBlock
    c2: np.ndarray
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    parent: Optional[str] = None
    placed: bool = False

    def node_index(self, node: str, file: str, line: int) -> int:
        """0-based c2_def section of a node given as ``last`` or a 1-based number."""
        if node == "last":
            return len(self.c2) - 1
        try:
            k = int(float(node))
        except ValueError:
            k = 0
        if not 1 <= k <= len(self.c2):
            raise HawcFileError(file, line, f"node {node!r} of {self.name}: allowed: 1 to "
                                            f"{len(self.c2)} (its c2_def sections) or last")
        return k - 1

    def points(self) -> np.ndarray:
        """The c2_def points in global coordinates (n, 3)."""
        return self.origin + self.c2[:, :3] @ self.R.T

    def node(self, k: int) -> np.ndarray:
        return self.points()[k]


@dataclass
class Joint:
    """A constraint: ``kind`` (fix0, fix1, bearing1, bearing2, bearing3, ...), the bodies
    and nodes it joins, its name and bearing vector (as written) and its line."""

    kind: str
    body1: Optional[str]
    body2: Optional[str]
    name: str = ""
    vector: Optional[list] = None
    line: int = 0
    file: str = ""


@dataclass
class ModelLayout:
    bodies: dict
    joints: list
    base: str
    notes: list

    def children(self, name: str) -> list:
        return [b.name for b in self.bodies.values() if b.parent == name]

    def path_to(self, name: str) -> list:
        """The bodies from the base to ``name`` (both included)."""
        out = [name]
        while self.bodies[out[-1]].parent is not None:
            out.append(self.bodies[out[-1]].parent)
        return out[::-1]


def body_blocks(structure: HtcBlock, file: str) -> dict:
    """Every main body's data block by name, a ``copy_main_body`` resolved to the body it
    copies (HawcFileError for a body without a name, or a copy of no body or of itself)."""
    blocks = {}
    for blk in structure.blocks:
        if blk.name != "main_body":
            continue
        cmd = blk.command("name")
        if cmd is None or not cmd.values:
            raise HawcFileError(blk.file or file, blk.line, "main_body without a name")
        blocks[cmd.values[0]] = blk
    data_of = {}
    for name, blk in blocks.items():
        data, seen = blk, {name}
        while data.command("copy_main_body") is not None:
            src = data.command("copy_main_body").values[0]
            if src not in blocks or src in seen:
                raise HawcFileError(data.file or file, data.command("copy_main_body").line,
                                    f"main_body {name}: copy_main_body {src}: no such body "
                                    "(or a circle of copies)")
            seen.add(src)
            data = blocks[src]
        data_of[name] = data
    return data_of


def _main_bodies(structure: HtcBlock, file: str) -> dict:
    return {name: BodyPlace(name=name, block=data, c2=c2_sections(data, name, file))
            for name, data in body_blocks(structure, file).items()}


def _body_node(block: HtcBlock, which: str, bodies: dict, file: str):
    cmd = _command(block, which, which.replace("body", "mbdy"))
    if cmd is None or len(cmd.values) < 2 or cmd.values[0] not in bodies:
        raise HawcFileError(block.file or file, block.line,
                            f"{block.name}: '{which} NAME NODE' with a main body's name "
                            f"expected (found {' '.join(cmd.values) if cmd else 'none'})")
    body = bodies[cmd.values[0]]
    return body, body.node_index(cmd.values[1], cmd.file or file, cmd.line)


def model_layout(root: HtcBlock, htc: Path) -> ModelLayout:
    """Every main body of ``new_htc_structure`` placed by the ``orientation`` block, and the
    ``constraint`` block's joints.  A body the orientation does not place is an error naming
    it; what the orientation says that is not geometry (initial rotation speeds) is noted."""
    file = str(htc)
    structure = root.block("new_htc_structure")
    if structure is None:
        raise HawcFileError(file, None, "no new_htc_structure block")
    bodies = _main_bodies(structure, file)
    orientation = structure.block("orientation")
    if orientation is None or orientation.block("base") is None:
        raise HawcFileError(structure.file or file, structure.line,
                            "new_htc_structure: no orientation block with a base")
    notes = []
    base_blk = orientation.block("base")
    cmd = _command(base_blk, "body", "mbdy")
    if cmd is None or not cmd.values or cmd.values[0] not in bodies:
        raise HawcFileError(base_blk.file or file, base_blk.line,
                            "orientation base: 'body NAME' with a main body's name "
                            "expected")
    base = bodies[cmd.values[0]]
    pos = _command(base_blk, "inipos")
    ang = [c.numbers(file) for n in ("body_eulerang", "mbdy_eulerang") for c in base_blk.all(n)]
    base.R = np.eye(3)
    for a in ang:
        base.R = base.R @ rot_xyz(a[:3])
    node1 = base.c2[0, :3] @ base.R.T
    base.origin = (np.array(pos.numbers(file)[:3]) if pos is not None else np.zeros(3)) - node1
    base.placed = True
    for blk in orientation.blocks:
        if blk.name != "relative":
            continue
        b1, n1 = _body_node(blk, "body1", bodies, file)
        b2, n2 = _body_node(blk, "body2", bodies, file)
        if not b1.placed:
            raise HawcFileError(blk.file or file, blk.line, f"orientation relative: "
                                                            f"{b1.name} is used before it is "
                                                            "placed")
        R = b1.R.copy()
        for c in blk.commands:
            if c.name in ("body2_eulerang", "mbdy2_eulerang"):
                R = R @ rot_xyz(c.numbers(file)[:3])
            elif c.name.endswith("ini_rotvec_d1"):
                notes.append(f"orientation of {b2.name}: {c.name} {' '.join(c.values)} "
                             f"({Path(c.file).name}, line {c.line}): HAWC2's initial "
                             "rotation speed, not geometry "
                             "(hawt's rotor speed comes from the operational data)")
        b2.R, b2.parent, b2.placed = R, b1.name, True
        b2.origin = b1.node(n1) - b2.c2[n2, :3] @ R.T
    unplaced = [n for n, b in bodies.items() if not b.placed]
    if unplaced:
        raise HawcFileError(orientation.file or file, orientation.line,
                            f"orientation: no placement of main body "
                            f"{', '.join(unplaced)}")
    joints = []
    constraint = structure.block("constraint")
    for blk in (constraint.blocks if constraint is not None else []):
        if blk.name == "fix0":
            c = _command(blk, "body", "mbdy")
            joints.append(Joint("fix0", None, c.values[0] if c else None, line=blk.line,
                                file=blk.file))
            continue
        c1, c2 = _command(blk, "body1", "mbdy1"), _command(blk, "body2", "mbdy2")
        vec = blk.command("bearing_vector")
        name = blk.command("name")
        joints.append(Joint(blk.name, c1.values[0] if c1 and c1.values else None,
                            c2.values[0] if c2 and c2.values else None,
                            name=name.values[0] if name and name.values else "",
                            vector=vec.numbers(file) if vec is not None else None,
                            line=blk.line, file=blk.file))
    return ModelLayout(bodies=bodies, joints=joints, base=base.name, notes=notes)
