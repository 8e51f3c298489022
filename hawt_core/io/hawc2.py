"""HAWC2 models -> hawt: a main body (its ``c2_def`` centre line and Timoshenko ``st`` set)
as a hawt Beam, with its ``damping_posdef`` Rayleigh damping.

Frames (HAWC2 manual, "main body" and "Structural data"): a blade's main body has z along
the span and its c2 section frame (x_c2, y_c2) turned about z by the c2_def twist; y points
to the pressure side, downwind for an upwind rotor (the DTU 10-MW's prebend, upwind, is
negative c2_def y).  hawt's blade frame has b1 span, b2 in the rotor plane, b3 flapwise
downwind, so (b1, b2, b3) = (z, x, y); a positive HAWC2 twist (about z, from x towards y) is
a positive hawt twist (about b1, from b2 towards b3).

A Timoshenko section (st columns TIMOSHENKO_COLUMNS) becomes the 6x6 stiffness and mass of
hawt's section at the c2 point (the reference line): the strain energy

    EA ea^2 + k_x G A gp2^2 + k_y G A gp3^2 + G I_p k1^2 + E I_x kp2^2 + E I_y kp3^2

with the axial strain ea = g11 + y_e k2 - x_e k3 at the elastic centre, the shear strains
at the shear centre (g12 - y_sh k1, g13 + x_sh k1) and the curvatures turned into the
principal bending axes (structural ``pitch`` about z): K = B^T D B.  The mass: m at the mass
centre (x_cg, y_cg), the radii of gyration ri_x, ri_y about the principal axes through the
elastic centre, moved to the c2 point (parallel axes through the mass centre).

``damping_posdef mx my mz kx ky kz``: Rayleigh damping of the body, the k-terms stiffness-
proportional per direction of deformation (x: in-plane, y: out of plane, z: axial and
torsion), the m-terms mass-proportional per direction of motion: hawt's BeamDamping with
mu = (kz, kx, ky, kz, ky, kx) on (g11, g12, g13, k1, k2, k3) (bending about b2 is the
deformation along y) and alpha = (mz, mx, my, mz, my, mx) on (v1, v2, v3, w1, w2, w3).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..model import Aerodynamics, Beam, BeamDamping, Polar
from ..numerics.rotations import skew
from .hawc2_files import (FPM_COLUMNS, TIMOSHENKO_COLUMNS, HawcFileError, model_folder,
                          read_ae, read_htc, read_pc, read_st, where)
from .hawc2_layout import body_blocks, c2_sections
from .imported import BladeAxis, sections_from_matrices, untwist_sections
from .turbine_yaml import TurbineFileError

__all__ = ["hawc2_body", "hawc2_aerodynamics", "timoshenko_matrices", "fpm_matrices",
           "thickness_polar", "body_st", "body_damping", "file_error"]


def _shear_and_bending_rows(st: dict, x, y) -> tuple:
    """(B (n, 6, 6) from hawt's strains (g11, g12, g13, k1, k2, k3) at the c2 point to the
    section's strains in its principal (pitched) axes: axial strain at the elastic centre,
    shear strains at the point (x, y), twist rate, curvatures; cos and sin of the pitch)."""
    n = len(st["r"])
    a = np.radians(st["pitch"])
    c, s = np.cos(a), np.sin(a)
    e2, e3 = st["x_e"], st["y_e"]
    B = np.zeros((n, 6, 6))
    one = np.ones(n)
    B[:, 0, 0], B[:, 0, 4], B[:, 0, 5] = one, e3, -e2
    B[:, 1, 1], B[:, 1, 2], B[:, 1, 3] = c, s, -c * y + s * x
    B[:, 2, 1], B[:, 2, 2], B[:, 2, 3] = -s, c, s * y + c * x
    B[:, 3, 3] = one
    B[:, 4, 4], B[:, 4, 5] = c, s
    B[:, 5, 4], B[:, 5, 5] = -s, c
    return B, c, s


def _mass_matrices(st: dict, c, s) -> np.ndarray:
    """(n, 6, 6) section mass at the c2 point, hawt's axes of the c2 frame: m at the mass
    centre (x_cg, y_cg), the radii of gyration ri_x, ri_y about the principal axes through
    the elastic centre, moved to the c2 point (parallel axes through the mass centre)."""
    n = len(st["r"])
    m = st["m"]
    R = np.zeros((n, 2, 2))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1] = c, -s, s, c
    Se = np.zeros((n, 2, 2))
    Se[:, 0, 0], Se[:, 1, 1] = m * st["ri_y"] ** 2, m * st["ri_x"] ** 2
    Se = R @ Se @ np.swapaxes(R, 1, 2)
    cg = np.stack([st["x_cg"], st["y_cg"]], -1)
    d = cg - np.stack([st["x_e"], st["y_e"]], -1)
    S = Se - m[:, None, None] * d[:, :, None] * d[:, None, :] \
        + m[:, None, None] * cg[:, :, None] * cg[:, None, :]
    M = np.zeros((n, 6, 6))
    for k in range(3):
        M[:, k, k] = m
    Sc = skew(np.concatenate([np.zeros((n, 1)), cg], -1))      # S(c) v = c x v
    M[:, :3, 3:] = -m[:, None, None] * Sc
    M[:, 3:, :3] = m[:, None, None] * Sc
    M[:, 3, 3] = S[:, 0, 0] + S[:, 1, 1]
    M[:, 4, 4], M[:, 5, 5] = S[:, 1, 1], S[:, 0, 0]
    M[:, 4, 5] = M[:, 5, 4] = -S[:, 0, 1]
    return M


def timoshenko_matrices(st: dict) -> tuple:
    """(K, M) (n, 6, 6) in hawt's axes of the c2 section frame (twisted) at the c2 point,
    from the st columns ``st`` (TIMOSHENKO_COLUMNS -> arrays of n stations)."""
    n = len(st["r"])
    # rows: axial strain at the elastic centre, principal shear strains at the shear
    # centre, twist rate, principal curvatures; columns: g11, g12, g13, k1, k2, k3
    B, c, s = _shear_and_bending_rows(st, st["x_sh"], st["y_sh"])
    E, G, A = st["E"], st["G"], st["A"]
    D = np.zeros((n, 6, 6))
    for k, v in enumerate((E * A, st["k_x"] * G * A, st["k_y"] * G * A, G * st["I_p"],
                           E * st["I_x"], E * st["I_y"])):
        D[:, k, k] = v
    K = np.swapaxes(B, 1, 2) @ D @ B
    return K, _mass_matrices(st, c, s)


#: BECAS's strain order (shear x, shear y, axial, bending x, bending y, twist) -> the rows of
#: _shear_and_bending_rows (axial, shear x, shear y, twist, bending x, bending y)
_BECAS_ROWS = (1, 2, 0, 4, 5, 3)


def fpm_matrices(st: dict) -> tuple:
    """(K, M) (n, 6, 6) as timoshenko_matrices, from an FPM st set (FPM_COLUMNS): its 6x6 at
    the elastic centre in the principal (pitched) axes, on BECAS's strains, carried to
    hawt's strains at the c2 point (K = B^T K_fpm B: the shear strains of the elastic
    centre, its couplings kept as given)."""
    n = len(st["r"])
    Kf = np.zeros((n, 6, 6))
    for i in range(6):
        for j in range(i, 6):
            Kf[:, i, j] = Kf[:, j, i] = st[f"K{i + 1}{j + 1}"]
    B, c, s = _shear_and_bending_rows(st, st["x_e"], st["y_e"])
    B = B[:, _BECAS_ROWS, :]
    K = np.swapaxes(B, 1, 2) @ Kf @ B
    return K, _mass_matrices(st, c, s)


def file_error(exc: HawcFileError) -> TurbineFileError:
    """A HAWC2 file's error as the importers raise it: its file, message and line."""
    return TurbineFileError(exc.file, [exc.message + (f" (line {exc.line})" if exc.line
                                                      else "")])


