"""Dynamic inflow and unsteady-airfoil states on the whole turbine (assembly/rotor_aero.py,
TurbineModel(inflow="oye", airfoil="jones")): unknowns after each blade's beam unknowns in the
one residual.

References, each test stating its tolerance:
* the aeroelastic blade on the spinning hub (assembly/aero_blade.py, a separate assembly with
  its own induction rows): with no rigid freedom the turbine's three blades are three copies
  of it, so its eigenvalues (Oye inflow; and the algebraic momentum balance for Oye's time
  constants going to zero) are the turbine's;
* the frozen wake (tests/test_turbine_aero.py's references): Oye's time constants going to
  infinity freeze the inductions;
* Lock's flap damping with Theodorsen's lag in Jones's approximation: the teeter exponent of
  a rigid flat-plate rotor solves ``I lam^2 + D(lam) lam + K = 0`` with ``D(lam)`` the
  integral over the blades of the circulatory lift's transfer function at the local reduced
  Laplace variable ``lam b / (Omega r)`` (written in the test);
* complex steps on the whole residual and central differences (Jacobians);
* the axisymmetric BEM steady state (the frozen wake's inductions), which the dynamic states
  must settle on.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sl

from hawt_core.aero.inflow import OYE_K
from hawt_core.aero.unsteady import JONES, IndicialLag
from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.assembly.aero_blade import AeroelasticBlade
from hawt_core.solvers.steady import constant_steady_state
from test_turbine_aero import (CHORD, LIFT_SLOPE, RHO, axisymmetric, check_structured_jacobians,
                               nrel5mw, rigid_teeter, teeter_exponent, teetering_rotor)


def finite_eigenvalues(E, A, limit=1e5):
    lam = sl.eigvals(A, E)
    return lam[np.isfinite(lam) & (np.abs(lam) < limit)]


def turbine_eigenvalues(model):
    y = constant_steady_state(model)
    E, A = (M.toarray() for M in model.linearize(y))
    return finite_eigenvalues(E, A), y


def blade_eigenvalues(blade):
    """The aeroelastic blade's finite eigenvalues by complex steps of its residual."""
    y = blade.steady_state()
    n, h = blade.n, 1e-30
    Jy = blade.residual(np.zeros((n, n)), y + 1j * h * np.eye(n)).imag.T / h
    Jd = blade.residual(1j * h * np.eye(n), np.broadcast_to(y, (n, n))).imag.T / h
    return finite_eigenvalues(Jd, -Jy)


def mismatch(a, b):
    """Largest distance from an eigenvalue of ``a`` to the nearest of ``b``, relative to
    max(1, |lam|) [-]."""
    return max(np.min(np.abs(x - b)) / max(1.0, abs(x)) for x in a)


def clamped_nrel(elements=4):
    """The NREL 5-MW, axisymmetric (rigid tower, no tilt or gravity, yaw locked) with a rigid
    shaft: no rigid freedom at all, the blades clamped to a hub spinning at 9.16 rpm.
    Undamped structure: these tests compare aerodynamic routes by dense QZ, whose noise on a
    pencil with structural damping is ~1e-6 (docs/structural_damping.md)."""
    t = axisymmetric(nrel5mw()).without_structural_damping()
    return replace(t, drivetrain=replace(t.drivetrain, stiffness=None))


