"""Mode tables as ``hawt modes`` prints them (the paper's Table 2 layout; the fixed-frame view
for three or more blades), for hawt's Mode objects and the hawt_msgs/Mode message alike.
"""

from __future__ import annotations

import numpy as np

__all__ = ['ordinal', 'mode_name', 'overdamped_text', 'overdamped_pairs', 'format_table', 'error_cell', 'error_note']


def ordinal(k: int) -> str:
    """1 -> '1st', 2 -> '2nd', 3 -> '3rd', 4 -> '4th' (the index of a mode in its group)."""
    return {1: "1st", 2: "2nd", 3: "3rd"}.get(k, f"{k}th")


def overdamped_text(m) -> str:
    """' (overdamped, slow)', ' (overdamped, fast)', ' (overdamped)' for the real roots of an
    overdamped mode (Mode.overdamped), '' otherwise (also for objects without the field)."""
    root = getattr(m, "overdamped", None)
    if not root:
        return ""
    return " (overdamped)" if root == "root" else f" (overdamped, {root})"


def duplicate_text(m) -> str:
    """' #2' for the second mode of one name (Mode.duplicate), '' otherwise."""
    k = getattr(m, "duplicate", None)
    return f" #{k}" if k else ""


def mode_name(m) -> str:
    """'1st antisymmetric flap', '1st backward-whirl lag', 'teeter', '1st side-side tower',
    '1st collective flap (overdamped, slow)'."""
    if m.family in ("yaw", "teeter"):
        return m.family
    return (f"{ordinal(m.index)} {(m.symmetry or '')} {m.family}".replace("  ", " ")
            + overdamped_text(m) + duplicate_text(m))


def overdamped_pairs(modes, rotor_speed: float) -> list:
    """[(slow, fast, zeta, natural frequency [Hz])] of the overdamped pairs among ``modes``
    (real roots -r1, -r2 marked "slow"/"fast" with one family, symmetry and index): the
    second-order system s^2 + 2 zeta w s + w^2 with those roots has w = sqrt(r1 r2) and
    zeta = (r1 + r2) / (2 w) >= 1."""
    slow = [m for m in modes if getattr(m, "overdamped", None) == "slow"]
    out = []
    for a in slow:
        for b in modes:
            if getattr(b, "overdamped", None) == "fast" and (b.family, b.symmetry, b.index) \
                    == (a.family, a.symmetry, a.index):
                r1, r2 = -a.real_per_rev * rotor_speed, -b.real_per_rev * rotor_speed
                w = float(np.sqrt(r1 * r2))
                out.append((a, b, (r1 + r2) / (2 * w), w / (2 * np.pi)))
                break
    return out


def _eigenvalue_text(freq: float, real: float) -> str:
    if abs(freq) < 5e-7 and abs(real) < 5e-7:
        return "0"
    if abs(freq) < 5e-7:
        return f"{real:+.6f}"
    return f"{real:+.6f} ± {freq:.6f} i"


def _fixed(m):
    """The fixed-frame frequency of a mode (Mode or the hawt_msgs/Mode message, whose whirl
    is empty for one and two blades), or None."""
    f = getattr(m, "fixed_frame_per_rev", None)
    return None if not getattr(m, "whirl", None) or f is None or not np.isfinite(f) else f


def error_cell(e) -> str:
    """An estimated relative error as a 12-wide table cell ('-' when not estimated)."""
    return f"{e:>+12.1e}" if e is not None else f"{'-':>12}"


def error_note(estimate: dict, elements: str = "elements") -> str:
    """The footer line saying where the estimated errors come from
    (``settings["error_estimate"]`` of hawt_core.analyses.accuracy)."""
    coarse, fine = estimate["elements"]
    if estimate.get("orders"):
        low, high = estimate["orders"]
        return (f"estimated errors: order {high} - order {low} on {fine} {elements} (relative; "
                "a bound on the largest error, conservative)")
    return (f"estimated errors: Richardson from {coarse} and {fine} {elements} (converged - "
            "reported, relative)")


def _error(m, shown: bool) -> str:
    return error_cell(getattr(m, "frequency_error", None)) if shown else ""


def format_table(header: str, modes, footer=(), unit: str = "per-rev") -> str:
    """The modes as a table like the paper's Table 2. ``modes``: objects with the attributes
    family, symmetry, index, frequency_per_rev, real_per_rev, frequency_hz, damping_ratio
    (Mode, or the hawt_msgs/Mode message of the ROS service).  Three or more blades (modes
    with fixed-frame fields): the fixed-frame eigenvalue, Hz and damping ratio, and the
    rotating-frame dominant frequency beside them.  ``unit``: of the eigenvalue column
    ("Hz" for a standing rotor, whose eigenvalues are given divided by 2 pi)."""
    fixed = bool(modes) and all(_fixed(m) is not None for m in modes)
    # estimated discretization errors (hawt_core.analyses.accuracy), when there are any
    est = any(getattr(m, "frequency_error", None) is not None for m in modes)
    extra = f"{'est. error':>12}" if est else ""
    if fixed:
        lines = [header, f"{'mode':<30}{'fixed-frame eigenvalue (per-rev)':>34}{'Hz':>11}"
                         f"{'damping':>11}{'rotating':>11}" + extra]
    else:
        lines = [header, f"{'mode':<30}{f'eigenvalue ({unit})':>28}{'Hz':>11}{'damping':>11}"
                 + extra]
    for m in modes:
        name = mode_name(m)
        if fixed:
            ev = _eigenvalue_text(m.fixed_frame_per_rev, m.real_per_rev)
            zeta = m.fixed_frame_damping_ratio
            damping = f"{zeta:>11.2e}" if np.isfinite(zeta) else f"{'-':>11}"
            lines.append(f"{name:<30}{ev:>34}{m.fixed_frame_hz:>11.5f}{damping}"
                         f"{m.frequency_per_rev:>11.5f}" + _error(m, est))
            continue
        ev = _eigenvalue_text(m.frequency_per_rev, m.real_per_rev)
        damping = f"{m.damping_ratio:>11.2e}" if np.isfinite(m.damping_ratio) else f"{'-':>11}"
        lines.append(f"{name:<30}{ev:>28}{m.frequency_hz:>11.5f}{damping}" + _error(m, est))
    return "\n".join(lines + list(footer))