def _body(root, name: str, htc: Path):
    """The data block of main body ``name`` (a copy_main_body resolved to the body copied)."""
    structure = root.block("new_htc_structure")
    if structure is None:
        raise TurbineFileError(str(htc), ["no new_htc_structure block"])
    try:
        blocks = body_blocks(structure, str(htc))
    except HawcFileError as exc:
        raise file_error(exc) from None
    if name not in blocks:
        raise TurbineFileError(str(htc), [f"main_body {name!r} not found; the file has "
                                          f"{', '.join(blocks) or 'none'}"])
    return blocks[name]


def _c2_def(body, name: str, htc: Path, flip: bool = False) -> np.ndarray:
    """The body's c2_def sections (n, 4): x, y, z, twist [deg] in main-body coordinates,
    z increasing (TurbineFileError naming the body otherwise); ``flip``: the body's frame
    turned half a turn about its y (x, z and the twist change sign: a tower, whose z points
    down)."""
    try:
        secs = c2_sections(body, name, str(htc))
    except HawcFileError as exc:
        raise file_error(exc) from None
    if flip:
        secs = secs * np.array([-1.0, 1.0, -1.0, -1.0])
    if np.any(np.diff(secs[:, 2]) <= 0):
        raise TurbineFileError(str(htc), [f"main_body {name}: c2_def z must "
                                          f"{'decrease' if flip else 'increase'} along the "
                                          "sections"])
    return secs


