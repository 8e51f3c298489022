"""Flexible tower: a beam clamped at the ground whose tip carries the yaw bearing.

References and tolerances (each test says which):
- Euler-Bernoulli cantilever with a tip mass M and tip rotary inertia J (uniform m, EI, L):
  mode W = A (cosh bx - cos bx) + B (sinh bx - sin bx), tip conditions
  EI W''(L) = J w^2 W'(L) and EI W'''(L) = -M w^2 W(L), w^2 = EI b^4 / m (Blevins, Formulas for
  Natural Frequency and Mode Shape, Table 8-8 with a tip mass; Laura et al. 1974); torsion with a
  tip inertia: (bL) tan(bL) = I1 L / J, w = b sqrt(GJ / I1).  The frequency equation (the 2x2
  determinant) is solved numerically here.
- Linear beam-column (cantilever under an axial compression P and a tip moment M0, Timoshenko &
  Gere): tip deflection M0 (1 - cos kL) / (P cos kL), tip slope M0 tan(kL) / (k EI),
  k = sqrt(P / EI) (-> M0 L^2 / 2EI and M0 L / EI as P -> 0).
- Newton-Euler for the nacelle + hub with accelerations differentiated numerically from an
  independent kinematic model (positions and rotation matrices as functions of time).
- The rigid-tower model (Table 2 of Patil, Lee & Hodges) for a very stiff tower.
"""
import dataclasses as dc
import warnings

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.optimize import brentq

from hawt_core.assembly import TurbineModel
from hawt_core.solvers.steady import constant_steady_state
from hawt_core.numerics.newton import newton
from hawt_core.io import load_turbine
from hawt_core.analyses.modal import modal_analysis
from hawt_core.model import Beam, Gravity, SectionTable
from hawt_core.rigid import RigidSystem
from hawt_core.numerics.rotations import rot1, rot2, rot3, tip_basis
from shared_results import paper_modal_analysis
from tower_turbines import soft_tower_turbine as _soft_tower_turbine
from tower_turbines import tower_beam as _tower

PAPER = load_turbine()


# ---------------------------------------------------------------------------- closed forms
def _cantilever_tip_mass_det(lam, a, kap):
    """det of the tip conditions / cosh^2; a = M/(mL), kap = J/(mL^3), lam = bL."""
    c, s, ch, sh = np.cos(lam), np.sin(lam), np.cosh(lam), np.sinh(lam)
    A = np.array([[ch + c - kap * lam ** 3 * (sh + s), sh + s - kap * lam ** 3 * (ch - c)],
                  [sh - s + a * lam * (ch - c), ch + c + a * lam * (sh - s)]])
    return np.linalg.det(A) / ch ** 2


def cantilever_tip_mass(L, m, EI, M, J, k=1):
    """First k bending frequencies [rad/s] of a uniform cantilever with tip mass and inertia."""
    a, kap = M / (m * L), J / (m * L ** 3)
    grid = np.linspace(0.05, 4.0 * k + 4.0, 4000)
    f = [_cantilever_tip_mass_det(x, a, kap) for x in grid]
    roots = [brentq(_cantilever_tip_mass_det, grid[i], grid[i + 1], args=(a, kap))
             for i in range(len(grid) - 1) if f[i] * f[i + 1] < 0]
    return [(r / L) ** 2 * np.sqrt(EI / m) for r in roots[:k]]


def rod_tip_inertia(L, I1, GJ, J):
    """First torsion frequency [rad/s] of a clamped rod with a tip inertia J."""
    b = brentq(lambda b: b * L * np.tan(b * L) - I1 * L / J, 1e-9 / L, (0.5 * np.pi - 1e-9) / L)
    return b * np.sqrt(GJ / I1)


