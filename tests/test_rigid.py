"""Tests of the rigid-body subsystem (hawt_core/rigid/kane.py).

References used (each test states its own):
- the paper's Eqs. 9-11 as restated in /work/shared/docs/theory.md ("Rigid bodies");
- an independent kinematic model written here from the documented frame conventions with
  explicit unit-vector formulas (no code shared with kane.py); velocities and angular
  velocities are obtained by differentiating positions and bases numerically
  (complex step, exact to round-off; 4th-order central differences where nested);
- Newton-Euler moment balances (about the yaw axis for the whole nacelle + hub system, about
  the teeter axis for the hub);
- Lagrange's equations built from an independently computed kinetic energy.
"""
from dataclasses import replace

import numpy as np
import pytest

from hawt_core.model import (Beam, Gravity, Hub, Nacelle, Rotor, SectionTable, Turbine)
from hawt_core.rigid import RigidSystem

H_CS = 1e-20          # complex step


def _blade():
    return Beam(8.42, SectionTable.uniform(mass=67.5772, i1=5.0, i2=1e-4, i3=4.9999,
                                           gj=21.8e3, ei2=4.36e6, ei3=21.8e6), 4)


def paper_turbine(**hub_changes):
    """Table 1 of the paper (two blades, rigid tower, no gravity)."""
    return Turbine("paper", Rotor(), replace(Hub(), **hub_changes), Nacelle(), _blade())


def general_turbine(blades=3, teeter=True, yaw_free=True, gravity=True):
    """Everything switched on: undersling, precone, tilt, springs, dampers, hub mass, gravity."""
    return Turbine(
        "general",
        Rotor(speed=4.3, blades=blades, precone=0.07),
        Hub(radius=1.3, undersling=0.35, teeter=teeter, inertia_lateral=80.0,
            inertia_longitudinal=30.0, teeter_stiffness=4.0e4, teeter_damping=2.0e3,
            mass=400.0),
        Nacelle(yaw_inertia=2.0e4, yaw_stiffness=3.0e5, yaw_damping=1.5e4, yaw_to_teeter=3.1,
                shaft_tilt=0.09, yaw_free=yaw_free, mass=900.0),
        _blade(), gravity=Gravity(enabled=gravity, g=9.81))


# ---------------------------------------------------------------- independent reference model
class Ref:
    """Frames, points and energies written from the documented conventions, independently."""

    def __init__(self, tb):
        self.Om = tb.rotor.speed
        self.nb = tb.rotor.blades
        self.beta = tb.rotor.precone
        self.tau = tb.nacelle.shaft_tilt
        self.d = tb.nacelle.yaw_to_teeter
        self.e = tb.hub.radius
        self.l = tb.hub.undersling

    def bases(self, qy, qh, t):
        n1, n2, n3 = np.eye(3)
        y1 = n1 + 0 * qy
        y2 = np.cos(qy) * n2 + np.sin(qy) * n3
        y3 = -np.sin(qy) * n2 + np.cos(qy) * n3
        c, s = np.cos(self.tau), np.sin(self.tau)
        yt1, yt2, yt3 = c * y1 - s * y3, y2, c * y3 + s * y1
        psi = self.Om * t
        s1 = np.cos(psi) * yt1 + np.sin(psi) * yt2
        s2 = -np.sin(psi) * yt1 + np.cos(psi) * yt2
        s3 = yt3 + 0 * psi
        h1 = np.cos(qh) * s1 + np.sin(qh) * s3
        h2 = s2 + 0 * qh
        h3 = -np.sin(qh) * s1 + np.cos(qh) * s3
        blades, roots = [], []
        for k in range(self.nb):
            ph = 2 * np.pi * k / self.nb
            a1 = np.cos(ph) * h1 + np.sin(ph) * h2
            a2 = -np.sin(ph) * h1 + np.cos(ph) * h2
            b1 = np.cos(self.beta) * a1 + np.sin(self.beta) * h3
            b3 = -np.sin(self.beta) * a1 + np.cos(self.beta) * h3
            blades.append(np.column_stack([b1, a2, b3]))
            roots.append(self.d * s3 + self.e * a1 - self.l * h3)
        return dict(y1=y1, s2=s2, s3=s3, H=np.column_stack([h1, h2, h3]),
                    B=np.array(blades), P=np.array(roots), SH=self.d * s3)


def cs_dt(f, t):
    """d f / d t by complex step (f real-analytic)."""
    return np.imag(f(t + 1j * H_CS)) / H_CS


def fd4(f, t, h=1e-3):
    return (f(t - 2 * h) - 8 * f(t - h) + 8 * f(t + h) - f(t + 2 * h)) / (12 * h)


def axial(W):
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


class Trajectory:
    """Cubic polynomial qy(t), qh(t) about t0; speeds from the paper's Eq. 7 (with tilt)."""

    def __init__(self, rng, t0, ref):
        self.t0 = t0
        self.ref = ref
        self.cy = rng.uniform(-1, 1, 4) * np.array([3.0, 0.8, 0.5, 0.3])
        self.ch = rng.uniform(-1, 1, 4) * np.array([0.4, 0.6, 0.5, 0.3])

    def q(self, t):
        s = t - self.t0
        return (sum(c * s ** i for i, c in enumerate(self.cy)),
                sum(c * s ** i for i, c in enumerate(self.ch)))

    def qdot(self, t):
        return tuple(cs_dt(lambda tt, j=j: self.q(tt)[j], t) for j in range(2))

    def u(self, t):
        """U1 = qy', U2 = omega^H . h2, computed from the bases (independent of Eq. 7)."""
        def Hmat(tt):
            qy, qh = self.q(tt)
            return self.ref.bases(qy, qh, tt)["H"]
        Hd = cs_dt(Hmat, t)
        w = axial(Hd @ Hmat(t).T)
        return self.qdot(t)[0], w @ Hmat(t)[:, 1]