def test_dynamic_states_settle_on_the_bem_steady_state():
    """Reference: the axisymmetric BEM steady state of the frozen-wake model.  NREL 5-MW at
    8 m/s, 8 elements, flexible drivetrain: with Oye's inflow the steady state has the
    frozen inductions (1e-8), Oye's first stages at (1 - k) of them (1e-12), and the same
    shaft twist (the rotor torque) within 1e-9; with Jones's airfoil too, every lag state is
    at its station's angle of attack (1e-10 rad: the steady state's Newton tolerance; the
    last step lands them within 2e-12 or closer) and the inductions within 1e-5, the
    twist 1e-6 (the pitch-rate terms read the Gauss points' angular velocity, which matches
    the rigid spin only to the discretization: 6e-5 rad/s at 8 elements, 2.4e-7 at 32);
    the aerodynamic unknowns are named per blade."""
    t = axisymmetric(nrel5mw())
    frozen = TurbineModel(t, elements=8, wind=Wind(8.0))
    model = TurbineModel(t, elements=8, wind=Wind(8.0), inflow="oye", airfoil="jones")
    assert model.aero.state_names == ("a", "a_tangential", "a_filter", "a_tangential_filter",
                                      "alpha_lag1", "alpha_lag2")
    assert model.blade_size == model.beam.n + 6 * 8 * 3
    assert model.n == frozen.n + 3 * 6 * 8 * 3
    assert model.dynamic_dimension() == frozen.dynamic_dimension() + 3 * 6 * 8 * 3
    inflow = TurbineModel(t, elements=8, wind=Wind(8.0), inflow="oye")
    y0, y = constant_steady_state(frozen), constant_steady_state(model)
    a, ap = frozen.aero.inductions
    out = {}
    nb = model.beam.n
    twist = model.layout["shaft_twist"]
    for m, yy, tol in ((inflow, constant_steady_state(inflow), 1e-8), (model, y, 1e-5)):
        lay = m.layout
        for k in range(3):
            assert np.abs(yy[lay.aero_states_of(k, "a")] - a).max() < tol
            assert np.abs(yy[lay.aero_states_of(k, "a_tangential")] - ap).max() < tol
            assert np.abs(yy[lay.aero_states_of(k, "a_filter")]
                          - (1 - OYE_K) * yy[lay.aero_states_of(k, "a")]).max() < 1e-12
        assert yy[twist] == pytest.approx(y0[twist], rel=1e-9 if tol < 1e-6 else 1e-6)
    lay = model.layout
    assert lay.names()[lay.aero_states_of(2, "alpha_lag2")[7, 2]] == \
        "blade2.aero.alpha_lag2[8].3"
    # the lag states equal the quasi-steady angle of attack of the blades' own motion
    q = y[:model.nq]
    v, w = model.rigid.root_motion(q, y[model.nq:model.nq + model.nu], 0.0)
    yb = np.stack([y[lay.blade_offset(k):lay.blade_offset(k) + model.blade_size]
                   for k in range(3)])
    model._blade_residual(np.zeros_like(yb), yb, v, w, None,
                          model._air_flat(model._air(q, y[model.nq:model.nq + model.nu], 0.0), 3),
                          out)
    for k in range(3):
        for s in ("alpha_lag1", "alpha_lag2"):
            assert np.abs(y[lay.aero_states_of(k, s)] - out["alpha"][..., k]).max() < 1e-10
    assert yb[0, nb:].size == model.n_aero


def test_oye_inflow_on_the_turbine_is_the_aeroelastic_blades():
    """Reference: the aeroelastic blade on the spinning hub (its own momentum rows and Oye
    filters).  NREL 5-MW, 8 m/s, 4 elements, no rigid freedom: every finite eigenvalue of
    the turbine with Oye's inflow is one of the blade's with Oye's inflow, and back, within
    1e-7 (found 3e-9); with Oye's time constants 1e-6 of theirs the turbine's eigenvalues of
    the structure (|lam| < 200 1/s; the inflow's own are at -1e6 / tau) approach the blade's
    with the algebraic momentum balance (quasi-steady inflow) within 1e-4, and with time
    constants 1e6 of theirs they approach the frozen wake's within 1e-4 (the inflow's own
    eigenvalues then near zero); frozen and quasi-steady differ by more than 1e-2."""
    t = clamped_nrel()
    n = 4
    model = TurbineModel(t, elements=n, wind=Wind(8.0), inflow="oye")
    assert model.nq == model.nu == 0
    lam, _ = turbine_eigenvalues(model)
    blade = AeroelasticBlade(t, 8.0, elements=n, inflow="oye")
    lam_b = blade_eigenvalues(blade)
    assert model.aero.tau1 == pytest.approx(blade.tau1, rel=1e-8)
    assert len(lam) == 3 * len(lam_b) == model.dynamic_dimension()
    assert mismatch(lam, lam_b) < 1e-7 and mismatch(lam_b, lam) < 1e-7

    def structural(x):
        return x[(np.abs(x) < 200) & (np.abs(x) > 0.1)]

    quasi = structural(blade_eigenvalues(AeroelasticBlade(t, 8.0, elements=n)))
    frozen = structural(turbine_eigenvalues(TurbineModel(t, elements=n, wind=Wind(8.0)))[0])
    for factor, reference in ((1e-6, quasi), (1e6, frozen)):
        m = TurbineModel(t, elements=n, wind=Wind(8.0), inflow="oye")
        m.aero.tau1 *= factor
        m.aero.tau2 = m.aero.tau2 * factor
        found = structural(turbine_eigenvalues(m)[0])
        assert mismatch(reference, found) < 1e-4
    assert mismatch(quasi, frozen) > 1e-2