# ---------------------------------------------------------------------------- 1. frequencies
def test_tower_frequencies_match_cantilever_with_tip_mass():
    """A three-bladed rotor with very stiff (but heavy, Table 1 mass) blades, a rigid hub and a
    locked yaw, turning slowly (0.05 rad/s), on a uniform tower: the first fore-aft (EI2),
    side-side (EI3) and torsion frequencies equal the closed-form cantilever with the rotor as
    a tip mass M and tip inertia J (polar inertia for side-side, lateral inertia = polar / 2
    for fore-aft and torsion; Euler-Bernoulli: tiny section rotary inertia i2, i3).
    Richardson extrapolation of N = 8, 16 tower elements (O(h^2)) within 2e-5 relative (the
    rest: blade flexibility and rotor speed); the N = 16 values themselves within 2e-3."""
    L, m, EI2, EI3, GJ, I1 = 40.0, 500.0, 1e11, 1.5e11, 8e10, 400.0
    mb, Lb, e, Mh, Jh = 67.5772, 8.42, 1.8, 2000.0, 3000.0
    M = Mh + 3 * mb * Lb
    Jpol = Jh + 3 * (mb * ((e + Lb) ** 3 - e ** 3) / 3 + 4.9999 * Lb)
    Jlat = Jh + 3 * (mb * ((e + Lb) ** 3 - e ** 3) / 6 + (5.0 + 0.0001) / 2 * Lb)
    ref = {"fore-aft": cantilever_tip_mass(L, m, EI2, M, Jlat)[0],
           "side-side": cantilever_tip_mass(L, m, EI3, M, Jpol)[0],
           "torsion": rod_tip_inertia(L, I1, GJ, Jlat)}
    blade = Beam(Lb, SectionTable.uniform(mass=mb, i1=5.0, i2=0.0001, i3=4.9999, gj=2e12,
                                          ei2=4e14, ei3=2e15), 4)
    T = dc.replace(PAPER, blade=blade, rotor=dc.replace(PAPER.rotor, speed=0.05, blades=3),
                   hub=dc.replace(PAPER.hub, teeter=False, mass=Mh, inertia_lateral=Jh,
                                  inertia_longitudinal=Jh),
                   nacelle=dc.replace(PAPER.nacelle, yaw_free=False, yaw_to_teeter=0.0,
                                      yaw_inertia=Jh))
    got = {}
    for N in (8, 16):
        model = TurbineModel(dc.replace(T, tower=_tower(L, m, EI2, EI3, GJ, I1, N)))
        y = constant_steady_state(model)
        E, A = model.linearize(y)
        lam, X = sl.eig(A.toarray(), E.toarray())
        tl = model.layout.tower()
        for name, comp in (("fore-aft", ("u", 2)), ("side-side", ("u", 1)),
                           ("torsion", ("theta", 0))):
            # the mode nearest to the reference whose tower tip moves in that direction
            cand = [i for i in range(len(lam)) if np.isfinite(lam[i]) and lam[i].imag > 0
                    and abs(lam[i].imag / ref[name] - 1) < 0.05]
            best = max(cand, key=lambda i: abs(X[getattr(tl, comp[0])[-1][comp[1]], i])
                       / np.abs(X[tl.u[-1], i]).max(initial=1e-300))
            got.setdefault(name, []).append(lam[best].imag)
    for name, (w8, w16) in got.items():
        rich = (4 * w16 - w8) / 3
        assert rich == pytest.approx(ref[name], rel=2e-5), (name, w8, w16, ref[name])
        assert w16 == pytest.approx(ref[name], rel=2e-3), name


# ---------------------------------------------------------------------------- 2. statics
def _static(T, N, t=0.0):
    model = TurbineModel(dc.replace(T, tower=dc.replace(T.tower, elements=N)))
    z = np.zeros(model.n)
    y, _ = newton(lambda y: model.residual(z, y, t), lambda y: model.jacobians(z, y, t)[0],
                  model.initial_guess(), tol=1e-12, what="statics")
    return model, y


