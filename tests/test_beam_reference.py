"""Frozen reference: the beam residual as it was before the fused rewrite (commit 458f73d),
kept verbatim (as free functions on a BeamElements instance) to test the fast
``BeamElements.residual`` against it at random complex states."""
from __future__ import annotations

import numpy as np
import pytest

from hawt_core.fem.beam import (F_, M_, OM_, ROOT_F, ROOT_M, ROOT_OM, ROOT_SIZE, ROOT_V, TH_,
                                U_, V_, BLOCK_SIZE, BeamElements)
from hawt_core.numerics.rotations import cross, q_apply, rot_apply, rot_T_apply
from hawt_core.fem.sections import mesh_beam
from hawt_core.model import Beam, SectionTable


class ReferenceBeam:
    """The old implementation, reading the element data of a BeamElements instance."""

    def __init__(self, beam: BeamElements):
        self.b = beam
        for k in ("N", "n", "eta", "w", "wa", "wb", "xg", "h", "m_vv", "m_vo", "m_ov", "m_oo",
                  "mass_per_length", "m_xi", "R"):
            setattr(self, k, getattr(beam, k))

    def split(self, y):
        return y[:, :ROOT_SIZE], y[:, ROOT_SIZE:].reshape(y.shape[0], self.N, BLOCK_SIZE)

    def nodal(self, y):
        root, blk = self.split(y)
        z = np.zeros_like(root[:, None, 0:3])
        u = np.concatenate([z, blk[:, :, U_]], 1)
        th = np.concatenate([z, blk[:, :, TH_]], 1)
        V = np.concatenate([root[:, None, ROOT_V], blk[:, :, V_]], 1)
        Om = np.concatenate([root[:, None, ROOT_OM], blk[:, :, OM_]], 1)
        return u, th, V, Om, blk[:, :, F_], blk[:, :, M_]

    def _at_gauss(self, a):
        return (a[:, :-1, None, :] * (1 - self.eta)[None, None, :, None]
                + a[:, 1:, None, :] * self.eta[None, None, :, None])

    def _to_nodes(self, integrand):
        ia = np.einsum("bngk,ng->bnk", integrand, self.wa)
        ib = np.einsum("bngk,ng->bnk", integrand, self.wb)
        z = np.zeros_like(ia[:, :1])
        return np.concatenate([ia, z], 1) + np.concatenate([z, ib], 1)

    def _const_to_nodes(self, c):
        half = 0.5 * self.h[None, :, None] * c
        z = np.zeros_like(half[:, :1])
        return np.concatenate([half, z], 1) + np.concatenate([z, half], 1)

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


SEC = dict(mass=67.5772, i1=5, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6, ei3=21.8e6)


def _random_case(N, B, rng, complex_=True, nonuniform=True):
    """A beam with non-uniform, fully coupled 6x6 section matrices and random complex
    states of O(1) (and O(1e-20) imaginary parts as in complex steps, plus O(1) ones)."""
    props = mesh_beam(Beam(8.42, SectionTable.uniform(**SEC), N))
    if nonuniform:
        from dataclasses import replace
        A = rng.standard_normal((N, 6, 6))
        mass = props.mass + 0.1 * (A + A.transpose(0, 2, 1))
        C = rng.standard_normal((N, 6, 6))
        comp = props.compliance + 1e-3 * C
        h = props.h * (1 + 0.3 * rng.random(N))
        nodes = np.concatenate([[props.nodes[0]], props.nodes[0] + np.cumsum(h)])
        props = replace(props, mass=mass, compliance=comp, h=h, nodes=nodes)
    beam = BeamElements(props)
    c = (lambda s: rng.standard_normal(s) + 1j * rng.standard_normal(s)) if complex_ \
        else rng.standard_normal
    y, yd = c((B, beam.n)), c((B, beam.n))
    v, w, g = c((B, 3)), c((B, 3)), c((B, 3))
    return beam, y, yd, v, w, g, c((B, 3)), c((B, 3))


@pytest.mark.parametrize("N,B", [(1, 1), (2, 3), (4, 2), (7, 5), (16, 2), (4, 40), (16, 9)])
def test_fast_residual_matches_reference(N, B):
    """Reference: the frozen pre-rewrite implementation above. Tolerance: 1e-12 relative to
    the largest residual entry (round-off of a different summation order), at random
    complex states, with and without gravity and tip loads; small and large batches (the
    two cross-product code paths)."""
    rng = np.random.default_rng(N * 100 + B)
    beam, y, yd, v, w, g, tf, tm = _random_case(N, B, rng)
    ref = ReferenceBeam(beam)
    for kw in ({}, {"g": g}, {"g": g, "tip_force": tf, "tip_moment": tm},
               {"tip_moment": tm}):
        a = beam.residual(yd, y, v, w, **kw)
        b = ref.residual(yd, y, v, w, **kw)
        assert a.shape == b.shape == (B, beam.n)
        assert a.dtype == b.dtype
        err = np.abs(a - b).max() / np.abs(b).max()
        assert err < 1e-12, (kw.keys(), err)


def test_fast_residual_real_and_mixed_dtypes():
    """Real inputs give a real output equal to the reference; complex root motion with a real
    state (the Jacobian w.r.t. the rigid unknowns) and complex-step seeds give the same
    imaginary parts (complex-step derivatives) as the reference."""
    rng = np.random.default_rng(7)
    beam, y, yd, v, w, g, _, _ = _random_case(4, 3, rng, complex_=False)
    ref = ReferenceBeam(beam)
    a, b = beam.residual(yd, y, v, w, g), ref.residual(yd, y, v, w, g)
    assert a.dtype == np.float64 and np.abs(a - b).max() <= 1e-12 * np.abs(b).max()
    vc = v + 1j * 1e-20 * rng.standard_normal(v.shape)
    a, b = beam.residual(yd, y, vc, w, g), ref.residual(yd, y, vc, w, g)
    assert a.dtype == np.complex128
    assert np.abs(a.imag - b.imag).max() <= 1e-12 * np.abs(b.imag).max()
    ys = y + 1e-20j * np.eye(beam.n)[:3]
    a, b = beam.residual(yd, ys, v, w, g), ref.residual(yd, ys, v, w, g)
    assert np.abs(a.imag - b.imag).max() <= 1e-12 * np.abs(b.imag).max()