def test_oye_inflow_after_a_wind_step_settles_on_the_new_bem_state():
    """Reference: the aeroelastic blade's quasi-steady BEM state at the new wind speed (a
    separate assembly with algebraic momentum rows).  The NREL 5-MW with no rigid freedom and
    blades 1e3 times stiffer, Oye's inflow with both time constants scaled by 0.02 (tau1 0.3
    s), 4 elements, in the steady state at 8 m/s; the wind steps to 8.5 m/s in 10 ms; after
    4 s (13 tau1) of simulation (0.5 deg steps) the axial inductions are the blade's at
    8.5 m/s within 5e-5 (found 1e-5; the change is 0.027; with the momentum balance at the
    initial wind speed instead of each element's own the error is 0.06), and at the end of
    the 10 ms ramp every station has covered less than a quarter of its change (the lag)."""
    from hawt_core.solvers.march import Simulator
    t = clamped_nrel()
    sec = t.blade.sections
    t = replace(t, blade=replace(t.blade, sections=replace(
        sec, ei2=sec.ei2 * 1e3, ei3=sec.ei3 * 1e3, gj=sec.gj * 1e3)))
    n = 4
    start = TurbineModel(t, elements=n, wind=Wind(8.0), inflow="oye")
    y0 = constant_steady_state(start)
    step = Wind(8.0, history=((0.0, 1.0), (0.01, 8.5 / 8.0), (1e3, 8.5 / 8.0)))
    model = TurbineModel(t, elements=n, wind=step, inflow="oye",
                         inductions=start.aero.inductions)
    model.aero.tau1 *= 0.02
    model.aero.tau2 = model.aero.tau2 * 0.02
    blade = AeroelasticBlade(t, 8.5, elements=n)
    a_new = blade.inductions(blade.steady_state())[0]
    sim = Simulator(model, step_deg=0.5, y0=y0, record=False)
    ia = model.layout.aero_states_of(0, "a")
    change = a_new - y0[ia]
    assert np.abs(change).max() > 0.02
    sim.run(0.01)                     # the end of the wind's ramp (0.03 tau1)
    big = np.abs(change) > 1e-3
    assert np.all(np.abs((sim.y[ia] - y0[ia])[big] / change[big]) < 0.25)
    sim.run(4.0 - sim.t)
    for k in range(3):
        assert np.abs(sim.y[model.layout.aero_states_of(k, "a")] - a_new).max() < 5e-5