def test_tower_top_statics_under_the_nacelle_weight_with_overhang():
    """Gravity on, rotor at rest with both blades vertical (t = 0), yaw locked, rigid hub:
    the rotor (hub 2000 kg + blades) hangs at d = 2.388 m downwind of the tower axis and the
    nacelle (5000 kg) has its mass centre 1 m upwind and 0.5 m to the side.  The tower
    (L = 30 m, EI2 = 5e10, EI3 = 7e10, nearly massless) is a cantilever under the axial load P
    (the whole weight) and the tip moments M2 = -g (m_rotor d + m_n c3), M3 = m_n g c2:
    deflections and slopes (Rodrigues parameters 2 tan(phi/2)) equal the linear beam-column
    closed form: Richardson of N = 4, 8 tower elements within 1e-6 relative (the rest is
    geometric nonlinearity, slope^2 ~ 1e-9); the root force equals minus the total weight
    (1e-12) and the tip section's axial force is -P within the tip slope's cosine (1e-5)."""
    L, EI2, EI3, g = 30.0, 5e10, 7e10, 9.81
    mh, mn, c2, c3 = 2000.0, 5000.0, 0.5, -1.0
    sec = SectionTable.uniform(mass=1e-3, i1=1e-3, i2=5e-4, i3=5e-4, gj=4e10, ei2=EI2, ei3=EI3)
    T = dc.replace(PAPER, tower=Beam(L, sec, 4), gravity=Gravity(True, g),
                   rotor=dc.replace(PAPER.rotor, speed=0.0),
                   hub=dc.replace(PAPER.hub, teeter=False, mass=mh),
                   nacelle=dc.replace(PAPER.nacelle, yaw_free=False, mass=mn, yaw_inertia=3e4,
                                      cg_offset=(0.0, c2, c3)))
    mb = 2 * 67.5772 * 8.42
    P = (mh + mb + mn) * g
    d = T.nacelle.yaw_to_teeter
    M2 = -g * ((mh + mb) * d + mn * c3)
    M3 = mn * g * c2
    vals = []
    for N in (4, 8):
        model, y = _static(T, N)
        tl = model.layout.tower()
        u, th = y[tl.u[-1]], y[tl.theta[-1]]
        vals.append(np.array([u[2], th[1], u[1], th[2]]))
        np.testing.assert_allclose(y[tl.root_force], [-(P + 1e-3 * L * g), 0, 0],
                                   atol=1e-12 * P)
        assert y[tl.F[-1][0]] == pytest.approx(-P, rel=1e-5)
    rich = (4 * vals[1] - vals[0]) / 3
    ref = []
    for M0, EI in ((M2, EI2), (M3, EI3)):
        k = np.sqrt(P / EI)
        defl = abs(M0) * (1 - np.cos(k * L)) / (P * np.cos(k * L))
        slope = 2 * np.tan(0.5 * abs(M0) * np.tan(k * L) / (k * EI))
        ref.append((defl, slope))
    # signs: M2 < 0 (the rotor's weight dominates) bends the top downwind (+t3), turning the
    # tip section by -phi about t2; M3 > 0 bends it towards +t2, turning it by +phi about t3
    expected = np.array([ref[0][0], -ref[0][1], ref[1][0], ref[1][1]])
    assert M2 < 0 < M3
    np.testing.assert_allclose(rich, expected, rtol=1e-6)
    # the plain values, and the familiar M L^2/2EI, M L/EI (P -> 0) within the P-delta effect
    np.testing.assert_allclose(vals[1], expected, rtol=2e-5)
    assert vals[1][0] == pytest.approx(-M2 * L ** 2 / (2 * EI2), rel=2e-3)


