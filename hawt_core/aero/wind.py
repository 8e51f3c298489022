"""The wind: uniform, turned by a misalignment, sheared by a vertical power law, deflected by
the tower (potential flow), and deterministic in time (piecewise-linear histories for steps
and ramps; the IEC extreme operating gust).

Frame: hawt's inertial frame N (docs/rigid-bodies.md): n1 up along the yaw axis, n3 downwind
along the unyawed shaft, n2 = n3 x n1; origin at the yaw axis at the tower top, which is
``origin_height`` above the ground.  A wind with ``direction`` 0 blows along +n3; a positive
``direction`` turns it about n1 (the yaw sense).  All evaluations are plain arithmetic on
arrays (complex-step safe in the positions).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional, Tuple

import numpy as np

__all__ = ["Wind", "ExtremeOperatingGust", "IEC_REFERENCE_SPEED", "IEC_TURBULENCE",
           "parse_wind_series", "WindSeries", "WIND_SERIES_ALLOWED",
           "potential_flow_shadow"]

#: IEC 61400-1 ed. 3, table 1: reference wind speed V_ref [m/s] by turbine class.
IEC_REFERENCE_SPEED = {"I": 50.0, "II": 42.5, "III": 37.5}
#: ... and the reference turbulence intensity I_ref by category.
IEC_TURBULENCE = {"A+": 0.18, "A": 0.16, "B": 0.14, "C": 0.12}


@dataclass(frozen=True)
class ExtremeOperatingGust:
    """IEC 61400-1 ed. 3, section 6.3.2.2: the hub-height speed dips, rises by V_gust and
    dips again over T = 10.5 s,

        V(z, t) = V(z) - 0.37 V_gust sin(3 pi t'/T) (1 - cos(2 pi t'/T)),   0 <= t' = t - start <= T,

    with V_gust = min(1.35 (V_e1 - V_hub), 3.3 sigma1 / (1 + 0.1 D / Lambda1)), V_e1 = 0.8 *
    1.4 V_ref, sigma1 = I_ref (0.75 V_hub + 5.6 m/s), Lambda1 = 0.7 z_hub up to 60 m, 42 m
    above (eqs. 11, 17, 18, 19)."""

    amplitude: float            # V_gust [m/s]
    start: float = 0.0          # [s]
    duration: float = 10.5      # T [s]

    @classmethod
    def iec(cls, hub_speed: float, rotor_diameter: float, hub_height: float,
            turbine_class: str = "I", turbulence: str = "B", start: float = 0.0):
        if turbine_class not in IEC_REFERENCE_SPEED:
            raise ValueError(f"turbine_class: {turbine_class!r} is not allowed; choose one of "
                             f"{', '.join(IEC_REFERENCE_SPEED)}")
        if turbulence not in IEC_TURBULENCE:
            raise ValueError(f"turbulence: {turbulence!r} is not allowed; choose one of "
                             f"{', '.join(IEC_TURBULENCE)}")
        v_e1 = 0.8 * 1.4 * IEC_REFERENCE_SPEED[turbine_class]
        sigma1 = IEC_TURBULENCE[turbulence] * (0.75 * hub_speed + 5.6)
        lam1 = 0.7 * hub_height if hub_height <= 60.0 else 42.0
        gust = min(1.35 * (v_e1 - hub_speed), 3.3 * sigma1 / (1.0 + 0.1 * rotor_diameter / lam1))
        return cls(amplitude=float(gust), start=float(start))

    def increment(self, t):
        """The change of the wind speed [m/s] at time t [s] (0 outside the gust)."""
        tt = np.asarray(t, float) - self.start
        T = self.duration
        inside = (tt >= 0.0) & (tt <= T)
        d = -0.37 * self.amplitude * np.sin(3 * np.pi * tt / T) * (1 - np.cos(2 * np.pi * tt / T))
        return np.where(inside, d, 0.0)


#: what a wind time series may be (parse_wind_series's error messages)
WIND_SERIES_ALLOWED = ("need a speed [m/s] or time:speed pairs 't0:U0,t1:U1,...' (times [s] "
                       ">= 0, increasing; speeds 0.1 to 100 m/s; linear between the points, "
                       "constant beyond them), e.g. '0:15,10:15,10.5:17' (15 m/s, then a "
                       "step to 17 m/s at 10 s), and optionally 'eog@T' (the IEC extreme "
                       "operating gust, class I, turbulence B, starting at T [s])")


@dataclass(frozen=True)
class WindSeries:
    """A wind history as text gives it (parse_wind_series): ``points`` ((t [s], U [m/s]),
    ...) of the hub-height speed, linear between them and constant beyond; ``gust_start``
    [s]: the IEC extreme operating gust (class I, turbulence B) added from then, or None."""
    points: Tuple[Tuple[float, float], ...]
    gust_start: Optional[float] = None

    @property
    def initial_speed(self) -> float:
        """The hub speed at t = 0 [m/s] (before the gust)."""
        return self.points[0][1]

    def wind(self, rotor_diameter: float, hub_height: float, **kwargs) -> "Wind":
        """The Wind (``kwargs``: its other fields); the gust's amplitude from the speed at
        its start and the rotor's diameter and hub height [m] (IEC 61400-1 ed. 3)."""
        w = Wind.from_series(self.points, **kwargs)
        if self.gust_start is None:
            return w
        u = float(w.hub_speed(self.gust_start))
        return replace(w, gust=ExtremeOperatingGust.iec(u, rotor_diameter, hub_height,
                                                         start=self.gust_start))

    def for_turbine(self, turbine, **kwargs) -> "Wind":
        """:meth:`wind` with the rotor diameter (tip radius in the rotor plane, precone
        included) and hub height (tower plus shaft height; without a tower the Wind's
        reference height) of ``turbine`` (model.Turbine)."""
        radius = float(turbine.distance_from_shaft(turbine.blade.length))
        height = (turbine.tower.length + turbine.nacelle.shaft_height
                  if turbine.tower is not None else
                  kwargs.get("reference_height", Wind.__dataclass_fields__[
                      "reference_height"].default))
        return self.wind(2.0 * radius, float(height), **kwargs)


