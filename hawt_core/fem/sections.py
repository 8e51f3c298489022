"""Cross-sectional matrices: station tables -> per-element 6x6 compliance and mass matrices.

Ordering: stiffness/compliance act on ``[F1, F2, F3, M1, M2, M3]`` <-> ``[g1, g2, g3, k1, k2, k3]``
(force strains gamma, moment strains kappa); the mass matrix maps ``[V; Omega]`` to
``[P; H]``. Everything is expressed in the untwisted reference cross-section frame b, about the
reference line.

Rigid directions (EA, GA2 or GA3 not given) get zero compliance, i.e. ``gamma_k = 0`` and the
corresponding section force is a Lagrange multiplier. Along the span, the section properties
are interpolated linearly between stations (docs/turbine-format.md); the mixed form integrates
the compliance over each element, so the element compliance is the Gauss average of the
inverse of the interpolated stiffness, and the element mass matrix the exact average of the
interpolated mass matrix.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
from scipy.interpolate import CubicSpline

from ..model import Beam, SectionTable
from ..numerics.rotations import rot1, skew, turn_e1_to


def station_compliance(t: SectionTable) -> np.ndarray:
    """Compliance matrices (ns, 6, 6) at the stations, reference frame b, rigid = 0."""
    ns = t.n_stations
    if t.stiffness_6x6 is not None:
        out = np.zeros((ns, 6, 6))
        for k in range(ns):
            S = np.array(t.stiffness_6x6[k], dtype=float)
            rigid = ~np.isfinite(np.diag(S))
            flex = ~rigid
            out[k][np.ix_(flex, flex)] = np.linalg.inv(S[np.ix_(flex, flex)])
        return out
    zeros = np.zeros(ns)
    inv = lambda a: zeros if a is None else 1.0 / a
    cp = np.zeros((ns, 6, 6))
    for j, val in enumerate((inv(t.ea), inv(t.ga2), inv(t.ga3), 1 / t.gj, 1 / t.ei2, 1 / t.ei3)):
        cp[:, j, j] = val
    twist = t.twist if t.twist is not None else zeros
    R = np.swapaxes(rot1(twist), -1, -2)  # reference components -> principal components
    xt = np.zeros((ns, 3))
    if t.tension_offset is not None:
        xt[:, 1:] = t.tension_offset
    # [F; M]_principal = T [F; M]_reference: forces turned, bending moments about the
    # tension centre, the torsional moment about the shear centre (the tension centre when
    # no shear centre is given): M1 - (x_s x F)_1
    T = np.zeros((ns, 6, 6))
    T[:, :3, :3] = R
    T[:, 3:, 3:] = R
    T[:, 3:, :3] = -R @ skew(xt)
    if t.shear_offset is not None:
        xs = np.zeros((ns, 3))
        xs[:, 1:] = t.shear_offset
        T[:, 3, :3] = -skew(xs)[:, 0, :]          # R leaves the torsion row alone
    return np.swapaxes(T, -1, -2) @ cp @ T


def station_mass(t: SectionTable) -> np.ndarray:
    """Mass matrices (ns, 6, 6) at the stations about the reference line, frame b."""
    if t.mass_6x6 is not None:
        return np.array(t.mass_6x6, dtype=float)
    ns = t.n_stations
    twist = t.twist if t.twist is not None else np.zeros(ns)
    R1 = rot1(twist)
    i_cg = R1 @ (np.eye(3) * np.stack([t.i1, t.i2, t.i3], -1)[:, None, :]) @ np.swapaxes(R1, -1, -2)
    xi = np.zeros((ns, 3))
    if t.cg_offset is not None:
        xi[:, 1:] = t.cg_offset
    m = t.mass[:, None, None]
    xs = skew(xi)
    # P = m (V - xi x Omega); H = I_ref Omega + m xi x V  (Hodges 2006, Eq. 5.x)
    i_ref = i_cg + m * (np.einsum("ni,ni->n", xi, xi)[:, None, None] * np.eye(3)
                        - xi[:, :, None] * xi[:, None, :])
    out = np.zeros((ns, 6, 6))
    out[:, :3, :3] = m * np.eye(3)
    out[:, :3, 3:] = -m * xs
    out[:, 3:, :3] = m * xs
    out[:, 3:, 3:] = i_ref
    return out


def element_average(stations: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Exact element averages of the piecewise-linear interpolant of ``values`` (ns, ...).

    ``stations`` and ``edges`` are in the same unit (e.g. metres); returns (len(edges)-1, ...).
    """
    flat = values.reshape(len(stations), -1)
    out = np.empty((len(edges) - 1, flat.shape[1]))
    for e in range(len(edges) - 1):
        a, b = edges[e], edges[e + 1]
        inner = stations[(stations > a) & (stations < b)]
        pts = np.concatenate([[a], inner, [b]])
        vals = np.stack([np.interp(pts, stations, flat[:, j]) for j in range(flat.shape[1])], -1)
        out[e] = np.trapezoid(vals, pts, axis=0) / (b - a)
    return out.reshape((len(edges) - 1,) + values.shape[1:])