def test_tower_top_loads_of_static_blade_loads_by_hand():
    """Rigid system at rest (t = 0, zero yaw and teeter, no tilt/precone, tower undeformed):
    the loads on the tower top are the blade root loads (blade 0's basis = n, blade 1's turned
    by pi about n3) moved to the tower-top point by hand (roots at d n3 +- e n1), plus the hub
    weight at d n3 and the nacelle's at its mass centre: 1e-12.  A horizontal (fore-aft) force
    F gives a tip force +F along t3 and a moment F x lever."""
    T = dc.replace(PAPER, tower=_tower(20.0, 300.0, 1e10, 1e10, 1e10, 100.0, 2),
                   gravity=Gravity(True, 9.81), hub=dc.replace(PAPER.hub, mass=700.0),
                   nacelle=dc.replace(PAPER.nacelle, mass=3000.0, cg_offset=(0.4, 0.3, -0.8)))
    r = RigidSystem(T)
    rng = np.random.default_rng(5)
    F = rng.standard_normal((2, 3)) * 1e3
    M = rng.standard_normal((2, 3)) * 1e3
    F[0] = [0.0, 0.0, 5000.0]     # a pure fore-aft push of blade 0 on the hub
    z2 = np.zeros(r.n_u)
    force, moment = r.tower_top_loads(np.zeros(r.n_q), z2, z2, 0.0, F, M)
    d, e, g = T.nacelle.yaw_to_teeter, T.hub.radius, 9.81
    B1 = np.diag([-1.0, -1.0, 1.0])
    pos = [np.array([e, 0, d]), np.array([-e, 0, d])]
    FN = [F[0], B1 @ F[1]]
    MN = [M[0], B1 @ M[1]]
    w_hub = np.array([-700.0 * g, 0, 0])
    w_nac = np.array([-3000.0 * g, 0, 0])
    f_ref = FN[0] + FN[1] + w_hub + w_nac
    m_ref = (np.cross(pos[0], FN[0]) + np.cross(pos[1], FN[1]) + MN[0] + MN[1]
             + np.cross([0, 0, d], w_hub) + np.cross([0.4, 0.3, -0.8], w_nac))
    np.testing.assert_allclose(force, f_ref, atol=1e-12 * np.abs(f_ref).max())
    np.testing.assert_allclose(moment, m_ref, atol=1e-12 * np.abs(m_ref).max())


# ---------------------------------------------------------------------------- Kane vs N-E
def _everything(blades=2, teeter=True, counterweight=0.0):
    T = _everything_base(blades, teeter)
    return dc.replace(T, hub=dc.replace(T.hub, counterweight_mass=counterweight,
                                        counterweight_radius=1.3 if counterweight else 0.0))


def _everything_base(blades, teeter):
    return dc.replace(
        PAPER, tower=_tower(20.0, 300.0, 1e10, 1e10, 1e10, 100.0, 2),
        gravity=Gravity(True, 9.81),
        rotor=dc.replace(PAPER.rotor, blades=blades, precone=0.05 if blades == 3 else 0.0),
        nacelle=dc.replace(PAPER.nacelle, shaft_tilt=0.1, yaw_stiffness=1e5, yaw_damping=1e3,
                           mass=3000.0, cg_offset=(0.4, -0.3, -0.8), inertia_pitch=2000.0,
                           inertia_roll=1500.0),
        hub=dc.replace(PAPER.hub, teeter=teeter, undersling=0.2, teeter_stiffness=1e4,
                       teeter_damping=1e2, mass=300.0, inertia_lateral=80.0,
                       inertia_longitudinal=30.0))


@pytest.mark.parametrize("blades,teeter,counterweight", [(2, True, 0.0), (3, False, 0.0),
                                                         (1, True, 450.0)])