def body_st(htc: Path, body, name: str) -> tuple:
    """(st columns {name: array}, st file path, 'set SET SUBSET' text) of a main body's
    timoschenko_input: TIMOSHENKO_COLUMNS, or FPM_COLUMNS with ``fpm 1``."""
    ti = body.block("timoschenko_input")
    if ti is None:
        raise TurbineFileError(str(htc), [f"main_body {name}: no timoschenko_input"])
    fname, sets = ti.command("filename"), ti.command("set")
    if fname is None or sets is None or len(sets.values) < 2:
        raise TurbineFileError(str(htc), [f"main_body {name}: timoschenko_input needs "
                                          "'filename' and 'set SET SUBSET'"])
    fpm = ti.command("fpm")                     # read_htc lower-cases command names
    full = fpm is not None and fpm.values[:1] == ["1"]
    if fpm is not None and fpm.values[:1] not in (["0"], ["1"]):
        raise TurbineFileError(str(htc), [f"main_body {name}: fpm {' '.join(fpm.values)} "
                                          f"({where(fpm)}); allowed: 0 (Timoshenko) or 1 "
                                          "(fully populated 6x6)"])
    # HAWC2 runs from the model's folder, usually the htc folder's parent
    tried = [(d / fname.values[0]).resolve() for d in (model_folder(htc), htc.parent)]
    st_path = next((p for p in tried if p.is_file()), None)
    if st_path is None:
        raise TurbineFileError(str(htc), [
            f"main_body {name}: timoschenko_input filename {fname.values[0]!r} not found "
            f"(looked for {', '.join(map(str, tried))})"])
    try:
        rows = read_st(st_path, int(float(sets.values[0])), int(float(sets.values[1])))
    except HawcFileError as exc:
        raise file_error(exc) from None
    columns = FPM_COLUMNS if full else TIMOSHENKO_COLUMNS
    if rows.shape[1] != len(columns):
        raise TurbineFileError(str(st_path), [
            f"set {sets.values[0]} subset {sets.values[1]}: {rows.shape[1]} columns; "
            f"{'an FPM' if full else 'a Timoshenko'} set has {len(columns)} (fpm "
            f"{1 if full else 0} in {htc.name})"])
    st = {k: rows[:, j] for j, k in enumerate(columns)}
    r = st["r"]
    if r[0] != 0 or np.any(np.diff(r) <= 0):
        raise TurbineFileError(str(st_path), [f"r = {r[:4].tolist()} ...: must start at 0 "
                                              "and increase"])
    return st, st_path, f"set {sets.values[0]} subset {sets.values[1]}"


def body_damping(htc: Path, body, name: str) -> tuple:
    """(BeamDamping or None, notes, the command taken) of a body's ``damping_posdef`` (or
    ``damping_aniso``, taken by the same rule and said so)."""
    for key in ("damping_posdef", "damping_aniso"):
        dp = body.command(key)
        if dp is None:
            continue
        mx, my, mz, kx, ky, kz = (dp.numbers(str(htc)) + [0.0] * 6)[:6]
        damping = BeamDamping(stiffness=(kz, kx, ky, kz, ky, kx),
                              mass=(mz, mx, my, mz, my, mx))
        note = f"{name}: {key} {mx:g} {my:g} {mz:g} {kx:g} {ky:g} {kz:g} -> {damping.text()}"
        if key == "damping_aniso":
            note += (" (HAWC2's anisotropic Rayleigh damping taken by damping_posdef's rule: "
                     "stiffness-proportional per direction of deformation)")
        return damping, [note], key
    return None, [], None


