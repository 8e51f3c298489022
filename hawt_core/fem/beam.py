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
"""
from __future__ import annotations

import numpy as np

from .sections import ElementProperties

#: Offsets inside the per-element block of 18 unknowns.
F_, M_, U_, TH_, V_, OM_ = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12),
                            slice(12, 15), slice(15, 18))
ROOT_F, ROOT_M, ROOT_V, ROOT_OM = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
ROOT_SIZE, BLOCK_SIZE = 12, 18


def cross(a, b):
    """Cross product on the last axis (complex-safe, faster than np.cross for small arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], -1)


def dot(a, b):
    return (a * b).sum(-1)


def rot_T_apply(theta, a):
    """``C(theta)^T a`` for Rodrigues parameters theta (..., 3)."""
    s = 0.25 * dot(theta, theta)
    return (((1 - s)[..., None] * a + cross(theta, a)
             + 0.5 * theta * dot(theta, a)[..., None]) / (1 + s)[..., None])


def rot_apply(theta, a):
    """``C(theta) a`` (b components -> B components)."""
    s = 0.25 * dot(theta, theta)
    return (((1 - s)[..., None] * a - cross(theta, a)
             + 0.5 * theta * dot(theta, a)[..., None]) / (1 + s)[..., None])


def q_apply(theta, a):
    """``Q(theta) a = (I + theta~/2 + theta theta^T/4) a``."""
    return a + 0.5 * cross(theta, a) + 0.25 * theta * dot(theta, a)[..., None]


def rotation_matrix(theta):
    """C(theta) as matrices (..., 3, 3) (for post-processing)."""
    eye = np.eye(3)
    return np.stack([rot_apply(theta, eye[k]) for k in range(3)], -1)