def test_kane_with_tower_motion_equals_newton_euler(blades, teeter, counterweight):
    """A smooth, arbitrary motion of the tower top (translation and finite rotation), yaw and
    teeter; every Kane row of the rigid system equals Newton-Euler for nacelle + hub with the
    accelerations of an INDEPENDENT kinematic model (positions, rotation matrices as functions
    of time, differentiated by complex step and central differences): the tower-top rows are
    the force and moment (about the tower-top point) on the tower; the teeter row is the
    hub's moment balance about the teeter axis; the yaw row is the balance about the yaw axis
    of nacelle + hub minus (y1 . h2) times the teeter row.  One blade: with a counterweight
    (a point mass on the hub opposite the blade).  Tolerance 1e-6 of the largest term (the
    O(dt^2) second differences)."""
    T = _everything(blades, teeter, counterweight)
    r = RigidSystem(T)
    Om0, d, e, lhd1, tilt = r.omega0, r.d, r.e, r.lhd1, r.tilt
    pre = T.rotor.precone
    th_c = np.array([[0.05, -0.1, 0.08], [0.3, 0.2, -0.25], [-0.4, 0.5, 0.3]])
    p_c = np.array([[0.1, 0.2, -0.3], [0.4, -0.6, 0.5], [0.7, 0.3, -0.2]])

    def state(t):
        """positions (TY, SH, nacelle cg, roots) and bases (T, Y, H, B_k) at time t."""
        th = th_c[0] + th_c[1] * t + th_c[2] * t * t
        Tt = tip_basis(th)
        qy = 0.3 + 0.7 * t - 0.5 * t * t
        qh = -0.1 + 0.4 * np.sin(2 * t) if teeter else 0.0 * t
        Y = Tt @ rot1(qy)
        S = Y @ rot2(tilt) @ rot3(Om0 * t)
        H = S @ rot2(-qh)
        TY = p_c[0] + p_c[1] * t + p_c[2] * t * t
        SH = TY + d * S[:, 2]
        cg = TY + Y @ np.array(T.nacelle.cg_offset)
        cw = SH + H @ np.array([-T.hub.counterweight_radius, 0.0, 0.0])
        roots, Bk = [], []
        for k in range(blades):
            ph = 2 * np.pi * k / blades
            roots.append(SH + H @ np.array([e * np.cos(ph), e * np.sin(ph), -lhd1]))
            Bk.append(H @ rot3(ph) @ rot2(-pre))
        return dict(th=th, Tt=Tt, qy=qy, qh=qh, Y=Y, H=H, TY=TY, SH=SH, cg=cg, cw=cw,
                    roots=roots, B=Bk)

    hc = 1e-30

    def rate(key, t):
        """complex-step time derivative of an array-valued entry of state()"""
        return np.imag(np.asarray(state(t + 1j * hc)[key])) / hc

    def omega(key, t):
        W = rate(key, t) @ np.asarray(state(t)[key]).T
        return np.array([W[2, 1], W[0, 2], W[1, 0]])

    def d2(fun, t, dt=1e-4):
        return (fun(t + dt) - fun(t - dt)) / (2 * dt)

    t = 0.37
    s = state(t)
    Tt, Y, H = s["Tt"], s["Y"], s["H"]
    w_T, w_Y, w_H = omega("Tt", t), omega("Y", t), omega("H", t)
    al_T, al_Y, al_H = (d2(lambda x: omega(k, x), t) for k in ("Tt", "Y", "H"))
    a_SH = d2(lambda x: rate("SH", x), t)
    a_cg = d2(lambda x: rate("cg", x), t)
    a_cw = d2(lambda x: rate("cw", x), t)
    # generalized speeds of the model from the trajectory
    y1, h2 = Y[:, 0], H[:, 1]
    U1 = rate("qy", t)
    qh_dot = rate("qh", t)
    U2 = U1 * (y1 @ h2) - qh_dot
    U1d = d2(lambda x: rate("qy", x), t)
    U2d = d2(lambda x: rate("qy", x) * (state(x)["Y"][:, 0] @ state(x)["H"][:, 1])
             - rate("qh", x), t)
    V = Tt.T @ rate("TY", t)
    Om = Tt.T @ w_T
    Vd = d2(lambda x: state(x)["Tt"].T @ rate("TY", x), t)
    Omd = d2(lambda x: state(x)["Tt"].T @ omega("Tt", x), t)
    tower = np.stack([s["th"], V, Om, Vd, Omd])
    q = np.array([s["qy"], s["qh"]] if teeter else [s["qy"]])
    u = np.array([U1, U2] if teeter else [U1])
    ud = np.array([U1d, U2d] if teeter else [U1d])
    rng = np.random.default_rng(11)
    Fb = rng.standard_normal((blades, 3)) * 2e3
    Mb = rng.standard_normal((blades, 3)) * 2e3
    res = r.generalized_forces(q, u, ud, t, Fb, Mb, tower)
    # --- Newton-Euler, in N
    g = np.array([-9.81, 0, 0])
    mh, mn = T.hub.mass, T.nacelle.mass
    FN = [s["B"][k] @ Fb[k] for k in range(blades)]
    MN = [s["B"][k] @ Mb[k] for k in range(blades)]
    IH = H @ r.hub_inertia @ H.T
    IY = Y @ r.nacelle_inertia @ Y.T
    dH_H = IH @ al_H + np.cross(w_H, IH @ w_H)
    dH_Y = IY @ al_Y + np.cross(w_Y, IY @ w_Y)
    rel = lambda p: p - s["TY"]
    mc = T.hub.counterweight_mass
    force = sum(FN) + (mh + mn + mc) * g - mh * a_SH - mn * a_cg - mc * a_cw
    mom_TY = (sum(np.cross(rel(s["roots"][k]), FN[k]) + MN[k] for k in range(blades))
              + np.cross(rel(s["SH"]), mh * (g - a_SH)) + np.cross(rel(s["cg"]), mn * (g - a_cg))
              + np.cross(rel(s["cw"]), mc * (g - a_cw)) - dH_H - dH_Y)
    scale = max(np.abs(force).max(), np.abs(mom_TY).max())
    np.testing.assert_allclose(res[r.n_u:r.n_u + 3], Tt.T @ force, atol=1e-6 * scale)
    np.testing.assert_allclose(res[r.n_u + 3:], Tt.T @ mom_TY, atol=1e-6 * scale)
    # teeter row: hub moment about the teeter axis through SH, plus the teeter spring/damper
    yaw_spring = -T.nacelle.yaw_stiffness * s["qy"] - T.nacelle.yaw_damping * U1
    if teeter:
        mom_SH = (sum(np.cross(s["roots"][k] - s["SH"], FN[k]) + MN[k] for k in range(blades))
                  + np.cross(s["cw"] - s["SH"], mc * (g - a_cw)) - dH_H)
        teeter_row = h2 @ mom_SH + T.hub.teeter_stiffness * s["qh"] + T.hub.teeter_damping * qh_dot
        assert res[1] == pytest.approx(teeter_row, abs=1e-6 * scale)
        yaw_row = y1 @ mom_TY + yaw_spring - (y1 @ h2) * teeter_row
    else:
        yaw_row = y1 @ mom_TY + yaw_spring
    assert res[0] == pytest.approx(yaw_row, abs=1e-6 * scale)


