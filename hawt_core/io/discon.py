"""ROSCO's controller input file (DISCON.IN): the values hawt's operating-point schedule reads.

Each line is ``VALUE [VALUE ...]  ! NAME - description``; ``read_discon`` returns
{NAME: float or list of floats} for the lines whose values are numbers (text values such as
file names are kept as strings). Missing keys are reported by ``discon_schedule`` naming the
file, the key and what it is for.
"""
from __future__ import annotations

from pathlib import Path

from .turbine_yaml import TurbineFileError, read_bounded

__all__ = ["read_discon", "discon_schedule", "SCHEDULE_KEYS"]

#: DISCON.IN key -> what the schedule takes from it.
SCHEDULE_KEYS = {
    "VS_RtPwr": "rated (electrical) power [W]",
    "VS_GenEff": "generator efficiency [%]",
    "VS_RefSpd": "rated generator speed [rad/s]",
    "VS_MinOMSpd": "minimum generator speed [rad/s]",
    "VS_TSRopt": "region-2 optimal tip-speed ratio [-]",
    "PC_FinePit": "below-rated (fine) pitch [rad]",
    "PC_MaxPit": "largest pitch [rad]",
    "WE_GearboxRatio": "gearbox ratio [-]",
}


def _value(text: str):
    parts = text.split()
    out = []
    for p in parts:
        try:
            out.append(float(p))
        except ValueError:
            return text.strip().strip('"')
    return out[0] if len(out) == 1 else out


def read_discon(path) -> dict:
    p = Path(path)
    text = read_bounded(p)
    out = {}
    for line in text.splitlines():
        if "!" not in line:
            continue
        value, _, rest = line.partition("!")
        name = rest.split()[0] if rest.split() else ""
        if name and value.strip():
            out[name] = _value(value)
    return out


def discon_schedule(path) -> dict:
    """The schedule's values from a DISCON.IN: rated_power [W], efficiency [-],
    rated_speed and min_speed [rad/s, rotor], tsr, fine_pitch and max_pitch [rad]."""
    d = read_discon(path)
    missing = [k for k in SCHEDULE_KEYS if not isinstance(d.get(k), float)]
    if missing:
        raise TurbineFileError(str(path), [f"{k}: missing or not a number; needed: "
                                           f"{SCHEDULE_KEYS[k]}" for k in missing])
    g = d["WE_GearboxRatio"]
    return {"rated_power": d["VS_RtPwr"], "efficiency": d["VS_GenEff"] / 100.0,
            "rated_speed": d["VS_RefSpd"] / g, "min_speed": d["VS_MinOMSpd"] / g,
            "tsr": d["VS_TSRopt"], "fine_pitch": d["PC_FinePit"], "max_pitch": d["PC_MaxPit"],
            "source": str(path)}