def test_jones_lag_gives_locks_teeter_damping_with_theodorsens_lag():
    """Reference: the teeter exponent of a rigid flat-plate rotor whose circulatory lift lags
    as Jones's approximation of Theodorsen's C(k) says, the root of ``I lam^2 + D(lam) lam +
    I w_n^2 = 0`` with ``D(lam) = 2 int_e^R (rho/2) 2 pi c Omega r^3 T(lam b / (Omega r))
    dr`` (T(s) = 1 - sum A_i s / (s + b_i); Gauss-Legendre, 400 points; Newton on the scalar
    equation) for the paper's teetering rotor with blades 1e4 times stiffer (module
    docstring of tests/test_turbine_aero.py), the air's added inertia (Theodorsen's
    non-circulatory lift, 2 int pi rho b^2 r^2 dr: 0.36 % of the rotor's) in ``I``: real part
    within 1e-5 (found 1.5e-7), frequency within 1e-6 (found 1e-7; blades 1e3 times stiffer
    bend under the air's inertia by 1.2e-6); the quasi-steady airfoil (no lag, no added mass)
    misses the real part by 4 %."""
    t = teetering_rotor(stiffness=1e4)
    n = 4
    omega = t.rotor.speed
    e, L = t.hub.radius, t.blade.length
    inertia, wn2 = rigid_teeter(t)
    x, wq = np.polynomial.legendre.leggauss(400)
    r, wq = e + (x + 1) / 2 * L, wq * L / 2
    semichord = CHORD / 2

    def damping(lam):
        s = lam * semichord / (omega * r)
        T = 1 - sum(Ai * s / (s + bi) for Ai, bi in zip(JONES.A, JONES.b))
        return 2 * 0.5 * RHO * LIFT_SLOPE * CHORD * omega * np.sum(wq * r ** 3 * T)

    # the air's added inertia about the teeter axis: Theodorsen's non-circulatory lift
    # pi rho b^2 h'' with h'' = r beta'' on both blades
    added = 2 * np.pi * RHO * semichord ** 2 * np.sum(wq * r ** 2)

    def f(lam):
        return (inertia + added) * lam ** 2 + damping(lam) * lam + inertia * wn2

    lam = 1j * np.sqrt(wn2)
    for _ in range(20):
        h = 1e-7
        lam = lam - f(lam) / ((f(lam + h) - f(lam - h)) / (2 * h))
    assert abs(f(lam)) < 1e-9 * inertia * wn2
    found = {}
    for airfoil in ("quasi-steady", "jones"):
        found[airfoil] = teeter_exponent(TurbineModel(
            t, elements=n, wind=Wind(1e-3), airfoil=airfoil,
            inductions=(np.zeros((n, 3)), np.zeros((n, 3)))))
    assert found["jones"].real == pytest.approx(lam.real, rel=1e-5)
    assert found["jones"].imag == pytest.approx(lam.imag, rel=1e-6)
    assert abs(found["quasi-steady"].real / lam.real - 1) > 0.03


def test_jones_airfoil_on_a_parked_blade_is_theodorsens_wing():
    """Reference: the cantilever wing of assembly/wing.py (Theodorsen's thin-airfoil loads,
    circulatory lift driven by the three-quarter-chord downwash through Jones's lag, the
    added-mass lift and moment, written for a straight wing in a stream with its own
    kinematics: h'' = -(V' + Omega x V)3, alpha' = Omega1) on the same beam, chord, axis,
    lift slope and air: Goland's wing (elastic axis 0.34 semi-chords ahead of mid-chord, so
    the aerodynamic centre lies 0.16 b ahead of the reference line) as the three blades of a
    parked rotor (0 rpm, no cone, clamped to the hub, pitched -90 deg so the chord lies along
    the wind, a flat-plate polar cl = 2 pi alpha acting at the quarter chord), 8 elements,
    in 100 m/s and 140 m/s (flutter at 147 m/s): every eigenvalue of the wing within 1e-7 of
    max(1, |lam|) of one of the turbine's (found 2e-8, dense QZ) and back, the turbine's
    below 300 1/s (its rotor and hub modes aside)."""
    from hawt_core.assembly.wing import WingModel
    from hawt_core.io.wing_yaml import load_wing
    from hawt_core.model import Aerodynamics, Polar
    from pathlib import Path
    wing = load_wing(Path(__file__).resolve().parents[1] / "hawt_core" / "data"
                     / "goland_wing.yaml")
    b, a, n = wing.chord / 2, wing.axis_semichords, 8
    slope = wing.lift_slope
    plate = Polar("flat plate", [-0.5, 0.5], [-0.5 * slope, 0.5 * slope], [0, 0], [0, 0])
    aero = Aerodynamics(stations=[0.0, 1.0], chord=[wing.chord] * 2, twist=[0.0, 0.0],
                        airfoil=[0, 0], polars=(plate,), skew_factor=0.0,
                        ac_chordwise=[(a + 0.5) * b] * 2)
    t = clamped_nrel()
    t = replace(t, blade=replace(wing.beam, elements=n), aerodynamics=aero,
                rotor=replace(t.rotor, speed=0.0, precone=0.0, pitch=-np.pi / 2))
    for speed in (100.0, 140.0):
        model = TurbineModel(t, wind=Wind(speed), rho=wing.density, airfoil="jones",
                             inductions=(np.zeros((n, 3)), np.zeros((n, 3))))
        found, _ = turbine_eigenvalues(model)
        reference = WingModel.from_wing(wing, elements=n).eigenvalues(speed)
        reference = reference[np.abs(reference) < 1e5]
        assert mismatch(reference, found) < 1e-7
        assert mismatch(found[np.abs(found) < 300], reference) < 1e-7


