"""Airfoil coefficients as smooth functions of the angle of attack, per blade station.

Each polar's lift, drag and moment tables become a C1 piecewise-cubic Hermite interpolant in
the angle of attack (slopes from Fritsch-Carlson, i.e. SciPy's PCHIP: no overshoot between
table points, so no spurious lift peaks, and a continuous derivative, so linearizations are
exact).  The evaluation is plain NumPy arithmetic on the angle and so accepts complex angles:
the complex-step derivative of a coefficient is its exact derivative (the interval is chosen
from the real part).  Outside a table's range the end cubic's tangent continues linearly.

Between the AeroDyn stations the coefficients are blended linearly in span between the two
neighbouring stations' airfoils (AeroDyn itself uses each node's own airfoil; at the nodes
the two agree).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.interpolate import PchipInterpolator

__all__ = ["HermiteTable", "AirfoilCurves", "StationPolars"]


def _hermite_cubic(t, y0, y1, d0, d1):
    """The cubic Hermite interpolant at the interval coordinate t in [0, 1] from the end
    values y0, y1 and the end slopes times the interval length d0, d1."""
    t2 = t * t
    t3 = t2 * t
    return (y0 * (2 * t3 - 3 * t2 + 1) + d0 * (t3 - 2 * t2 + t)
            + y1 * (-2 * t3 + 3 * t2) + d1 * (t3 - t2))


class HermiteTable:
    """Several curves y_k(x) on one grid x (strictly increasing), as one C1 piecewise-cubic
    Hermite interpolant each (PCHIP slopes); ``__call__`` evaluates all of them at once."""

    def __init__(self, x: np.ndarray, ys: Sequence[np.ndarray]):
        self.x = np.asarray(x, float)
        if self.x.ndim != 1 or self.x.size < 2 or np.any(np.diff(self.x) <= 0):
            raise ValueError("HermiteTable: x must be at least 2 strictly increasing values")
        self.y = np.array([np.asarray(y, float) for y in ys])            # (m, n)
        if self.y.shape[1] != self.x.size:
            raise ValueError("HermiteTable: every curve needs one value per x")
        if self.x.size == 2:
            self.d = np.repeat(np.diff(self.y, axis=1) / np.diff(self.x), 2, axis=1)
        else:
            self.d = np.array([PchipInterpolator(self.x, y).derivative()(self.x)
                               for y in self.y])
        self.h = np.diff(self.x)

    def __call__(self, q) -> np.ndarray:
        """Values (m, *q.shape) at the points q (real or complex)."""
        q = np.asarray(q)
        x, h = self.x, self.h
        i = np.clip(np.searchsorted(x, q.real, side="right") - 1, 0, x.size - 2)
        t = (q - x[i]) / h[i]
        y0, y1 = self.y[:, i], self.y[:, i + 1]
        d0, d1 = self.d[:, i] * h[i], self.d[:, i + 1] * h[i]
        inside = (q.real >= x[0]) & (q.real <= x[-1])
        cubic = _hermite_cubic(t, y0, y1, d0, d1)
        if np.all(inside):
            return cubic
        # beyond the ends: the end value plus the end slope times the distance
        ex = (slice(None),) + (None,) * q.ndim
        lo = self.y[:, 0][ex] + self.d[:, 0][ex] * (q - x[0])
        hi = self.y[:, -1][ex] + self.d[:, -1][ex] * (q - x[-1])
        return np.where(q.real < x[0], lo, np.where(q.real > x[-1], hi, cubic))


@dataclass
class AirfoilCurves:
    """One polar's cl, cd, cm as a HermiteTable (rows 0, 1, 2)."""

    name: str
    table: HermiteTable

    @classmethod
    def from_polar(cls, polar) -> "AirfoilCurves":
        return cls(polar.name, HermiteTable(polar.alpha, (polar.cl, polar.cd, polar.cm)))


class StationPolars:
    """The coefficients at given blade stations: each station between two AeroDyn stations
    blends their airfoils linearly in span.

    ``aero``: hawt_core.model.Aerodynamics; ``stations``: fractions of the blade length (0 to
    1) where the coefficients are wanted.  ``coefficients(alpha)`` -> (cl, cd, cm), each of
    the shape of ``alpha`` whose last axis runs over the stations (any leading axes, real or
    complex)."""

    def __init__(self, aero, stations):
        self.stations = np.asarray(stations, float)
        s = np.asarray(aero.stations, float)
        k = np.clip(np.searchsorted(s, self.stations, side="right") - 1, 0, s.size - 2)
        w = np.clip((self.stations - s[k]) / (s[k + 1] - s[k]), 0.0, 1.0)
        a0, a1 = aero.airfoil[k], aero.airfoil[k + 1]
        same = a0 == a1
        w = np.where(same, 0.0, w)
        self.curves = [AirfoilCurves.from_polar(p) for p in aero.polars]
        self.first, self.second, self.weight = a0, a1, w
        self._blended = np.flatnonzero(w > 0)
        self._stack = _StackedTables([c.table for c in self.curves])

    def coefficients(self, alpha):
        """(cl, cd, cm) at the angles of attack ``alpha`` [rad] (last axis: the stations)."""
        alpha = np.asarray(alpha)
        out = self._stack(alpha, self.first)
        b = self._blended
        if b.size:
            w = self.weight[b]
            out[..., b] = (1.0 - w) * out[..., b] + w * self._stack(alpha[..., b],
                                                                    self.second[b])
        return out[0], out[1], out[2]


class _StackedTables:
    """Several HermiteTables (each its own grid) evaluated in one vectorized pass, each point
    with the table its station names: the grids are laid end to end, each shifted by its
    index times a span larger than any grid, so one searchsorted finds every point's
    interval; the interval is clipped to the point's own table, and beyond its ends the
    end cubic's tangent continues linearly (HermiteTable's rule)."""

    def __init__(self, tables: Sequence[HermiteTable]):
        lo = min(float(t.x[0]) for t in tables)
        hi = max(float(t.x[-1]) for t in tables)
        self.span = 2.0 * (hi - lo) + 1.0
        sizes = np.array([t.x.size for t in tables])
        self.start = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        self.last = self.start + sizes - 1                       # index of each grid's end
        self.x = np.concatenate([t.x for t in tables])
        self.shifted = np.concatenate([t.x + k * self.span for k, t in enumerate(tables)])
        self.y = np.concatenate([t.y for t in tables], axis=1)   # (m, total)
        self.d = np.concatenate([t.d for t in tables], axis=1)
        self.h = np.append(np.diff(self.x), 1.0)                 # only in-grid entries used

    def __call__(self, q, table) -> np.ndarray:
        """Values (m, *q.shape), m the tables' curves (cl, cd, cm); ``table``
        (q.shape[-1],): the table of each station."""
        q = np.asarray(q)
        table = np.broadcast_to(table, q.shape)
        first, last = self.start[table], self.last[table]
        key = q.real + table * self.span
        i = np.clip(np.searchsorted(self.shifted, key, side="right") - 1, first, last - 1)
        h = self.h[i]
        out = _hermite_cubic((q - self.x[i]) / h, self.y[:, i], self.y[:, i + 1],
                             self.d[:, i] * h, self.d[:, i + 1] * h)
        below, above = q.real < self.x[first], q.real > self.x[last]
        if np.any(below) or np.any(above):
            lo = self.y[:, first] + self.d[:, first] * (q - self.x[first])
            hi = self.y[:, last] + self.d[:, last] * (q - self.x[last])
            out = np.where(below, lo, np.where(above, hi, out))
        return out
