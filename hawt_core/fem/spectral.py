"""Higher-order (p-version) mixed beam elements: the same geometrically exact equations as
fem/beam.py, with polynomial fields of degree p per element and the section properties
read where the integrals need them.

Why: the paper's element (fem/beam.py) is second order with element-averaged properties.
On a real blade, whose mass and stiffness change 10-100x along the span, its constant is
large: the NREL 5-MW's first flap frequency is 34 % low at 4 elements and 1.3 % low at 16
(a uniform blade: 0.7 % and 0.05 %): the element's average mass sits at its nodes, and a
heavy root's mass is carried out to the first node.

Discretization of element e (span [s_e, s_e + h_e], local coordinate xi in [0, 1]):

- u, theta, V, Omega: continuous, degree p, Lagrange polynomials on the p + 1
  Gauss-Lobatto-Legendre points (the ends shared with the neighbours);
- F, M: discontinuous, degree p - 1, Lagrange polynomials on the p Gauss-Legendre points
  (their values there are the unknowns; each lies between two consecutive GLL nodes);
- equilibrium and kinematics weighted with the degree-p basis (Galerkin; equilibrium
  integrated by parts: ``-int phi' F + int phi (kappa x F + f - Pdot - Omega x P) + [phi F]``),
  strain-displacement with the degree-(p - 1) basis;
- every integral by Gauss-Legendre quadrature of ``gauss`` points on each of the p cells
  between consecutive GLL nodes (composite: the integrands' section properties, gravity and
  aerodynamic loads are read at these points, the properties interpolated linearly between
  the file's stations as the format says), so a p-element mesh has the Gauss points of an
  h-mesh of N p elements (what the aerodynamic states and loads index);
- p = 1 is the paper's element with the property variation integrated inside each element
  instead of element averages (equal to fem/beam.py for uniform properties).

Unknowns and rows are laid out exactly as fem/beam.py's for N p "cells" (the intervals
between consecutive nodes): root block [F0, M0, V0, Omega0], then per cell c = e p + k
[F, M at the k-th Gauss-Legendre point of element e, u, theta, V, Omega at node c + 1];
rows [node-0 equilibrium and kinematics] and per cell [strain-displacement k of element e,
node c + 1 equilibrium, node c + 1 kinematics].  So every consumer of the layout (the
turbine's state layout, mode shapes, tip deflections, outputs) reads a p-element mesh as
it reads a mesh of N p elements.

Curved reference line (prebend, sweep): the mesh is uniform in arc length; every Gauss
point carries its own section frame (the smallest rotation turning b1 onto the line's
tangent there) and its turned 6x6 matrices, so the element follows the line's curvature
instead of a polygon (vectors in the frame b turned by theta, as fem/beam.py).
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..model import Beam
from ..numerics.limits import MAX_ORDER
from ..numerics.rotations import LEVI_CIVITA_9, rot1, skew, turn_e1_to
from .beam import (BLOCK_SIZE, ROOT_SIZE, CellLayout, _cross_components, q_stacked,
                   turn_stacked)
from .damping import DampingCoefficients, section_operators
from .sections import (ElementProperties, reference_line, sections_at, station_compliance,
                       station_mass)

__all__ = ["SpectralBeamElements", "gll_points", "lagrange_basis"]


def gll_points(p: int) -> np.ndarray:
    """The p + 1 Gauss-Lobatto-Legendre points on [0, 1] (ends included), increasing."""
    if p < 1:
        raise ValueError(f"order: {p} is not allowed; need an integer >= 1")
    if p == 1:
        return np.array([0.0, 1.0])
    inner = np.polynomial.legendre.Legendre.basis(p).deriv().roots()
    return np.concatenate([[0.0], 0.5 * (np.sort(inner.real) + 1.0), [1.0]])


def lagrange_basis(nodes: np.ndarray, x: np.ndarray):
    """(values, derivatives) (len(x), len(nodes)) of the Lagrange polynomials on ``nodes``
    at ``x`` (product form; exact to round-off for the small degrees used here)."""
    nodes, x = np.asarray(nodes, float), np.asarray(x, float)
    m = len(nodes)
    diff = nodes[:, None] - nodes[None, :]
    np.fill_diagonal(diff, 1.0)
    denom = diff.prod(axis=1)                                     # (m,)
    xm = x[:, None] - nodes[None, :]                              # (len(x), m)
    val = np.empty((len(x), m))
    der = np.zeros((len(x), m))
    for j in range(m):
        others = [i for i in range(m) if i != j]
        val[:, j] = np.prod(xm[:, others], axis=1) / denom[j]
        for l in others:
            rest = [i for i in others if i != l]
            der[:, j] += np.prod(xm[:, rest], axis=1) / denom[j]
    return val, der


def _arc_length_parameter(beam: Beam, fine: int = 4001):
    """(x of s, s of x, total arc length S, positions X(x) function or None) of the beam's
    reference line: ``x(s)`` maps an arc length [m] to the b1 coordinate [m]."""
    L = float(beam.length)
    xf = np.linspace(0.0, L, fine)
    pos = reference_line(beam.sections, L, xf)
    if pos is None:
        same = lambda s: np.asarray(s, float)
        return same, same, L, None
    sf = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pos, axis=0), axis=1))])
    line = lambda x: reference_line(beam.sections, L, np.asarray(x, float))
    return (lambda s: np.interp(s, sf, xf)), (lambda x: np.interp(x, xf, sf)), \
        float(sf[-1]), line


#: Gauss-Legendre points per piece of a cell between stations, for the property moments
MOMENT_POINTS = 8


def property_moments(beam: Beam, s_nodes, eta, w, x_of_s, s_of_x):
    """Effective compliance and mass matrices (N, G, 6, 6), section frame, at the G Gauss
    points of each cell: ``R~_g = int_cell R(s) l_g(s) ds / (h w_g)`` with ``l_g`` the
    Lagrange polynomial through the cell's Gauss points (product integration).  With them
    the cell's G-point rule integrates ``R(s) f(s)`` exactly for every polynomial f of
    degree < G, whatever the properties do between the file's stations (linear stiffness and
    mass between stations, kinks at the stations: the pieces between stations are
    integrated by MOMENT_POINTS-point Gauss rules).  Every integrand of the mixed form is
    affine in the section matrices, so the quadrature's error is that of the fields alone."""
    L = float(beam.length)
    st = s_of_x(np.asarray(beam.sections.stations, float) * L)
    xm, wm = np.polynomial.legendre.leggauss(MOMENT_POINTS)
    xm, wm = 0.5 * (xm + 1.0), 0.5 * wm
    N, G = len(s_nodes) - 1, len(eta)
    pts, wts, cell = [], [], []
    for c in range(N):
        a, b = s_nodes[c], s_nodes[c + 1]
        cuts = np.concatenate([[a], st[(st > a) & (st < b)], [b]])
        lo, hi = cuts[:-1, None], cuts[1:, None]
        pts.append(((lo + (hi - lo) * xm[None]) - a).ravel() / (b - a))   # local eta
        wts.append(((hi - lo) * wm[None]).ravel())
        cell.append(np.full(pts[-1].size, c))
    eta_s, w_s, cell = np.concatenate(pts), np.concatenate(wts), np.concatenate(cell)
    h = np.diff(s_nodes)
    s_s = s_nodes[cell] + h[cell] * eta_s
    sec = sections_at(beam.sections, np.clip(x_of_s(s_s) / L, 0.0, 1.0))
    lg, _ = lagrange_basis(eta, eta_s)                                # (S, G)
    s_g = s_nodes[:-1, None] + h[:, None] * np.asarray(eta)[None, :]
    at_points = sections_at(beam.sections, np.clip(x_of_s(s_g.ravel()) / L, 0.0, 1.0))
    out = []
    for M, M_g in ((station_compliance(sec), station_compliance(at_points)),
                   (station_mass(sec), station_mass(at_points))):
        acc = np.zeros((N, G, 6, 6))
        np.add.at(acc, cell, (w_s[:, None] * lg)[:, :, None, None] * M[:, None])
        acc /= (h[:, None] * w[None, :])[..., None, None]
        # a cell across a steep change (a blade root) can get an indefinite moment at a
        # point (the Lagrange weights change sign): a negative compliance or mass there
        # makes spurious, even unstable, modes on coarse meshes; such a cell keeps the
        # properties sampled at its points (positive; exact only for smooth properties)
        sym = 0.5 * (acc + np.swapaxes(acc, -1, -2))
        scale = np.abs(sym).max(axis=(-1, -2), keepdims=True)[..., 0] + 1e-300
        bad = (np.linalg.eigvalsh(sym) < -1e-12 * scale).any(axis=(1, 2))
        acc[bad] = M_g.reshape(N, G, 6, 6)[bad]
        out.append(acc)
    return out