def sections_at(t: SectionTable, x: np.ndarray) -> SectionTable:
    """The section table interpolated linearly (every property, as the file format says) at
    the span fractions ``x``."""
    out = {"stations": x}
    for name in ("mass", "i1", "i2", "i3", "gj", "ei2", "ei3", "ea", "ga2", "ga3", "twist",
                 "cg_offset", "tension_offset", "shear_offset", "stiffness_6x6", "mass_6x6"):
        a = getattr(t, name)
        if a is None:
            out[name] = None
            continue
        flat = np.asarray(a, float).reshape(len(t.stations), -1)
        cols = [np.interp(x, t.stations, flat[:, j]) if np.all(np.isfinite(flat[:, j]))
                else np.full(len(x), np.inf) for j in range(flat.shape[1])]
        out[name] = np.stack(cols, -1).reshape((len(x),) + np.shape(a)[1:])
    return SectionTable(**out)


def element_compliance(t: SectionTable, length: float, nodes: np.ndarray,
                       points: int = 8) -> np.ndarray:
    """Element averages (N, 6, 6) of the compliance, with the stiffness properties
    interpolated linearly between stations (Gauss-Legendre, ``points`` per element and per
    station interval inside the element, so breakpoints are honoured)."""
    xg, wg = np.polynomial.legendre.leggauss(points)
    st = t.stations * length
    out = np.empty((len(nodes) - 1, 6, 6))
    for e in range(len(nodes) - 1):
        a, b = nodes[e], nodes[e + 1]
        cuts = np.concatenate([[a], st[(st > a) & (st < b)], [b]])
        lo, hi = cuts[:-1, None], cuts[1:, None]
        x = (0.5 * (hi - lo) * xg[None] + 0.5 * (hi + lo)).ravel()
        w = (0.5 * (hi - lo) * wg[None]).ravel()
        comp = station_compliance(sections_at(t, np.clip(x / length, 0.0, 1.0)))
        out[e] = np.einsum("k,kij->ij", w, comp) / (b - a)
    return out


@dataclass(frozen=True, eq=False)
class ElementProperties:
    """Per-element data of a meshed beam.

    nodes: span coordinates of the N+1 nodes along b1 [m] (what the section stations are
    fractions of); h: element lengths (N,) [m]; compliance: (N, 6, 6) and mass: (N, 6, 6)
    in each element's section frame (untwisted).
    A curved reference line (prebend, sweep) is a polygon of straight elements:
    ``positions`` (N+1, 3) of the nodes in the root frame b [m] and ``frames`` (N, 3, 3),
    the element section frames a (columns: a1 along the element, a2, a3) in b.  None
    means the straight line along b1: positions (nodes, 0, 0), frames the identity.
    ``tip_mass`` [kg], ``tip_inertia`` [kg m^2]: the rigid tip body (model.Beam).
    """

    nodes: np.ndarray
    h: np.ndarray
    compliance: np.ndarray
    mass: np.ndarray
    positions: Optional[np.ndarray] = None
    frames: Optional[np.ndarray] = None
    tip_mass: float = 0.0
    tip_inertia: tuple = (0.0, 0.0, 0.0)

    @property
    def n_elements(self) -> int:
        return len(self.h)

    @property
    def curved(self) -> bool:
        return self.frames is not None

    def node_positions(self) -> np.ndarray:
        """(N+1, 3) undeformed node positions in the root frame b [m]."""
        if self.positions is not None:
            return np.asarray(self.positions, float)
        return straight_line(self.nodes)

    def element_frames(self) -> np.ndarray:
        """(N, 3, 3) element section frames in b (the identity for a straight beam)."""
        if self.frames is not None:
            return np.asarray(self.frames, float)
        return np.broadcast_to(np.eye(3), (self.n_elements, 3, 3))


