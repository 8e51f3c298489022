"""The turbine file (YAML): the writer, and an exact comparison of two turbines.

    dump_turbine(turbine, header=None) -> str   # YAML text that loads back to an equal Turbine
    turbines_equal(a, b) -> bool                # exact field-by-field comparison
"""
from __future__ import annotations

from dataclasses import fields, is_dataclass
from typing import Any

import numpy as np
import yaml

from ..model import PITT_PETERS_SKEW, Beam, SectionTable, Turbine
from .turbine_yaml import MASS_DIAGONAL, MASS_PROPS, SCALAR_PROPS, STIFF_PROPS

__all__ = ["dump_turbine", "turbines_equal"]


class _Dumper(yaml.SafeDumper):
    """Lists of numbers in flow style ``[0.0, 1.0]``, everything else in block style."""

    def represent_list(self, data):
        flow = all(not isinstance(x, (list, tuple, dict)) for x in data)
        return self.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _Dumper.represent_list)


def _compact(a: np.ndarray):
    """A uniform array as one value (scalar or matrix), otherwise the list per station."""
    a = np.asarray(a, dtype=float)
    if len(a) > 0 and np.all(a == a[0]) and not np.any(np.isnan(a)):
        return a[0].tolist()
    return a.tolist()


def _table_dict(t: SectionTable) -> dict:
    out = {"stations": t.stations.tolist()}
    derived = {}
    if t.mass_6x6 is not None:
        derived.update({k: t.mass_6x6[:, j, j] for k, j in zip(MASS_PROPS, MASS_DIAGONAL)})
    if t.stiffness_6x6 is not None:
        for k, j in zip(STIFF_PROPS, range(6)):
            diag = t.stiffness_6x6[:, j, j]
            derived[k] = diag if np.all(np.isfinite(diag)) else None
    for key in SCALAR_PROPS:
        value = getattr(t, key)
        if key in derived:
            same = (value is None and derived[key] is None) or (
                value is not None and derived[key] is not None
                and np.array_equal(value, derived[key]))
            if same:
                continue
        if value is not None:
            out[key] = _compact(value)
    for key in ("cg_offset", "tension_offset", "shear_offset", "stiffness_6x6", "mass_6x6",
                "prebend", "sweep"):
        value = getattr(t, key)
        if value is not None:
            out[key] = _compact(value)
    return out


def _aero_dict(a) -> dict:
    out = {"stations": a.stations.tolist(), "chord": _compact(a.chord),
           "twist": _compact(a.twist), "airfoil": [int(i) for i in a.airfoil]}
    for key in ("ac_prebend", "ac_sweep", "cant", "ac_chordwise"):
        if getattr(a, key) is not None:
            out[key] = _compact(getattr(a, key))
    if a.skew_factor != PITT_PETERS_SKEW:
        out["skew_factor"] = float(a.skew_factor)
    out["polars"] = [{"name": str(p.name),
                      **({"reynolds": float(p.reynolds)} if p.reynolds is not None else {}),
                      **({"thickness": float(p.thickness)} if p.thickness is not None else {}),
                      "alpha": p.alpha.tolist(), "cl": p.cl.tolist(), "cd": p.cd.tolist(),
                      "cm": p.cm.tolist()} for p in a.polars]
    return out


def _percent(z: float) -> float:
    """100 z as the decks write it (0.477465, not 0.47746500000000003), provided the reader's
    value / 100 gives back z exactly."""
    for digits in (15, 16, 17):
        v = float(f"{100.0 * z:.{digits}g}")
        if v / 100.0 == z:
            return v
    return float(100.0 * z)


def _beam_dict(b: Beam) -> dict:
    out = {"length": float(b.length), "elements": int(b.elements)}
    if int(b.order) != 1:
        out["order"] = int(b.order)
    if b.tip_mass:
        out["tip_mass"] = float(b.tip_mass)
    if any(b.tip_inertia):
        out["tip_inertia"] = [float(v) for v in b.tip_inertia]
    if b.damping is not None and b.damping.enabled:
        d = b.damping
        out["damping"] = {}
        if any(d.stiffness):
            out["damping"]["stiffness"] = [float(v) for v in d.stiffness]
        if any(d.mass):
            out["damping"]["mass"] = [float(v) for v in d.mass]
        if d.modal:
            out["damping"]["modal_percent"] = {k: [_percent(z) for z in v]
                                               for k, v in d.modal.items()}
    out["sections"] = _table_dict(b.sections)
    return out