def active_trajectory(rng, t0, ref, r):
    """A Trajectory that keeps the coordinates ``r`` (RigidSystem) does not have at 0."""
    tr = Trajectory(rng, t0, ref)
    if not r.yaw_free:
        tr.cy[:] = 0.0
    if not r.teeter:
        tr.ch[:] = 0.0
    return tr


def omega_of(Bfun, t):
    """Angular velocity (in N) of the basis Bfun(t) (columns = unit vectors)."""
    return axial(cs_dt(Bfun, t) @ Bfun(t).T)


def udot_traj(traj, t):
    return np.array([fd4(lambda tt: np.array(traj.u(tt))[j], t) for j in range(2)])


# ---------------------------------------------------------------- Eqs. 9-11 (theory.md)
def eq10_11(tb, qh, U1, U2, t):
    Om, d, e, l = tb.rotor.speed, tb.nacelle.yaw_to_teeter, tb.hub.radius, tb.hub.undersling
    c, s = np.cos(Om * t), np.sin(Om * t)
    w = np.array([Om * np.sin(qh) + c * np.cos(qh) * U1, U2,
                  Om * np.cos(qh) - c * np.sin(qh) * U1])
    v = np.array([-l * U2 - d * s * np.cos(qh) * U1,
                  l * (Om * np.sin(qh) + c * np.cos(qh) * U1)
                  + e * (Om * np.cos(qh) - c * np.sin(qh) * U1) - d * c * U1,
                  d * s * np.sin(qh) * U1 - e * U2])
    return v, w


def eq9(tb, q, u, udot, t, F, M):
    """The paper's Eq. 9 (theory.md), blade U = 0, blade D = 1; returns (value, scale)."""
    Om, e, l = tb.rotor.speed, tb.hub.radius, tb.hub.undersling
    kh, ch = tb.hub.teeter_stiffness, tb.hub.teeter_damping
    A, C = tb.hub.inertia_lateral, tb.hub.inertia_longitudinal
    qh, U1, U2, U2d = q[1], u[0], u[1], udot[1]
    c = np.cos(Om * t)
    Fu, Mu, Fd, Md = F[0], M[0], F[1], M[1]
    terms = [Mu[1], e * Fd[2], kh * qh, l * Fd[0], ch * U2, -Md[1], -e * Fu[2], -l * Fu[0],
             -(A - C) * (Om * np.sin(qh) + c * np.cos(qh) * U1)
             * (Om * np.cos(qh) - c * np.sin(qh) * U1),
             -A * U2d]
    return sum(terms), max(abs(x) for x in terms)


def eq8(tb, q, u, udot, t, F, M):
    """The paper's Eq. 8 as printed in the PDF text, with the single lost sign restored
    (the '+' in '- cos(psi) F^d_2 [e sin qh + lhd1 cos qh]'); teeter damper omitted (ch = 0).
    Returns (value, largest term)."""
    Om, d, e, l = (tb.rotor.speed, tb.nacelle.yaw_to_teeter, tb.hub.radius,
                   tb.hub.undersling)
    A, C, Iy = tb.hub.inertia_lateral, tb.hub.inertia_longitudinal, tb.nacelle.yaw_inertia
    kh, ky, cy = tb.hub.teeter_stiffness, tb.nacelle.yaw_stiffness, tb.nacelle.yaw_damping
    assert tb.hub.teeter_damping == 0.0
    qy, qh, U1, U2, U1d = q[0], q[1], u[0], u[1], udot[0]
    c, s, ch, sh = np.cos(Om * t), np.sin(Om * t), np.cos(qh), np.sin(qh)
    Fu, Mu, Fd, Md = F[0], M[0], F[1], M[1]
    W = U2 + s * U1
    terms = [d * c * Fd[1], d * s * Fd[0] * ch, d * s * Fd[2] * sh, d * s * Fu[2] * sh,
             c * (Mu[0] * ch - Mu[2] * sh), s * kh * qh,
             c * ((A - C) * ch * U2 * (Om * ch - c * sh * U1)
                  + C * sh * (Om * s * sh * U1 + Om * sh * W + c * ch * U1 * W)
                  + A * ch * (Om * s * ch * U1 + Om * ch * W - c * sh * U1 * W)),
             (A - Iy - c ** 2 * (A - (A - C) * sh ** 2)) * U1d,
             -ky * qy, -d * c * Fu[1], -d * s * Fu[0] * ch, -c * (Md[0] * ch + Md[2] * sh),
             -c * Fd[1] * (e * sh + l * ch), -c * Fu[1] * (e * sh - l * ch), -cy * U1]
    return sum(terms), max(abs(x) for x in terms)


def random_state(rng, n=2):
    q = np.array([rng.uniform(-np.pi, np.pi), rng.uniform(-0.6, 0.6)])[:n]
    u = rng.uniform(-1.5, 1.5, n)
    udot = rng.uniform(-3, 3, n)
    t = rng.uniform(0, 3)
    return q, u, udot, t


