"""A whole HAWC2 model (``.htc`` with its st, ae, pc files and operational data) -> a hawt
turbine: ``hawt import hawc2 MODEL.htc`` and TURBINE = a ``.htc`` path.

What maps to what (HAWC2's global frame: z down, y downwind; hawc2_layout.py):

- the roles of the main bodies come from the model's topology, not their names: the tower
  is the body the orientation's base places (a body named ``tower`` above a monopile or
  jacket base instead); the blades are the aero block's ``link`` bodies; the rotor bearing
  is the ``bearing1``/``bearing3`` on the way from the tower to blade 1; the nacelle is
  every body between the tower and that bearing (towertop, connector ...), the rotating
  hub every body between the bearing and the blades (shaft, hub1..3);
- tower and blade: flexible beams (hawc2.py ``hawc2_body``; a tower's frame turned half a
  turn about its y, (t1, t2, t3) = (-z, -x, y));
- nacelle: the mass, mass centre and inertia of its bodies' concentrated masses and beams
  (a beam's mass lumped at the middle of each st interval), in hawt's nacelle frame
  (y1 up along the tower, y2 = -x, y3 = y downwind); the yaw bearing locked unless a
  bearing joins the tower and the nacelle;
- rotor geometry from the placed bodies: the shaft axis (the rotor bearing's
  ``bearing_vector``) gives the tilt; the blade roots (blade node 1) the hub radius and the
  rotor apex (the point of the shaft axis in the roots' plane), hence the overhang from the
  yaw axis and the shaft height above the tower top; blade 1's z the precone;
- drivetrain: the rotor bearing body's torsion between its first and last node
  (1/k = integral dr / (G I_p)), its ``damping_posdef`` kz as the stiffness-proportional
  damping (c = kz k), the concentrated inertia at its first node as the generator
  (low-speed-shaft equivalent, gear ratio 1) held at the rotor speed (HAWC2's generator is a
  controller DLL, which hawt does not run);
- hub: every other mass on the rotating side (the hub's concentrated mass, the shaft and hub
  beams), at the apex, its inertia about the shaft and (mean) across it;
- aerodynamics: the aero block (hawc2.py ``hawc2_aerodynamics``); the tower's drag from the
  aerodrag block;
- rotor speed and pitch: HAWCStab2's operational data (the ``hawcstab2`` block's
  ``operational_data_filename``, the ``operation=`` file, or the one ``.opt`` /
  ``operation.dat`` in the model's data folder): the rated (largest) speed and its pitch.

What is read and not taken is listed in the warnings and notes, never dropped.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import numpy as np

from ..model import (Drivetrain, Gravity, Hub, Nacelle, Rotor, TowerAerodynamics, Turbine)
from .hawc2 import body_damping, body_st, file_error, hawc2_aerodynamics, hawc2_body
from .hawc2_files import HawcFileError, model_folder, read_htc, read_opt, where
from .hawc2_layout import ModelLayout, model_layout
from .imported import ELEMENTS, ImportResult, hub_yaw_share, package_version
from .turbine_yaml import TurbineFileError

__all__ = ["read_hawc2", "IMPORTER", "MAIN"]

IMPORTER = f"hawt {package_version('hawt')} HAWC2 importer"
MAIN = "HAWC2 main"

#: Top-level htc blocks that describe how HAWC2 runs, not the turbine: noted, not warned.
RUN_BLOCKS = ("simulation", "output", "output_at_time", "hawcstab2")


class _Masses:
    """Point masses with their own inertia (global frame): totals about the mass centre."""

    def __init__(self):
        self.m, self.p, self.I = [], [], []

    def add(self, m: float, p, inertia=None):
        self.m.append(float(m))
        self.p.append(np.asarray(p, float))
        self.I.append(np.zeros((3, 3)) if inertia is None else np.asarray(inertia, float))

    def take_points_at(self, p, tol: float = 1e-6) -> float:
        """Remove the inertia-free point masses at ``p`` and return their sum [kg]."""
        at = [k for k in range(len(self.m)) if np.linalg.norm(self.p[k] - p) <= tol
              and not np.any(self.I[k])]
        taken = sum(self.m[k] for k in at)
        for k in reversed(at):
            del self.m[k], self.p[k], self.I[k]
        return float(taken)

    def total(self) -> tuple:
        """(mass, mass centre, inertia tensor about the mass centre), global frame."""
        m = np.array(self.m)
        M = float(m.sum())
        if M == 0:
            return 0.0, np.zeros(3), sum(self.I, np.zeros((3, 3)))
        p = np.array(self.p)
        c = m @ p / M
        d = p - c
        Ipt = (m * (d * d).sum(1)).sum() * np.eye(3) - (m[:, None] * d).T @ d
        return M, c, Ipt + sum(self.I, np.zeros((3, 3)))


def _body_masses(htc: Path, lay: ModelLayout, name: str, masses: _Masses, notes: list,
                 skip_node: Optional[int] = None) -> list:
    """Add a (rigid-taken) body's beam mass and concentrated masses to ``masses``; the
    concentrated masses at node ``skip_node`` (0-based) are returned instead (the
    generator's)."""
    body = lay.bodies[name]
    st, st_path, _ = body_st(htc, body.block, name)
    r, m = st["r"], st["m"]
    pts = body.points()
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    s = 0.5 * (r[1:] + r[:-1]) / r[-1] * arc[-1]
    dm = 0.5 * (m[1:] + m[:-1]) * np.diff(r)
    for k in range(len(dm)):
        masses.add(dm[k], [np.interp(s[k], arc, pts[:, j]) for j in range(3)])
    notes.append(f"{name}: taken as rigid; its beam's {dm.sum():.6g} kg ({st_path.name}) "
                 "lumped at the middle of each st interval")
    held = []
    for c in body.block.all("concentrated_mass"):
        v = c.numbers(str(htc))
        if len(v) < 8:
            raise TurbineFileError(c.file or str(htc), [
                f"main_body {name}: concentrated_mass ({where(c)}) needs node, x, y, z, "
                "mass, Ixx, Iyy, Izz"])
        k = body.node_index(str(int(v[0])), c.file or str(htc), c.line)
        Ib = np.diag(v[5:8])
        if len(v) >= 11:
            Ib[0, 1] = Ib[1, 0] = v[8]
            Ib[0, 2] = Ib[2, 0] = v[9]
            Ib[1, 2] = Ib[2, 1] = v[10]
        p = body.node(k) + body.R @ np.array(v[1:4])
        I_g = body.R @ Ib @ body.R.T
        if skip_node is not None and k == skip_node:
            held.append((v[4], p, I_g, c))
        else:
            masses.add(v[4], p, I_g)
    return held


def _operational_data(htc: Path, root, operation) -> tuple:
    """(path, {column: array}) of HAWCStab2's operational data, or (None, None)."""
    folder = model_folder(htc)
    if operation is not None:
        path = Path(operation)
    else:
        hs2 = root.block("hawcstab2")
        cmd = hs2.command("operational_data_filename") if hs2 is not None else None
        if cmd is not None and cmd.values:
            path = folder / cmd.values[0]
        else:
            found = sorted(set((folder / "data").glob("*.opt"))
                           | set((folder / "data").glob("operation.dat")))
            if len(found) != 1:
                return None, None
            path = found[0]
    if not path.is_file():
        raise TurbineFileError(str(path), ["operational data file not found"])
    try:
        return path, read_opt(path)
    except HawcFileError as exc:
        raise file_error(exc) from None


def _roles(lay: ModelLayout, root, htc: Path) -> dict:
    """Which bodies are the tower, the blades, the nacelle and the rotating hub, and which
    joint is the rotor bearing."""
    file = str(htc)
    bodies = lay.bodies
    tower = lay.base
    if "tower" in bodies and tower != "tower":
        tower = "tower"
    if not any(j.kind == "fix0" and j.body2 == lay.base for j in lay.joints):
        raise TurbineFileError(file, [f"the base body {lay.base} is not fixed to the ground "
                                      "(no fix0): hawt's tower is clamped at its base"])
    aero = root.block("aero")
    links = [c for c in aero.all("link")] if aero is not None else []
    blades = [c.values[2] for c in links if len(c.values) >= 3 and c.values[2] in bodies]
    if not blades:
        blades = [j.body2 for j in lay.joints if j.kind == "bearing2" and j.body2 in bodies]
    if not blades:
        raise TurbineFileError(file, ["no blades: neither the aero block's 'link N "
                                      "mbdy_c2_def BODY' nor bearing2 (pitch) joints name one"])
    path = lay.path_to(blades[0])
    if tower not in path:
        raise TurbineFileError(file, [f"blade {blades[0]} is not placed on the tower "
                                      f"{tower} (orientation chain {' -> '.join(path)})"])
    path = path[path.index(tower):]
    rotor = None
    for j in lay.joints:
        if j.kind in ("bearing1", "bearing3") and j.body2 in path and j.body1 in path \
                and path.index(j.body2) == path.index(j.body1) + 1:
            rotor = j
            break
    if rotor is None:
        raise TurbineFileError(file, ["no bearing1 or bearing3 (the rotor bearing) between "
                                      f"the tower and {blades[0]} ({' -> '.join(path)})"])
    k = path.index(rotor.body2)
    nacelle = path[1:k]
    blade_set = set(blades)
    rotating = []
    todo = [rotor.body2]
    while todo:
        b = todo.pop()
        if b in blade_set:
            continue
        rotating.append(b)
        todo += lay.children(b)
    below = lay.path_to(tower)[:-1]
    return {"tower": tower, "blades": blades, "rotor": rotor, "nacelle": nacelle,
            "rotating": rotating, "below": below}


def read_hawc2(path, operation=None) -> ImportResult:
    """Read a HAWC2 model (its main ``.htc`` file) into a hawt :class:`Turbine`.

    ``operation``: HAWCStab2 operational data (``.opt``/``operation.dat``) to take the
    rotor speed and pitch from (default: the model's own, see the module docstring).
    Raises :class:`TurbineFileError` naming the file (and line) for anything unreadable or
    outside what hawt models; returns the turbine with the import's warnings and notes."""
    htc = Path(path)
    if htc.suffix.lower() != ".htc":
        raise TurbineFileError(str(htc), ["a HAWC2 model is read from its main '.htc' file"])
    if not htc.is_file():
        raise TurbineFileError(str(htc), ["file not found"])
    htc = htc.resolve()
    file = str(htc)
    try:
        root = read_htc(htc)
        lay = model_layout(root, htc)
    except HawcFileError as exc:
        raise file_error(exc) from None
    warnings, notes = [], list(lay.notes)
    roles = _roles(lay, root, htc)
    B = lay.bodies
    tower_b, blade_b = B[roles["tower"]], B[roles["blades"][0]]
    for b in roles["below"]:
        warnings.append(f"main_body {b} (below the tower, {where(B[b].block)}) read but not "
                        "modelled: hawt clamps the tower at its base")

    # hawt's nacelle frame Y from the tower's: y1 up along the tower, y3 = its y (downwind)
    y1, y3 = -tower_b.R[:, 2], tower_b.R[:, 1]
    y2 = np.cross(y3, y1)
    Y = np.stack([y1, y2, y3], 1)
    top = tower_b.points()[-1]

    # rotor axis (downwind, hawt's s3) from the rotor bearing's vector
    rj = roles["rotor"]
    shaft = B[rj.body2]
    if rj.vector is not None and len(rj.vector) >= 4:
        coo = int(rj.vector[0])
        frame = {0: np.eye(3), 1: B[rj.body1].R, 2: shaft.R}.get(coo, shaft.R)
        axis = frame @ np.array(rj.vector[1:4])
    else:
        axis = shaft.R[:, 2]
    s3 = axis / np.linalg.norm(axis)
    if s3 @ y3 < 0:
        s3 = -s3
    p0 = shaft.points()[0]
    roots = np.array([B[b].points()[0] for b in roles["blades"]])
    along = (roots[0] - p0) @ s3
    apex = p0 + along * s3
    radial = roots[0] - apex
    radius = float(np.linalg.norm(radial))
    if np.any(np.abs((roots - p0) @ s3 - along) > 1e-6 * max(radius, 1.0)):
        raise TurbineFileError(file, ["the blade roots do not lie in one plane across the "
                                      "shaft: hawt's blades are identical and equally coned"])
    tilt = float(math.asin(np.clip(s3 @ y1, -1, 1)))
    # where the shaft axis meets the yaw axis (y1 through the tower top): least squares
    A = np.stack([s3, -y1], 1)
    (t_s, u_y), *_ = np.linalg.lstsq(A, top - apex, rcond=None)
    miss = float(np.linalg.norm(apex + t_s * s3 - (top + u_y * y1)))
    if miss > 1e-3:
        warnings.append(f"the shaft axis passes {miss:.4g} m beside the yaw axis: hawt's "
                        "shaft meets it (the offset is not modelled)")
    yaw_to_apex = -float(t_s)          # apex from the yaw axis along s3 (negative upwind)
    shaft_height = float(u_y)
    blade_z = blade_b.R[:, 2]
    cones = [float(math.asin(np.clip(B[b].R[:, 2] @ s3, -1, 1))) for b in roles["blades"]]
    cone = cones[0]
    if max(cones) - min(cones) > 1e-9:
        raise TurbineFileError(file, [f"blade cones {np.degrees(cones).round(6).tolist()} "
                                      "deg differ: hawt's blades are identical"])
    # the blade's own turn about its axis in the hub (a pitch built into the orientation):
    # hawt's b2 is the direction of motion of a rotor turning about +s3
    b1 = blade_z
    b2 = np.cross(s3, radial / radius)
    b2 -= (b2 @ b1) * b1
    b2 /= np.linalg.norm(b2)
    b3 = np.cross(b1, b2)
    xb = blade_b.R[:, 0]
    built_pitch = float(math.atan2(xb @ b3, xb @ b2))
    aero = root.block("aero")
    hub_vec = aero.command("hub_vec") if aero is not None else None
    if abs(built_pitch) > math.pi / 2:
        # the leading edge (x) points against hawt's motion: the rotor turns the other way
        # round; hawt models its mirror image (the same dynamics, the lateral axis reversed)
        built_pitch = float(math.atan2(xb @ b3, -(xb @ b2)))
        notes.append("the rotor turns anticlockwise seen from upwind: hawt models its mirror "
                     "image (the same dynamics, the lateral axis reversed)")
    if hub_vec is not None:
        notes.append(f"aero: hub_vec {' '.join(hub_vec.values)}: the rotation sense, taken "
                     "from the blades' leading edges (x)")

    # tower and blade beams
    tower, tnotes = hawc2_body(htc, roles["tower"], flip=True, root=root, **ELEMENTS["tower"])
    blade, bnotes = hawc2_body(htc, roles["blades"][0], root=root, **ELEMENTS["blade"])
    notes += tnotes + bnotes
    for b in roles["blades"][1:]:
        if B[b].block is not blade_b.block:
            warnings.append(f"main_body {b} has its own data (not copy_main_body "
                            f"{roles['blades'][0]}): hawt's blades are identical, "
                            f"{roles['blades'][0]} taken")

    # nacelle: masses of the bodies between the tower and the rotor bearing
    nac = _Masses()
    for name in roles["nacelle"]:
        _body_masses(htc, lay, name, nac, notes)
    yaw_bearing = nac.take_points_at(top)
    if yaw_bearing:
        notes.append(f"nacelle: {yaw_bearing:g} kg of point masses at the tower top taken as "
                     "the yaw bearing mass (it does not yaw)")
    M_n, c_n, I_n = nac.total()
    cg = Y.T @ (c_n - top)
    I_y = Y.T @ I_n @ Y
    off = np.abs(I_y - np.diag(np.diag(I_y))).max()
    if off > 1e-6 * max(np.abs(np.diag(I_y)).max(), 1.0):
        warnings.append(f"nacelle: products of inertia up to {off:.4g} kg m^2 in hawt's "
                        "nacelle frame read but not modelled (hawt's nacelle inertia is "
                        "diagonal)")

    # rotating side: the generator at the rotor bearing's node, the rest is the hub
    rot = _Masses()
    bearing_node = 0
    gen = []
    for name in roles["rotating"]:
        gen += _body_masses(htc, lay, name, rot, notes,
                            skip_node=bearing_node if name == rj.body2 else None)
    J_gen = 0.0
    for m, p, I_g, c in gen:
        J_gen += float(s3 @ I_g @ s3)
        if m:
            rot.add(m, p)
            notes.append(f"{rj.body2}: concentrated_mass ({where(c)}) at the rotor bearing: "
                         f"its {m:g} kg counted with the hub")
    M_h, c_h, I_h = rot.total()
    d_h = c_h - apex
    if M_h and np.linalg.norm(d_h) > 1e-2:
        notes.append(f"hub: the rotating masses' centre lies {d_h @ s3:+.4g} m along the "
                     f"shaft and {np.linalg.norm(d_h - (d_h @ s3) * s3):.4g} m off it from the "
                     "rotor apex; hawt puts the hub mass at the apex")
    P = np.eye(3) - np.outer(s3, s3)
    i_long = float(s3 @ I_h @ s3)
    i_lat = float(0.5 * np.trace(P @ I_h @ P))
    hub = Hub(radius=radius, teeter=False, inertia_lateral=i_lat,
              inertia_longitudinal=i_long, mass=M_h)
    nacelle = Nacelle(yaw_inertia=float(I_y[0, 0] + M_n * (cg[1] ** 2 + cg[2] ** 2))
                      + hub_yaw_share(hub, tilt, yaw_to_apex),
                      yaw_to_teeter=yaw_to_apex, shaft_tilt=tilt,
                      yaw_free=_yaw_free(lay, roles, notes), mass=M_n,
                      cg_offset=tuple(float(v) for v in cg),
                      inertia_pitch=float(I_y[1, 1]), inertia_roll=float(I_y[2, 2]),
                      shaft_height=shaft_height, yaw_bearing_mass=yaw_bearing)
    drivetrain = _drivetrain(htc, lay, rj.body2, J_gen, notes, warnings)

    # operation: rotor speed and pitch
    opt_path, opt = _operational_data(htc, root, operation)
    if opt is not None:
        rated = float(opt["rpm"].max())
        k = int(np.argmax(opt["rpm"] >= rated * (1 - 1e-6)))
        speed, pitch_deg = rated * math.pi / 30.0, float(opt["pitch"][k])
        notes.append(f"rotor: {rated:g} rpm and pitch {pitch_deg:g} deg, the rated point "
                     f"({opt['wind_speed'][k]:g} m/s) of {opt_path.name}")
    else:
        rv = next((c for blk in root.walk() if blk.name == "relative" for c in blk.commands
                   if c.name.endswith("ini_rotvec_d1")), None)
        if rv is None or not rv.numbers(file)[3:4] or rv.numbers(file)[3] == 0:
            raise TurbineFileError(file, ["no operational data (a hawcstab2 block's "
                                          "operational_data_filename, one data/*.opt or "
                                          "data/operation.dat) and no initial rotor speed: "
                                          "give the operational data file (--operation)"])
        speed, pitch_deg = abs(rv.numbers(file)[3]), 0.0
        warnings.append(f"no operational data: the rotor speed is the initial rotation speed "
                        f"{speed:g} rad/s ({rv.name}, line {rv.line}), the pitch 0")
    rotor = Rotor(speed=speed, blades=int(_blade_count(root, roles, file)), precone=cone,
                  pitch=built_pitch - math.radians(pitch_deg))

    aerodynamics, anotes = (hawc2_aerodynamics(htc, root=root) if aero is not None
                            else (None, []))
    notes += anotes
    if aero is None:
        notes.append("no aero block: the turbine has no aerodynamics")
    wind = root.block("wind")
    if wind is not None and wind.command("density") is not None:
        notes.append(f"wind: density {wind.command('density').values[0]} kg/m^3 (hawt's "
                     "aeroelastic analyses take the air density as their own setting)")
    for blk in root.blocks:
        if blk.name in RUN_BLOCKS or blk.name in ("new_htc_structure", "aero", "aerodrag"):
            continue
        warnings.append(f"block {blk.name} ({where(blk)}) read but not modelled" +
                        {"dll": " (HAWC2's controllers: hawt runs its own or ROSCO)",
                         "wind": " (hawt's wind is set per analysis)"}.get(blk.name, ""))
    for j in lay.joints:
        if j.kind not in ("fix0", "fix1", "bearing1", "bearing2", "bearing3"):
            warnings.append(f"constraint {j.kind} ({where(j)}) read but not modelled")
    notes.append("pitch bearings (bearing2) held at the operating pitch: hawt's blades have "
                 "no pitch degree of freedom")
    turbine = Turbine(name=htc.stem, rotor=rotor, hub=hub, nacelle=nacelle, blade=blade,
                      tower=tower, gravity=Gravity(enabled=True, g=9.81),
                      drivetrain=drivetrain, aerodynamics=aerodynamics,
                      tower_aerodynamics=_tower_drag(root, roles["tower"], tower, file,
                                                     notes))
    base = tower_b.points()[0] @ y1
    if abs(base) > 1e-9:
        notes.append(f"tower: its base is {abs(base):g} m {'above' if base > 0 else 'below'} "
                     "HAWC2's origin (hawt measures from the tower base)")
    sources = {MAIN: file}
    if opt_path is not None:
        sources["operational data"] = str(opt_path)
    return ImportResult(turbine=turbine, importer=IMPORTER, main_role=MAIN,
                        warnings=warnings, notes=notes, sources=sources)


def _yaw_free(lay: ModelLayout, roles: dict, notes: list) -> bool:
    chain = [roles["tower"]] + roles["nacelle"]
    for j in lay.joints:
        if j.body1 in chain and j.body2 in chain and j.kind.startswith("bearing"):
            notes.append(f"yaw: {j.kind} {j.name} between {j.body1} and {j.body2}: a free "
                         "yaw bearing")
            return True
    notes.append("yaw: the nacelle is fixed to the tower (fix1): yaw locked")
    return False


def _drivetrain(htc: Path, lay: ModelLayout, name: str, J_gen: float, notes: list,
                warnings: list):
    """The rotor bearing body's torsion as the shaft, the generator inertia at its bearing
    node; None when the generator carries no inertia (a rigid shaft at the rotor speed)."""
    if J_gen <= 0:
        notes.append("drivetrain: no generator inertia at the rotor bearing: a rigid shaft "
                     "at the rotor speed")
        return None
    body = lay.bodies[name]
    st, st_path, _ = body_st(htc, body.block, name)
    r = st["r"]
    gj = st["G"] * st["I_p"]
    flex = float(np.sum(np.diff(r) * 0.5 * (1 / gj[1:] + 1 / gj[:-1])))
    k = 1.0 / flex
    damping, _, key = body_damping(htc, body.block, name)
    c = damping.stiffness[0] * k if damping is not None else 0.0
    notes.append(f"drivetrain: {name}'s torsion {k:.6g} N m/rad ({st_path.name}), damping "
                 f"{c:.6g} N m s/rad ({key or 'none'} kz x stiffness), generator inertia "
                 f"{J_gen:.6g} kg m^2 on the low-speed shaft (gear ratio 1)")
    warnings.append("drivetrain: HAWC2's generator torque is its controller DLL's, not "
                    "modelled: hawt holds the generator at the rotor speed "
                    "(drivetrain.generator: prescribed)")
    return Drivetrain(stiffness=k, damping=c, generator_inertia=J_gen, gearbox_ratio=1.0,
                      generator="prescribed")


def _blade_count(root, roles: dict, file: str) -> int:
    aero = root.block("aero")
    nb = aero.command("nblades") if aero is not None else None
    n = int(float(nb.values[0])) if nb is not None and nb.values else len(roles["blades"])
    if n != len(roles["blades"]):
        raise TurbineFileError(file, [f"aero nblades {n} but {len(roles['blades'])} blade "
                                      "bodies linked"])
    return n


def _tower_drag(root, tower_name: str, tower, file: str, notes: list):
    drag = root.block("aerodrag")
    for el in (drag.blocks if drag is not None else []):
        name = el.command("mbdy_name")
        if el.name != "aerodrag_element" or name is None or name.values[:1] != [tower_name]:
            continue
        secs = np.array([c.numbers(file)[:3] for c in el.all("sec")])
        if secs.ndim != 2 or len(secs) < 2:
            raise TurbineFileError(file, [f"aerodrag_element {tower_name} ({where(el)}): "
                                          "two or more 'sec z cd diameter' lines expected"])
        notes.append(f"tower drag: aerodrag_element {tower_name}, {len(secs)} sections")
        return TowerAerodynamics(stations=np.clip(secs[:, 0] / tower.length, 0, 1),
                                 diameter=secs[:, 2], drag=secs[:, 1])
    return None
