"""Geometrically-exact mixed beam finite elements (Hodges 1990), vectorized over beams x elements.

Equations (docs/theory.md), in the moving root frame b of the beam, for a beam initially
straight along ``b1``:

    F' + kappa x F + f              = Pdot + Omega x P
    M' + kappa x M + (e1 + gamma) x F + m = Hdot + Omega x H + V x P
    u' = C^T (e1 + gamma) - e1,     theta' = Q kappa
    udot = C^T V - v - omega x (x1 e1 + u),   thetadot = Q (Omega - C omega)
    [gamma; kappa] = R [F; M],      [P; H] = mu [V; Omega]

Discretization (the variant of theory.md that reproduces the paper's Table 2):
``u, theta, V, Omega`` are nodal and linear in each element, ``F, M`` constant per element; the
equilibrium and kinematic equations are weighted with the linear (hat) test functions and
integrated by Gauss quadrature (exact for the inertia and kinematic terms); the
strain-displacement relations are integrated element by element.  The root node is clamped
(``u0 = theta0 = 0``); the root section loads ``F0, M0`` are unknowns: they are the loads the
beam exerts on the body it is clamped to, in the root frame.  The tip is free, or carries a
prescribed load.

Unknowns of one beam (``n_beam = 12 + 18 N``), ordered for a narrow band:
    [F0, M0, V_0, Omega_0,  (F_e, M_e, u_e, theta_e, V_e, Omega_e) for e = 1..N]
Residual rows in the same block order:
    [node-0 equilibrium (force, moment), node-0 kinematics (u, theta),
     (element-e strain-displacement (u, theta), node-e equilibrium, node-e kinematics) ...]
All arithmetic is complex-safe (complex-step Jacobians).

Curved reference line (prebend, sweep: fem/sections.py mesh_beam): a polygon of straight
elements, element e with the constant section frame ``A_e`` (columns a1 along the element).
As in GXBeam, ``theta`` parametrizes the rotation of the section *from its undeformed
orientation* (so it is continuous through the kinks and zero at the clamp), and every
section vector is carried in the frame ``b`` turned by that rotation, ``x* = A_e x_B``:
there the element's equations are those above with ``e1`` replaced by the element's
tangent ``t_e = A_e e1``, the reference position ``x1 e1`` by the point of the polygon, and
the section matrices turned, ``R* = A R A^T`` and ``mu* = A mu A^T`` (A = diag(A_e, A_e);
cross products are invariant under the common rotation).  The nodal ``V, Omega`` and the
element ``F, M`` unknowns are in these components; at the root (theta = 0) they are root
frame components, so the coupling to the hub is unchanged, and a straight beam
(``A_e = I``) is exactly the formulation above.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..numerics.rotations import LEVI_CIVITA_9, cross as cross3, dot, rot_apply
from .damping import DampingCoefficients, section_operators
from .sections import ElementProperties

#: Offsets inside the per-element block of 18 unknowns.
F_, M_, U_, TH_, V_, OM_ = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12),
                            slice(12, 15), slice(15, 18))
ROOT_F, ROOT_M, ROOT_V, ROOT_OM = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
ROOT_SIZE, BLOCK_SIZE = 12, 18


def _cross_components(x, z, dtype):
    """x x z on the last axis (broadcast), component by component on strided views: for
    the large batches of the complex-step Jacobians 3-4x faster than gathering permuted
    copies (x[..., [1, 2, 0]] ...) and than the Levi-Civita matmul."""
    out = np.empty(np.broadcast_shapes(x.shape, z.shape), dtype)
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.subtract(x[..., j] * z[..., k], x[..., k] * z[..., j], out=out[..., i])
    return out


def turn_stacked(thg, T, sgn, cross):
    """The stacked vectors T (..., m, 3) turned by the rotation parameters ``thg`` (..., 3):
    C^T (sgn +1) or C (sgn -1) per vector (Wiener-Milenkovic, docs/theory.md), with
    ``cross(x, z, shape)`` the residual's cross product; returns (turned, thg[..., None, :])."""
    th1 = thg[..., None, :]
    thT = cross(th1[..., :, None], T[..., None, :], T.shape)
    dots = dot(T, th1)[..., None]
    ss = (0.25 * dot(thg, thg))[..., None, None]
    return (((1 - ss) * T + sgn * thT + 0.5 * th1 * dots) / (1 + ss)), th1