def test_flexible_tower_rigid_rows_reduce_to_the_rigid_tower_at_rest():
    """With the tower top at rest and undeformed, the flexible-tower Kane code (general vector
    form with the 6 extra speeds) gives the rigid-tower rows, root motion and gravity of the
    original code, 2 and 3 blades, everything switched on (1e-12 relative); the tower-top rows
    are complex-step safe (an imaginary step gives the derivative, 1e-9 against differences)."""
    for blades, teeter in ((2, True), (3, False)):
        T = _everything(blades, teeter)
        rf = RigidSystem(T)
        rr = RigidSystem(dc.replace(T, tower=None))
        rng = np.random.default_rng(2)
        q, u, ud = (rng.standard_normal(rf.n_q), rng.standard_normal(rf.n_u),
                    rng.standard_normal(rf.n_u))
        F, M = rng.standard_normal((blades, 3)) * 1e3, rng.standard_normal((blades, 3)) * 1e3
        a = rf.dynamics(q, u, ud, 0.4, F, M)
        b = rr.dynamics(q, u, ud, 0.4, F, M)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
        for x, y in zip(rf.root_motion(q, u, 0.4), rr.root_motion(q, u, 0.4)):
            np.testing.assert_allclose(x, y, atol=1e-12 * np.abs(y).max())
        np.testing.assert_allclose(rf.gravity_in_root(q, 0.4), rr.gravity_in_root(q, 0.4),
                                   atol=1e-14)
        tw = rng.standard_normal((5, 3)) * 0.1
        dt = np.zeros((5, 3))
        dt[2, 1] = 1.0
        cs = np.imag(rf.generalized_forces(q, u, ud, 0.4, F, M, tw + 1e-30j * dt)) / 1e-30
        h = 1e-6
        fd = (rf.generalized_forces(q, u, ud, 0.4, F, M, tw + h * dt)
              - rf.generalized_forces(q, u, ud, 0.4, F, M, tw - h * dt)) / (2 * h)
        np.testing.assert_allclose(cs, fd, atol=1e-6 * np.abs(fd).max())
    with pytest.raises(ValueError, match="rigid tower"):
        RigidSystem(PAPER).root_motion([0.0, 0.0], [0.0, 0.0], 0.0, np.zeros((5, 3)))