def parse_wind_series(text: str, name: str = "wind") -> WindSeries:
    """``"0:15,10:15,10.5:17"`` -> WindSeries(((0.0, 15.0), (10.0, 15.0), (10.5, 17.0))):
    the hub-height wind speed [m/s] against time [s], piecewise linear (a plain speed
    ``"15"``: one point); a token ``eog@T`` adds the IEC extreme operating gust from T [s].
    ValueError naming ``name``, the text and what is allowed."""
    def bad(why=""):
        return ValueError(f"{name}: {text!r} is not allowed; {why}{WIND_SERIES_ALLOWED}")
    if not isinstance(text, str) or not text.strip():
        raise bad()
    parts = [p.strip() for p in text.split(",")]
    gusts = [p for p in parts if p.lower().startswith("eog@")]
    parts = [p for p in parts if not p.lower().startswith("eog@")]
    gust = None
    if len(gusts) > 1:
        raise bad("one gust at most; ")
    if gusts:
        try:
            gust = float(gusts[0][4:])
        except ValueError:
            raise bad() from None
        if not (math.isfinite(gust) and gust >= 0):
            raise bad("the gust's start must be a time >= 0 [s]; ")
    if not parts:
        raise bad()
    points = []
    for part in parts:
        try:
            values = [float(f) for f in part.split(":")]
        except ValueError:
            raise bad() from None
        if len(values) == 1 and len(parts) == 1:
            values = [0.0, values[0]]
        if len(values) != 2 or not all(math.isfinite(v) for v in values):
            raise bad()
        points.append((values[0], values[1]))
    times = [p[0] for p in points]
    if times[0] < 0 or any(b <= a for a, b in zip(times, times[1:])):
        raise bad("the times must be >= 0 and increase; ")
    if not all(0.1 <= u <= 100.0 for _, u in points):
        raise bad("a speed is outside 0.1 to 100 m/s; ")
    return WindSeries(tuple(points), gust)


def potential_flow_shadow(x, y, radius):
    """Velocity (u, v) / U of a uniform flow along +x past a cylinder of ``radius`` at the
    origin: u = 1 - R^2 (x^2 - y^2) / rho^4, v = -2 R^2 x y / rho^4 (outside the cylinder;
    inside it, e.g. a point above the tower top that the caller masks, rho is held at R)."""
    r2 = radius * radius
    rho2 = x * x + y * y
    rho2 = np.where(np.real(rho2) > r2, rho2, r2 + 0 * rho2)
    return 1.0 - r2 * (x * x - y * y) / (rho2 * rho2), -2.0 * r2 * x * y / (rho2 * rho2)