def hawc2_body(htc, name: str = "blade1", elements: int = 3, order: int = 6,
               flip: bool = False, root=None) -> tuple:
    """(Beam, notes) of the main body ``name`` of the HAWC2 model file ``htc`` (the notes
    also name every command and block of the body that is read but not modelled): its c2_def
    line (prebend and sweep; the twist turning the sections), its Timoshenko st set
    (``timoschenko_input``; ``fpm 1``: the fully populated 6x6) and its ``damping_posdef``.  The
    stations are the st file's r over its last value, taken as fractions of the span
    along z.  ``flip``: the body's z points against its span (a tower: HAWC2's z is down),
    so its frame is turned half a turn about y first (x, z, the twist, the st file's x
    offsets and principal-axis pitch change sign): a tower's (t1, t2, t3) = (-z, -x, y).
    ``root``: the htc file already read (read_htc), else it is read here."""
    htc = Path(htc)
    try:
        root = read_htc(htc) if root is None else root
    except HawcFileError as exc:
        raise file_error(exc) from None
    body = _body(root, name, htc)
    st, st_path, set_text = body_st(htc, body, name)
    secs = _c2_def(body, name, htc, flip)
    if flip:
        st = dict(st)
        for k in ("x_cg", "x_sh", "x_e", "pitch"):
            if k in st:
                st[k] = -st[k]
        if "K11" in st:
            # the 6x6's couplings would have to be turned with the frame: not done yet
            raise TurbineFileError(str(htc), [f"main_body {name}: an FPM st set (fpm 1) on a "
                                              "tower is not read yet; allowed: fpm 0"])
    r = st["r"]
    x, y, z, twist_deg = secs.T
    length = float(z[-1] - z[0])
    # hawt's axes (b1, b2, b3) = (z, x, y); BladeAxis takes IEC (x, y, z) = (b3, -b2, b1)
    axis = BladeAxis(np.stack([y, -x, z], -1), (z - z[0]) / length)
    stations, sweep, prebend = axis.stations(r / r[-1])
    twist = np.radians(np.interp(r / r[-1] * length + z[0], z, twist_deg))
    K, M = fpm_matrices(st) if "K11" in st else timoshenko_matrices(st)
    sec = sections_from_matrices(stations, untwist_sections(K, twist),
                                 untwist_sections(M, twist), prebend=prebend, sweep=sweep)
    notes = [f"{name}: {len(r)} st stations ({st_path.name} {set_text}), c2_def line of "
             f"{len(z)} sections, length {length:.6g} m"]
    damping, dnotes, taken = body_damping(htc, body, name)
    notes += dnotes
    # what the body says that the beam does not take: named, never dropped silently
    read = {"name", "type", "nbodies", "node_distribution", taken}
    why = {"damping": "hawt takes damping_posdef", "damping_aniso": "hawt takes damping_posdef",
           "concentrated_mass": "point masses on a body are not modelled yet",
           "gravity": "hawt's gravity is the turbine's"}
    for cmd in body.commands:
        if cmd.name in read:
            continue
        notes.append(f"{name}: {cmd.name} {' '.join(cmd.values)} ({where(cmd)}) read but "
                     "not modelled" + (f" ({why[cmd.name]})" if cmd.name in why else ""))
    if body.command("nbodies") is not None:
        notes.append(f"{name}: nbodies {' '.join(body.command('nbodies').values)}: HAWC2's "
                     f"discretization; hawt meshes the beam with {elements} elements of "
                     f"order {order}")
    for blk in body.blocks:
        if blk.name not in ("timoschenko_input", "c2_def"):
            notes.append(f"{name}: block {blk.name} ({where(blk)}) read but not modelled")
    return Beam(length=length, sections=sec, elements=elements, order=order,
                damping=damping), notes


def thickness_polar(tables: list, thickness: float) -> tuple:
    """(alpha [deg], cl, cd, cm) at relative ``thickness`` [%] from a pc set's ``tables``
    [(thickness, name, rows)]: HAWC2's rule, linear in thickness between the two tables
    that bracket it (each on the union of their angles), the nearest table beyond the
    thinnest and thickest."""
    tabs = sorted(tables, key=lambda t: t[0])
    ts = np.array([t[0] for t in tabs])
    if thickness <= ts[0]:
        r = tabs[0][2]
        return r[:, 0], r[:, 1], r[:, 2], r[:, 3]
    if thickness >= ts[-1]:
        r = tabs[-1][2]
        return r[:, 0], r[:, 1], r[:, 2], r[:, 3]
    j = int(np.searchsorted(ts, thickness))
    (t0, _, a), (t1, _, b) = tabs[j - 1], tabs[j]
    w = (thickness - t0) / (t1 - t0)
    alpha = np.union1d(a[:, 0], b[:, 0])
    alpha = alpha[(alpha >= max(a[0, 0], b[0, 0])) & (alpha <= min(a[-1, 0], b[-1, 0]))]
    out = [alpha]
    for c in (1, 2, 3):
        out.append((1 - w) * np.interp(alpha, a[:, 0], a[:, c])
                   + w * np.interp(alpha, b[:, 0], b[:, c]))
    return tuple(out)