def q_stacked(th1, T2, cross):
    """Q(theta) applied to the stacked vectors T2 (..., 2, 3) (``th1`` from turn_stacked)."""
    thT2 = cross(th1[..., :, None], T2[..., None, :], T2.shape)
    return T2 + 0.5 * thT2 + 0.25 * th1 * dot(T2, th1)[..., None]


class CellLayout:
    """What both discretizations share (this module's and fem/spectral.py's): the unknowns
    of a root block and N cells of 18 ([F, M, u, theta, V, Omega], module docstring), and
    the rigid tip body on the last node.  Needs ``N``, ``n``, ``props``, ``tip_mass``,
    ``tip_inertia``."""

    def _differential_mask(self) -> np.ndarray:
        d = np.zeros(self.n, bool)
        d[ROOT_V] = d[ROOT_OM] = True
        blk = d[ROOT_SIZE:].reshape(self.N, BLOCK_SIZE)
        blk[:, U_] = blk[:, TH_] = blk[:, V_] = blk[:, OM_] = True
        return d

    def _mark_rate_loads(self, cells: np.ndarray):
        """Mark the section loads whose rates the residual reads (structural damping:
        ``cells`` (N, 6) per cell's [F, M]) as differential unknowns."""
        blk = self.differential[ROOT_SIZE:].reshape(self.N, BLOCK_SIZE)
        blk[:, F_] |= cells[:, 0:3]
        blk[:, M_] |= cells[:, 3:6]

    def split(self, y):
        """Views of a (B, n) array: root (B,12) and element blocks (B,N,18)."""
        return y[:, :ROOT_SIZE], y[:, ROOT_SIZE:].reshape(y.shape[0], self.N, BLOCK_SIZE)

    def nodal(self, y):
        """Nodal u, theta, V, Omega (B, N+1, 3) and element F, M (B, N, 3) of a (B, n) array."""
        root, blk = self.split(y)
        z = np.zeros_like(root[:, None, 0:3])
        u = np.concatenate([z, blk[:, :, U_]], 1)
        th = np.concatenate([z, blk[:, :, TH_]], 1)
        V = np.concatenate([root[:, None, ROOT_V], blk[:, :, V_]], 1)
        Om = np.concatenate([root[:, None, ROOT_OM], blk[:, :, OM_]], 1)
        return u, th, V, Om, blk[:, :, F_], blk[:, :, M_]

    def _tip_body_loads(self, yd, y, g):
        """(B, 6) loads of the rigid tip body on the tip node, added to its equilibrium rows:
        F = m (C g - Vdot - Omega x V), M = -(J Omegadot + Omega x J Omega), from the tip
        node's theta, V, Omega and rates (turned-b components, as the rows)."""
        o = ROOT_SIZE + BLOCK_SIZE * (self.N - 1)
        th, V, Om = y[:, o + 9:o + 12], y[:, o + 12:o + 15], y[:, o + 15:o + 18]
        Vd, Omd = yd[:, o + 12:o + 15], yd[:, o + 15:o + 18]
        F = -self.tip_mass * (Vd + cross3(Om, V))
        if g is not None:
            F = F + self.tip_mass * rot_apply(th, g)
        J = self.tip_inertia
        M = -(Omd @ J.T + cross3(Om, Om @ J.T))
        return np.concatenate([F, M], -1)

    def dynamic_dimension(self) -> int:
        """Dynamic states of one clamped beam: 2 per flexible section direction and element
        (a direction with zero compliance is a constraint whose section load is a Lagrange
        multiplier): 6N with rigid axial and shear directions, 12N with all six flexible."""
        # nonzero compliance rows in the section frames (the turned R mixes a rigid
        # direction with a flexible one)
        flexible = np.any(self.props.compliance != 0, axis=2).sum()
        return int(2 * flexible)

    def rigid_body_state(self, v, w):
        """Unknowns (n,) of one undeformed beam in rigid motion (v, w constant, real), with the
        section forces left at zero: a starting guess for steady-state Newton iterations."""
        y = np.zeros(self.n)
        Vn = v[None, :] + np.cross(w[None, :], self.props.node_positions())
        y[ROOT_V] = Vn[0]
        y[ROOT_OM] = w
        blk = y[ROOT_SIZE:].reshape(self.N, BLOCK_SIZE)
        blk[:, V_] = Vn[1:]
        blk[:, OM_] = w
        return y


