"""The coupled turbine residual: Jacobians, layout, symmetry.

References: plain coloured complex-step Jacobians of the whole residual (an independent, slower
route through the same code), central finite differences, and the blade-relabelling symmetry
that Peters' Fast Floquet relies on (exact identity of the equations)."""
import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from hawt_core.assembly import TurbineModel
from hawt_core.solvers.steady import constant_steady_state, is_time_invariant_at
from hawt_core.io import load_turbine
from hawt_core.model import Beam, Gravity, SectionTable
from tower_turbines import soft_tower_turbine


def _random_state(m, seed=3):
    rng = np.random.default_rng(seed)
    return rng.standard_normal(m.n), m.initial_guess() + 1e-2 * rng.standard_normal(m.n)


def _variants():
    T = load_turbine()
    yield "paper", T
    yield "everything-on", dc.replace(T, gravity=Gravity(True, 9.81),
                     rotor=dc.replace(T.rotor, precone=0.05),
                     nacelle=dc.replace(T.nacelle, shaft_tilt=0.1, yaw_stiffness=1e5, yaw_damping=1e3),
                     hub=dc.replace(T.hub, undersling=0.2, teeter_stiffness=1e4, teeter_damping=1e2, mass=300.0))
    yield "3-blade-rigid-hub", dc.replace(T, rotor=dc.replace(T.rotor, blades=3),
                                          hub=dc.replace(T.hub, teeter=False))
    # flexible towers (tower unknowns after the blades; tower-top motion in Kane's equations)
    tower = Beam(20.0, SectionTable.uniform(mass=300.0, i1=100.0, i2=50.0, i3=50.0, gj=1e9,
                                            ei2=2e9, ei3=3e9), 3)
    yield "flexible-tower", dc.replace(T, tower=tower)
    yield "flexible-tower-everything-on", dc.replace(T, tower=tower, gravity=Gravity(True, 9.81),
                     rotor=dc.replace(T.rotor, precone=0.05),
                     nacelle=dc.replace(T.nacelle, shaft_tilt=0.1, yaw_stiffness=1e5,
                                        yaw_damping=1e3, mass=2000.0, cg_offset=(0.3, 0.2, -0.5),
                                        inertia_pitch=800.0, inertia_roll=600.0),
                     hub=dc.replace(T.hub, undersling=0.2, teeter_stiffness=1e4, teeter_damping=1e2, mass=300.0))
    yield "flexible-tower-3-blade-no-rigid-dofs", dc.replace(
        T, tower=dc.replace(tower, elements=2), rotor=dc.replace(T.rotor, blades=3),
        hub=dc.replace(T.hub, teeter=False), nacelle=dc.replace(T.nacelle, yaw_free=False))


VARIANTS = [pytest.param(turbine, id=name) for name, turbine in _variants()]