# ---------------------------------------------------------------------------- 4. stiff tower
def test_very_stiff_tower_reproduces_the_rigid_tower_table2():
    """A very stiff tower (EI = GJ = 1e16 N m^2, 1000 kg/m, 20 m) under the paper's rotor: every
    Floquet mode of the rigid-tower analysis (Table 2 rotor, N = 4, Radau 400 steps) is found
    with the same label and frequency within 1e-5 relative (4.6e-7 seen; the physical shift
    scales as 1/EI: 4.6e-6 at 1e15); the real parts (here Radau's numerical dissipation, up to
    2e-4 per-rev at 34/rev, and the teeter pair's +-0.045) within 2e-5 per-rev (8e-8 seen;
    the stiff tower rows' conditioning can move the dissipation of the 34/rev modes by ~1e-5);
    the tower modes lie far above the temporal resolution (not reported).  No RuntimeWarning
    (the consistent subspace's dimension is counted exactly: no rank decision to doubt)."""
    rigid = paper_modal_analysis()     # modal_analysis(PAPER, elements=4, steps=400)
    T = dc.replace(PAPER, tower=_tower(20.0, 1000.0, 1e16, 1e16, 1e16, 500.0, 2, False))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no rank-gap or conditioning note
        stiff = modal_analysis(T, elements=4, steps=400)
    assert len(stiff.modes) == len(rigid.modes)
    for a, b in zip(rigid.modes, stiff.modes):
        assert (a.family, a.symmetry, a.index) == (b.family, b.symmetry, b.index)
        assert b.frequency_per_rev == pytest.approx(a.frequency_per_rev, rel=1e-5, abs=1e-9)
        assert b.real_per_rev == pytest.approx(a.real_per_rev, abs=2e-5)
    assert not any(m.family == "tower" for m in stiff.modes)


# ---------------------------------------------------------------------------- 5. coupling
@pytest.fixture(scope="module")
def soft_tower_turbine():
    """The paper's rotor (hub 1000 kg, nacelle 3000 kg) on a soft 25 m tower (400 kg/m,
    EI = 6e8 N m^2, GJ = 1.5e9 N m^2)."""
    return _soft_tower_turbine()


def test_flexible_tower_couples_with_the_rotor(soft_tower_turbine):
    """Floquet analysis of the paper's rotor on a soft tower: the first fore-aft and side-side
    tower modes appear, labelled 'tower', undamped (|damping| < 1e-6), at frequencies between
    the rotor lumped rigidly on the tower top (closed form with M = hub + nacelle + blades and
    the rotor's largest inertia, the lower bound up to blade dynamics: 0.641/rev) and the bare
    tower (1.1445/rev); the tower torsion appears; the Table 2 rotor modes that the tower does
    not touch (symmetric torsion, 2nd antisymmetric flap) keep their rigid-tower values within
    1e-4; Fast Floquet (T/2 with the relabelling) equals the full-period analysis (1e-6);
    no RuntimeWarning from either."""
    T = soft_tower_turbine
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no rank-gap or conditioning note
        res = modal_analysis(T, elements=4, steps=400)
        full = modal_analysis(T, elements=4, steps=400, fast=False)
    w0 = T.rotor.speed
    mb = 2 * 67.5772 * 8.42
    Ib = 2 * 67.5772 * (10.22 ** 3 - 1.8 ** 3) / 3
    M = 1000.0 + 3000.0 + mb
    J = Ib + 50.0 + 2000.0 + (1000.0 + mb) * 2.388 ** 2
    low = cantilever_tip_mass(25.0, 400.0, 6e8, M, J)[0] / w0
    high = cantilever_tip_mass(25.0, 400.0, 6e8, 0.0, 0.0)[0] / w0
    assert high == pytest.approx(3.5160 / 25.0 ** 2 * np.sqrt(6e8 / 400) / w0, rel=1e-4)
    for direction in ("fore-aft", "side-side"):
        m = res.find("tower", direction, 1)
        assert low < m.frequency_per_rev < high, (direction, m.frequency_per_rev, low, high)
        assert abs(m.damping_ratio) < 1e-6
    assert res.find("tower", "torsion", 1).frequency_per_rev > 10
    rigid = paper_modal_analysis()     # modal_analysis(PAPER, elements=4, steps=400)
    for key in (("torsion", "symmetric", 1), ("torsion", "symmetric", 2),
                ("flap", "antisymmetric", 2)):
        assert res.find(*key).frequency_per_rev == pytest.approx(
            rigid.find(*key).frequency_per_rev, rel=1e-4), key
    assert len(full.modes) == len(res.modes)
    for a, b in zip(res.modes, full.modes):
        assert b.frequency_per_rev == pytest.approx(a.frequency_per_rev, rel=1e-6, abs=1e-8)
        assert b.real_per_rev == pytest.approx(a.real_per_rev, abs=1e-6)
    assert "tower" in res.table()