def hawc2_aerodynamics(htc, blade: int = 1, root=None) -> tuple:
    """(Aerodynamics, notes) of the htc file's ``aero`` block: the ae set of blade
    ``blade`` (radius, chord, relative thickness, pc set), its polars interpolated in
    thickness at every station as HAWC2 does (thickness_polar; one polar per distinct
    thickness), the aerodynamic twist from the linked body's c2_def (hawt's sign: the
    structural twist's), stations as fractions of the ae radius's last value.  HAWC2's
    model options (induction, tip loss, dynamic stall, aerosections) are named in the notes
    as read but not taken: hawt's aerodynamics are its own.  ``root``: the htc file already
    read (read_htc), else it is read here."""
    htc = Path(htc)
    try:
        root = read_htc(htc) if root is None else root
        aero = root.block("aero")
        if aero is None:
            raise TurbineFileError(str(htc), ["no aero block"])
        need = {k: aero.command(k) for k in ("ae_filename", "pc_filename", "ae_sets")}
        missing = [k for k, v in need.items() if v is None or not v.values]
        if missing:
            raise TurbineFileError(str(htc), [f"aero: {', '.join(missing)} missing"])
        link = next((c for c in aero.all("link") if c.values[:1] == [str(blade)]), None)
        if link is None or len(link.values) < 3:
            raise TurbineFileError(str(htc), [f"aero: no 'link {blade} mbdy_c2_def BODY'"])
        base = model_folder(htc)
        ae_set = int(float(need["ae_sets"].values[min(blade, len(need["ae_sets"].values)) - 1]))
        ae = read_ae(base / need["ae_filename"].values[0], ae_set)
        pc_path = base / need["pc_filename"].values[0]
        sets = {int(p) for p in ae[:, 3]}
        pcs = {k: read_pc(pc_path, k) for k in sets}
    except HawcFileError as exc:
        raise file_error(exc) from None
    secs = _c2_def(_body(root, link.values[2], htc), link.values[2], htc)
    r, chord, thick, pcset = ae.T
    x, y, z, twist_deg = secs.T
    stations = r / r[-1]
    at = stations * (z[-1] - z[0]) + z[0]
    twist = np.radians(np.interp(at, z, twist_deg))
    # the aerodynamic nodes on the c2_def line (AeroDyn's BlCrvAC, -BlSwpAC); HAWC2's
    # aerodynamic centre is the quarter chord, a quarter of the chord ahead of the c2 line
    # (the half chord) towards the leading edge
    ac_sweep = np.interp(at, z, x) - x[0]
    ac_prebend = np.interp(at, z, y) - y[0]
    polars, index, key_of = [], [], {}
    for t, k in zip(thick, pcset.astype(int)):
        key = (k, round(float(t), 6))
        if key not in key_of:
            alpha, cl, cd, cm = thickness_polar(pcs[k], float(t))
            key_of[key] = len(polars)
            polars.append(Polar(name=f"pc{k}_t{t:g}", alpha=np.radians(alpha), cl=cl, cd=cd,
                                cm=cm, thickness=float(t) / 100.0))
        index.append(key_of[key])
    notes = [f"aerodynamics: {len(r)} ae stations (set {ae_set}), {len(polars)} polars "
             f"interpolated in thickness from pc set(s) {sorted(sets)}"]
    for cmd in aero.commands:
        if cmd.name not in ("nblades", "link", "ae_filename", "pc_filename", "ae_sets",
                            "hub_vec"):
            notes.append(f"aero: {cmd.name} {' '.join(cmd.values)} ({where(cmd)}) read but "
                         "not taken (hawt's own aerodynamic models: docs/aerodynamics.md)")
    notes.append("aerodynamics: the loads act at the quarter chord (HAWC2's aerodynamic "
                 "centre), a quarter chord ahead of the c2_def line (ac_chordwise)")
    return Aerodynamics(stations=stations, chord=chord, twist=twist,
                        airfoil=np.array(index), polars=tuple(polars), ac_sweep=ac_sweep,
                        ac_prebend=ac_prebend, ac_chordwise=0.25 * chord), notes