# ================================================================= tests
def test_names_and_sizes():
    """Reference: the interface in docs/ARCHITECTURE.md (exact)."""
    r = RigidSystem(paper_turbine())
    assert r.coordinates == ("yaw", "teeter") and r.speeds == ("yaw_rate", "teeter_speed")
    assert (r.n_q, r.n_u) == (2, 2)
    r = RigidSystem(paper_turbine(teeter=False))
    assert r.coordinates == ("yaw",) and r.speeds == ("yaw_rate",)
    tb = paper_turbine()
    tb = replace(tb, nacelle=replace(tb.nacelle, yaw_free=False))
    r = RigidSystem(tb)
    assert r.coordinates == ("teeter",) and r.speeds == ("teeter_speed",)
    tb = replace(tb, hub=replace(tb.hub, teeter=False))
    r = RigidSystem(tb)
    assert r.n_q == r.n_u == 0
    v, w = r.root_motion(np.zeros(0), np.zeros(0), 0.3)
    assert v.shape == w.shape == (2, 3)
    assert r.dynamics(np.zeros(0), np.zeros(0), np.zeros(0), 0.3,
                      np.ones((2, 3)), np.ones((2, 3))).shape == (0,)
    # paper reading of Table 1: the nacelle body alone carries Iy - Ihlat
    assert RigidSystem(paper_turbine()).nacelle_yaw_inertia == 16599.0 - 50.0