class BeamElements(CellLayout):
    """The discretized beam operator for ``B`` identical beams sharing one mesh.

    ``props``: ElementProperties (mesh, 6x6 compliance and mass per element).
    ``gauss``: number of Gauss points per element, the same for every integrated term
    (default 3: 2 already integrate the inertia and kinematic terms exactly; the third point
    is for the rotation-dependent terms, which are not polynomial in theta).
    """

    #: batch x elements above which cross products use index gathers (fewer flops)
    #: rather than one small matmul per product (fewer NumPy calls)
    BIG = 64

    def __init__(self, props: ElementProperties, gauss: int = 3,
                 damping: Optional[DampingCoefficients] = None):
        self.props = props
        self.N = props.n_elements
        self.n = ROOT_SIZE + BLOCK_SIZE * self.N
        xg, wg = np.polynomial.legendre.leggauss(gauss)
        self.eta = 0.5 * (xg + 1.0)  # (G,)
        self.w = 0.5 * wg            # (G,), sum 1
        h = props.h
        frames = props.element_frames()
        #: element tangents t_e (N, 3) and Gauss-point positions (N, G, 3) in b [m]
        self.tangent = np.ascontiguousarray(frames[:, :, 0])
        pos = props.node_positions()
        self.points = (pos[:-1, None, :] * (1 - self.eta)[None, :, None]
                       + pos[1:, None, :] * self.eta[None, :, None])
        A6 = np.zeros((self.N, 6, 6))
        A6[:, :3, :3] = A6[:, 3:, 3:] = frames
        turn = lambda S: A6 @ S @ A6.transpose(0, 2, 1)   # section frame -> turned-b frame
        # weights for the two hat functions of each element at the Gauss points: (N, G)
        self.wa = h[:, None] * (self.w * (1 - self.eta))[None, :]
        self.wb = h[:, None] * (self.w * self.eta)[None, :]
        self.xg = props.nodes[:-1, None] + h[:, None] * self.eta[None, :]  # (N, G)
        self.h = h
        mu = turn(props.mass) if props.curved else props.mass
        self.m_vv, self.m_vo = mu[:, :3, :3], mu[:, :3, 3:]
        self.m_ov, self.m_oo = mu[:, 3:, :3], mu[:, 3:, 3:]
        self.mass_per_length = mu[:, 0, 0]
        # m * xi (mass-centre offset times mass), read off mu_ov = m xi~ (for gravity moments)
        self.m_xi = np.stack([mu[:, 5, 1], mu[:, 3, 2], mu[:, 4, 0]], -1)
        #: compliance (N, 6, 6) acting on the F, M unknowns (turned-b components)
        self.R = turn(props.compliance) if props.curved else props.compliance
        self.mass = mu
        #: the rigid tip body: mass [kg] and inertia (3, 3) [kg m^2] in turned-b components
        self.tip_mass = float(props.tip_mass)
        J = np.diag(np.asarray(props.tip_inertia, float))
        self.tip_inertia = frames[-1] @ J @ frames[-1].T
        self._has_tip_body = self.tip_mass != 0 or np.any(J != 0)
        # structural damping (fem/damping.py), per element: the viscous section loads
        # mu_hat dF/dt and the mass-proportional load's operator (transposed)
        self.damping = damping
        mu_hat, alpha_mu = section_operators(damping, props.compliance, mu,
                                             A6 if props.curved else None)
        self._muhatT = None if mu_hat is None else np.ascontiguousarray(
            mu_hat.transpose(0, 2, 1))
        self._amuT = None if alpha_mu is None else np.ascontiguousarray(
            alpha_mu.transpose(0, 2, 1))[:, None]
        self.differential = self._differential_mask()
        if mu_hat is not None:
            self._mark_rate_loads(np.any(mu_hat != 0, axis=1))
        self._precompute()

    # ------------------------------------------------------------------ residual
    def _precompute(self):
        """Constant operators of the fused residual (see :meth:`residual`)."""
        N = self.N
        n = self.n
        # rows: the G Gauss-point interpolations and the element difference (right - left)
        self._Lg = np.vstack([np.stack([1 - self.eta, self.eta], -1), [[-1.0, 1.0]]])
        # hat weights (left, right) and their sum, per element: (N, 3, G)
        self._W3 = np.stack([self.wa, self.wb, self.wa + self.wb], 1)
        # index of every (element, end, field) entry of the stacked nodal fields in the
        # concatenation [y | yd | 0] (B, 2n+1): fields [u, th, V, Om, ud, thd, Vd, Omd]
        idx = np.empty((N, 2, 24), int)
        blk = ROOT_SIZE + BLOCK_SIZE * np.arange(N)[:, None] + np.arange(6, 18)[None, :]
        idx[:, 1, :12] = blk
        idx[:, 1, 12:] = n + blk
        idx[1:, 0] = idx[:-1, 1]
        zero = 2 * n
        idx[0, 0] = zero
        idx[0, 0, 6:12] = np.arange(6, 12)
        idx[0, 0, 18:24] = n + np.arange(6, 12)
        self._gather = idx.reshape(N, 48)
        self._fm_idx = (ROOT_SIZE + BLOCK_SIZE * np.arange(N)[:, None]
                        + np.arange(6)[None, :])                   # (N, 6) of F, M
        self._muT = np.ascontiguousarray(self.mass.transpose(0, 2, 1))
        self._RT = np.ascontiguousarray(self.R.transpose(0, 2, 1))  # (N, 6, 6)
        self._X0 = self.points[:, :, None, :]                      # (N, G, 1, 3)
        self._mxi4 = self.m_xi[:, None, None, :, None]            # (N, 1, 1, 3, 1)
        self._mpl = self.mass_per_length[:, None, None, None]
        self._halfh = 0.5 * self.h[:, None, None]
        self._sgn3 = np.array([1.0, 1.0, -1.0])[:, None]
        self._sgn4 = np.array([1.0, 1.0, -1.0, -1.0])[:, None]
        self._t = self.tangent[:, None, :]                         # (N, 1, 3)
        self._t4 = self.tangent[:, None, None, :]                  # (N, 1, 1, 3)

    def residual(self, yd, y, v, w, g=None, tip_force=None, tip_moment=None, wind=None,
                 section_loads=None, capture=None):
        """Residual (B, n) of B beams.

        yd, y: (B, n) time derivative and value of the unknowns.
        v, w: (B, 3) inertial velocity of the root point and angular velocity of the root
            frame, in the root frame b [m/s, rad/s].
        g: (B, 3) gravity vector in the root frame [m/s^2] or None.
        tip_force, tip_moment: (B, 3) loads applied at the tip, in the tip section frame B
            (for a curved beam: b turned by the tip's rotation theta).
        wind: (B, 3) a uniform air velocity in the root frame [m/s], or (B, m, 3) several
            root-frame vectors, or None; it reaches ``section_loads`` in each Gauss point's
            section frame ((N, G, B, 3) or (N, G, B, m, 3)).
        section_loads: None, or ``f(sections) -> (force, moment)``, distributed loads per
            unit length [N/m, N m/m] at the Gauss points (N, G, B, 3), section-frame (turned-b)
            components, acting at the reference line; ``sections`` is a dict of the Gauss-point
            arrays (N, G, B, 3) ``V``, ``Omega`` (section velocities), ``Vdot``,
            ``Omegadot`` (their rates), ``position`` (the deformed reference line's point
            relative to the root, root-frame b components [m]), ``theta`` (the rotation
            parameters: numerics.rotations.rot_apply turns b components into the section
            frame's) and ``wind`` (the air velocity in the section frame, None without
            ``wind``).  Aerodynamic loads enter the one residual this way.
        capture: None, or a dict that receives the pieces the rows are assembled from,
            for fem/beam_jacobian.py: ``integrand`` (N, G, B, 18), the Gauss-point integrand
            [-(equilibrium), kinematics, strain-displacement] before the hat weights,
            ``element`` (N, B, 6), the element constants h/2 [kappa x F, kappa x M +
            (t + gamma) x F] added to both ends' equilibrium rows, and ``tip`` (B, 6) or
            None, the rigid tip body's loads on the tip node.

        Fused implementation (about 70 NumPy calls whatever B and N, every product a single
        BLAS call or N of them): Gauss-point arrays are laid out (element, Gauss point, beam,
        component); the nodal fields of both element ends are gathered with one index array
        and interpolated to the Gauss points (and differenced) by one matmul; the rotation
        operators C^T, C, Q act on stacked vectors; cross products are outer products
        contracted with the Levi-Civita tensor; all hat-weighted integrals are one matmul.
        tests/test_beam_reference.py compares it with the original term-by-term version.
        """
        B, n, N = y.shape[0], self.n, self.N
        dt = np.result_type(y, yd, v, w, *(a for a in (g, tip_force, tip_moment, wind)
                                           if a is not None))
        Y = np.empty((B, 2 * n + 1), dtype=np.result_type(y, yd))
        Y[:, :n] = y
        Y[:, n:2 * n] = yd
        Y[:, 2 * n] = 0.0
        ends = Y[:, self._gather].reshape(B, N, 2, 24).transpose(1, 2, 0, 3).reshape(N, 2, -1)
        G = len(self.eta)
        ag = (self._Lg @ ends).reshape(N, G + 1, B, 24)          # (N, G+1, B, 24)
        a = ag[:, :G]
        ug, thg, Vg, Omg = a[..., 0:3], a[..., 3:6], a[..., 6:9], a[..., 9:12]
        # a contiguous copy of the rotation parameters, used in many products and dot
        # products below (on the strided view they are 2x slower)
        thg = np.ascontiguousarray(thg)
        udg, thdg = a[..., 12:15], a[..., 15:18]
        E9 = LEVI_CIVITA_9

        big = B * N > self.BIG

        def cross(x, z, shape):                                 # x (.., 3, 1), z (.., 1, 3)
            if big:   # large batches (Jacobians): fewer flops; small: fewer NumPy calls
                return _cross_components(x[..., 0], z[..., 0, :], dt).reshape(shape)
            return ((x * z).reshape(-1, 9) @ E9).reshape(shape)

        # section loads and strains (element constants), (N, B, .)
        FM = y[:, self._fm_idx].transpose(1, 0, 2)              # (N, B, 6)
        strain = FM @ self._RT                                  # (N, B, 6)
        gam, kap = strain[..., :3], strain[..., 3:]
        e1g = gam + self._t                                     # t_e + gamma (e1 + gamma)
        FM2 = FM.reshape(N, B, 2, 3)
        kFM = cross(kap[:, :, None, :, None], FM2[..., None, :], (N, B, 2, 3))
        eF = cross(e1g[..., :, None], FM[..., None, 0:3], (N, B, 3))

        # momenta [P, H], [Pdot, Hdot]
        X = a.reshape(N, G, B, 2, 12)[..., 6:12].reshape(N, -1, 6)  # [[V, Om], [Vd, Omd]]
        PH = (X @ self._muT).reshape(N, G, B, 2, 6)
        P = PH[..., 0, 0:3]
        # Om x [P, H] and V x P
        OmPH = cross(Omg[..., None, :, None], PH[..., 0, :].reshape(N, G, B, 2, 1, 3),
                     (N, G, B, 6))
        VP = cross(Vg[..., :, None], P[..., None, :], (N, G, B, 3))

        # rotations at the Gauss points: C^T V, C^T (e1 + gam), C w [, C g] [, C wind]
        grav = g is not None
        airy = wind is not None
        several = airy and np.ndim(wind) == 3
        m_wind = (np.shape(wind)[1] if several else 1) if airy else 0
        viscous = self._amuT is not None
        wxp = cross(w[:, :, None], (ug + self._X0)[..., None, :], (N, G, B, 3))
        nT = 3 + grav + viscous + m_wind
        T = np.empty((N, G, B, nT, 3), dtype=dt)
        T[..., 0, :] = Vg
        T[..., 1, :] = e1g[:, None]
        T[..., 2, :] = w
        if grav:
            T[..., 3, :] = g
        if viscous:            # the root frame's velocity at the section: C (v + w x p)
            T[..., 3 + grav, :] = wxp + v
        if airy:
            T[..., nT - m_wind:, :] = wind if several else wind[:, None, :]
        sgn = self._sgn4 if grav else self._sgn3
        if viscous or airy:
            sgn = np.concatenate([sgn, -np.ones((viscous + m_wind, 1))])
        rT, th1 = turn_stacked(thg, T, sgn, cross)              # th1 (N, G, B, 1, 3)
        # Q [Om - C w, kap]
        T2 = np.empty((N, G, B, 2, 3), dtype=dt)
        np.subtract(Omg, rT[..., 2, :], out=T2[..., 0, :])
        T2[..., 1, :] = kap[:, None]
        q = q_stacked(th1, T2, cross)

        # integrands at the Gauss points: [equilibrium f, m | kinematics u, theta | strain
        # displacement u, theta]
        I = np.empty((N, G, B, 18), dtype=dt)
        t = np.empty((N, G, B, 6), dtype=dt)                   # [Pd + Om x P, Hd + Om x H]
        np.add(PH[..., 1, :], OmPH, out=t)
        t[..., 3:6] += VP
        if grav:
            gB = rT[..., 3, :]
            t[..., 0:3] -= self._mpl * gB
            t[..., 3:6] -= cross(self._mxi4, gB[..., None, :], gB.shape)
        if viscous:            # mass-proportional damping of the relative velocities
            rel = np.empty((N, G, B, 6), dtype=dt)
            np.subtract(Vg, rT[..., 3 + grav, :], out=rel[..., 0:3])
            rel[..., 3:6] = T2[..., 0, :]
            t += rel @ self._amuT
        if section_loads is not None:
            force, moment = section_loads({
                "V": Vg, "Omega": Omg, "Vdot": a[..., 18:21], "Omegadot": a[..., 21:24],
                "position": ug + self._X0, "theta": thg,
                "wind": (rT[..., nT - m_wind:, :] if several else rT[..., nT - 1, :])
                if airy else None})
            t[..., 0:3] -= force
            t[..., 3:6] -= moment
        np.negative(t, out=I[..., 0:6])
        I[..., 6:9] = (udg - rT[..., 0, :]) + v + wxp
        np.subtract(thdg, q[..., 0, :], out=I[..., 9:12])
        np.subtract(rT[..., 1, :], self._t4, out=I[..., 12:15])
        I[..., 15:18] = q[..., 1, :]
        S = (self._W3 @ I.reshape(N, G, -1)).reshape(N, 3, B, 18)

        # element constants: hat integrals 0.5 h c to both ends; -int phi' F
        c6 = np.empty((N, B, 6), dtype=dt)
        c6[..., 0:3] = kFM[:, :, 0]
        np.add(kFM[:, :, 1], eF, out=c6[..., 3:6])
        c6 *= self._halfh
        if self._muhatT is not None:       # the viscous section loads mu_hat dF/dt
            FMd = yd[:, self._fm_idx].transpose(1, 0, 2) @ self._muhatT
            FM = FM + FMd
            # and the viscous force's moment, t x F_d (gamma x F_d: second order): without
            # it a shear-flexible section's viscous shear force did work on the slope rate
            c6[..., 3:6] += self._halfh * np.cross(self._t, FMd[..., 0:3])
        S[:, 0, :, 0:6] += c6 + FM
        S[:, 1, :, 0:6] += c6 - FM
        if capture is not None:
            capture["integrand"], capture["element"], capture["tip"] = I, c6, None

        out = np.empty((B, n), dtype=dt)
        out[:, :12] = S[0, 0, :, :12]
        out[:, 0:6] -= y[:, 0:6]
        blk = out[:, ROOT_SIZE:].reshape(B, N, BLOCK_SIZE)
        blk[:, :, 6:18] = S[:, 1, :, :12].transpose(1, 0, 2)
        blk[:, :-1, 6:18] += S[1:, 0, :, :12].transpose(1, 0, 2)
        np.subtract(ag[:, G, :, 0:6], S[:, 2, :, 12:18], out=blk.transpose(1, 0, 2)[..., 0:6])
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

    # ------------------------------------------------------------------ helpers
    def pattern_blocks(self):
        """Block sizes of the unknowns (root block, then N element blocks)."""
        return [ROOT_SIZE] + [BLOCK_SIZE] * self.N

    @property
    def elements(self) -> int:
        """Elements of the mesh (N: one cell each)."""
        return self.N

    @property
    def order(self) -> int:
        """Polynomial degree of the fields (model.Beam.order): 1."""
        return 1

    def station_points(self) -> int:
        """Gauss points per pattern block (numerics.jacobian.beam_station_pattern)."""
        return len(self.eta)
