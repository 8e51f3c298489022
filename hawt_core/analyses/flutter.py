"""``flutter``: the aeroelastic modes of a cantilever wing in a uniform stream against the flow
speed, and the flutter speed (the lowest speed at which an oscillatory mode's damping crosses
zero, refined by Brent's method) and the static divergence speed.

The wing's linearization about its undeformed state (the equilibrium at zero incidence) is
exact (complex-step Jacobians of assembly/wing.py's residual); its eigenvalues lambda give
frequency |Im lambda| and damping ratio -Re lambda / |lambda|. The modes considered are the
oscillatory ones below ``band`` [rad/s] (default: twice the frequency of the ``modes``-th
oscillatory mode at the first speed)."""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..aero.unsteady import JONES, QUASI_STEADY
from ..assembly.wing import WingModel
from ..results.flutter import FlutterResult

__all__ = ["flutter", "MAX_SPEEDS"]

#: Most speeds of one sweep.
MAX_SPEEDS = 1000


def _oscillatory(lam, band):
    keep = (lam.imag > 1e-6 * np.maximum(1.0, np.abs(lam))) & (lam.imag < band)
    return lam[keep]


def flutter(wing, speeds, elements=None, modes: int = 4, unsteady: bool = True,
            band=None, progress=None) -> FlutterResult:
    """Sweep ``speeds`` [m/s] (increasing, > 0) for the model.Wing ``wing``; ``modes``: how
    many of the lowest oscillatory modes to report; ``unsteady``: Wagner's lag (Jones's two
    states per Gauss point) or quasi-steady circulatory lift (C = 1)."""
    speeds = np.asarray(speeds, float)
    if speeds.ndim != 1 or speeds.size < 2 or np.any(speeds <= 0) \
            or np.any(np.diff(speeds) <= 0) or speeds.size > MAX_SPEEDS:
        raise ValueError(f"speeds: need 2 to {MAX_SPEEDS} increasing speeds > 0 [m/s]")
    model = WingModel.from_wing(wing, elements=elements, lag=JONES if unsteady else QUASI_STEADY)
    if band is None:
        lam0 = np.sort(_oscillatory(model.eigenvalues(speeds[0]), np.inf).imag)
        band = 2.0 * lam0[min(modes, lam0.size) - 1] if lam0.size else np.inf
    freq = np.full((speeds.size, modes), np.nan)
    zeta = np.full((speeds.size, modes), np.nan)
    growth = np.empty(speeds.size)
    static = np.empty(speeds.size)

    def measures(U):
        lam = model.eigenvalues(U)
        osc = _oscillatory(lam, band)
        real = lam[np.abs(lam.imag) <= 1e-6 * np.maximum(1.0, np.abs(lam))]
        return (osc, np.max(osc.real) if osc.size else -np.inf,
                np.max(real.real) if real.size else -np.inf)

    for i, U in enumerate(speeds):
        osc, growth[i], static[i] = measures(U)
        osc = osc[np.argsort(osc.imag)][:modes]
        freq[i, :osc.size] = osc.imag
        zeta[i, :osc.size] = -osc.real / np.abs(osc)
        if progress is not None:
            progress((i + 1) / speeds.size, f"{U:.4g} m/s")
    # tolerance for "zero": undamped modes (no aerodynamic damping) sit at round-off
    tiny = 1e-9 * band
    U_f = f_f = U_d = None
    up = np.flatnonzero((growth[:-1] <= tiny) & (growth[1:] > tiny))
    if up.size:
        i = int(up[0])
        U_f = float(brentq(lambda U: measures(U)[1] - tiny, speeds[i], speeds[i + 1],
                           xtol=1e-9 * speeds[i + 1]))
        osc = measures(U_f)[0]
        f_f = float(abs(osc[np.argmax(osc.real)].imag))
    up = np.flatnonzero((static[:-1] <= tiny) & (static[1:] > tiny))
    if up.size:
        i = int(up[0])
        U_d = float(brentq(lambda U: measures(U)[2] - tiny, speeds[i], speeds[i + 1],
                           xtol=1e-9 * speeds[i + 1]))
    return FlutterResult(case=wing.name, speeds=speeds, frequency=freq, damping_ratio=zeta,
                         flutter_speed=U_f, flutter_frequency=f_f, divergence_speed=U_d,
                         settings={"elements": int(model.beam.elements), "band_rad_s": float(band),
                                   "aerodynamics": "strip theory, Theodorsen with "
                                   + (JONES.name if unsteady else "C = 1 (quasi-steady)"),
                                   "density": wing.density, "lift_slope": wing.lift_slope})