@pytest.mark.parametrize("lhd1", [0.0, 0.4])
def test_blade_U_root_motion_equals_eqs_10_11(lhd1):
    """Reference: Eqs. 10, 11 (theory.md) for blade U = blade 0; tolerance 1e-12 relative."""
    tb = paper_turbine(undersling=lhd1)
    r = RigidSystem(tb)
    rng = np.random.default_rng(1)
    for _ in range(20):
        q, u, _, t = random_state(rng)
        v, w = r.root_motion(q, u, t)
        v_ref, w_ref = eq10_11(tb, q[1], u[0], u[1], t)
        scale = max(np.abs(v_ref).max(), np.abs(w_ref).max())
        np.testing.assert_allclose(v[0], v_ref, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(w[0], w_ref, rtol=0, atol=1e-12 * scale)


def _check_root_motion_against_reference(tb, seed, n=8):
    """Every blade: v = d/dt(root point), w from dB/dt B^T, along a trajectory through the
    state; both from the independent Ref model; expressed in the blade's own basis."""
    r, ref = RigidSystem(tb), Ref(tb)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        t0 = rng.uniform(0, 3)
        tr = active_trajectory(rng, t0, ref, r)
        qy, qh = tr.q(t0)
        U1, U2 = tr.u(t0)
        q = np.array([qy, qh])[[i for i, f in enumerate((r.yaw_free, r.teeter)) if f]]
        u = np.array([U1, U2])[[i for i, f in enumerate((r.yaw_free, r.teeter)) if f]]
        v, w = r.root_motion(q, u, t0)
        for k in range(tb.rotor.blades):
            def P(tt, k=k):
                a, b = tr.q(tt)
                return ref.bases(a, b, tt)["P"][k]

            def Bk(tt, k=k):
                a, b = tr.q(tt)
                return ref.bases(a, b, tt)["B"][k]
            B = Bk(t0)
            v_ref = B.T @ cs_dt(P, t0)
            w_ref = B.T @ omega_of(Bk, t0)
            scale = max(np.abs(v_ref).max(), 1.0)
            np.testing.assert_allclose(v[k], v_ref, rtol=0, atol=1e-12 * scale)
            np.testing.assert_allclose(w[k], w_ref, rtol=0, atol=1e-12 * scale)


def test_blade_D_root_motion_independent():
    """Reference: blade D's root point and basis (d1 = -h1, d2 = -h2, d3 = h3) written out
    independently, differentiated along a trajectory (complex step); 1e-12 relative.  Also
    checks that D's motion is NOT blade U's formula (the sign trap in theory.md)."""
    tb = paper_turbine(undersling=0.3)
    _check_root_motion_against_reference(tb, seed=2)
    r = RigidSystem(tb)
    q, u, _, t = random_state(np.random.default_rng(3))
    v, w = r.root_motion(q, u, t)
    # D = U's formula with the hub turned by 180 deg: D's basis at (psi, qh) is U's basis at
    # (psi + pi, -qh), where omega . h2 is -U2; so D's motion is Eqs. 10-11 evaluated there
    v_u, w_u = eq10_11(tb, -q[1], u[0], -u[1], t + np.pi / tb.rotor.speed)
    np.testing.assert_allclose(v[1], v_u, atol=1e-12 * np.abs(v_u).max())
    np.testing.assert_allclose(w[1], w_u, atol=1e-12 * np.abs(w_u).max())
    assert np.abs(v[1] - v[0]).max() > 1e-3


@pytest.mark.parametrize("teeter,yaw_free", [(True, True), (False, True), (True, False)])
def test_general_root_motion_independent(teeter, yaw_free):
    """Reference: independent Ref model (3 blades, tilt, precone, undersling); 1e-12 rel."""
    _check_root_motion_against_reference(general_turbine(3, teeter, yaw_free), seed=4)


def test_two_blade_general_root_motion_independent():
    """Reference: independent Ref model (2 blades, tilt, precone, undersling); 1e-12 rel."""
    _check_root_motion_against_reference(general_turbine(2), seed=5)


def test_gravity_in_root():
    """Reference: -g n1 projected on the independent Ref bases; 1e-14 absolute (g = 9.81)."""
    tb = general_turbine(3)
    r, ref = RigidSystem(tb), Ref(tb)
    rng = np.random.default_rng(6)
    for _ in range(5):
        q, _, _, t = random_state(rng)
        g = r.gravity_in_root(q, t)
        B = ref.bases(q[0], q[1], t)["B"]
        for k in range(3):
            np.testing.assert_allclose(g[k], B[k].T @ np.array([-9.81, 0, 0]), atol=1e-13)
    # paper turbine at t = 0: blade 0 points up, so gravity is -g along b1
    tb = replace(paper_turbine(), gravity=Gravity(enabled=True, g=9.81))
    g = RigidSystem(tb).gravity_in_root(np.zeros(2), 0.0)
    np.testing.assert_allclose(g, [[-9.81, 0, 0], [9.81, 0, 0]], atol=1e-14)
    assert not np.any(RigidSystem(paper_turbine()).gravity_in_root(np.zeros(2), 0.3))


def test_kinematics():
    """Reference: Eq. 7 (qy' = U1, U2 = -qh' - sin(psi) U1); exact to round-off."""
    tb = paper_turbine()
    r = RigidSystem(tb)
    rng = np.random.default_rng(7)
    q, u, _, t = random_state(rng)
    qd = rng.uniform(-1, 1, 2)
    res = r.kinematics(q, qd, u, t)
    psi = tb.rotor.speed * t
    np.testing.assert_allclose(res, [qd[0] - u[0], qd[1] + u[1] + np.sin(psi) * u[0]],
                               atol=1e-15)
    np.testing.assert_allclose(r.kinematics(q, r.qdot(q, u, t), u, t), 0, atol=1e-15)


@pytest.mark.parametrize("lhd1,kh", [(0.0, 0.0), (0.37, 2.5e3)])
def test_teeter_equation_equals_eq9(lhd1, kh):
    """Reference: Eq. 9 (theory.md), random states and root loads, same sign;
    tolerance 1e-13 x the largest term of Eq. 9 (round-off).  Teeter damper 0 here."""
    tb = paper_turbine(undersling=lhd1, teeter_stiffness=kh)
    r = RigidSystem(tb)
    rng = np.random.default_rng(8)
    for _ in range(20):
        q, u, ud, t = random_state(rng)
        F = rng.normal(0, 2e4, (2, 3))
        M = rng.normal(0, 5e3, (2, 3))
        res = r.dynamics(q, u, ud, t, F, M)
        ref, scale = eq9(tb, q, u, ud, t, F, M)
        assert abs(res[1] - ref) <= 1e-13 * scale


def test_yaw_equation_equals_printed_eq8():
    """Reference: the paper's Eq. 8 (damaged in the PDF) as printed, with one lost sign
    restored (see eq8); random states and root loads, undersling and springs; the yaw row must
    equal it with the same sign to 1e-13 x its largest term.  (Found by a least-squares fit of
    the printed terms to the derived equation: all other printed signs come out as printed.)"""
    tb = paper_turbine(undersling=0.3, teeter_stiffness=3e3)
    tb = replace(tb, nacelle=replace(tb.nacelle, yaw_stiffness=1e5, yaw_damping=3e3))
    r = RigidSystem(tb)
    rng = np.random.default_rng(12)
    for _ in range(20):
        q, u, ud, t = random_state(rng)
        F = rng.normal(0, 2e4, (2, 3))
        M = rng.normal(0, 5e3, (2, 3))
        ref, scale = eq8(tb, q, u, ud, t, F, M)
        assert abs(r.dynamics(q, u, ud, t, F, M)[0] - ref) <= 1e-13 * scale


def test_teeter_damper_is_dissipative_not_eq9_sign():
    """Reference: Eq. 9 with its damper term '+ch U2' replaced by the relative-rate damper
    ch qh' = -ch (U2 + sin(psi) U1) (Eq. 9's sign would be anti-damping); 1e-13 relative.
    Also: with the yaw locked, the damper's power -ch qh'^2 is <= 0."""
    tb = paper_turbine(undersling=0.2, teeter_stiffness=1e3, teeter_damping=700.0)
    r = RigidSystem(tb)
    rng = np.random.default_rng(9)
    for _ in range(10):
        q, u, ud, t = random_state(rng)
        F = rng.normal(0, 2e4, (2, 3))
        M = rng.normal(0, 5e3, (2, 3))
        ref, scale = eq9(tb, q, u, ud, t, F, M)
        psi = tb.rotor.speed * t
        ref = ref - 700.0 * u[1] - 700.0 * (u[1] + np.sin(psi) * u[0])
        assert abs(r.dynamics(q, u, ud, t, F, M)[1] - ref) <= 1e-13 * scale
    # power of the damper alone: U2-equation force x U2 with yaw locked (qh' = -U2)
    tb2 = replace(tb, nacelle=replace(tb.nacelle, yaw_free=False),
                  hub=replace(tb.hub, teeter_stiffness=0.0, inertia_lateral=0.0,
                              inertia_longitudinal=0.0))
    r2 = RigidSystem(tb2)
    for U2 in (-0.7, 0.3):
        f = r2.dynamics(np.array([0.1]), np.array([U2]), np.zeros(1), 0.4,
                        np.zeros((2, 3)), np.zeros((2, 3)))[0]
        assert f * U2 < 0


def _newton_euler(tb, seed, n=6):
    """Compare Kane's residual with Newton-Euler balances computed from the Ref model:
    yaw: y1 . (sum of external moments about TY - dH_TY/dt) of nacelle + shaft + hub;
    teeter: h2 . (moments on the hub about SH - d(I w)/dt);
    Kane's yaw row must equal yaw_NE - (y1 . h2) teeter_NE, Kane's teeter row teeter_NE."""
    r, ref = RigidSystem(tb), Ref(tb)
    In = r.nacelle_yaw_inertia   # checked separately (paper: Iy - Ihlat)
    A, C = tb.hub.inertia_lateral, tb.hub.inertia_longitudinal
    mh = tb.hub.mass
    g = np.array([-tb.gravity.g, 0, 0]) if tb.gravity.enabled else np.zeros(3)
    ky, cy = tb.nacelle.yaw_stiffness, tb.nacelle.yaw_damping
    kh, ch = tb.hub.teeter_stiffness, tb.hub.teeter_damping
    nb = tb.rotor.blades
    act = [i for i, f in enumerate((r.yaw_free, r.teeter)) if f]
    rng = np.random.default_rng(seed)
    for _ in range(n):
        t0 = rng.uniform(0, 3)
        tr = active_trajectory(rng, t0, ref, r)

        def basesf(tt):
            a, b = tr.q(tt)
            return ref.bases(a, b, tt)

        def Hmom(tt, about_TY=True):
            """Angular momentum (N) of hub (about SH or TY) + nacelle (about TY)."""
            bs = basesf(tt)
            Hm = bs["H"]
            w = axial(cs_dt(lambda x: basesf(x)["H"], tt) @ Hm.T)
            I_H = Hm @ np.diag([A, A, C]) @ Hm.T
            out = I_H @ w
            if about_TY:
                vSH = cs_dt(lambda x: basesf(x)["SH"], tt)
                out = out + mh * np.cross(bs["SH"], vSH) + In * tr.qdot(tt)[0] * bs["y1"]
            return out

        bs = basesf(t0)
        qy, qh = tr.q(t0)
        qyd, qhd = tr.qdot(t0)
        U = np.array(tr.u(t0))
        Ud = udot_traj(tr, t0)
        F = rng.normal(0, 2e4, (nb, 3))
        M = rng.normal(0, 5e3, (nb, 3))
        FN = np.einsum("kij,kj->ki", bs["B"], F)
        MN = np.einsum("kij,kj->ki", bs["B"], M)
        y1, h2 = bs["y1"], bs["H"][:, 1]
        # yaw: external moments about TY (blade loads, yaw spring/damper, hub weight)
        Mext = (np.cross(bs["P"], FN) + MN).sum(0) - (ky * qy + cy * qyd) * y1 \
            + mh * np.cross(bs["SH"], g)
        dH = fd4(Hmom, t0)
        yaw_ne = y1 @ (Mext - dH)
        # teeter: moments on the hub about SH (blade loads, teeter spring/damper on qh, qh')
        rho = bs["P"] - bs["SH"]
        Mh = (np.cross(rho, FN) + MN).sum(0) + (kh * qh + ch * qhd) * h2
        teet_ne = h2 @ (Mh - fd4(lambda x: Hmom(x, False), t0))
        scale = max(np.abs(Mext).max(), np.abs(dH).max(), 1.0)
        res = r.dynamics(np.array([qy, qh])[act], U[act], Ud[act], t0, F, M)
        # with a rigid hub the teeter balance is a constraint (hinge) reaction, not an equation
        expect = np.array([yaw_ne - (y1 @ h2) * teet_ne * r.teeter, teet_ne])[act]
        np.testing.assert_allclose(res, expect, rtol=0, atol=1e-9 * scale)


def test_yaw_equation_newton_euler_paper():
    """Reference: Newton-Euler about the yaw axis + sin(psi) x teeter equation (theory.md),
    paper configuration with undersling and springs; 1e-9 x the largest moment (4th-order
    differences of the angular momentum, h = 1e-3 s)."""
    tb = paper_turbine(undersling=0.3, teeter_stiffness=3e3, teeter_damping=200.0)
    tb = replace(tb, nacelle=replace(tb.nacelle, yaw_stiffness=1e5, yaw_damping=3e3))
    _newton_euler(tb, seed=10)


@pytest.mark.parametrize("blades,teeter,yaw_free",
                         [(3, False, True), (3, True, True), (2, True, True),
                          (2, True, False), (4, False, True)])
def test_newton_euler_general(blades, teeter, yaw_free):
    """Reference: Newton-Euler balances (see _newton_euler) with tilt, precone, undersling,
    hub mass, gravity, springs and dampers; 1e-9 x the largest moment."""
    _newton_euler(general_turbine(blades, teeter, yaw_free), seed=11 + blades)


def _lagrange_check(tb, seed, n=4):
    """Lagrange's equations from an independently computed kinetic energy T(q, qdot, t),
    potential V (springs, hub weight), Rayleigh function (dampers) and the virtual work of
    the root loads; mapped to Kane's speeds by dqdot/dU:
        Kane_1 = L_y + (y1.s2) L_h,  Kane_2 = -L_h,  L_j = Q_j - [d/dt dT/dqd_j - dT/dq_j
        + dV/dq_j + dR/dqd_j]."""
    r, ref = RigidSystem(tb), Ref(tb)
    In = r.nacelle_yaw_inertia
    A, C = tb.hub.inertia_lateral, tb.hub.inertia_longitudinal
    mh = tb.hub.mass
    mc, cw = tb.hub.counterweight_mass, np.array([-tb.hub.counterweight_radius, 0.0, 0.0])
    g = tb.gravity.g if tb.gravity.enabled else 0.0
    ky, cy = tb.nacelle.yaw_stiffness, tb.nacelle.yaw_damping
    kh, ch = tb.hub.teeter_stiffness, tb.hub.teeter_damping
    nb = tb.rotor.blades

    def T(q, qd, t):
        # velocities by a complex-step directional derivative along (qd, 1)
        def pos(s):
            bs = ref.bases(q[0] + s * qd[0], q[1] + s * qd[1], t + s)
            return bs["H"], bs["SH"], bs["SH"] + bs["H"] @ cw
        Hm, SH, _ = pos(0.0)
        Hd = np.imag(pos(1j * H_CS)[0]) / H_CS
        vSH = np.imag(pos(1j * H_CS)[1]) / H_CS
        vcw = np.imag(pos(1j * H_CS)[2]) / H_CS
        w = axial(Hd @ Hm.T)
        return (0.5 * In * qd[0] ** 2 + 0.5 * w @ (Hm @ np.diag([A, A, C]) @ Hm.T) @ w
                + 0.5 * mh * vSH @ vSH + 0.5 * mc * vcw @ vcw)

    def grad(f, x, h):
        """4th-order central differences (fd4) along each coordinate."""
        return np.array([fd4(lambda s, e=e: f(x + s * e), 0.0, h) for e in np.eye(2)])

    rng = np.random.default_rng(seed)
    for _ in range(n):
        t0 = rng.uniform(0, 3)
        tr = Trajectory(rng, t0, ref)
        q = np.array(tr.q(t0))
        qd = np.array(tr.qdot(t0))
        dTdqd = lambda tt: grad(lambda x: T(np.array(tr.q(tt)), x, tt),
                                np.array(tr.qdot(tt)), 1e-3)
        ddt = fd4(dTdqd, t0)
        dTdq = grad(lambda x: T(x, qd, t0), q, 1e-4)
        def V(x):
            bs_ = ref.bases(x[0], x[1], t0)
            return (0.5 * ky * x[0] ** 2 + 0.5 * kh * x[1] ** 2 + mh * g * bs_["SH"][0]
                    + mc * g * (bs_["SH"] + bs_["H"] @ cw)[0])
        dV = grad(V, q, 1e-4)
        dR = np.array([cy * qd[0], ch * qd[1]])
        # virtual work of the root loads
        F = rng.normal(0, 2e4, (nb, 3))
        M = rng.normal(0, 5e3, (nb, 3))
        bs = ref.bases(q[0], q[1], t0)
        FN = np.einsum("kij,kj->ki", bs["B"], F)
        MN = np.einsum("kij,kj->ki", bs["B"], M)
        Q = np.zeros(2)
        for j in range(2):
            dq = np.zeros(2, complex)
            dq[j] = 1j * H_CS
            bj = ref.bases(q[0] + dq[0], q[1] + dq[1], t0)
            dP = np.imag(bj["P"]) / H_CS
            dth = axial((np.imag(bj["H"]) / H_CS) @ bs["H"].T)
            Q[j] = np.sum(FN * dP) + MN.sum(0) @ dth
        L = Q - (ddt - dTdq + dV + dR)
        y1s2 = bs["y1"] @ bs["s2"]
        expect = np.array([L[0] + y1s2 * L[1], -L[1]])
        U = np.array(tr.u(t0))
        Ud = udot_traj(tr, t0)
        res = r.dynamics(q, U, Ud, t0, F, M)
        scale = max(np.abs(ddt).max(), np.abs(Q).max(), 1.0)
        np.testing.assert_allclose(res, expect, rtol=0, atol=1e-7 * scale)
        # kinetic energy of the rigid bodies
        assert abs(r.hub_kinetic_energy(q, U, t0) - T(q, qd, t0)) <= 1e-12 * T(q, qd, t0)


def test_lagrange_paper():
    """Reference: Lagrange's equations with an independent kinetic energy (see
    _lagrange_check), paper turbine; 1e-7 x the largest term (nested finite differences)."""
    _lagrange_check(paper_turbine(undersling=0.25, teeter_stiffness=2e3,
                                  teeter_damping=100.0), seed=20)


@pytest.mark.parametrize("blades", [2, 3])
def test_lagrange_general(blades):
    """Reference: as test_lagrange_paper, everything switched on; 1e-7 x largest term."""
    _lagrange_check(general_turbine(blades), seed=21 + blades)


def test_lagrange_one_blade_with_counterweight():
    """Reference: as test_lagrange_paper, one blade on a teetering hub with a 400 kg
    counterweight 1.6 m opposite it (its kinetic energy and weight in T and V), everything
    else switched on; 1e-7 x largest term."""
    tb = general_turbine(1)
    _lagrange_check(replace(tb, hub=replace(tb.hub, counterweight_mass=400.0,
                                            counterweight_radius=1.6)), seed=29)


def test_energy_power_balance_yaw_locked():
    """Reference: with the yaw locked, no tilt and no loads, the hub's Jacobi integral
    J = T2 - T0 + V (T2, T0: parts of the kinetic energy quadratic in / free of qh') obeys
    dJ/dt = -ch qh'^2 along solutions (Omega0 prescribed). Integrated with RK4 over one rev;
    tolerance 1e-8 relative."""
    tb = paper_turbine(teeter_stiffness=5e2, teeter_damping=3.0, undersling=0.2)
    tb = replace(tb, nacelle=replace(tb.nacelle, yaw_free=False))
    r = RigidSystem(tb)
    z3 = np.zeros((2, 3))
    A = tb.hub.inertia_lateral

    def rhs(t, y):
        q, u = y[:1], y[1:2]
        # dynamics is linear in udot with coefficient -Ihlat
        f0 = r.dynamics(q, u, np.zeros(1), t, z3, z3)[0]
        qhd = r.qdot(q, u, t)[0]
        return np.array([qhd, f0 / A, 3.0 * qhd ** 2])    # last: energy dissipated, ch qh'^2

    def J(t, y):
        q, u = y[:1], y[1:2]
        T2 = 0.5 * A * u[0] ** 2
        T0 = r.hub_kinetic_energy(q, np.zeros(1), t)
        return T2 - T0 + 0.5 * 5e2 * q[0] ** 2

    y = np.array([0.3, 0.5, 0.0])   # qh, U2, dissipated energy
    t, nstep = 0.0, 2000
    h = 2 * np.pi / tb.rotor.speed / nstep
    J0 = J(t, y)
    for _ in range(nstep):
        k1 = rhs(t, y)
        k2 = rhs(t + h / 2, y + h / 2 * k1)
        k3 = rhs(t + h / 2, y + h / 2 * k2)
        k4 = rhs(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
    assert y[2] > 0
    assert abs(J(t, y) + y[2] - J0) <= 1e-8 * abs(J0)


def test_blade_relabelling_symmetry():
    """Reference: Fast-Floquet symmetry (theory.md). Two blades: at psi + pi with
    (qy, -qh), (U1, -U2) blade 0 takes blade 1's place; yaw row unchanged, teeter row negated.
    Three blades, rigid hub: at psi + 2 pi/3 blade k takes blade k+1's place. 1e-12 relative."""
    rng = np.random.default_rng(30)
    for tb, flip in ((general_turbine(2), np.array([1.0, -1.0])),
                     (general_turbine(3, teeter=False), np.array([1.0]))):
        r = RigidSystem(tb)
        np.testing.assert_array_equal(r.relabelling_signs(), np.concatenate([flip, flip]))
        nb = tb.rotor.blades
        dt = 2 * np.pi / nb / tb.rotor.speed
        for _ in range(5):
            q, u, ud, t = random_state(rng, r.n_q)
            F = rng.normal(0, 1e4, (nb, 3))
            M = rng.normal(0, 1e4, (nb, 3))
            v, w = r.root_motion(q, u, t)
            v2, w2 = r.root_motion(flip * q, flip * u, t + dt)
            perm = (np.arange(nb) + 1) % nb
            np.testing.assert_allclose(v2, v[perm], atol=1e-12 * np.abs(v).max())
            np.testing.assert_allclose(w2, w[perm], atol=1e-12 * np.abs(w).max())
            np.testing.assert_allclose(r.gravity_in_root(flip * q, t + dt),
                                       r.gravity_in_root(q, t)[perm], atol=1e-12)
            res = r.dynamics(q, u, ud, t, F, M)
            res2 = r.dynamics(flip * q, flip * u, flip * ud, t + dt, F[perm], M[perm])
            np.testing.assert_allclose(res2, flip * res, atol=1e-11 * np.abs(res).max())
    with pytest.raises(ValueError):
        RigidSystem(general_turbine(3, teeter=True)).relabelling_signs()


@pytest.mark.parametrize("blades,teeter", [(2, True), (3, True), (3, False)])
def test_complex_step_safety(blades, teeter):
    """Reference: central finite differences (h = 1e-6) of every output w.r.t. every input;
    complex-step derivatives (h = 1e-20) must agree to 1e-6 relative, and real inputs with
    zero imaginary part must give the real result exactly."""
    tb = general_turbine(blades, teeter)
    r = RigidSystem(tb)
    rng = np.random.default_rng(40)
    q, u, ud, t = random_state(rng, r.n_q)
    qd = rng.uniform(-1, 1, r.n_q)
    F = rng.normal(0, 1e4, (blades, 3))
    M = rng.normal(0, 1e4, (blades, 3))
    args = [q, qd, u, ud, F, M]

    def outputs(q, qd, u, ud, F, M):
        v, w = r.root_motion(q, u, t)
        return np.concatenate([v.ravel(), w.ravel(), r.gravity_in_root(q, t).ravel(),
                               r.kinematics(q, qd, u, t), r.dynamics(q, u, ud, t, F, M),
                               np.atleast_1d(r.hub_kinetic_energy(q, u, t))])
    base = outputs(*args)
    assert np.isrealobj(base)
    cargs = [a.astype(complex) for a in args]
    np.testing.assert_allclose(outputs(*cargs), base, rtol=1e-14, atol=1e-14)
    for i, a in enumerate(args):
        for j in range(a.size):
            def shifted(delta):
                b = [x.astype(type(delta)) if isinstance(delta, complex) else x.copy()
                     for x in args]
                b[i].flat[j] += delta
                return outputs(*b)
            d_cs = np.imag(shifted(1j * H_CS)) / H_CS
            hh = 1e-6 * max(1.0, abs(a.flat[j]))
            d_fd = (shifted(hh) - shifted(-hh)) / (2 * hh)
            scale = max(np.abs(d_fd).max(), 1e-3)
            np.testing.assert_allclose(d_cs, d_fd, rtol=0, atol=1e-6 * scale)


def test_rigid_rotor_teeter_frequency_end_to_end():
    """Reference: theory.md, "Checks with known answers": with rigid blades, no teeter
    spring and the yaw locked the rotor teeters at sqrt((C - A)/B) per-rev (A, B, C: rotor
    inertias about h1, h2, h3), 0.99901/rev for Table 1.  The rigid blades' root loads ON THE
    HUB are computed here independently (minus the blades' inertia forces/moments, positions
    differentiated numerically along trajectories); this checks the sign of the loads.
    Tolerance 1e-7 relative (finite differences)."""
    tb = paper_turbine()
    tb = replace(tb, nacelle=replace(tb.nacelle, yaw_free=False))
    r, ref = RigidSystem(tb), Ref(tb)
    m, I1, I2, I3, ell = 67.5772, 5.0, 1e-4, 4.9999, 8.42
    e, Om = tb.hub.radius, tb.rotor.speed
    xg, wg = np.polynomial.legendre.leggauss(4)
    xg, wg = 0.5 * ell * (xg + 1), 0.5 * ell * wg
    t0 = 0.31

    def residual(c):
        tr = Trajectory(np.random.default_rng(0), t0, ref)
        tr.cy[:] = 0.0
        tr.ch[:] = c
        F, M = np.zeros((2, 3)), np.zeros((2, 3))
        for k in range(2):
            def Bk(tt, k=k):
                return ref.bases(*tr.q(tt), tt)["B"][k]

            def pt(tt, x, k=k):
                bs = ref.bases(*tr.q(tt), tt)
                return bs["P"][k] + x * bs["B"][k][:, 0]
            B = Bk(t0)
            w = omega_of(Bk, t0)
            al = fd4(lambda tt: omega_of(Bk, tt), t0)
            J = B @ np.diag([I1, I2, I3]) @ B.T
            FN, MN = np.zeros(3), np.zeros(3)
            for x, wt in zip(xg, wg):
                a = fd4(lambda tt: cs_dt(lambda s: pt(s, x), tt), t0)
                FN -= wt * m * a
                MN -= wt * (x * np.cross(B[:, 0], m * a) + J @ al + np.cross(w, J @ w))
            F[k], M[k] = B.T @ FN, B.T @ MN
        qh = tr.q(t0)[1]
        U2 = tr.u(t0)[1]
        U2d = udot_traj(tr, t0)[1]
        return r.dynamics(np.array([qh]), np.array([U2]), np.array([U2d]), t0, F, M)[0]

    eps = 1e-4
    c_q = (residual([eps, 0, 0, 0]) - residual([-eps, 0, 0, 0])) / (2 * eps)     # d/d qh
    c_a = (residual([0, 0, eps, 0]) - residual([0, 0, -eps, 0])) / (2 * eps)     # qh'' = 2 eps
    # R = a U2' + c qh with U2' = -qh''  ->  qh'' = (c/a) qh
    a = -c_a / 2.0
    freq = np.sqrt(-c_q / a) / Om
    S2 = m * ((e + ell) ** 3 - e ** 3) / 3
    A = tb.hub.inertia_lateral + 2 * ell * I1
    B = tb.hub.inertia_lateral + 2 * (S2 + ell * I2)
    C = tb.hub.inertia_longitudinal + 2 * (S2 + ell * I3)
    assert abs(freq - np.sqrt((C - A) / B)) <= 1e-7
    assert abs(freq - 0.99901) < 5e-6


# ---------------------------------------------------------------- batches of instants
# With a rigid tower every public method of RigidSystem accepts a batch (leading dimensions on
# q, u, their rates, t and the root loads). Reference: the same method evaluated one instant
# at a time; the batched results must equal those to round-off (1e-12 relative).
BATCH_RTOL = 1e-12
BATCH_K = 5
BATCH_CONFIGS = {
    "paper": lambda: paper_turbine(),
    "general_gravity": lambda: general_turbine(blades=2, gravity=True),
    "general_no_gravity": lambda: general_turbine(blades=2, gravity=False),
    "three_blades_rigid_hub": lambda: general_turbine(blades=3, teeter=False, gravity=True),
    "yaw_locked": lambda: general_turbine(blades=2, yaw_free=False, gravity=True),
    "yaw_locked_rigid_hub": lambda: general_turbine(blades=2, yaw_free=False, teeter=False,
                                                    gravity=True),
}


def _batch_close(batch, single):
    single = np.asarray(single)
    batch = np.asarray(batch)
    assert batch.shape == single.shape
    scale = max(np.abs(single).max(initial=0.0), 1e-300)
    np.testing.assert_allclose(batch, single, rtol=BATCH_RTOL, atol=BATCH_RTOL * scale)


@pytest.fixture(params=sorted(BATCH_CONFIGS))
def batch_case(request):
    rs = RigidSystem(BATCH_CONFIGS[request.param]())
    rng = np.random.default_rng(7)
    nb = rs.n_blades
    data = dict(q=0.2 * rng.standard_normal((BATCH_K, rs.n_q)),
                qd=0.3 * rng.standard_normal((BATCH_K, rs.n_q)),
                u=0.3 * rng.standard_normal((BATCH_K, rs.n_u)),
                ud=0.5 * rng.standard_normal((BATCH_K, rs.n_u)),
                t=rng.uniform(0.0, 2.0, BATCH_K),
                F=1e3 * rng.standard_normal((BATCH_K, nb, 3)),
                M=1e3 * rng.standard_normal((BATCH_K, nb, 3)))
    return rs, data


def test_batched_methods_equal_per_instant(batch_case):
    """Reference: per-instant evaluation.  root_motion, gravity_in_root, kinematics, dynamics
    and hub_kinetic_energy of a batch of instants equal the single-instant results."""
    rs, d = batch_case
    q, qd, u, ud, t, F, M = (d[k] for k in ("q", "qd", "u", "ud", "t", "F", "M"))
    single = [dict(rm=rs.root_motion(q[i], u[i], t[i]),
                   g=rs.gravity_in_root(q[i], t[i]),
                   kin=rs.kinematics(q[i], qd[i], u[i], t[i]),
                   dyn=rs.dynamics(q[i], u[i], ud[i], t[i], F[i], M[i]),
                   ke=rs.hub_kinetic_energy(q[i], u[i], t[i])) for i in range(BATCH_K)]
    v, w = rs.root_motion(q, u, t)
    _batch_close(v, np.stack([s["rm"][0] for s in single]))
    _batch_close(w, np.stack([s["rm"][1] for s in single]))
    _batch_close(rs.gravity_in_root(q, t), np.stack([s["g"] for s in single]))
    _batch_close(rs.kinematics(q, qd, u, t), np.stack([s["kin"] for s in single]))
    _batch_close(rs.dynamics(q, u, ud, t, F, M), np.stack([s["dyn"] for s in single]))
    ke = rs.hub_kinetic_energy(q, u, t)
    assert np.shape(ke) == (BATCH_K,)
    _batch_close(ke, np.array([s["ke"] for s in single]))