class BeamElements:
    """The discretized beam operator for ``B`` identical beams sharing one mesh.

    ``props``: ElementProperties (mesh, 6x6 compliance and mass per element).
    ``gauss``: number of Gauss points per element (2 integrates the inertia and kinematic
    terms exactly; 3 is used for the rotation-dependent terms by default).
    """

    def __init__(self, props: ElementProperties, gauss: int = 3):
        self.props = props
        self.N = props.n_elements
        self.n = ROOT_SIZE + BLOCK_SIZE * self.N
        xg, wg = np.polynomial.legendre.leggauss(gauss)
        self.eta = 0.5 * (xg + 1.0)  # (G,)
        self.w = 0.5 * wg            # (G,), sum 1
        h = props.h
        # weights for the two hat functions of each element at the Gauss points: (N, G)
        self.wa = h[:, None] * (self.w * (1 - self.eta))[None, :]
        self.wb = h[:, None] * (self.w * self.eta)[None, :]
        self.xg = props.nodes[:-1, None] + h[:, None] * self.eta[None, :]  # (N, G)
        self.h = h
        mu = props.mass
        self.m_vv, self.m_vo = mu[:, :3, :3], mu[:, :3, 3:]
        self.m_ov, self.m_oo = mu[:, 3:, :3], mu[:, 3:, 3:]
        self.mass_per_length = mu[:, 0, 0]
        # mass-centre offset (for gravity moments): m xi~ = mu_ov
        # m * xi (mass-centre offset times mass), read off mu_ov = m xi~ (for gravity moments)
        self.m_xi = np.stack([mu[:, 5, 1], mu[:, 3, 2], mu[:, 4, 0]], -1)
        self.R = props.compliance
        self.differential = self._differential_mask()

    # ------------------------------------------------------------------ layout helpers
    def _differential_mask(self) -> np.ndarray:
        d = np.zeros(self.n, bool)
        d[ROOT_V] = d[ROOT_OM] = True
        blk = d[ROOT_SIZE:].reshape(self.N, BLOCK_SIZE)
        blk[:, U_] = blk[:, TH_] = blk[:, V_] = blk[:, OM_] = True
        return d

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

    def _at_gauss(self, a):
        """Linear interpolation of nodal (B, N+1, 3) to Gauss points (B, N, G, 3)."""
        return (a[:, :-1, None, :] * (1 - self.eta)[None, None, :, None]
                + a[:, 1:, None, :] * self.eta[None, None, :, None])

    def _to_nodes(self, integrand):
        """Hat-function weighted integrals of a Gauss-point field (B,N,G,3) -> (B, N+1, 3)."""
        ia = np.einsum("bngk,ng->bnk", integrand, self.wa)
        ib = np.einsum("bngk,ng->bnk", integrand, self.wb)
        z = np.zeros_like(ia[:, :1])
        return np.concatenate([ia, z], 1) + np.concatenate([z, ib], 1)

    def _const_to_nodes(self, c):
        """Hat-weighted integrals of an element-constant field (B,N,3) -> (B,N+1,3)."""
        half = 0.5 * self.h[None, :, None] * c
        z = np.zeros_like(half[:, :1])
        return np.concatenate([half, z], 1) + np.concatenate([z, half], 1)

    # ------------------------------------------------------------------ residual
    def residual(self, yd, y, v, w, g=None, tip_force=None, tip_moment=None):
        """Residual (B, n) of B beams.

        yd, y: (B, n) time derivative and value of the unknowns.
        v, w: (B, 3) inertial velocity of the root point and angular velocity of the root
            frame, in the root frame b [m/s, rad/s].
        g: (B, 3) gravity vector in the root frame [m/s^2] or None.
        tip_force, tip_moment: (B, 3) loads applied at the tip, in the tip section frame B.
        """
        u, th, V, Om, F, M = self.nodal(y)
        ud, thd, Vd, Omd, _, _ = self.nodal(yd)
        root, _ = self.split(y)
        strain = np.einsum("nij,bnj->bni", self.R, np.concatenate([F, M], -1))
        gam, kap = strain[..., :3], strain[..., 3:]

        thg, Vg, Omg = self._at_gauss(th), self._at_gauss(V), self._at_gauss(Om)
        Vdg, Omdg, ug = self._at_gauss(Vd), self._at_gauss(Omd), self._at_gauss(u)
        udg, thdg = self._at_gauss(ud), self._at_gauss(thd)

        mv = lambda m, a: np.einsum("nij,bngj->bngi", m, a)
        P = mv(self.m_vv, Vg) + mv(self.m_vo, Omg)
        H = mv(self.m_ov, Vg) + mv(self.m_oo, Omg)
        Pd = mv(self.m_vv, Vdg) + mv(self.m_vo, Omdg)
        Hd = mv(self.m_ov, Vdg) + mv(self.m_oo, Omdg)

        f_int = -(Pd + cross(Omg, P))
        m_int = -(Hd + cross(Omg, H) + cross(Vg, P))
        if g is not None:
            gB = rot_apply(thg, g[:, None, None, :])  # gravity in B at the Gauss points
            f_grav = self.mass_per_length[None, :, None, None] * gB
            f_int = f_int + f_grav
            m_int = m_int + cross(self.m_xi[None, :, None, :], gB)

        e1 = np.zeros(3)
        e1[0] = 1.0
        f_const = cross(kap, F)
        m_const = cross(kap, M) + cross(e1 + gam, F)
        eq_f = self._to_nodes(f_int) + self._const_to_nodes(f_const)
        eq_m = self._to_nodes(m_int) + self._const_to_nodes(m_const)
        # - int phi' F : +F_{i+1} - F_i ; boundary terms: -F0 at the root, +F_tip at the tip
        zF = np.zeros_like(F[:, :1])
        eq_f = eq_f + np.concatenate([F, zF], 1) - np.concatenate([zF, F], 1)
        eq_m = eq_m + np.concatenate([M, zF], 1) - np.concatenate([zF, M], 1)
        eq_f[:, 0] -= root[:, ROOT_F]
        eq_m[:, 0] -= root[:, ROOT_M]
        if tip_force is not None:
            eq_f[:, -1] += tip_force
        if tip_moment is not None:
            eq_m[:, -1] += tip_moment

        # kinematics, hat-weighted
        pos = ug.copy()
        pos[..., 0] += self.xg[None]
        k_u = udg - rot_T_apply(thg, Vg) + v[:, None, None, :] + cross(w[:, None, None, :], pos)
        cw = rot_apply(thg, np.broadcast_to(w[:, None, None, :], thg.shape))
        k_t = thdg - q_apply(thg, Omg - cw)
        kin_u = self._to_nodes(k_u)
        kin_t = self._to_nodes(k_t)

        # strain-displacement per element
        e1g = np.broadcast_to(e1 + gam[:, :, None, :], thg.shape)
        su = rot_T_apply(thg, e1g) - e1
        sd_u = (u[:, 1:] - u[:, :-1]) - np.einsum("bngk,ng->bnk", su, self.wa + self.wb)
        st = q_apply(thg, np.broadcast_to(kap[:, :, None, :], thg.shape))
        sd_t = (th[:, 1:] - th[:, :-1]) - np.einsum("bngk,ng->bnk", st, self.wa + self.wb)

        B = y.shape[0]
        out = np.empty((B, self.n), dtype=np.result_type(y, yd, v, w))
        out[:, 0:3] = eq_f[:, 0]
        out[:, 3:6] = eq_m[:, 0]
        out[:, 6:9] = kin_u[:, 0]
        out[:, 9:12] = kin_t[:, 0]
        blk = out[:, ROOT_SIZE:].reshape(B, self.N, BLOCK_SIZE)
        blk[:, :, 0:3] = sd_u
        blk[:, :, 3:6] = sd_t
        blk[:, :, 6:9] = eq_f[:, 1:]
        blk[:, :, 9:12] = eq_m[:, 1:]
        blk[:, :, 12:15] = kin_u[:, 1:]
        blk[:, :, 15:18] = kin_t[:, 1:]
        return out

    # ------------------------------------------------------------------ helpers
    def pattern_blocks(self):
        """Block sizes of the unknowns (root block, then N element blocks)."""
        return [ROOT_SIZE] + [BLOCK_SIZE] * self.N

    def rigid_body_state(self, v, w):
        """Unknowns (n,) of one undeformed beam in rigid motion (v, w constant, real), with the
        section forces left at zero: a starting guess for steady-state Newton iterations."""
        y = np.zeros(self.n)
        x = self.props.nodes
        Vn = v[None, :] + np.cross(w[None, :], np.stack([x, 0 * x, 0 * x], -1))
        y[ROOT_V] = Vn[0]
        y[ROOT_OM] = w
        blk = y[ROOT_SIZE:].reshape(self.N, BLOCK_SIZE)
        blk[:, V_] = Vn[1:]
        blk[:, OM_] = w
        return y
