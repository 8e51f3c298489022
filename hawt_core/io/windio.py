"""WindIO turbine files -> hawt turbines, read and validated with the field's own package
(``windio``: its YAML loader and its JSON-schema validation, run first).

What is read (WindIO 2.x; angles in degrees, rotor speeds in rpm, SI otherwise), under
``components``:

- ``blade``: ``reference_axis`` (its z extent is the blade length; x and -y are the
  prebend and sweep of a curved reference line; the section grids are the axis curves'
  parameter, so a station s sits at the axis point of parameter s),
  ``outer_shape.twist``, ``structure.elastic_properties``: the 6x6 stiffness
  (``stiffness_matrix`` K11..K66) and the mass matrix built from ``inertia_matrix`` (mass,
  cm_x, cm_y, i_edge, i_flap, i_plr, i_cp), both in the twisted section frame;
- ``hub``: diameter (blade-root radius), cone_angle (precone), ``elastic_properties``
  (mass, inertia about the shaft and across it);
- ``drivetrain``: ``outer_shape`` (uptilt, overhang, distance_tt_hub), ``gearbox.gear_ratio``,
  ``generator.elastic_properties`` (the generator's inertia about the shaft),
  ``elastic_properties`` (the nacelle: mass, mass centre, inertia; the shaft's
  spring_constant and damping_coefficient);
- ``yaw.elastic_properties.mass`` (the yaw bearing);
- ``tower``: ``reference_axis`` (z: base and top), ``structure.elastic_properties``
  (K44, K55 bending, K66 torsion, mass), the layer material's E and rho (rotary inertia);
- ``assembly``: number_of_blades, rotor_orientation; ``control.rated_rotor_speed``.

The section frame of the elastic properties.  The schema's prose describes x towards the
trailing edge and y towards the suction side; the data of the WindIO example turbines
follow the IEC / BeamDyn section frame instead (x flapwise towards the suction side, y
chordwise towards the trailing edge, z along the span: K44 is the edgewise stiffness, i_edge
the inertia about x, cm_y the chordwise offset).  They equal, entry for entry, the BeamDyn
blade files WISDEM wrote from them (the IEA 15-MW's in the ``rosco`` wheel: tested), so they
are read in that frame (:data:`hawt_core.io.imported.IEC_TO_HAWT`).  The mass matrix of a
section with mass centre (cm_x, cm_y) is BeamDyn's
``[[m 1, -m S(c)], [m S(c), J]]`` with ``J = [[i_edge, -i_cp, 0], [-i_cp, i_flap, 0],
[0, 0, i_plr]]``.

Signs (hawt_core.model; as for OpenFAST decks): an upwind rotor's overhang, uptilt and cone
are ElastoDyn's negative OverHang, ShftTilt, PreCone; the overhang is horizontal in WindIO
and along the tilted shaft in hawt (``overhang / cos(tilt)``); the height of the shaft's
crossing with the yaw axis above the tower top is ``distance_tt_hub - overhang tan(tilt)``.

What hawt cannot honour is refused naming the key; what is read but not modelled (aerodynamic
shape and airfoils, controller, structural damping, the monopile or
floater, products of inertia, the hub's mass-centre offset) is a warning, never dropped.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..model import Beam, Drivetrain, Gravity, Hub, Nacelle, Rotor, SectionTable, Turbine
from .imported import (ELEMENTS, BladeAxis, ImportResult, hub_yaw_share, iec_axes_to_hawt,
                       interp_stations, package_version, sections_from_matrices,
                       untwist_sections)
from .turbine_yaml import TurbineFileError

__all__ = ["read_windio", "IMPORTER", "STANDARD_GRAVITY", "MAIN"]

#: Importer name and version written into the header of converted files.
IMPORTER = (f"hawt {package_version('hawt')} WindIO importer "
            f"(windio {package_version('windio')})")

#: Role of the WindIO file in ``ImportResult.sources``.
MAIN = "WindIO turbine"

#: A WindIO turbine file names no gravity: standard gravity [m/s^2] (ISO 80000-3) is used.
STANDARD_GRAVITY = 9.80665

#: The WindIO schema versions read (2.x: angles in degrees, rotor speeds in rpm).
VERSIONS = ("2",)


def _need_windio():
    try:
        import windIO
        import jsonschema
    except ImportError:
        raise TurbineFileError("windio", [
            "reading WindIO files needs the optional package windio: "
            "pip install 'hawt[turbines]' (or pip install windio)"]) from None
    return windIO, jsonschema


class _File:
    """The WindIO data being read, with its file name and the notes and warnings so far."""

    def __init__(self, path: Path, data: dict):
        self.path = path
        self.data = data
        self.warnings: list = []
        self.notes: list = []
        self.used: set = set()            # dotted keys read (see unused())

    def error(self, key: str, message: str) -> TurbineFileError:
        return TurbineFileError(str(self.path), [f"{key}: {message}"])

    def _lookup(self, key: str) -> tuple:
        """(found, value) at a dotted key (``components.hub.diameter``; a list item as
        ``layers[0]``)."""
        node = self.data
        for part in key.split("."):
            name, _, index = part.partition("[")
            if not isinstance(node, dict) or name not in node:
                return False, None
            node = node[name]
            if index:
                k = int(index.rstrip("]"))
                if not isinstance(node, list) or not -len(node) <= k < len(node):
                    return False, None
                node = node[k]
        return True, node

    def get(self, key: str, required: bool = True, default=None):
        """The value at a dotted key, counted as read."""
        self.used.add(key)
        found, value = self._lookup(key)
        if not found and required:
            raise self.error(key, "required key is missing")
        return value if found else default

    def has(self, key: str) -> bool:
        """Whether a dotted key holds a value (without counting it as read)."""
        found, value = self._lookup(key)
        return found and value is not None

    def number(self, key: str, rule: str = "finite", required: bool = True,
               default: float = 0.0) -> float:
        value = self.get(key, required=required, default=None)
        if value is None:
            return default
        try:
            x = float(value)
        except (TypeError, ValueError, OverflowError):
            raise self.error(key, f"{str(value)[:40]!r} must be a number") from None
        ok = {"finite": True, "> 0": x > 0, ">= 0": x >= 0}[rule]
        if not (math.isfinite(x) and ok):
            raise self.error(key, f"{value!r} must be {rule} and finite")
        return x

    def array(self, key: str, n: int | None = None) -> np.ndarray:
        value = self.get(key)
        try:
            a = np.array(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise self.error(key, "must be a list of numbers") from None
        if a.ndim != 1 or not np.all(np.isfinite(a)) or (n is not None and a.size != n):
            raise self.error(key, f"must be a list of {n or 'finite'} finite numbers"
                             + (f" (one per grid point; got {a.size})" if n else ""))
        return a

    def grid(self, key: str) -> np.ndarray:
        g = self.array(key)
        if g.size < 2 or g[0] != 0.0 or g[-1] != 1.0 or np.any(np.diff(g) <= 0):
            raise self.error(key, f"{g.tolist()[:6]}...: must increase strictly from 0 to 1")
        return g

    def curve(self, key: str) -> tuple:
        """A ``{grid, values}`` pair (grid in [0, 1])."""
        g = self.grid(f"{key}.grid")
        return g, self.array(f"{key}.values", g.size)

    def unused(self, reasons: dict, depth: int = 6):
        """The keys (down to ``depth`` levels) that nothing read, neither themselves nor
        inside them, grouped under the nearest key of ``reasons`` (dotted key -> why it is
        not used); one warning per group, so nothing read is dropped silently."""
        groups: dict = {}

        def touched(path):
            return any(u == path or u.startswith(path + ".") or path.startswith(u + ".")
                       for u in self.used)

        def walk(node, path, level):
            for k, v in node.items():
                sub = f"{path}.{k}" if path else str(k)
                if not touched(sub):
                    owner = max((r for r in reasons if sub == r or sub.startswith(r + ".")),
                                key=len, default=path or "(top level)")
                    groups.setdefault(owner, []).append(sub)
                elif isinstance(v, dict) and level < depth and sub not in self.used:
                    walk(v, sub, level + 1)

        walk(self.data, "", 1)
        for owner, keys in groups.items():
            why = reasons.get(owner, "not used by hawt's structural model")
            if keys == [owner]:
                self.warnings.append(f"{self.path.name}: {owner} read but not modelled ({why})")
                continue
            shown = ", ".join(k[len(owner) + 1:] if k.startswith(owner + ".") else k
                              for k in keys)
            self.warnings.append(f"{self.path.name}: {owner}: {shown} read but not modelled "
                                 f"({why})")


#: Why the parts of a WindIO file that hawt does not read are not used (hawt_core.io.windio
#: warns once per part, naming its keys).
UNUSED_REASONS = {
    "airfoils": "aerodynamics: hawt's turbine is in a vacuum",
    "materials": "layup materials: hawt reads the beam properties computed from them",
    "control": "the controller is not modelled; only rated_rotor_speed is used",
    "assembly": "descriptive",
    "components.blade.outer_shape": "aerodynamic shape",
    "components.blade.structure": "layup: hawt reads the beam properties computed from it",
    "components.hub": "sizing inputs (WISDEM)",
    "components.drivetrain": "sizing inputs (WISDEM)",
    "components.tower": "sizing inputs and aerodynamics",
    "components.monopile": "hawt clamps the tower at its base",
    "components.floating_platform": "hawt clamps the tower at its base",
    "components.mooring": "hawt clamps the tower at its base",
}


#: What windio's v1.0 -> v2.0 converter leaves of a v1 control block and the v2 schema does
#: not allow, and the v2 keys hawt fills from it: v2 key -> (v1 group, v1 key).
V1_CONTROL = {"rated_rotor_speed": ("torque", "VS_maxspd"),
              "min_rotor_speed": ("torque", "VS_minspd"),
              "optimal_tsr": ("torque", "tsr")}


#: WindIO 1.x rigid-body keys (WISDEM's elastic_properties_mb) -> 2.0's, which the converter
#: of windio 2.x leaves behind: system_mass -> mass, system_inertia (about the body's mass
#: centre; the hub's in its shaft-aligned axes, the nacelle's in the tower-top axes) ->
#: inertia, system_center_mass (tower-top axes: x downwind, z up) -> location.
V1_RIGID_BODY = {"system_mass": "mass", "system_inertia": "inertia",
                 "system_center_mass": "location"}

#: WISDEM's sizing inputs in 1.x files that the 2.0 schema does not allow and windio's
#: converter leaves in: removed, each named (none is a property hawt models).
V1_SIZING_KEYS = {"components.blade.structure.joint": ("bolt", "nonmaterial_cost",
                                                       "reinforcement_layer_ps",
                                                       "reinforcement_layer_ss"),
                  "components.tower": ("tower_mass_user",),
                  "components.monopile": ("monopile_mass_user",)}


def _v1_masses(path: Path, v1: dict, data: dict, messages: list) -> None:
    """The hub's, nacelle's and yaw system's masses of a 1.x file (``v1``, as read) put
    where 2.0 has them in the converted ``data`` (V1_RIGID_BODY): hub.elastic_properties_mb
    -> hub.elastic_properties; nacelle.elastic_properties_mb (WISDEM 3.x writes it there)
    or nacelle.drivetrain.elastic_properties_mb (with spring_constant and
    damping_coefficient) -> drivetrain.elastic_properties, their yaw_mass ->
    yaw.elastic_properties.mass; a key of theirs that 2.0 has no place for is named."""
    comps = v1.get("components") if isinstance(v1, dict) else None
    out = data.get("components") if isinstance(data, dict) else None
    if not isinstance(comps, dict) or not isinstance(out, dict):
        return
    nacelle = comps.get("nacelle") if isinstance(comps.get("nacelle"), dict) else {}
    drivetrain = nacelle.get("drivetrain") if isinstance(nacelle.get("drivetrain"),
                                                          dict) else {}
    sources = [("hub", (comps.get("hub") or {}).get("elastic_properties_mb"),
                "components.hub.elastic_properties_mb"),
               ("drivetrain", nacelle.get("elastic_properties_mb"),
                "components.nacelle.elastic_properties_mb"),
               ("drivetrain", drivetrain.get("elastic_properties_mb"),
                "components.nacelle.drivetrain.elastic_properties_mb")]
    moved, left = [], []
    # the converter keeps the hub's 1.x group (2.0 allows unknown keys there): moved, not
    # left behind to be reported as unread
    if isinstance(out.get("hub"), dict):
        out["hub"].pop("elastic_properties_mb", None)
    for target, group, where in sources:
        if not isinstance(group, dict):
            continue
        body = out.setdefault(target, {}).setdefault("elastic_properties", {})
        for key, value in group.items():
            if key in V1_RIGID_BODY:
                body[V1_RIGID_BODY[key]] = value
                moved.append(f"{where}.{key} -> components.{target}.elastic_properties."
                             f"{V1_RIGID_BODY[key]}")
            elif key in ("spring_constant", "damping_coefficient") and target == "drivetrain":
                body[key] = value
                moved.append(f"{where}.{key} -> components.drivetrain.elastic_properties."
                             f"{key}")
            elif key == "yaw_mass":
                out.setdefault("yaw", {}).setdefault("elastic_properties", {})["mass"] = value
                moved.append(f"{where}.yaw_mass -> components.yaw.elastic_properties.mass")
            else:
                left.append(f"{where}.{key}")
    # 2.0 requires a rigid body's location and inertia: a 1.x hub gives no mass centre (at
    # the hub centre), a 1.x yaw system only its mass (a point mass at the tower top)
    for target in ("hub", "yaw"):
        body = (out.get(target) or {}).get("elastic_properties")
        if isinstance(body, dict) and "mass" in body:
            for key, zero in (("location", [0.0, 0.0, 0.0]), ("inertia", [0.0] * 6)):
                if key not in body:
                    body[key] = zero
                    moved.append(f"components.{target}.elastic_properties.{key} = {zero} "
                                 "(1.x gives none)")
    if moved:
        messages.append(f"{path.name}: the 1.x masses put where 2.0 has them (windio's "
                        f"converter leaves them out): {'; '.join(moved)}")
    removed = []
    for where, keys in V1_SIZING_KEYS.items():
        node = data
        for part in where.split("."):
            node = node.get(part) if isinstance(node, dict) else None
        for key in keys:
            if isinstance(node, dict) and key in node:
                node.pop(key)
                removed.append(f"{where}.{key}")
    if removed:
        messages.append(f"{path.name}: WISDEM's sizing inputs {', '.join(removed)} (1.x keys "
                        "the 2.0 schema does not allow) removed")
    if left:
        messages.append(f"{path.name}: {', '.join(left)} read but not used (the inertia "
                        "about the mass centre is taken; 2.0 has no place for these)")


def _from_v1(path: Path, v1: dict, windIO, messages: list) -> dict:
    """A WindIO 1.x file (no ``windIO_version``) converted by windio's own converter
    (windIO.converters.windIO2windIO.v1p0_to_v2p0; its messages captured, a component it
    could not convert refused with its traceback's last line), then its control block
    completed (V1_CONTROL, rpm as the converter leaves them) and the v1 groups the v2
    schema does not allow removed, both told in ``messages``; ``v1``: the file as already
    loaded (its masses, which the converter leaves behind: _v1_masses)."""
    import contextlib
    import io
    import tempfile
    from windIO.converters.windIO2windIO import v1p0_to_v2p0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "v2.yaml"
        log = io.StringIO()
        try:
            with contextlib.redirect_stdout(log):
                v1p0_to_v2p0(str(path), str(out)).convert()
            data = windIO.load_yaml(out)
        except Exception as exc:
            raise TurbineFileError(str(path), [f"a WindIO 1.x file (no windIO_version) that "
                                               "windio's v1.0 -> v2.0 converter cannot convert "
                                               f"({type(exc).__name__}: {exc})"]) from None
    text = log.getvalue()
    if "Traceback" in text:
        last = [ln for ln in text.splitlines() if ln.strip()][-3:]
        raise TurbineFileError(str(path), ["a WindIO 1.x file (no windIO_version) that "
                                           "windio's v1.0 -> v2.0 converter cannot convert: "
                                           + " / ".join(ln.strip() for ln in last)])
    messages.append(f"{path.name}: a WindIO 1.x file (no windIO_version): converted to 2.0 "
                    "by windio's converter (v1p0_to_v2p0), validated as 2.0 (windio 2.x ships "
                    "no 1.x schema)")
    _v1_masses(path, v1, data, messages)
    control = data.get("control")
    if isinstance(control, dict):
        filled = []
        for key, (group, old) in V1_CONTROL.items():
            value = (control.get(group) or {}).get(old) if isinstance(control.get(group),
                                                                     dict) else None
            if key not in control and isinstance(value, (int, float)):
                control[key] = float(value)
                filled.append(f"control.{key} = {group}.{old} = {value:g}")
        dropped = [g for g in ("supervisory", "pitch", "torque") if g in control]
        for g in dropped:
            control.pop(g)
        if dropped:
            filled.append(f"control.{', control.'.join(dropped)} (1.x groups the 2.0 schema "
                          "does not allow) removed")
        if filled:
            messages.append(f"{path.name}: the 1.x control block completed for the 2.0 "
                            f"schema: {'; '.join(filled)}")
    return data


def _validate(path: Path, messages: list | None = None):
    """Load with windIO's loader and validate against its turbine schema; any failure ->
    TurbineFileError naming the file and the instance path of each schema error.  A 1.x
    file is converted first (_from_v1; what that did is appended to ``messages``)."""
    windIO, jsonschema = _need_windio()
    messages = [] if messages is None else messages
    try:
        data = windIO.load_yaml(path)
    except Exception as exc:                        # ruamel raises many kinds
        raise TurbineFileError(str(path), [f"not readable as YAML by windIO.load_yaml "
                                           f"({type(exc).__name__}: {exc})"]) from None
    if not isinstance(data, dict):
        raise TurbineFileError(str(path), ["a WindIO turbine file is a mapping of keys "
                                           "(windIO_version, name, assembly, components)"])
    if "windIO_version" not in data and {"assembly", "components"} <= set(data):
        data = _from_v1(path, data, windIO, messages)
    version = str(data.get("windIO_version", ""))
    if version.split(".")[0] not in VERSIONS:
        raise TurbineFileError(str(path), [
            f"windIO_version = {version!r}: hawt reads WindIO 2.x (angles in degrees); "
            "convert older files with windIO's converters (windIO.converters)"])
    try:
        windIO.validate(dict(data), schema_type="turbine/turbine_schema")
    except jsonschema.exceptions.ValidationError as exc:
        lines = [ln.strip()[:300] for ln in str(exc.message).splitlines()
                 if ln.strip().startswith("Error ")][:20]
        raise TurbineFileError(str(path), [
            "fails the WindIO turbine schema (windIO.validate, windio "
            f"{package_version('windio')})"] + (lines or [str(exc.message)])) from None
    return data


def _sign(f: _File) -> float:
    """-1 for an upwind rotor (ElastoDyn's negative overhang, tilt and cone), +1 downwind."""
    orientation = str(f.get("assembly.rotor_orientation", required=False,
                            default="upwind")).lower()
    return -1.0 if orientation == "upwind" else 1.0


def _blade(f: _File) -> Beam:
    key = "components.blade.structure.elastic_properties"
    if not f.has(key):
        raise f.error(key, "required: hawt needs the blade's beam properties (6x6 stiffness "
                           "and inertia); a blade given only by its layup (structure.layers) "
                           "needs a cross-section solver first (e.g. WISDEM's PreComp)")
    ref = "components.blade.reference_axis"
    curves = {a: f.curve(f"{ref}.{a}") for a in ("x", "y", "z")}
    z = curves["z"][1]
    if not np.all(np.diff(z) > 0):
        raise f.error(f"{ref}.z.values", f"{z[0]} .. {z[-1]} m: must run outward (tip > root), "
                                         "strictly increasing")
    # the axis at its points, on the grid the section properties are given on
    grid = np.union1d(*(np.union1d(curves[a][0], curves["z"][0]) for a in ("x", "y")))
    axis = BladeAxis(np.stack([np.interp(grid, *curves[a]) for a in ("x", "y", "z")], -1),
                     grid)
    length = axis.length
    if axis.bend > 0:
        f.notes.append(f"blade: prebend and sweep from {ref}.x, -{ref}.y (up to "
                       f"{axis.bend:.3g} m; a curved reference line)")
    sk, st = f"{key}.stiffness_matrix", f"{key}.inertia_matrix"
    gk, gm = f.grid(f"{sk}.grid"), f.grid(f"{st}.grid")
    stations = np.union1d(gk, gm)
    K = np.zeros((gk.size, 6, 6))
    given = f.get(sk)
    for i in range(6):
        for j in range(i, 6):
            name = f"K{i + 1}{j + 1}"
            if name in given:
                K[:, i, j] = K[:, j, i] = f.array(f"{sk}.{name}", gk.size)
    bad = [f"K{k}{k}" for k in range(1, 7) if np.any(K[:, k - 1, k - 1] <= 0)]
    if bad:
        raise f.error(f"{sk}.{bad[0]}", "missing or not > 0: hawt's blade takes the full 6x6 "
                                        "stiffness, whose diagonal K11..K66 must be > 0")
    m = f.array(f"{st}.mass", gm.size)
    if np.any(m <= 0):
        raise f.error(f"{st}.mass", "every value must be > 0 [kg/m]")
    opt = {k: (f.array(f"{st}.{k}", gm.size) if k in f.get(st) else np.zeros(gm.size))
           for k in ("cm_x", "cm_y", "i_edge", "i_flap", "i_plr", "i_cp")}
    for k in ("i_edge", "i_flap", "i_plr"):
        if np.any(opt[k] <= 0):
            raise f.error(f"{st}.{k}", "every value must be > 0 [kg m]: hawt's beam needs the "
                                       "section's rotary inertia")
    M = np.zeros((gm.size, 6, 6))
    cx, cy = opt["cm_x"], opt["cm_y"]
    for k in range(3):
        M[:, k, k] = m
    # BeamDyn's section mass matrix [[m 1, -m S(c)], [m S(c), J]], c = (cm_x, cm_y, 0)
    M[:, 0, 5] = M[:, 5, 0] = -m * cy
    M[:, 1, 5] = M[:, 5, 1] = m * cx
    M[:, 2, 3] = M[:, 3, 2] = m * cy
    M[:, 2, 4] = M[:, 4, 2] = -m * cx
    M[:, 3, 3], M[:, 4, 4], M[:, 5, 5] = opt["i_edge"], opt["i_flap"], opt["i_plr"]
    M[:, 3, 4] = M[:, 4, 3] = -opt["i_cp"]
    gt, tw = f.curve("components.blade.outer_shape.twist")
    twist = -np.radians(np.interp(stations, gt, tw))   # towards feather -> minus hawt's
    K, M = (iec_axes_to_hawt(interp_stations(stations, g, A)) for g, A in ((gk, K), (gm, M)))
    _damping(f, key)
    f.notes.append("blade: the 6x6 stiffness and the mass matrix of "
                   f"{key} (IEC section frame, turned by outer_shape.twist into hawt's "
                   "blade frame)")
    span, sweep, prebend = axis.stations(stations)
    sec = sections_from_matrices(span, untwist_sections(K, twist), untwist_sections(M, twist),
                                 prebend=prebend, sweep=sweep)
    return Beam(length=length, sections=sec, **ELEMENTS["blade"])


def _damping(f: _File, key: str):
    """Structural damping coefficients: warned about when nonzero (hawt's beams are
    undamped)."""
    mu = f.get(f"{key}.structural_damping.mu", required=False)
    if mu is not None and np.any(np.asarray(mu, float) != 0):
        f.warnings.append(f"{f.path.name}: {key}.structural_damping.mu = {list(mu)} read but "
                          "not modelled (undamped beams)")


def _tower_elastic_properties(f: _File, key: str) -> tuple:
    """(stations, {K44, K55, K66}, mass) of the tower's given beam properties."""
    sk, st = f"{key}.stiffness_matrix", f"{key}.inertia_matrix"
    gk, gm = f.grid(f"{sk}.grid"), f.grid(f"{st}.grid")
    stations = np.union1d(gk, gm)
    k = {n: np.interp(stations, gk, f.array(f"{sk}.{n}", gk.size)) for n in ("K44", "K55", "K66")}
    mass = np.interp(stations, gm, f.array(f"{st}.mass", gm.size))
    for n, v in list(k.items()) + [("mass", mass)]:
        if np.any(v <= 0):
            raise f.error(f"{sk if n != 'mass' else st}.{n}", "every value must be > 0")
    return stations, k, mass


def _tower_from_layers(f: _File, mat: dict, e: float, rho: float, outfit: float) -> tuple:
    """(stations, {K44, K55, K66}, mass) of a tower given by its outer diameter and one
    isotropic wall layer (WindIO's layers, as WISDEM's TowerSE sizes them): a circular tube
    of outer diameter D and wall t, I = pi/64 (D^4 - (D - 2t)^4), EI = E I (both bending
    axes), GJ = G 2I, mass = outfitting_factor x rho pi/4 (D^2 - (D - 2t)^2); D and t
    linear between their grids' points, on the union of the grids."""
    layers = f.get("components.tower.structure.layers", required=False) or []
    if len(layers) != 1:
        raise f.error("components.tower.structure.layers", f"{len(layers)} layers: without "
                      "structure.elastic_properties hawt computes the tower from one wall "
                      "layer; allowed: one")
    lay = "components.tower.structure.layers[0].thickness"
    dia = "components.tower.outer_shape.outer_diameter"
    gd, gt = f.grid(f"{dia}.grid"), f.grid(f"{lay}.grid")
    stations = np.union1d(gd, gt)
    D = np.interp(stations, gd, f.array(f"{dia}.values", gd.size))
    t = np.interp(stations, gt, f.array(f"{lay}.values", gt.size))
    if np.any(t <= 0) or np.any(2 * t > D):
        raise f.error(lay, "every wall thickness must be > 0 and at most half the outer "
                           "diameter")
    g = float(np.atleast_1d(mat.get("G", 0.0))[0])
    if not g > 0:
        nu = float(np.atleast_1d(mat.get("nu", 0.3))[0])
        g = e / (2 * (1 + nu))
    inner = D - 2 * t
    i_area = np.pi / 64 * (D ** 4 - inner ** 4)
    area = np.pi / 4 * (D ** 2 - inner ** 2)
    f.notes.append(f"tower: beam properties of a circular tube from the outer diameter "
                   f"and its one wall layer ({len(stations)} stations; E {e:g}, G {g:g}, rho "
                   f"{rho:g}, outfitting factor {outfit:g} on the mass)")
    return stations, {"K44": e * i_area, "K55": e * i_area, "K66": g * 2 * i_area}, \
        outfit * rho * area


def _tower(f: _File) -> Beam | None:
    """The tower beam (None: no tower given, rigid), clamped at its base."""
    if not f.has("components.tower"):
        f.notes.append("tower: none given (components.tower): rigid")
        return None
    key = "components.tower.structure.elastic_properties"
    ref = "components.tower.reference_axis"
    _, z = f.curve(f"{ref}.z")
    for a in ("x", "y"):
        off = f.curve(f"{ref}.{a}")[1]
        if np.ptp(off) > 1e-6 * (z[-1] - z[0]):
            raise f.error(f"{ref}.{a}.values", "hawt's tower is straight and vertical; "
                                               "allowed: constant")
    height = float(z[-1] - z[0])
    if not height > 0:
        raise f.error(f"{ref}.z.values", f"{z[0]} .. {z[-1]} m: the top must be above the base")
    # rotary inertia per length of a homogeneous wall: rho I = (rho / E) EI
    layers = f.get("components.tower.structure.layers", required=False) or []
    mats = {m.get("name"): m for m in (f.get("materials", required=False) or [])}
    names = sorted({lay.get("material") for lay in layers if isinstance(lay, dict)})
    if len(names) != 1 or names[0] not in mats:
        raise f.error("components.tower.structure.layers", f"materials {names}: hawt needs one "
                      "layer material listed under materials (its E and rho give the tower's "
                      "rotary inertia)")
    mat = mats[names[0]]
    f.used.discard("materials")                    # only this material's E and rho are used
    f.used.add(f"materials.{names[0]}")
    e = float(np.atleast_1d(mat.get("E", 0.0))[0])
    rho = float(mat.get("rho", 0.0))
    if not (e > 0 and rho > 0):
        raise f.error(f"materials.{names[0]}", f"E = {mat.get('E')!r}, rho = {mat.get('rho')!r}: "
                      "must be > 0")
    outfit = f.number("components.tower.structure.outfitting_factor", rule="> 0",
                      required=False, default=1.0)
    source = key
    if f.has(key):
        stations, k, mass = _tower_elastic_properties(f, key)
    else:
        stations, k, mass = _tower_from_layers(f, mat, e, rho, outfit)
        source = "the tube of components.tower.structure.layers"
    ei = 0.5 * (k["K44"] + k["K55"])
    i23 = outfit * rho / e * ei
    f.notes.append(f"tower: {height:g} m from z = {z[0]:g} m; bending K55 (fore-aft) and K44 "
                   f"(side-side), torsion K66 and mass from {source}; rotary inertia "
                   f"{outfit:g} x rho/E x EI of {names[0]} (rho = {rho:g}, E = {e:g})")
    _damping(f, key)
    sec = SectionTable(stations=stations, mass=mass, i1=2 * i23, i2=i23, i3=i23, gj=k["K66"],
                       ei2=k["K55"], ei3=k["K44"])
    return Beam(length=height, sections=sec, **ELEMENTS["tower"])


def _rigid_body(f: _File, key: str):
    """(mass, location (3,), inertia (6,)) of a WindIO rigid body; products of inertia
    (entries 3..5) warned about when nonzero (hawt's bodies have principal axes along its
    frames)."""
    mass = f.number(f"{key}.mass", rule=">= 0")
    loc = np.zeros(3)
    given = f.get(f"{key}.location", required=False)
    if given is not None:
        loc[:len(given)] = f.array(f"{key}.location")
    inertia = np.zeros(6)
    given = f.get(f"{key}.inertia", required=False)
    if given is not None:
        inertia[:len(given)] = f.array(f"{key}.inertia")
    if np.any(inertia[:3] < 0):
        raise f.error(f"{key}.inertia", f"{inertia[:3].tolist()}: moments of inertia must be "
                                        ">= 0")
    if np.any(inertia[3:] != 0):
        f.warnings.append(f"{f.path.name}: {key}.inertia products of inertia "
                          f"{inertia[3:].tolist()} read "
                          "but not modelled (principal axes along hawt's frames)")
    return mass, [float(v) for v in loc], [float(v) for v in inertia]


def read_windio(path) -> ImportResult:
    """Read a WindIO turbine file into a hawt :class:`Turbine` (validated by windio first).

    Raises :class:`TurbineFileError` naming the file and key for anything unreadable or
    unsupported; returns the turbine with the warnings and notes of the import."""
    p = Path(path)
    if not p.is_file():
        raise TurbineFileError(str(p), ["file not found"])
    p = p.resolve()
    converted: list = []
    data = _validate(p, converted)
    try:
        return _read(p, data, converted)
    except TurbineFileError as exc:
        if not converted:
            raise
        # a 1.x ontology (WISDEM's input) may lack what WISDEM sizes (the hub's mass)
        raise TurbineFileError(exc.source, exc.errors + [
            "(the file is WindIO 1.x, converted to 2.0 by windio's converter: a 1.x turbine "
            "ontology often leaves the hub and nacelle masses to WISDEM's sizing; give them "
            "under components.hub.elastic_properties, or import WISDEM's 2.x output)"]) \
            from None


def _read(p: Path, data: dict, converted: list) -> ImportResult:
    """read_windio's work on the validated data (``converted``: what a 1.x conversion did)."""
    f = _File(p, data)
    f.warnings += converted
    f.used.update(("windIO_version", "name", "comments"))     # descriptive, checked above
    name = p.stem
    s = _sign(f)
    nb = int(f.number("assembly.number_of_blades", rule="> 0", required=False, default=3))
    rpm = f.number("control.rated_rotor_speed", rule="> 0", required=False, default=0.0)
    if not rpm > 0:
        raise f.error("control.rated_rotor_speed", "required: hawt analyses the rotor at a "
                      "speed [rpm] (WindIO files give it under control)")
    hub_key = "components.hub"
    radius = 0.5 * f.number(f"{hub_key}.diameter", rule="> 0")
    cone = math.radians(f.number(f"{hub_key}.cone_angle", required=False))
    hub_mass, hub_loc, hub_inertia = _rigid_body(f, f"{hub_key}.elastic_properties")
    if hub_loc[0] != 0.0:
        f.warnings.append(f"{p.name}: {hub_key}.elastic_properties.location = "
                          f"{hub_loc} (hub mass centre off the apex) read but not "
                          "modelled: the hub mass is at the rotor apex")
    lateral = 0.5 * (hub_inertia[1] + hub_inertia[2])
    hub = Hub(radius=radius, teeter=False, inertia_lateral=lateral,
              inertia_longitudinal=hub_inertia[0], mass=hub_mass)

    dt = "components.drivetrain"
    tilt = s * math.radians(f.number(f"{dt}.outer_shape.uptilt", rule=">= 0"))
    overhang = f.number(f"{dt}.outer_shape.overhang", rule=">= 0")
    tt_hub = f.number(f"{dt}.outer_shape.distance_tt_hub", rule=">= 0")
    along = overhang / math.cos(tilt)                  # along the tilted shaft
    shaft_height = tt_hub - overhang * math.tan(abs(tilt))
    nac_mass, nac_loc, nac_inertia = _rigid_body(f, f"{dt}.elastic_properties")
    cg = (nac_loc[2], -nac_loc[1], nac_loc[0])          # (x down, y left, z up) -> hawt Y
    nac_yaw = nac_inertia[2] + nac_mass * (nac_loc[0] ** 2 + nac_loc[1] ** 2)
    yaw_mass = 0.0
    if f.has("components.yaw.elastic_properties"):
        yaw_mass, yaw_loc, yaw_inertia = _rigid_body(f, "components.yaw.elastic_properties")
        if any(yaw_loc) or any(yaw_inertia):
            f.warnings.append(f"{p.name}: components.yaw.elastic_properties location and "
                              "inertia read but not modelled: the yaw bearing is a point mass "
                              "at the tower top")
    nacelle = Nacelle(yaw_inertia=nac_yaw + hub_yaw_share(hub, tilt, along),
                      yaw_to_teeter=s * along, shaft_tilt=tilt,
                      yaw_free=False, mass=nac_mass, cg_offset=cg,
                      inertia_pitch=nac_inertia[1], inertia_roll=nac_inertia[0],
                      shaft_height=shaft_height, yaw_bearing_mass=yaw_mass)
    f.notes.append("yaw bearing: locked (a WindIO file gives no yaw stiffness); set "
                   "nacelle.yaw_free and yaw_stiffness in the hawt file to free it")
    drivetrain = None
    spring = f.number(f"{dt}.elastic_properties.spring_constant", rule="> 0", required=False,
                      default=0.0)
    if spring:
        gen_key = f"{dt}.generator.elastic_properties"
        gen_inertia = (_rigid_body(f, gen_key)[2][0]
                       if f.has(gen_key) else 0.0)
        drivetrain = Drivetrain(
            stiffness=spring, generator="prescribed",
            damping=f.number(f"{dt}.elastic_properties.damping_coefficient", rule=">= 0",
                             required=False),
            generator_inertia=gen_inertia,
            gearbox_ratio=f.number(f"{dt}.gearbox.gear_ratio", rule="> 0", required=False,
                                   default=1.0))
        f.notes.append("drivetrain: shaft torsion from drivetrain.elastic_properties "
                       "(spring_constant, damping_coefficient), the generator's inertia about "
                       "the shaft, held at the rotor speed (drivetrain.generator: prescribed; "
                       "its torque controller is not modelled)")
        eff = f.number(f"{dt}.gearbox.efficiency", required=False, default=1.0)
        if eff != 1.0:
            f.warnings.append(f"{p.name}: {dt}.gearbox.efficiency = {eff} read but not "
                              "modelled (an ideal gearbox)")
    else:
        f.notes.append("drivetrain: no shaft spring_constant: a rigid shaft at the rotor speed")

    blade = _blade(f)
    tower = _tower(f)
    f.unused(UNUSED_REASONS)
    f.notes.append(f"gravity: {STANDARD_GRAVITY} m/s^2 (a WindIO turbine names none)")
    turbine = Turbine(name=name, rotor=Rotor(speed=rpm * math.pi / 30.0, blades=nb,
                                             precone=s * cone),
                      hub=hub, nacelle=nacelle, blade=blade, tower=tower,
                      gravity=Gravity(enabled=True, g=STANDARD_GRAVITY),
                      drivetrain=drivetrain)
    return ImportResult(turbine=turbine, importer=IMPORTER, main_role=MAIN,
                        warnings=f.warnings, notes=f.notes, sources={MAIN: str(p)},
                        packages={"windIO": "windio"})