def test_structured_jacobians_with_aerodynamic_states():
    """Reference: plain coloured complex steps on the whole residual and central differences
    (step 1e-6), within 1e-9 and 1e-5 of the largest entry: the teetering rotor with free
    yaw, gravity, tilt and a 15 deg yaw misalignment, and the NREL 5-MW with its flexible
    tower in a sheared wind, both with Oye's inflow and Jones's lag, at a perturbed state
    and rates (every aerodynamic row reached)."""
    cases = [
        (teetering_rotor(stiffness=1.0, gravity=True, tilt=0.1, yaw_free=True), 2,
         Wind(7.0, direction=np.radians(15.0))),
        (replace(nrel5mw(), rotor=replace(nrel5mw().rotor, speed=1.0)), 2,
         Wind(9.0, shear_exponent=0.2))]
    rng = np.random.default_rng(5)
    for t, n, wind in cases:
        model = TurbineModel(t, elements=n, wind=wind, inflow="oye", airfoil="jones")
        aero_cols = [model.layout.aero_states_of(k, s)[0, 1] for k in range(model.n_blades)
                     for s in model.aero.state_names]
        check_structured_jacobians(model, rng, aero_cols, random_columns=4)


def test_aerodynamic_model_names_are_checked_and_a_vacuum_has_no_states():
    """Bad model names fail naming the field and the choices; in a vacuum (and with the
    default frozen, quasi-steady model) a blade's block is its beam's."""
    t = axisymmetric(nrel5mw())
    with pytest.raises(ValueError, match="inflow: 'pitt' is not allowed; choose one of "
                                         "frozen, oye"):
        TurbineModel(t, elements=2, wind=Wind(8.0), inflow="pitt")
    with pytest.raises(ValueError, match="airfoil: 'bl' is not allowed"):
        TurbineModel(t, elements=2, wind=Wind(8.0), airfoil="bl")
    for kw in ({}, {"wind": Wind(8.0)}):
        m = TurbineModel(t, elements=2, **kw)
        assert m.blade_size == m.beam.n and m.n_aero == 0
    assert IndicialLag().states == JONES.states == 2


def test_modes_with_inflow_states_name_the_inflow_modes():
    """The NREL 5-MW, axisymmetric (rigid tower, no tilt or gravity, yaw locked) at 8 m/s,
    2 elements, Oye's inflow (multi-blade coordinates, time-invariant): the non-oscillatory
    modes led by the induction states (most of the modes below 3 per-rev: 48) are labelled
    ``aerodynamic`` (symmetry ``inflow``), hidden from the table with their count, and every
    other mode is structural; the settings name the model."""
    from hawt_core.analyses.modal import modal_analysis
    t = axisymmetric(nrel5mw())
    res = modal_analysis(t, elements=2, wind=Wind(8.0), inflow="oye", max_per_rev=3.0,
                         method="hill")
    aero = [m for m in res.modes if m.family == "aerodynamic"]
    assert len(aero) > len(res.modes) / 2
    assert all(m.symmetry == "inflow" and abs(m.frequency_per_rev) < 1e-3 for m in aero)
    table = res.table()
    assert f"({len(aero)} non-oscillatory modes of the blades' aerodynamic states" in table
    listed = table.split("\n")[2:-3]
    assert len(listed) == len(res.modes) - len(aero)
    assert {m.family for m in res.modes} - {"aerodynamic"} <= {
        "flap", "lag", "torsion", "drivetrain", "axial", "shear"}
    assert res.settings["inflow"] == "oye" and "Oye dynamic inflow" in \
        res.settings["aerodynamics"]


