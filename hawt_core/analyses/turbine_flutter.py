"""``turbine_flutter``: the overspeed flutter of a turbine in wind: the aeroelastic Floquet
modes (frozen-wake blade-element loads, modal_analysis(wind=...)) at a sweep of rotor speeds
at one wind speed and pitch, tracked as in a Campbell diagram, and the lowest rotor speed at
which a mode's damping ratio crosses below -DAMPING_TOL (linear interpolation between the
two sweep points around the crossing: refine the sweep there for more digits).
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..results.flutter import TurbineFlutterResult
from .campbell import campbell

__all__ = ["turbine_flutter", "DAMPING_TOL"]

#: A mode is unstable when its damping ratio is below -DAMPING_TOL (modes without aerodynamic
#: damping, e.g. in-plane lag modes at zero lift, sit at |zeta| ~ 1e-5 by round-off and the
#: marching's own dissipation).
DAMPING_TOL = 1e-4


def turbine_flutter(turbine, wind, speeds, elements: Optional[int] = None,
                    method: Optional[str] = None, steps: Optional[int] = None,
                    executor=None, progress=None, rho: float = 1.225,
                    max_hz: Optional[float] = None, inflow: str = "frozen",
                    airfoil: str = "quasi-steady") -> TurbineFlutterResult:
    """Sweep the rotor ``speeds`` [rad/s] of ``turbine`` (its pitch) in ``wind``
    (aero.wind.Wind; ``inflow``, ``airfoil``: modal_analysis's); returns the tracked modes
    and the first damping crossing."""
    result = campbell(turbine, speeds, elements=elements, steps=steps, method=method,
                      executor=executor, progress=progress, wind=wind, rho=rho, max_hz=max_hz,
                      frame="rotating", inflow=inflow, airfoil=airfoil)
    W = result.speeds
    best = None                           # (speed, track label, frequency [Hz], index)
    for t in result.tracks:
        z = t.damping_ratio
        f = t.hz("rotating")
        for i in range(len(W)):
            if not np.isfinite(z[i]) or z[i] >= -DAMPING_TOL:
                continue
            if i == 0 or not np.isfinite(z[i - 1]):
                cand = (W[i], t.label, f[i], i)         # unstable where the track starts
            else:
                s = (z[i - 1] + DAMPING_TOL) / (z[i - 1] - z[i])
                cand = (W[i - 1] + s * (W[i] - W[i - 1]), t.label,
                        f[i - 1] + s * (f[i] - f[i - 1]), i)
            if best is None or cand[0] < best[0]:
                best = cand
            break
    return TurbineFlutterResult(
        turbine=turbine.name, campbell=result, wind_speed=float(wind.speed),
        pitch_deg=float(np.degrees(-turbine.rotor.pitch)),
        flutter_speed=None if best is None else float(best[0]),
        flutter_mode=None if best is None else best[1],
        flutter_frequency_hz=None if best is None else float(best[2]),
        unstable_at_start=best is not None and best[3] == 0)