def dump_turbine(turbine: Turbine, header: str | None = None) -> str:
    """YAML text of ``turbine`` that :func:`load_turbine` reads back to an equal Turbine.

    Floats are written with the shortest repr that round-trips exactly; uniform per-station
    properties are written as one number.  ``header``: comment lines (without ``#``) put on
    top, e.g. where an imported turbine came from.
    """
    r, h, n, g = turbine.rotor, turbine.hub, turbine.nacelle, turbine.gravity
    data = {
        "name": str(turbine.name),
        "rotor": {"speed": float(r.speed), "blades": int(r.blades), "precone": float(r.precone),
                  **({"pitch": float(r.pitch)} if r.pitch else {})},
        "hub": {"radius": float(h.radius), "undersling": float(h.undersling),
                "teeter": bool(h.teeter), "inertia_lateral": float(h.inertia_lateral),
                "inertia_longitudinal": float(h.inertia_longitudinal),
                "teeter_stiffness": float(h.teeter_stiffness),
                "teeter_damping": float(h.teeter_damping), "mass": float(h.mass),
                **({"counterweight_mass": float(h.counterweight_mass),
                    "counterweight_radius": float(h.counterweight_radius)}
                   if h.counterweight_mass or h.counterweight_radius else {})},
        "nacelle": {"yaw_inertia": float(n.yaw_inertia), "yaw_stiffness": float(n.yaw_stiffness),
                    "yaw_damping": float(n.yaw_damping),
                    "yaw_to_teeter": float(n.yaw_to_teeter), "shaft_tilt": float(n.shaft_tilt),
                    "yaw_free": bool(n.yaw_free), "mass": float(n.mass),
                    **({"cg_offset": [float(x) for x in n.cg_offset]}
                       if any(float(x) != 0.0 for x in n.cg_offset) else {}),
                    **({"inertia_pitch": float(n.inertia_pitch)} if n.inertia_pitch else {}),
                    **({"inertia_roll": float(n.inertia_roll)} if n.inertia_roll else {}),
                    **({"shaft_height": float(n.shaft_height)} if n.shaft_height else {}),
                    **({"yaw_bearing_mass": float(n.yaw_bearing_mass)}
                       if n.yaw_bearing_mass else {})},
        "blade": _beam_dict(turbine.blade),
        "tower": {"rigid": True} if turbine.tower is None else _beam_dict(turbine.tower),
        "gravity": {"enabled": bool(g.enabled), "g": float(g.g)},
    }
    dt = turbine.drivetrain
    if dt is not None:
        data["drivetrain"] = {**({"stiffness": float(dt.stiffness)}
                                 if dt.stiffness is not None else {}),
                              "damping": float(dt.damping),
                              "generator_inertia": float(dt.generator_inertia),
                              "gearbox_ratio": float(dt.gearbox_ratio),
                              "generator": str(dt.generator),
                              **({"generator_torque_slope": float(dt.generator_torque_slope)}
                                 if dt.generator_torque_slope else {})}
    if turbine.aerodynamics is not None:
        data["aerodynamics"] = _aero_dict(turbine.aerodynamics)
    ta = turbine.tower_aerodynamics
    if ta is not None:
        data["tower_aerodynamics"] = {"stations": ta.stations.tolist(),
                                      "diameter": _compact(ta.diameter),
                                      "drag": _compact(ta.drag)}
    top = ("# hawt turbine file, written by hawt_core.io.dump_turbine.\n"
           "# SI units (m, kg, s, N), angles in rad, rotor speed in rad/s; "
           "see docs/turbine-format.md.\n")
    if header:
        top += "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
    return top + yaml.dump(data, Dumper=_Dumper, sort_keys=False, width=100)


def turbines_equal(a: Any, b: Any) -> bool:
    """True if two Turbines (or model dataclasses) hold exactly the same values."""
    if is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return False
        return all(turbines_equal(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)):
        return len(a) == len(b) and all(turbines_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if a is None or b is None:
            return False
        return np.shape(a) == np.shape(b) and bool(np.array_equal(a, b))
    return a == b