def test_commands_take_the_aerodynamic_model_and_refuse_it_without_wind(tmp_path, capsys):
    """``hawt simulate FILE --wind U --inflow oye --airfoil jones``: a short simulation with
    the states runs and reports finite values; ``--inflow`` and ``--airfoil`` without
    ``--wind`` (modes, campbell, simulate, a wing's flutter) fail naming the flag, and a
    model name outside the choices is refused by the parser; ``modes --wind`` runs Oye +
    Jones unless told otherwise (the table's header says which)."""
    import json
    from hawt_core import cli
    from hawt_core.io import dump_turbine
    f = tmp_path / "rotor.yaml"
    f.write_text(dump_turbine(teetering_rotor(stiffness=1.0)))
    assert cli.main(["simulate", str(f), "--wind", "6", "--rotor-speed", "5", "-n", "2",
                     "--duration", "0.05", "--step-deg", "5", "--inflow", "oye",
                     "--airfoil", "jones", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["steps"] > 0 and all(np.isfinite(v) for v in out["final"].values())
    for argv in (["modes", str(f), "-n", "2", "--inflow", "oye"],
                 ["campbell", str(f), "--speeds", "1:2:2", "--airfoil", "jones"],
                 ["simulate", str(f), "--duration", "1", "--inflow", "oye"],
                 ["flutter", "goland", "--airfoil", "jones"]):
        assert cli.main(argv) != 0
        err = capsys.readouterr().err
        assert ("--inflow: only used with --wind" in err
                or "--airfoil: only used with --wind" in err), err
    assert cli.main(["modes", str(f), "--wind", "6", "--inflow", "pitt-peters"]) != 0
    assert "--inflow: invalid choice: 'pitt-peters'" in capsys.readouterr().err
    # the stability analyses' default in wind is HAWCStab2's kind (Oye + Jones); the frozen
    # wake with quasi-steady airfoils (OpenFAST's linearization) when asked
    point = ["modes", str(f), "--wind", "6", "--rotor-speed", "5", "-n", "2"]
    for extra, words in (([], ("Oye dynamic inflow", "Jones two-state")),
                         (["--inflow", "frozen", "--airfoil", "quasi-steady"],
                          ("frozen wake", "quasi-steady airfoils"))):
        assert cli.main(point + extra) == 0
        header = capsys.readouterr().out.splitlines()[0]
        assert all(w in header for w in words), header


def test_dynamic_inflow_follows_the_actual_rotor_speed():
    """Reference: invariance.  The same physical state written two ways: the NREL 5-MW
    (axisymmetric, free generator, Oye's inflow) at nominal speed Omega0 with the generator
    turning 8 % faster (generator_rate = 0.08 Omega0), and the same turbine at nominal speed
    1.08 Omega0 with generator_rate 0 (the initial BEM state's blades and inductions in
    both): the blades' unknowns and inductions identical, so the
    aerodynamic loads (the swirl a' Omega r and the quasi-steady inductions use the rotor's
    actual speed, rigid.rotor_spin) and the inflow rows agree to 1e-12 of their size; the
    swirl at the nominal speed would differ by 5e-4 (checked: it fails)."""
    from hawt_core.control.loop import free_generator
    t = free_generator(axisymmetric(nrel5mw()))
    w0 = t.rotor.speed
    A = TurbineModel(t, elements=4, wind=Wind(8.0), inflow="oye")
    B = TurbineModel(replace(t, rotor=replace(t.rotor, speed=1.08 * w0)), elements=4,
                     wind=Wind(8.0), inflow="oye")
    y = A.initial_guess()                   # the BEM state: blades deflected, inductions
    lay = A.layout
    assert np.abs(y[lay.aero_states_of(0, "a_tangential")]).max() > 1e-3
    ya, yb = y.copy(), y.copy()
    ya[lay["generator_rate"]] = 0.08 * w0
    yb[lay["generator_rate"]] = 0.0
    nq, nr = A.nq, A.nq + A.nu
    assert A.rigid.rotor_spin(ya[:nq], ya[nq:nr], 0.0) == pytest.approx(1.08 * w0, rel=1e-14)
    Fa, Ma = A.aero_loads(ya, 0.0)
    Fb, Mb = B.aero_loads(yb, 0.0)
    assert np.abs(Fa - Fb).max() <= 1e-12 * np.abs(Fa).max()
    assert np.abs(Ma - Mb).max() <= 1e-12 * np.abs(Ma).max()
    rows = np.concatenate([lay.aero_states_of(k, s).ravel() for k in range(3)
                           for s in A.aero.state_names])
    ra = A.residual(np.zeros(A.n), ya, 0.0)[rows]
    rb = B.residual(np.zeros(B.n), yb, 0.0)[rows]
    assert np.abs(ra - rb).max() <= 1e-12 * max(np.abs(ra).max(), 1.0)
