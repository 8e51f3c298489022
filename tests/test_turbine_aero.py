"""The whole turbine in wind (assembly/rotor_aero.py, TurbineModel(wind=...)): blade-element
loads in the one residual, frozen wake; aeroelastic Floquet (``hawt modes --wind``).

References (each test states its tolerance):
* Lock's flap damping: a rigid blade flapping about a hinge on the shaft axis with
  quasi-steady strip theory (lift slope a, no drag, no inflow) obeys
  beta'' + (gamma/8) Omega beta' + nu^2 Omega^2 beta = 0, gamma = rho a c R^4 / I
  (Johnson, Helicopter Theory, 1980, section 5.3: the "Lock number"); for a teetering
  two-bladed rotor with the blades from the hub radius e to R the same derivation gives the
  real part of the teeter exponent -C / (2 I) with C = 2 (rho a c Omega / 2) (R^4 - e^4) / 4
  and I the rotor's teeter inertia (closed-form integrals in the test);
* the aeroelastic blade of assembly/aero_blade.py (a separate assembly: SpinningBlade, its own
  induction unknowns): in axisymmetric flow each blade of the turbine carries its loads;
* torque balance: in steady operation the flexible shaft's twist times its stiffness is the
  rotor's aerodynamic torque (generator power = aerodynamic power; the shaft damper does no
  work in a steady state);
* the structured Jacobians against plain coloured complex steps on the whole residual, and
  complex steps against central differences;
* Hill's method in multi-blade coordinates against Radau IIA monodromy (two independent
  Floquet solutions) in wind.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
import yaml

from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.assembly.aero_blade import AeroelasticBlade
from hawt_core.io import dump_turbine, load_turbine, turbine_from_dict
from hawt_core.solvers.steady import constant_steady_state
from meshes import load_paper_mesh

RHO = 1.225
LIFT_SLOPE = 2 * np.pi
CHORD = 0.5


def teetering_rotor(stiffness=1e3, gravity=False, tilt=0.0, yaw_free=False):
    """The paper's two-bladed teetering turbine, blades ``stiffness`` times stiffer, with a
    flat-plate airfoil (cl = 2 pi alpha, no drag or moment) of uniform chord and no twist."""
    d = yaml.safe_load(dump_turbine(load_turbine()))
    sec = d["blade"]["sections"]
    for k in ("gj", "ei2", "ei3"):
        sec[k] = float(sec[k]) * stiffness
    d["nacelle"].update(yaw_free=yaw_free, shaft_tilt=tilt, yaw_stiffness=0.0)
    d["gravity"]["enabled"] = gravity
    d["aerodynamics"] = {
        "stations": [0.0, 1.0], "chord": [CHORD, CHORD], "twist": [0.0, 0.0], "airfoil": [0, 0],
        "polars": [{"name": "flat plate", "alpha": [-0.5, 0.5],
                    "cl": [-0.5 * LIFT_SLOPE, 0.5 * LIFT_SLOPE], "cd": [0.0, 0.0],
                    "cm": [0.0, 0.0]}]}
    return turbine_from_dict(d)


def nrel5mw():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_paper_mesh("nrel5mw")


def quiet_shipped(name):
    """The shipped turbine as loaded (the file's mesh)."""
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_any(name)


def axisymmetric(t, rpm=9.16, pitch_deg=0.0):
    """``t`` on a rigid tower, yaw locked, no tilt or gravity: axisymmetric in axial wind."""
    return replace(t, tower=None, gravity=replace(t.gravity, enabled=False),
                   nacelle=replace(t.nacelle, yaw_free=False, shaft_tilt=0.0),
                   rotor=replace(t.rotor, speed=rpm * np.pi / 30,
                                 pitch=-np.radians(pitch_deg)))


def test_teeter_damping_is_locks_closed_form():
    """Reference: Lock's quasi-steady flap damping (module docstring).  A flat plate at zero
    angle of attack (wind 1 mm/s, inductions frozen at zero) carries no steady lift, so the
    teeter exponent's real part is pure aerodynamic damping: -C / (2 I) within 1e-5 (found
    4e-7 with blades 1e3 times stiffer, 5e-6 with 1e2, 1e-8 with 1e4: the blades' residual
    flexibility); in a vacuum it is 0 (1e-9)."""
    t = teetering_rotor()
    n = 4
    omega = t.rotor.speed
    e, L = t.hub.radius, t.blade.length
    R = e + L
    inertia, wn2 = rigid_teeter(t)
    C = 2 * 0.5 * RHO * LIFT_SLOPE * CHORD * omega * (R ** 4 - e ** 4) / 4
    expected = -C / (2 * inertia)
    found = {}
    for wind in (None, Wind(1e-3)):
        kw = {} if wind is None else {
            "wind": wind, "inductions": (np.zeros((n, 3)), np.zeros((n, 3)))}
        found[wind is None] = teeter_exponent(TurbineModel(t, elements=n, **kw))
    assert abs(found[True].real) <= 1e-9 * omega
    assert found[False].real == pytest.approx(expected, rel=1e-5)
    # and the frequency: the centrifugal teeter stiffness over the teeter inertia, damped:
    # sqrt(w_n^2 - (C / 2 I)^2)
    assert found[False].imag == pytest.approx(np.sqrt(wn2 - expected ** 2), rel=1e-5)


def rigid_teeter(t):
    """(I [kg m^2], w_n^2 [1/s^2]) of the rigid teetering rotor ``t`` (uniform blades): the
    teeter inertia, blades as lines along h1 plus the hub's lateral inertia, and the
    centrifugal teeter stiffness Omega^2 (I_33 - I_11) of the spinning rotor (Euler's
    equations: the blades give I_b, the hub Ihlong - Ihlat) over it."""
    e, L = t.hub.radius, t.blade.length
    R = e + L
    m = float(np.mean(t.blade.sections.mass))
    inertia = 2 * m * (R ** 3 - e ** 3) / 3 + t.hub.inertia_lateral
    blades = inertia - t.hub.inertia_lateral
    wn2 = t.rotor.speed ** 2 * (blades + t.hub.inertia_longitudinal
                                - t.hub.inertia_lateral) / inertia
    return inertia, wn2


def teeter_exponent(model):
    """The exponent (Im > 0) of the mode with the largest teeter share (teeter angle times
    the rotor radius against the largest displayed motion) about the model's constant steady
    state, dense QZ of its linearization."""
    import scipy.linalg as sl
    y = constant_steady_state(model)
    E, A = (M.toarray() for M in model.linearize(y))
    lam, X = sl.eig(A, E)
    ok = np.isfinite(lam) & (np.abs(lam) < 1e6)
    lam, X = lam[ok], X[:, ok]
    rows, wts = model.display_rows()
    share = np.abs(X[model.layout["teeter"]]) * wts[0] / np.abs(X[rows] * wts[:, None]).max(0)
    return lam[int(np.argmax(share * (lam.imag > 0)))]


def test_each_blade_carries_the_aeroelastic_blade_loads_and_the_shaft_their_torque():
    """References: the aeroelastic blade on the spinning hub (separate assembly) and the
    torque balance of a steady state.  NREL 5-MW, axisymmetric (rigid tower, no tilt or
    gravity), 8 m/s, 9.16 rpm: the turbine's steady state is every blade in the blade
    model's state (turbine residual at it below 1e-12 of the load scale; Newton moves it by
    less than 1e-9 m), and with the flexible drivetrain the shaft twist times the stiffness
    is the rotor's torque 3 x the blade's root torque within 1e-8."""
    t = axisymmetric(nrel5mw())
    n = 8
    blade = AeroelasticBlade(t, 8.0, elements=n)
    yb = blade.steady_state()
    torque, _ = blade.root_loads(yb)
    model = TurbineModel(t, elements=n, wind=Wind(8.0))
    assert model.rigid.shaft_flexible
    y0 = model.initial_guess()
    r0 = model.residual(np.zeros(model.n), y0, 0.0)
    assert np.abs(r0[model.nq + model.nu:]).max() <= 1e-12 * model.load_scale()
    y = constant_steady_state(model)
    for k in range(3):
        b = model.layout.blade(k)
        assert np.abs(y[b.u[1:]] - y0[b.u[1:]]).max() < 1e-9
    twist = y[model.layout["shaft_twist"]]
    shaft = -t.drivetrain.stiffness * twist
    assert -shaft == pytest.approx(3 * torque, rel=1e-8)
    assert 3 * torque * t.rotor.speed > 1e6          # a rotor producing power (about 2 MW)


def test_structured_jacobians_in_wind_equal_complex_steps_on_the_whole_residual():
    """Reference: plain coloured complex steps on the whole residual (jacobians_reference)
    and central differences (step 1e-6 of each unknown's scale): the teetering rotor with free
    yaw, gravity, tilt and a 15 deg yaw misalignment (the wind turns with yaw, tilt, azimuth
    and teeter), and the NREL 5-MW with its flexible tower and drivetrain in a sheared wind
    with tower shadow (the wind at each Gauss point's position), within 1e-9 of the
    largest entry (complex steps) and 1e-5 (differences)."""
    cases = [
        (teetering_rotor(stiffness=1.0, gravity=True, tilt=0.1, yaw_free=True), 3,
         Wind(7.0, direction=np.radians(15.0))),
        (replace(nrel5mw(), rotor=replace(nrel5mw().rotor, speed=1.0)), 3,
         Wind(9.0, shear_exponent=0.2, tower_radius=3.0))]
    rng = np.random.default_rng(3)
    for t, n, wind in cases:
        check_structured_jacobians(TurbineModel(t, elements=n, wind=wind), rng)
    # the shipped file's mesh (the p-version: blades 3 elements of order 6, tower 2 of order
    # 4, whose element blocks keep only the entries the equations can fill) with Oye's
    # inflow and Jones's unsteady airfoil states at every Gauss point
    shipped = quiet_shipped("nrel5mw")
    shipped = replace(shipped, rotor=replace(shipped.rotor, speed=1.0))
    check_structured_jacobians(TurbineModel(shipped, wind=Wind(9.0, shear_exponent=0.2,
                                                               tower_radius=3.0),
                                            inflow="oye", airfoil="jones"), rng)


def check_structured_jacobians(model, rng, columns=(), random_columns=6):
    """The structured Jacobians of ``model`` at a perturbed state and rates against plain
    complex steps on the whole residual (1e-9 of the largest entry) and central differences
    (step 1e-6; 1e-5) on the rigid columns, ``columns`` and ``random_columns`` random ones.
    A second state, rates and time check the blocks whose dR/dydot the model computes once
    and reuses (TurbineModel._block_jacobians, constant_rates)."""
    for tt, size in ((1.9, 3e-2), (0.37, 1e-3)):    # the second is the one checked below
        y = model.initial_guess() + size * rng.standard_normal(model.n)
        yd = size * rng.standard_normal(model.n)
        Jy, Jd = model.jacobians(yd, y, tt)
        Ry, Rd = model.jacobians_reference(yd, y, tt)
        for J, Jr in ((Jy, Ry), (Jd, Rd)):
            assert abs(J - Jr).max() <= 1e-9 * abs(Jr).max()
    cols = list(range(model.nq + model.nu)) + list(columns) + list(
        rng.choice(model.n, random_columns, replace=False))
    dense = Jy.toarray()
    for c in cols:
        h = 1e-6 * max(1.0, abs(y[c]))
        yp, ym = y.copy(), y.copy()
        yp[c] += h
        ym[c] -= h
        fd = (model.residual(yd, yp, tt) - model.residual(yd, ym, tt)) / (2 * h)
        assert np.abs(fd - dense[:, c]).max() <= 1e-5 * max(1.0, np.abs(dense).max())


def test_in_a_vacuum_nothing_changes():
    """Reference: the model without wind (the paper's): the residual of a turbine with an
    aerodynamics section and no wind equals that of the same turbine without the section
    (exactly), so every structural result (Table 2) is unchanged."""
    t = teetering_rotor(stiffness=1.0, gravity=True, tilt=0.1, yaw_free=True)
    bare = replace(t, aerodynamics=None)
    a, b = TurbineModel(t, elements=3), TurbineModel(bare, elements=3)
    y = a.initial_guess() + 1e-3 * np.random.default_rng(0).standard_normal(a.n)
    assert np.array_equal(a.residual(0 * y, y, 0.3), b.residual(0 * y, y, 0.3))
    assert a.aero is None


def test_wind_needs_an_aerodynamics_section_and_an_upwind_direction():
    """Bad input: a turbine without aerodynamics in wind, and a wind from behind the rotor,
    are refused naming the field."""
    with pytest.raises(ValueError, match="no aerodynamics section"):
        TurbineModel(load_turbine(), elements=2, wind=Wind(8.0))
    with pytest.raises(ValueError, match="direction"):
        TurbineModel(teetering_rotor(), elements=2, wind=Wind(8.0, direction=np.radians(120)),
                     inductions=(np.zeros((2, 3)), np.zeros((2, 3))))


def _captured_relative_wind(model, y, t):
    """The relative air velocity W (N, G, beams, 3) the strips saw in one residual call."""
    seen = {}
    loads = model.aero.strips.loads

    def spy(W, alpha=None):
        seen["W"] = W
        return loads(W, alpha)
    model.aero.strips.loads = spy
    try:
        model.residual(np.zeros(model.n), y, t)
    finally:
        model.aero.strips.loads = loads
    return seen["W"]


def test_shear_and_tower_shadow_reach_each_gauss_point():
    """Reference: the geometry by hand.  The teetering rotor (no tilt, precone or pitch,
    blades undeformed in rigid rotation, inductions zero) at azimuth 0: blade 0 points up, its
    Gauss points at height z0 + e + x, blade 1's at z0 - e - x; the axial component of the
    relative wind there is the power law U (z / z_ref)^alpha (1e-12), and with a tower shadow
    below the tower top the potential flow's 1 - R^2 / d^2 at the rotor's distance d from the
    tower axis (1e-12).  A uniform wind written as a field (a constant history) gives the
    uniform path's residual exactly (1e-13): positions and rotations of both paths agree."""
    t = teetering_rotor()
    n = 3
    zero = (np.zeros((n, 3)), np.zeros((n, 3)))
    z0 = 30.0
    shear = Wind(8.0, shear_exponent=0.2, reference_height=z0, origin_height=z0)
    model = TurbineModel(t, elements=n, wind=shear, inductions=zero)
    y = model.initial_guess()
    W = _captured_relative_wind(model, y, 0.0)
    x = model.beam.xg[..., 0] if model.beam.xg.ndim == 3 else model.beam.xg
    e = t.hub.radius
    up = shear.speed * ((z0 + e + x) / z0) ** 0.2
    down = shear.speed * ((z0 - e - x) / z0) ** 0.2
    assert np.allclose(W[:, :, 0, 2], up, rtol=1e-12, atol=0)
    assert np.allclose(W[:, :, 1, 2], down, rtol=1e-12, atol=0)
    R_t = 1.5
    shadow = Wind(8.0, tower_radius=R_t)
    model = TurbineModel(t, elements=n, wind=shadow, inductions=zero)
    W = _captured_relative_wind(model, y, 0.0)
    d = t.nacelle.yaw_to_teeter
    assert np.allclose(W[:, :, 1, 2], 8.0 * (1 - R_t ** 2 / d ** 2), rtol=1e-12, atol=0)
    assert np.allclose(W[:, :, 0, 2], 8.0, rtol=1e-12, atol=0)
    tilted = teetering_rotor(stiffness=1.0, gravity=True, tilt=0.1, yaw_free=True)
    rng = np.random.default_rng(5)
    a = TurbineModel(tilted, elements=n, wind=Wind(7.0, direction=0.2), inductions=zero)
    b = TurbineModel(tilted, elements=n, wind=Wind(7.0, direction=0.2,
                                                    history=((0.0, 1.0), (99.0, 1.0))),
                     inductions=zero)
    assert b.aero.field and not a.aero.field
    yy = a.initial_guess() + 1e-2 * rng.standard_normal(a.n)
    ra, rb = a.residual(0 * yy, yy, 0.4), b.residual(0 * yy, yy, 0.4)
    assert np.abs(ra - rb).max() <= 1e-13 * np.abs(ra).max()


def test_simulated_teeter_decay_is_locks_damping():
    """Reference: Lock's damping again (first test), now from the nonlinear time simulation
    (implicit midpoint, 1 deg steps) of the stiff flat-plate rotor in 1 mm/s wind: a 0.01 rad
    teeter perturbation decays as exp(-C t / (2 I)); the log-decrement of the teeter peaks
    over three revolutions gives C / (2 I) within 0.5 % (found 0.14 %: the nonlinear
    amplitude, the step)."""
    from hawt_core.solvers.march import Simulator
    from test_simulate import decay_rate
    t = teetering_rotor()
    n = 4
    model = TurbineModel(t, elements=n, wind=Wind(1e-3),
                         inductions=(np.zeros((n, 3)), np.zeros((n, 3))))
    omega = t.rotor.speed
    e, R = t.hub.radius, t.hub.radius + t.blade.length
    m = float(np.mean(t.blade.sections.mass))
    inertia = 2 * m * (R ** 3 - e ** 3) / 3 + t.hub.inertia_lateral
    rate = 2 * 0.5 * RHO * LIFT_SLOPE * CHORD * omega * (R ** 4 - e ** 4) / 4 / (2 * inertia)
    sim = Simulator(model, step_deg=1.0, perturb={"teeter": 0.01}, method="step")
    sim.run(3 * model.period)
    h = sim.history()
    found, peaks = decay_rate(h["time"], h["teeter"])
    assert peaks >= 2
    print(f"\nsimulated decay {found:.6f} 1/s, Lock {rate:.6f} 1/s")
    assert found == pytest.approx(rate, rel=5e-3)


def _shaft_totals(model, y, t=0.0):
    """(aerodynamic torque about the shaft axis through the hub centre SH [N m], thrust of
    blade 0 along it [N], blade 0's root force along it [N]) at the state y, from
    TurbineModel.aero_loads turned into N with the rigid frames (here, not in the code)."""
    F, M = model.aero_loads(y, t)
    q = y[:model.nq]
    fr = model.rigid.frames(q, t)
    B, s3 = fr["B"], fr["S"][:, 2]
    P = model.rigid.root_points(q, t) - model.rigid.teeter_point(fr)     # from SH, in N
    FN, MN = np.einsum("kij,kj->ki", B, F), np.einsum("kij,kj->ki", B, M)
    torque = float(sum(s3 @ (np.cross(P[k], FN[k]) + MN[k]) for k in range(len(F))))
    root = B[0] @ y[model.layout.blade(0).root_force]
    return torque, float(s3 @ FN[0]), float(s3 @ root)


def test_integrated_aerodynamic_loads_carry_the_shaft_torque_and_the_root_thrust():
    """Reference: the equilibrium of the steady state (NREL 5-MW, axisymmetric: rigid tower,
    no tilt or gravity; 8 m/s, 9.16 rpm): in steady rotation the inertial loads have no
    component along the shaft axis and no moment about it, so the aerodynamic loads
    integrated along the blades (TurbineModel.aero_loads, what the node's rotor_state
    carries) balance the shaft's torque (its twist x stiffness) and, along the shaft, each
    blade's root force, in the limit of the mesh.  The mixed elements converge to it at
    second order: torque 3.1e-3, 6.4e-4, 1.5e-4 apart at 8, 16, 32 elements (each < 1.3 x
    the h^2 bound 3.2e-3 (8 / N)^2; ratio of successive errors > 3.5), thrust < 2e-4 and
    decreasing.  In a vacuum the loads are zero."""
    t = axisymmetric(nrel5mw())
    errors = []
    for n in (8, 16, 32):
        model = TurbineModel(t, elements=n, wind=Wind(8.0))
        y = constant_steady_state(model)
        torque, thrust, root = _shaft_totals(model, y)
        shaft = t.drivetrain.stiffness * y[model.layout["shaft_twist"]]
        assert torque > 1e6                             # ~2 MN m: the rotor drives the shaft
        errors.append((abs(torque / shaft - 1), abs(thrust / root - 1)))
    for n, (e_torque, e_thrust) in zip((8, 16, 32), errors):
        assert e_torque < 1.3 * 3.2e-3 * (8 / n) ** 2 and e_thrust < 2e-4, errors
    assert errors[0][0] / errors[1][0] > 3.5 and errors[1][0] / errors[2][0] > 3.5, errors
    assert errors[0][1] > errors[1][1] > errors[2][1], errors
    vacuum = TurbineModel(t, elements=4)
    F, M = vacuum.aero_loads(vacuum.initial_guess(), 0.0)
    assert not F.any() and not M.any()