def straight_line(x) -> np.ndarray:
    """Points (len(x), 3) ``(x, 0, 0)`` of the straight reference line along b1 [m]."""
    x = np.asarray(x, float)
    return np.stack([x, 0 * x, 0 * x], -1)


def reference_line(t: SectionTable, length: float, x: np.ndarray) -> Optional[np.ndarray]:
    """Points (len(x), 3) of the reference line in the root frame b [m] at the span
    coordinates ``x`` [m] along b1: ``(x, sweep(x), prebend(x))``, the offsets interpolated
    by a not-a-knot cubic spline through the stations (so that a refined mesh follows a
    smooth line, not the station polygon; two stations give a straight line); None when
    the table has neither prebend nor sweep."""
    if t.prebend is None and t.sweep is None:
        return None
    st = t.stations * length
    out = np.zeros((len(x), 3))
    out[:, 0] = x
    for col, off in ((1, t.sweep), (2, t.prebend)):
        if off is None or not np.any(off):
            continue
        spline = CubicSpline(st, off) if len(st) > 2 else (
            lambda z, o=off: np.interp(z, st, o))
        out[:, col] = spline(x)
    return out


def mesh_beam(beam: Beam, elements: int | None = None,
              pitch: float = 0.0) -> ElementProperties:
    """Uniform mesh of ``elements`` (default ``beam.elements``) with averaged properties.

    ``pitch`` [rad]: the beam turned as a rigid body about its root axis b1 (a blade's
    collective pitch, model.Rotor): its reference line and every element's section frame
    turned by rot1(pitch), so a prebent blade's bend turns with it.

    With prebend or sweep, the nodes sit on the reference line at equal spacing along b1;
    each element is the straight chord between its nodes (length ``h``), its section frame
    the smallest rotation of b turning b1 onto the chord (fem/beam.py, "Curved reference
    line"): the polygon converges to the line at second order, like the elements
    themselves."""
    n = int(beam.elements if elements is None else elements)
    if n < 1:
        raise ValueError(f"elements: {n} is not allowed; need an integer >= 1")
    nodes = np.linspace(0.0, beam.length, n + 1)
    st = beam.sections.stations * beam.length
    comp = element_compliance(beam.sections, beam.length, nodes)
    mass = element_average(st, station_mass(beam.sections), nodes)
    pos = reference_line(beam.sections, beam.length, nodes)
    tip = dict(tip_mass=float(beam.tip_mass), tip_inertia=tuple(map(float, beam.tip_inertia)))
    if pos is None and pitch == 0:
        return ElementProperties(nodes=nodes, h=np.diff(nodes), compliance=comp, mass=mass,
                                 **tip)
    if pos is None:
        pos = straight_line(nodes)
    chord = np.diff(pos, axis=0)
    h = np.linalg.norm(chord, axis=1)
    frames = turn_e1_to(chord / h[:, None])
    if pitch != 0:
        P = rot1(float(pitch))
        pos, frames = pos @ P.T, P @ frames
    # the section tables give properties per unit length of the line: the element's
    # chord carries them (the projected length along b1 would shorten it)
    return ElementProperties(nodes=nodes, h=h, compliance=comp, mass=mass, positions=pos,
                             frames=frames, **tip)
