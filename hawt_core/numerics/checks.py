"""Validation of scalar inputs, one validator per quantity, used by every entry point (the
command line, the turbine file, the node's parameters and its service requests): each returns
the validated value or raises ValueError naming the field, the value given and the whole
allowed range (hawt_core.numerics.limits), so that two entry points never contradict each
other."""
from __future__ import annotations

import math
import reprlib

import numpy as np

from .limits import (MAX_ELEMENTS, MAX_PERTURB_ANGLE, MAX_PERTURB_RATE, MAX_ROTOR_SPEED,
                     MAX_STEP_DEG)

__all__ = ["check_elements", "check_rotor_speed", "check_number", "check_step_deg",
           "check_perturbation_value", "short_repr", "elements_allowed", "rotor_speed_allowed",
           "STEP_DEG_ALLOWED"]


_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = 60
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = 6
_REPR.maxlevel = 3


def short_repr(value) -> str:
    """repr of a value given by the user, bounded in length (never the whole of a hostile
    value: a 400-digit integer, a million-element list, a deeply nested mapping)."""
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, np.ndarray):
        return np.array2string(value, threshold=8)[:200]
    return _REPR.repr(value)


def elements_allowed(maximum: int = MAX_ELEMENTS) -> str:
    return f"need an integer from 1 to {maximum}"


def rotor_speed_allowed(positive: bool = False) -> str:
    low = "> 0" if positive else ">= 0"
    return f"need a finite number {low} and <= {MAX_ROTOR_SPEED:g} [rad/s]"


STEP_DEG_ALLOWED = f"need a finite number > 0 and <= {MAX_STEP_DEG:g} [deg of rotor azimuth]"


def _float(value):
    """float(value), or NaN for what is not a number (bools are not numbers here)."""
    if isinstance(value, (bool, np.bool_)):
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        return math.nan


def check_elements(elements, field: str = "elements", maximum: int = MAX_ELEMENTS) -> int:
    """Validated element count (an integer from 1 to ``maximum``)."""
    v = _float(elements)
    if not (math.isfinite(v) and v.is_integer() and 1 <= v <= maximum):
        raise ValueError(f"{field}: {short_repr(elements)} is not allowed; "
                         f"{elements_allowed(maximum)}")
    return int(v)


def check_rotor_speed(speed, field: str = "rotor_speed", positive: bool = False) -> float:
    """Validated rotor speed [rad/s]: finite, >= 0 (> 0 with ``positive``), at most
    MAX_ROTOR_SPEED."""
    s = _float(speed)
    if not (math.isfinite(s) and (s > 0 if positive else s >= 0) and s <= MAX_ROTOR_SPEED):
        raise ValueError(f"{field}: {short_repr(speed)} is not allowed; "
                         f"{rotor_speed_allowed(positive)}")
    return s


def check_step_deg(step, field: str = "step_deg") -> float:
    """Validated simulation time step [deg of rotor azimuth]: > 0 and <= MAX_STEP_DEG."""
    s = _float(step)
    if not (math.isfinite(s) and 0 < s <= MAX_STEP_DEG):
        raise ValueError(f"{field}: {short_repr(step)} is not allowed; {STEP_DEG_ALLOWED}")
    return s


def check_perturbation_value(name: str, value) -> float:
    """An initial perturbation of the rigid angle ``name`` [rad] or of its rate
    (``..._rate``, [rad/s]): finite and within MAX_PERTURB_ANGLE / MAX_PERTURB_RATE."""
    rate = name.endswith("_rate")
    limit, unit = (MAX_PERTURB_RATE, "rad/s") if rate else (MAX_PERTURB_ANGLE, "rad")
    v = _float(value)
    if not (math.isfinite(v) and abs(v) <= limit):
        raise ValueError(f"perturb {name}: {short_repr(value)} is not allowed; need a finite "
                         f"number from {-limit:g} to {limit:g} [{unit}]")
    return v


def check_number(field: str, value, minimum=None, positive=False) -> float:
    """A finite number (> 0 with ``positive``, >= ``minimum`` when given); the message states
    the whole allowed range."""
    v = _float(value)
    need = "a finite number" + (" > 0" if positive else
                                f" >= {minimum:g}" if minimum is not None else "")
    if not (math.isfinite(v) and (not positive or v > 0)
            and (minimum is None or v >= minimum)):
        raise ValueError(f"{field}: {short_repr(value)} is not allowed; need {need}")
    return v