@pytest.mark.parametrize("turbine", VARIANTS)
def test_structured_jacobians_equal_plain_complex_step(turbine):
    """Structured Jacobians (batched by subsystem) equal the plain coloured complex-step
    Jacobians of the whole residual to round-off (1e-12 relative), and central differences
    to 1e-6 relative (a random state, random rates, t = 0.3 s). With a flexible tower the
    differences also cover the tower-top columns (theta, V, Omega of the tip node) in dR/dy
    and the tip rates in dR/dydot."""
    m = TurbineModel(turbine, elements=3)
    # two states, rates and times: the second checks the beam blocks' dR/dydot, which the
    # model computes once and reuses (TurbineModel._block_jacobians, constant_rates)
    for seed, tt in ((7, 1.3), (3, 0.3)):
        yd, y = _random_state(m, seed)
        Jy, Jd = m.jacobians(yd, y, tt)
        Ry, Rd = m.jacobians_reference(yd, y, tt)
        scale = max(abs(Ry).max(), abs(Rd).max())
        assert abs(Jy - Ry).max() <= 1e-12 * scale
        assert abs(Jd - Rd).max() <= 1e-12 * scale
    # central differences on a few columns of dR/dy, including rigid ones
    for j in [0, 1, m.nq + m.nu, m.n // 2, m.n - 1]:
        e = np.zeros(m.n)
        h = 1e-6 * max(1.0, abs(y[j]))
        e[j] = h
        fd = (m.residual(yd, y + e, 0.3) - m.residual(yd, y - e, 0.3)) / (2 * h)
        np.testing.assert_allclose(Jy[:, j].toarray().ravel(), fd, atol=1e-6 * scale)
    if m.tower is not None:
        tl = m.layout.tower()
        for j in np.concatenate([tl.theta[-1], tl.V[-1], tl.Omega[-1]]):
            e = np.zeros(m.n)
            e[j] = 1e-6
            fd = (m.residual(yd, y + e, 0.3) - m.residual(yd, y - e, 0.3)) / 2e-6
            np.testing.assert_allclose(Jy[:, j].toarray().ravel(), fd, atol=1e-6 * scale)
        for j in np.concatenate([tl.V[-1], tl.Omega[-1]]):
            e = np.zeros(m.n)
            e[j] = 1e-6
            fd = (m.residual(yd + e, y, 0.3) - m.residual(yd - e, y, 0.3)) / 2e-6
            np.testing.assert_allclose(Jd[:, j].toarray().ravel(), fd, atol=1e-6 * scale)


def _n_blade_variants():
    """Rotors with 3, 4, 5 blades on a rigid hub, free yaw, with gravity, tilt, precone,
    undersling and springs; and three blades on the soft flexible tower."""
    T = load_turbine()
    for nb in (3, 4, 5):
        yield f"{nb}-blades-gravity-tilt", dc.replace(
            T, rotor=dc.replace(T.rotor, blades=nb, precone=0.05), gravity=Gravity(True, 9.81),
            hub=dc.replace(T.hub, teeter=False, undersling=0.2, mass=300.0),
            nacelle=dc.replace(T.nacelle, shaft_tilt=0.1, yaw_stiffness=1e5, yaw_damping=1e3))
    st = soft_tower_turbine()
    yield "3-blades-soft-tower-gravity", dc.replace(
        st, rotor=dc.replace(st.rotor, blades=3), hub=dc.replace(st.hub, teeter=False),
        gravity=Gravity(True, 9.81))


SYMMETRY_VARIANTS = ([VARIANTS[0], pytest.param(soft_tower_turbine(), id="soft-tower")]
                     + [pytest.param(t, id=name) for name, t in _n_blade_variants()])


@pytest.mark.parametrize("turbine", SYMMETRY_VARIANTS)
def test_blade_relabelling_symmetry_of_the_equations(turbine):
    """R(S ydot, S y, t + T/Nb) = S_rows R(ydot, y, t), with S the blade relabelling (blade
    k+1's unknowns in blade k's slot; for two blades the teeter sign flips) and S_rows the
    same map on the equations: the identity behind Fast Floquet and the multi-blade
    transform, to round-off (1e-9), for the paper's turbine, its rotor on a soft flexible
    tower, and 3, 4, 5 blades with free yaw, gravity, tilt and precone.  With three or more
    blades the opposite direction (S^T) must violate it by more than 1e-6: the check can
    tell the directions apart."""
    m = TurbineModel(turbine, elements=3)
    S = m.blade_relabelling()
    yd, y = _random_state(m, 7)
    t = 0.21
    tau = m.period / m.n_blades
    lhs = m.residual(S @ yd, S @ y, t + tau)
    rhs = S @ m.residual(yd, y, t)
    np.testing.assert_allclose(lhs, rhs, atol=1e-9 * np.abs(rhs).max())
    if m.n_blades >= 3:
        St = S.T.tocsr()
        wrong = m.residual(St @ yd, St @ y, t + tau) - St @ m.residual(yd, y, t)
        assert np.abs(wrong).max() > 1e-6 * np.abs(rhs).max()


def test_layout_names_and_indices():
    """Named access: every unknown has a unique name; blade layouts point at their blocks."""
    m = TurbineModel(load_turbine(), elements=4)
    names = m.layout.names()
    assert len(names) == m.n == len(set(names))
    assert names[m.layout["teeter"]] == "teeter"
    b1 = m.layout.blade(1)
    assert names[b1.u[4, 2]] == "blade1.u[4].3"
    assert names[b1.root_force[0]] == "blade1.root_force.1"
    with pytest.raises(KeyError, match="available"):
        m.layout["pitch"]
    with pytest.raises(IndexError, match="blades 0..1"):
        m.layout.blade(2)


def test_steady_state_root_tension_and_time_invariance():
    """No gravity: the steady state is constant in the rotating frame, zero deflection, root
    tension m Omega0^2 (e l + l^2/2) = 123930.9 N on both blades (closed form, 1e-9)."""
    T = load_turbine()
    m = TurbineModel(T, elements=4)
    y = constant_steady_state(m)
    ref = 67.5772 * 6.02 ** 2 * (1.8 * 8.42 + 8.42 ** 2 / 2)
    for k in range(2):
        assert y[m.layout.blade(k).root_force[0]] == pytest.approx(ref, rel=1e-9)
        assert np.abs(y[m.layout.blade(k).u[1:]]).max() < 1e-12
    assert is_time_invariant_at(m, y)


@pytest.mark.parametrize("speed", [3.99, 4.0, 6.02, 8.0])
def test_steady_state_with_the_ignorable_yaw_angle(speed):
    """Free yaw, no spring: the yaw angle is ignorable (its column of dR/dy vanishes, so the
    Newton matrix is singular). The bordered Newton steps converge at every speed (4.0 rad/s
    used to diverge) and leave the yaw angle at 0 exactly; residual below 1e-9 of the loads."""
    m = TurbineModel(load_turbine(), elements=2, rotor_speed=speed)
    y = constant_steady_state(m)
    assert y[m.layout["yaw"]] == 0.0
    scale = np.abs(m.residual(np.zeros(m.n), m.initial_guess(), 0.0)).max()
    assert np.abs(m.residual(np.zeros(m.n), y, 0.3)).max() <= 1e-9 * scale


def test_periodic_steady_state_free_yaw_gravity():
    """Gravity and a free yaw: the periodic steady state by harmonic balance; the harmonics
    are raised until the residual BETWEEN the collocation times is below 1e-8 of the loads
    (an independent check of the interpolated solution); yaw angle 0 at t = 0."""
    from hawt_core.solvers.periodic import periodic_steady_state
    T = load_turbine()
    m = TurbineModel(dc.replace(T, gravity=Gravity(True, 9.81)), elements=2)
    ps = periodic_steady_state(m, harmonics=8)
    scale = np.abs(m.residual(np.zeros(m.n), m.initial_guess(), 0.0)).max()
    for t in np.linspace(0, m.period, 7)[:-1] + 0.013:
        assert np.abs(m.residual(ps.rate_at(t), ps.at(t), t)).max() <= 1e-8 * scale
    assert ps.states[0, m.layout["yaw"]] == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("turbine", VARIANTS)
def test_batched_residual_equals_one_instant_at_a_time(turbine):
    """Reference: the residual evaluated at one instant at a time (the path the Jacobian,
    steady-state and Floquet tests check against the paper's equations). A batch of K = 5
    random states, rates and times in ONE call (the time-parallel simulation's evaluation,
    vectorized through Kane's equations and the beams for a rigid tower) gives the same rows
    to 1e-13 relative, for real and complex (complex-step) arguments."""
    m = TurbineModel(turbine, elements=3)
    rng = np.random.default_rng(7)
    K = 5
    Y = m.initial_guess() + 1e-2 * rng.standard_normal((K, m.n))
    Yd = rng.standard_normal((K, m.n))
    T = rng.uniform(0, 2, K)
    for Y_ in (Y, Y + 1e-20j * rng.standard_normal((K, m.n))):
        R = m.residual(Yd, Y_, T)
        ref = np.array([m.residual(Yd[k], Y_[k], T[k]) for k in range(K)])
        assert R.shape == (K, m.n)
        scale = np.abs(ref).max()
        assert np.abs(R.real - ref.real).max() <= 1e-13 * scale
        assert np.abs(R.imag - ref.imag).max() <= 1e-13 * np.abs(ref.imag).max() + 1e-300


@pytest.mark.parametrize("turbine", VARIANTS)
def test_coupling_jacobians_equal_plain_complex_step(turbine):
    """Reference: the plain coloured complex-step Jacobians of the whole residual, at two
    times (azimuths). The coupling blocks, which the window solver replaces every window
    (solvers/march/window.py), are to 1e-12 relative:

    * every row outside the tower in the columns ``cols`` (rigid unknowns, tower-top theta,
      V, Omega) and their rates: equal to the reference;
    * the tower's own rows: zero, except the tip rows, where the tower's beam terms add to
      the coupling: the reference minus the coupling must then not change with the time
      (the beam does not see the azimuth; the coupling does: the check can fail);
    * the coupling rows at the root loads: equal, and no other entry of the rigid rows.
    Several times in one call equal one time at a time (1e-14)."""
    m = TurbineModel(turbine, elements=3)
    yd, y = _random_state(m)
    n, to = m.n, (m.layout.tower_offset if m.tower is not None else m.n)
    out = np.arange(n) < to                       # rows outside the tower
    tip = np.zeros(n, bool)
    tip[getattr(m, "_tip_rows", [])] = True
    tower_rest = ~out & ~tip
    beam_part = []
    for t in (0.3, 0.7):
        c = m.coupling_jacobians(yd, y, t)
        Ry, Rd = (J.toarray() for J in m.jacobians_reference(yd, y, t))
        cols, rows, kc = c["cols"], c["rows"], c["row_cols"]
        scale = max(np.abs(Ry).max(), np.abs(Rd).max())
        for J, R in ((c["y_cols"], Ry), (c["ydot_cols"], Rd)):
            assert np.abs(J[out] - R[out][:, cols]).max() <= 1e-12 * scale
            assert np.abs(J[tower_rest]).max(initial=0.0) == 0.0
        beam_part.append([Ry[tip][:, cols] - c["y_cols"][tip],
                          Rd[tip][:, cols] - c["ydot_cols"][tip]])
        assert np.abs(c["y_rows"] - Ry[np.ix_(rows, kc)]).max() <= 1e-12 * scale
        nr = m.nq + m.nu
        others = np.setdiff1d(np.arange(n), np.concatenate([cols, kc]))
        assert np.abs(Ry[np.ix_(np.arange(nr), others)]).max(initial=0.0) == 0.0
        assert np.abs(Rd[np.ix_(np.arange(nr), np.setdiff1d(np.arange(n), cols))]).max(
            initial=0.0) == 0.0
    for a, b in zip(*beam_part):
        assert np.abs(a - b).max(initial=0.0) <= 1e-12 * scale
    if m.tower is not None and m.nq + m.nu:   # the check above has something to see (with
        # no rigid unknown, a fixed yaw and a prescribed speed, these columns do not turn)
        c3, c7 = (m.coupling_jacobians(yd, y, t)["y_cols"][tip] for t in (0.3, 0.7))
        assert np.abs(c3 - c7).max() > 1e-6 * np.abs(c3).max()
    # several times at once (one call) = one time at a time
    c = m.coupling_jacobians(yd, y, 0.3)
    cm = m.coupling_jacobians(yd, y, np.array([0.3, 0.7]))
    c7 = m.coupling_jacobians(yd, y, 0.7)
    for key in ("y_cols", "ydot_cols", "y_rows"):
        assert np.abs(cm[key][0] - c[key]).max() <= 1e-14 * scale
        assert np.abs(cm[key][1] - c7[key]).max() <= 1e-14 * scale


@pytest.mark.parametrize("turbine", [VARIANTS[0], VARIANTS[2], VARIANTS[3], VARIANTS[5]])
def test_dynamic_dimension_count_equals_exact_deflation(turbine):
    """TurbineModel.dynamic_dimension (two states per rigid coordinate and per flexible
    section direction of every element) equals the number of finite eigenvalues found by
    exact deflation of the linearized pencil (modal.dynamic_dimension, O(n^3)): exact, for
    rigid-axial blades, 3 blades, and flexible towers (with flexible-EA blades below)."""
    from hawt_core.analyses.modal import dynamic_dimension, periodic_dae
    from hawt_core.solvers.periodic import periodic_steady_state
    m = TurbineModel(turbine, elements=3)
    dae = periodic_dae(m, periodic_steady_state(m))
    assert m.dynamic_dimension() == dynamic_dimension(dae)
    flex = dc.replace(turbine, blade=dc.replace(turbine.blade, sections=dc.replace(
        turbine.blade.sections, ea=np.full(2, 5e9))))
    m = TurbineModel(flex, elements=3)
    assert m.dynamic_dimension() == dynamic_dimension(periodic_dae(m, periodic_steady_state(m)))


@pytest.mark.parametrize("blades", [3, 4])
def test_harmonic_balance_by_preconditioned_gmres_equals_the_sparse_lu(monkeypatch, blades):
    """Reference: the same harmonic-balance Newton iteration with a sparse LU of the whole
    (2H+1) n Jacobian.  Solving its steps by GMRES with the time-averaged preconditioner
    in multi-blade coordinates gives the same periodic steady state (gravity, tilt, a
    flexible tower, a drivetrain; 3 and 4 blades) to 1e-9 of its scale."""
    import hawt_core.solvers.periodic as per
    from hawt_core.model import Drivetrain
    from tower_turbines import tower_beam
    base = load_turbine(
        Path(__file__).resolve().parents[1] / "hawt_core" / "data" / "three_blade_rotor.yaml")
    t = dc.replace(base, gravity=Gravity(True, 9.81),
                   rotor=dc.replace(base.rotor, blades=blades),
                   nacelle=dc.replace(base.nacelle, shaft_tilt=0.1, yaw_free=False),
                   hub=dc.replace(base.hub, teeter=False),
                   tower=tower_beam(20.0, 500.0, 2e9, 2e9, 3e9, 200.0, 3, False),
                   drivetrain=Drivetrain(stiffness=3e6, damping=1e3))
    m = TurbineModel(t, elements=3)
    direct = per.periodic_steady_state(m, harmonics=4)
    monkeypatch.setattr(per, "ITERATIVE_UNKNOWNS", 0)
    lu = per.spl.splu
    full = []

    def no_full_lu(A, *a, **k):         # the GMRES path never factors the whole system
        if A.shape[0] > m.n + 10:
            full.append(A.shape)
        return lu(A, *a, **k)
    monkeypatch.setattr(per.spl, "splu", no_full_lu)
    krylov = per.periodic_steady_state(m, harmonics=4)
    assert not full, full
    assert not direct.constant and direct.harmonics == krylov.harmonics
    scale = np.abs(direct.states).max()
    assert np.abs(krylov.states - direct.states).max() <= 1e-9 * scale