class SpectralBeamElements(CellLayout):
    """The discretized beam operator of order ``order`` (p) for ``B`` identical beams sharing
    one mesh of ``elements`` elements on ``beam`` (model.Beam), turned by ``pitch`` [rad]
    about b1 (fem/sections.py mesh_beam).  The interface is BeamElements' (residual, nodal,
    split, rigid_body_state, differential, ...) on the N p cells (module docstring).
    ``gauss``: Gauss-Legendre points per cell."""

    BIG = 64

    def __init__(self, beam: Beam, elements: int, order: int, pitch: float = 0.0,
                 gauss: int = 3, damping: Optional[DampingCoefficients] = None):
        p = int(order)
        if not 1 <= p <= MAX_ORDER:
            raise ValueError(f"order: {order!r} is not allowed; need an integer from 1 to "
                             f"{MAX_ORDER}")
        Ne = int(elements)
        if Ne < 1:
            raise ValueError(f"elements: {elements!r} is not allowed; need an integer >= 1")
        self.order, self.elements = p, Ne
        self.N = Ne * p                                  # cells
        self.n = ROOT_SIZE + BLOCK_SIZE * self.N
        G = int(gauss)
        xg, wg = np.polynomial.legendre.leggauss(G)
        self.eta = 0.5 * (xg + 1.0)
        self.w = 0.5 * wg
        self.gauss = G
        Q = self.Q = p * G                               # Gauss points per element

        # ---- mesh in arc length: element ends, GLL nodes, cells, Gauss points
        x_of_s, s_of_x, S, line = _arc_length_parameter(beam)
        xi_n = gll_points(p)
        he = S / Ne
        s_nodes = np.concatenate([e * he + he * xi_n[:-1] for e in range(Ne)] + [[S]])
        h = np.diff(s_nodes)                             # (N,) cell lengths
        s_g = s_nodes[:-1, None] + h[:, None] * self.eta[None, :]          # (N, G)
        xi_q = ((s_g.reshape(Ne, Q) - (np.arange(Ne) * he)[:, None]) / he)  # (Ne, Q) in [0,1]
        xi_q = xi_q[0]                                   # the same in every element
        W = (h[:, None] * self.w[None, :]).reshape(Ne, Q)                  # weights [m]
        self.h = h
        self.he = np.full(Ne, he)
        x_nodes = x_of_s(s_nodes)
        self.xg = x_of_s(s_g)                            # (N, G) b1 coordinate [m]

        # ---- bases at the Gauss points of an element
        Lq, dLq = lagrange_basis(xi_n, xi_q)             # (Q, p+1)
        xi_f = 0.5 * (np.polynomial.legendre.leggauss(p)[0] + 1.0)
        Pq, _ = lagrange_basis(xi_f, xi_q)               # (Q, p)
        self._Lq = Lq
        self._Pq = Pq
        #: node weights (Ne, p+1, Q): int phi_j (.) ; strain weights (Ne, p, Q): int psi_k (.)
        self._WL = W[:, None, :] * Lq.T[None]
        self._WP = W[:, None, :] * Pq.T[None]
        #: constant operators: C[e, j, k] = int phi_j' psi_k (the -int phi' F term),
        #: D[e, k, j] = int psi_k phi_j' (the strain rows' u', theta')
        dphi = dLq / he                                  # (Q, p+1) d/ds
        self._C = np.einsum("eq,qj,qk->ejk", W, dphi, Pq)
        self._D = self._C.transpose(0, 2, 1).copy()

        # ---- geometry and properties at the Gauss points
        xq = self.xg.reshape(-1)
        L = float(beam.length)
        if line is None:
            X = np.stack([xq, 0 * xq, 0 * xq], -1)
            tang = np.broadcast_to(np.array([1.0, 0.0, 0.0]), X.shape).copy()
            pos_nodes = np.stack([x_nodes, 0 * x_nodes, 0 * x_nodes], -1)
        else:
            X = line(xq)
            d = 1e-6 * L
            lo, hi = np.clip(xq - d, 0.0, L), np.clip(xq + d, 0.0, L)
            tang = (line(hi) - line(lo))
            tang /= np.linalg.norm(tang, axis=1)[:, None]
            pos_nodes = line(x_nodes)
        A = turn_e1_to(tang)                             # (Ne Q, 3, 3) section frames in b
        chord = np.diff(pos_nodes, axis=0)
        frames = turn_e1_to(chord / np.linalg.norm(chord, axis=1)[:, None])
        if pitch != 0:
            P = rot1(float(pitch))
            X, A, pos_nodes, frames = X @ P.T, P @ A, pos_nodes @ P.T, P @ frames
        self.curved = line is not None or pitch != 0
        comp, mass = (m.reshape(-1, 6, 6) for m in property_moments(
            beam, s_nodes, self.eta, self.w, x_of_s, s_of_x))
        A6 = np.zeros((len(xq), 6, 6))
        A6[:, :3, :3] = A6[:, 3:, 3:] = A
        turn = lambda M: A6 @ M @ A6.transpose(0, 2, 1)
        self.R = turn(comp).reshape(Ne, Q, 6, 6)
        self.mass = turn(mass).reshape(Ne, Q, 6, 6)
        self._RT = np.ascontiguousarray(self.R.transpose(0, 1, 3, 2))
        self._muT = np.ascontiguousarray(self.mass.transpose(0, 1, 3, 2))
        self._t = (A[:, :, 0]).reshape(Ne, Q, 1, 3)
        self._X0 = X.reshape(Ne, Q, 1, 3)
        # structural damping (fem/damping.py): the F, M rates' viscous loads on the
        # equilibrium rows, -int phi_j' mu_hat psi_k (Ne, p+1, p, 6, 6), and the
        # mass-proportional load's operator at the Gauss points (Ne, Q, 6, 6)^T
        self.damping = damping
        mu_hat, alpha_mu = section_operators(damping, comp, self.mass.reshape(-1, 6, 6),
                                             A6)
        self._Cmu = self._amuT = None
        if mu_hat is not None:
            mq = mu_hat.reshape(Ne, Q, 6, 6)
            self._Cmu = np.einsum("eq,qj,qk,eqab->ejkab", W, dphi, Pq, mq)
            # the viscous force's moment in the moment rows, + int phi_j t x F_d (the
            # strains' part, gamma x F_d, second order): without it a shear-flexible
            # section's viscous shear force did work on the slope rate instead of the shear
            # strain rate (a uniform cantilever with uniform mu: zeta 1.99 x mu w / 2)
            tF = np.zeros((Ne, Q, 6, 6))
            tF[..., 3:6, :] = skew(self._t.reshape(Ne, Q, 3)) @ mq[..., 0:3, :]
            self._Cmu -= np.einsum("eq,qj,qk,eqab->ejkab", W, Lq, Pq, tF)
        if alpha_mu is not None:
            self._amuT = np.ascontiguousarray(
                alpha_mu.reshape(Ne, Q, 6, 6).transpose(0, 1, 3, 2))
        self.points = X.reshape(self.N, G, 3)
        mq = self.mass.reshape(Ne, Q, 6, 6)
        self._mpl = mq[:, :, 0, 0][:, :, None, None]
        self._mxi = np.stack([mq[..., 5, 1], mq[..., 3, 2], mq[..., 4, 0]], -1)[:, :, None, :,
                                                                                  None]

        # ---- the cells as an ElementProperties (layout, energy, plots, bounds)
        cw = self.w
        comp_c = np.einsum("g,cgij->cij", cw, comp.reshape(self.N, G, 6, 6))
        mass_c = np.einsum("g,cgij->cij", cw, mass.reshape(self.N, G, 6, 6))
        self.props = ElementProperties(
            nodes=x_nodes, h=h, compliance=comp_c, mass=mass_c,
            positions=pos_nodes if self.curved else None,
            frames=frames if self.curved else None,
            tip_mass=float(beam.tip_mass), tip_inertia=tuple(map(float, beam.tip_inertia)))
        self.mass_per_length = mass_c[:, 0, 0]
        self.tip_mass = float(beam.tip_mass)
        Jt = np.diag(np.asarray(beam.tip_inertia, float))
        At = A[-1] if self.curved else np.eye(3)
        self.tip_inertia = At @ Jt @ At.T
        self._has_tip_body = self.tip_mass != 0 or np.any(Jt != 0)
        self.differential = self._differential_mask()
        if self._Cmu is not None:          # damped section loads: their rates are read
            self._mark_rate_loads(np.any(self._Cmu != 0, axis=(1, 3)).reshape(self.N, 6))
        self._index()

    # ------------------------------------------------------------------ layout
    def _index(self):
        """Gather indices: every element's p + 1 nodes' [u, th, V, Om, rates] (24) in the
        concatenation [y | yd | 0] (2n + 1), and its p load coefficients (6) in y."""
        Ne, p, n = self.elements, self.order, self.n
        node = np.empty((self.N + 1, 24), int)
        zero = 2 * n
        node[0, :] = zero
        node[0, 6:12] = np.arange(6, 12)
        node[0, 18:24] = n + np.arange(6, 12)
        blk = ROOT_SIZE + BLOCK_SIZE * np.arange(self.N)[:, None] + np.arange(6, 18)[None, :]
        node[1:, :12] = blk
        node[1:, 12:] = n + blk
        gidx = np.arange(Ne)[:, None] * p + np.arange(p + 1)[None, :]      # (Ne, p+1)
        self._gather = node[gidx].reshape(Ne, (p + 1) * 24)
        cells = np.arange(Ne)[:, None] * p + np.arange(p)[None, :]
        self._fm_idx = (ROOT_SIZE + BLOCK_SIZE * cells[..., None]
                        + np.arange(6)[None, None, :])                    # (Ne, p, 6)

    def pattern_blocks(self):
        """Block sizes for the element-level block-tridiagonal pattern: the root block, then
        one block of p cells per element (an element couples all its cells and the node it
        shares with its left neighbour)."""
        return [ROOT_SIZE] + [BLOCK_SIZE * self.order] * self.elements

    def station_points(self) -> int:
        """Gauss points per pattern block (numerics.jacobian.beam_station_pattern)."""
        return self.Q

    # ------------------------------------------------------------------ residual
    def residual(self, yd, y, v, w, g=None, tip_force=None, tip_moment=None, wind=None,
                 section_loads=None, capture=None):
        """Residual (B, n) of B beams; arguments as BeamElements.residual (the Gauss-point
        arrays handed to ``section_loads`` are (N, G, B, 3) over the cells).  ``capture``:
        receives ``integrand`` (Ne, Q, B, 18) and ``tip`` (B, 6) or None."""
        B, n, Ne, p, Q, G = y.shape[0], self.n, self.elements, self.order, self.Q, self.gauss
        dt = np.result_type(y, yd, v, w, *(a for a in (g, tip_force, tip_moment, wind)
                                           if a is not None))
        Y = np.empty((B, 2 * n + 1), dtype=np.result_type(y, yd))
        Y[:, :n] = y
        Y[:, n:2 * n] = yd
        Y[:, 2 * n] = 0.0
        ends = Y[:, self._gather].reshape(B, Ne, p + 1, 24).transpose(1, 2, 0, 3)
        a = (self._Lq @ ends.reshape(Ne, p + 1, B * 24)).reshape(Ne, Q, B, 24)
        ug, thg, Vg, Omg = a[..., 0:3], a[..., 3:6], a[..., 6:9], a[..., 9:12]
        thg = np.ascontiguousarray(thg)
        udg, thdg = a[..., 12:15], a[..., 15:18]
        FMk = y[:, self._fm_idx].transpose(1, 2, 0, 3)                 # (Ne, p, B, 6)
        FM = (self._Pq @ FMk.reshape(Ne, p, B * 6)).reshape(Ne, Q, B, 6)
        big = B * Ne * p > self.BIG

        def cross(x, z, shape):
            if big:
                return _cross_components(x[..., 0], z[..., 0, :], dt).reshape(shape)
            return ((x * z).reshape(-1, 9) @ LEVI_CIVITA_9).reshape(shape)

        strain = FM @ self._RT                                          # (Ne, Q, B, 6)
        gam, kap = strain[..., :3], strain[..., 3:]
        e1g = gam + self._t
        FM2 = FM.reshape(Ne, Q, B, 2, 3)
        kFM = cross(kap[..., None, :, None], FM2[..., None, :], (Ne, Q, B, 2, 3))
        eF = cross(e1g[..., :, None], FM[..., None, 0:3], (Ne, Q, B, 3))

        X = a.reshape(Ne, Q, B, 2, 12)[..., 6:12]                       # [[V, Om], [Vd, Omd]]
        PH = (X.reshape(Ne, Q, B * 2, 6) @ self._muT).reshape(Ne, Q, B, 2, 6)
        P = PH[..., 0, 0:3]
        OmPH = cross(Omg[..., None, :, None], PH[..., 0, :].reshape(Ne, Q, B, 2, 1, 3),
                     (Ne, Q, B, 6))
        VP = cross(Vg[..., :, None], P[..., None, :], (Ne, Q, B, 3))

        grav = g is not None
        airy = wind is not None
        several = airy and np.ndim(wind) == 3
        m_wind = (np.shape(wind)[1] if several else 1) if airy else 0
        viscous = self._amuT is not None
        wxp = cross(w[:, :, None], (ug + self._X0)[..., None, :], (Ne, Q, B, 3))
        nT = 3 + grav + viscous + m_wind
        T = np.empty((Ne, Q, B, nT, 3), dtype=dt)
        T[..., 0, :] = Vg
        T[..., 1, :] = e1g
        T[..., 2, :] = w
        if grav:
            T[..., 3, :] = g
        if viscous:            # the root frame's velocity at the section: C (v + w x p)
            T[..., 3 + grav, :] = wxp + v
        if airy:
            T[..., nT - m_wind:, :] = wind if several else wind[:, None, :]
        sgn = np.array([1.0, 1.0, -1.0] + [-1.0] * (grav + viscous + m_wind))[:, None]
        rT, th1 = turn_stacked(thg, T, sgn, cross)
        T2 = np.empty((Ne, Q, B, 2, 3), dtype=dt)
        np.subtract(Omg, rT[..., 2, :], out=T2[..., 0, :])
        T2[..., 1, :] = kap
        q = q_stacked(th1, T2, cross)

        I = np.empty((Ne, Q, B, 18), dtype=dt)
        t = np.empty((Ne, Q, B, 6), dtype=dt)
        np.add(PH[..., 1, :], OmPH, out=t)
        t[..., 3:6] += VP
        if grav:
            gB = rT[..., 3, :]
            t[..., 0:3] -= self._mpl * gB
            t[..., 3:6] -= cross(self._mxi, gB[..., None, :], gB.shape)
        if viscous:            # mass-proportional damping of the relative velocities
            rel = np.empty((Ne, Q, B, 6), dtype=dt)
            np.subtract(Vg, rT[..., 3 + grav, :], out=rel[..., 0:3])
            rel[..., 3:6] = T2[..., 0, :]
            t += rel @ self._amuT
        if section_loads is not None:
            cells = lambda z: None if z is None else z.reshape((self.N, G) + z.shape[2:])
            force, moment = section_loads({
                "V": cells(Vg), "Omega": cells(Omg), "Vdot": cells(a[..., 18:21]),
                "Omegadot": cells(a[..., 21:24]), "position": cells(ug + self._X0),
                "theta": cells(thg),
                "wind": cells((rT[..., nT - m_wind:, :] if several else rT[..., nT - 1, :])
                              if airy else None)})
            t[..., 0:3] -= force.reshape(Ne, Q, B, 3)
            t[..., 3:6] -= moment.reshape(Ne, Q, B, 3)
        np.negative(t, out=I[..., 0:6])
        I[..., 0:3] += kFM[..., 0, :]
        I[..., 3:6] += kFM[..., 1, :] + eF
        I[..., 6:9] = (udg - rT[..., 0, :]) + v + wxp
        np.subtract(thdg, q[..., 0, :], out=I[..., 9:12])
        np.subtract(rT[..., 1, :], self._t, out=I[..., 12:15])
        I[..., 15:18] = q[..., 1, :]
        if capture is not None:
            capture["integrand"], capture["tip"] = I, None

        Ir = I.reshape(Ne, Q, B * 18)
        # node rows (Ne, p+1, B, 12): int phi_j I[0:12], minus int phi_j' F on equilibrium
        Sn = (self._WL @ Ir).reshape(Ne, p + 1, B, 18)[..., 0:12].copy()
        Sn[..., 0:6] -= (self._C @ FMk.reshape(Ne, p, B * 6)).reshape(Ne, p + 1, B, 6)
        if self._Cmu is not None:          # the viscous section loads diag(mu) dF/dt
            FMd = yd[:, self._fm_idx].transpose(1, 2, 0, 3)             # (Ne, p, B, 6)
            Sn[..., 0:6] -= np.einsum("ejkab,ekBb->ejBa", self._Cmu, FMd)
        # strain rows (Ne, p, B, 6): int psi_k [u', theta'] - int psi_k I[12:18]
        St = (self._D @ ends[..., 0:6].reshape(Ne, p + 1, B * 6)).reshape(Ne, p, B, 6)
        St -= (self._WP @ Ir).reshape(Ne, p, B, 18)[..., 12:18]

        out = np.empty((B, n), dtype=dt)
        blk = out[:, ROOT_SIZE:].reshape(B, self.N, BLOCK_SIZE)
        nodes = np.zeros((self.N + 1, B, 12), dtype=dt)
        nodes[:-1].reshape(Ne, p, B, 12)[:] = Sn[:, :p]
        nodes[p::p] += Sn[:, p]
        out[:, :12] = nodes[0]
        out[:, 0:6] -= y[:, 0:6]
        blk[:, :, 6:18] = nodes[1:].transpose(1, 0, 2)
        blk[:, :, 0:6] = St.reshape(self.N, B, 6).transpose(1, 0, 2)
        if tip_force is not None:
            blk[:, -1, 6:9] += tip_force
        if tip_moment is not None:
            blk[:, -1, 9:12] += tip_moment
        if self._has_tip_body:
            tip = self._tip_body_loads(yd, y, g)
            blk[:, -1, 6:12] += tip
            if capture is not None:
                capture["tip"] = tip
        return out