# ---------------------------------------------------------------------------- layout
def test_tower_layout_names(soft_tower_turbine):
    """Tower unknowns follow the blades, named 'tower.u[3].1' etc.  (The blade relabelling
    symmetry with this tower: test_assembly.test_blade_relabelling_symmetry_of_the_equations.)"""
    m = TurbineModel(soft_tower_turbine, elements=3)
    names = m.layout.names()
    assert len(names) == m.n == len(set(names))
    tl = m.layout.tower()
    assert tl.u.shape == (5, 3) and tl.u[0, 0] == -1
    assert names[tl.u[3, 0]] == "tower.u[3].1"
    assert names[tl.root_force[2]] == "tower.root_force.3"
    assert m.layout.tower_offset == m.layout.blade_offset(1) + m.beam.n
    assert m.differential.shape == (m.n,)
    with pytest.raises(ValueError, match="rigid"):
        TurbineModel(PAPER, elements=3).layout.tower()


# ---------------------------------------------------------------------------- file format
def test_nacelle_mass_properties_in_the_turbine_file():
    """nacelle.cg_offset / inertia_pitch / inertia_roll: read, validated (three finite numbers;
    inertias >= 0), written back only when not the defaults (the default file's dump does not
    change), and the model refuses a yaw inertia below the hub's share plus the nacelle's
    offset mass with a flexible tower."""
    import yaml
    from hawt_core.io import TurbineFileError, dump_turbine, turbine_from_dict
    from hawt_core.io import turbines_equal
    d = yaml.safe_load(dump_turbine(PAPER))
    assert not {"cg_offset", "inertia_pitch", "inertia_roll"} & set(d["nacelle"])
    d["nacelle"].update(cg_offset=[0.5, 0, -1], inertia_pitch=100.0, inertia_roll=50)
    t = turbine_from_dict(d)
    assert t.nacelle.cg_offset == (0.5, 0.0, -1.0) and t.nacelle.inertia_roll == 50.0
    assert turbines_equal(turbine_from_dict(yaml.safe_load(dump_turbine(t))), t)
    for bad, msg in (([1, 2], "three numbers"), ([0, float("nan"), 0], "finite")):
        d["nacelle"]["cg_offset"] = bad
        with pytest.raises(TurbineFileError, match=msg):
            turbine_from_dict(d)
    d["nacelle"]["cg_offset"] = [0, 0, 0]
    d["nacelle"]["inertia_pitch"] = -1.0
    with pytest.raises(TurbineFileError, match="inertia_pitch"):
        turbine_from_dict(d)
    heavy = dc.replace(PAPER, tower=_tower(20.0, 300.0, 1e10, 1e10, 1e10, 100.0, 2),
                       nacelle=dc.replace(PAPER.nacelle, mass=5000.0, cg_offset=(0, 0, -2.0)))
    with pytest.raises(ValueError, match="yaw_inertia"):
        RigidSystem(heavy)
    RigidSystem(dc.replace(heavy, tower=None))      # rigid tower: unchanged behaviour
