"""Cross-sectional matrices: station tables -> per-element 6x6 compliance and mass matrices.

Ordering: stiffness/compliance act on ``[F1, F2, F3, M1, M2, M3]`` <-> ``[g1, g2, g3, k1, k2, k3]``
(force strains gamma, moment strains kappa); the mass matrix maps ``[V; Omega]`` to
``[P; H]``. Everything is expressed in the untwisted reference cross-section frame b, about the
reference line.

Rigid directions (EA, GA2 or GA3 not given) get zero compliance, i.e. ``gamma_k = 0`` and the
corresponding section force is a Lagrange multiplier. Along the span, the compliance and mass
matrices are interpolated linearly between stations and averaged exactly over each element
(the mixed form integrates the compliance over the element, so its average is what enters).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import Beam, SectionTable


def skew(a: np.ndarray) -> np.ndarray:
    """Skew matrices of vectors ``a`` (..., 3) -> (..., 3, 3), with ``skew(a) @ b = a x b``."""
    a = np.asarray(a)
    z = np.zeros_like(a[..., 0])
    return np.stack([np.stack([z, -a[..., 2], a[..., 1]], -1),
                     np.stack([a[..., 2], z, -a[..., 0]], -1),
                     np.stack([-a[..., 1], a[..., 0], z], -1)], -2)


def rot1(angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about axis 1 by ``angle`` (...,) [rad]: columns are the turned axes."""
    c, s = np.cos(angle), np.sin(angle)
    one, zero = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([one, zero, zero], -1),
                     np.stack([zero, c, -s], -1),
                     np.stack([zero, s, c], -1)], -2)


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
    # [F; M]_principal = T [F; M]_reference: forces turned, moments about the tension centre.
    T = np.zeros((ns, 6, 6))
    T[:, :3, :3] = R
    T[:, 3:, 3:] = R
    T[:, 3:, :3] = -R @ skew(xt)
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


@dataclass(frozen=True, eq=False)
class ElementProperties:
    """Per-element data of a meshed beam.

    nodes: span coordinates of the N+1 nodes [m]; h: element lengths (N,) [m];
    compliance: (N, 6, 6); mass: (N, 6, 6); rigid: bool (3,) for the force strains.
    """

    nodes: np.ndarray
    h: np.ndarray
    compliance: np.ndarray
    mass: np.ndarray
    rigid: np.ndarray

    @property
    def n_elements(self) -> int:
        return len(self.h)


def mesh_beam(beam: Beam, elements: int | None = None) -> ElementProperties:
    """Uniform mesh of ``elements`` (default ``beam.elements``) with averaged properties."""
    n = int(beam.elements if elements is None else elements)
    if n < 1:
        raise ValueError(f"elements: {n} is not allowed; need an integer >= 1")
    nodes = np.linspace(0.0, beam.length, n + 1)
    st = beam.sections.stations * beam.length
    comp = element_average(st, station_compliance(beam.sections), nodes)
    mass = element_average(st, station_mass(beam.sections), nodes)
    rigid = np.array([np.all(np.abs(comp[:, k, :]) == 0) for k in range(3)])
    return ElementProperties(nodes=nodes, h=np.diff(nodes), compliance=comp, mass=mass, rigid=rigid)
