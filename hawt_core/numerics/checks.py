"""Validation of scalar inputs: each check returns the validated value or raises ValueError
naming the field, the value given and what is allowed."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["check_elements", "check_rotor_speed", "check_number"]


def check_elements(elements) -> int:
    """Validated element count (an integer >= 1) or ValueError naming the field."""
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)):
        try:
            ok = float(elements) == int(elements)
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise ValueError(f"elements: {elements!r} is not allowed; need an integer >= 1")
    n = int(elements)
    if n < 1:
        raise ValueError(f"elements: {n} is not allowed; need an integer >= 1")
    return n


def check_rotor_speed(speed) -> float:
    """Validated rotor speed (finite, >= 0, rad/s) or ValueError naming the field."""
    try:
        s = float(speed)
    except (TypeError, ValueError):
        raise ValueError(f"rotor_speed: {speed!r} is not allowed; "
                         "need a finite number >= 0 [rad/s]") from None
    if not np.isfinite(s) or s < 0:
        raise ValueError(f"rotor_speed: {speed!r} is not allowed; "
                         "need a finite number >= 0 [rad/s]")
    return s


def check_number(field: str, value, minimum=None, positive=False) -> float:
    """A finite number (> 0 with ``positive``, >= ``minimum`` when given)."""
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{field}: {value!r} is not allowed; need a finite number") from None
    if not math.isfinite(v):
        raise ValueError(f"{field}: {value!r} is not allowed; need a finite number")
    if positive and v <= 0:
        raise ValueError(f"{field}: {value!r} is not allowed; need a number > 0")
    if minimum is not None and v < minimum:
        raise ValueError(f"{field}: {value!r} is not allowed; need a number >= {minimum}")
    return v