@dataclass(frozen=True)
class Wind:
    """A deterministic wind field.

    ``speed`` [m/s] at ``reference_height`` [m above ground] (the hub height); ``direction``
    [rad] of the wind about n1 from n3; ``shear_exponent``: V(z) = speed (z / z_ref)^alpha;
    ``origin_height`` [m]: height of N's origin (the tower top) above the ground;
    ``history``: ((t0, s0), (t1, s1), ...) a piecewise-linear factor on the speed against
    time (constant beyond the ends; a step is two points close together, a ramp two points
    apart); ``gust``: an ExtremeOperatingGust added to the hub-height speed;
    ``tower_radius`` [m] > 0: the tower's potential-flow shadow below the tower top.
    """

    speed: float
    direction: float = 0.0
    shear_exponent: float = 0.0
    reference_height: float = 90.0
    origin_height: float = 90.0
    history: Tuple[Tuple[float, float], ...] = ()
    gust: Optional[ExtremeOperatingGust] = None
    tower_radius: float = 0.0

    def __post_init__(self):
        for name in ("speed", "direction", "shear_exponent", "reference_height",
                     "origin_height", "tower_radius"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(f"wind.{name}: {v!r} is not allowed; need a finite number")
        if self.speed < 0:
            raise ValueError(f"wind.speed: {self.speed!r} is not allowed; need >= 0 [m/s]")
        if self.reference_height <= 0:
            raise ValueError(f"wind.reference_height: {self.reference_height!r} is not "
                             "allowed; need > 0 [m]")
        times = [p[0] for p in self.history]
        if any(b <= a for a, b in zip(times, times[1:])):
            raise ValueError("wind.history: the times must increase strictly")

    @classmethod
    def from_series(cls, points, **kwargs) -> "Wind":
        """The wind whose hub-height speed follows ``points`` ((t, U), ...) [s, m/s]
        (parse_wind_series), linear between them and constant beyond; ``kwargs``: the other
        fields (direction, shear...)."""
        points = tuple((float(a), float(b)) for a, b in points)
        u0 = points[0][1]
        history = tuple((a, b / u0) for a, b in points) if len(points) > 1 else ()
        return cls(u0, history=history, **kwargs)

    def hub_speed(self, t):
        """The speed at the reference height at time t [s] (history and gust applied)."""
        t = np.asarray(t, float)
        s = self.speed * np.ones_like(t)
        if self.history:
            ts, fs = zip(*self.history)
            s = s * np.interp(t, ts, fs)
        if self.gust is not None:
            s = s + self.gust.increment(t)
        return s

    def velocity(self, t, points):
        """Wind velocity (..., 3) [m/s] in N components at the points (..., 3) [m, N] at time
        t [s] (a scalar, or an array broadcastable to ``points.shape[:-1]``)."""
        points = np.asarray(points)
        height = self.origin_height + points[..., 0]
        if self.shear_exponent:
            ratio = np.maximum(height.real, 1e-3) + 1j * height.imag \
                if np.iscomplexobj(height) else np.maximum(height, 1e-3)
            factor = (ratio / self.reference_height) ** self.shear_exponent
        else:
            factor = np.ones_like(height)
        speed = self.hub_speed(t) * factor
        c, s = math.cos(self.direction), math.sin(self.direction)
        # the wind's direction: n3 turned about n1 by `direction`, c n3 + s n1 x n3 = c n3 - s n2
        d2, d3 = -s, c
        u = np.zeros(points.shape, dtype=np.result_type(points, float))
        if self.tower_radius > 0:
            # coordinates along the wind (x, unit d) and across it (y, unit n1 x d =
            # d2 n3 - d3 n2) in the horizontal plane
            x = d3 * points[..., 2] + d2 * points[..., 1]
            y = d2 * points[..., 2] - d3 * points[..., 1]
            below = points[..., 0].real < 0
            ux, uy = potential_flow_shadow(x, y, self.tower_radius)
            ux = np.where(below, ux, 1.0)
            uy = np.where(below, uy, 0.0)
            u[..., 1] = speed * (d2 * ux - d3 * uy)
            u[..., 2] = speed * (d3 * ux + d2 * uy)
        else:
            u[..., 1] = speed * d2
            u[..., 2] = speed * d3
        return u
