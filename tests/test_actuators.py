"""The turbine's actuators (hawt_core.rigid.actuators, RigidSystem.set_controls): pitch bearings
turning each blade's root frame by a known function of time, and the generator torque.

References, each test stating its tolerance:
* the blade mesh turned by the same pitch (fem/sections.py mesh_beam(pitch)): a different code
  path that must give the same turbine (steady state and eigenvalues);
* rigid-body dynamics of the pitch bearing: the root torsional moment of a stiff blade pitched
  back and forth is its polar inertia about the pitch axis times the pitch acceleration,
  the inertia integrated in the test from the section table;
* Newton's second law for the drivetrain: a constant generator torque T decelerates the rotor
  at N T / (J_rotor + N^2 J_gen), J_rotor integrated in the test from the section table.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import yaml

from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.io import dump_turbine, load_turbine, turbine_from_dict
from hawt_core.numerics.rotations import rot1
from hawt_core.rigid import ControlInputs
from hawt_core.solvers.march import Simulator
from test_rotor_aero_states import mismatch, turbine_eigenvalues
from test_turbine_aero import axisymmetric, nrel5mw


def stiff_paper_turbine(speed, stiffness=1e2, drivetrain=None):
    """The paper's turbine, blades ``stiffness`` times stiffer, hub fixed to the shaft, yaw
    locked, no gravity, spinning at ``speed`` [rad/s]."""
    d = yaml.safe_load(dump_turbine(load_turbine()))
    sec = d["blade"]["sections"]
    for k in ("gj", "ei2", "ei3"):
        sec[k] = float(sec[k]) * stiffness
    d["nacelle"].update(yaw_free=False)
    d["hub"].update(teeter=False)
    d["gravity"]["enabled"] = False
    d["rotor"]["speed"] = speed
    if drivetrain is not None:
        d["drivetrain"] = drivetrain
    return turbine_from_dict(d)


def section_integral(turbine, integrand, n=4001):
    """Integral over the blade span [m] of ``integrand(s, table)`` with the section table's
    values linearly interpolated (a dict of arrays at the points s [m])."""
    S, L = turbine.blade.sections, turbine.blade.length
    x = np.linspace(0.0, 1.0, n)
    tab = {k: np.interp(x, S.stations, getattr(S, k)) for k in ("mass", "i1", "i2", "i3")}
    cg = S.cg_offset if S.cg_offset is not None else np.zeros((S.n_stations, 2))
    tab["cg2"] = np.interp(x, S.stations, cg[:, 0])
    tab["cg3"] = np.interp(x, S.stations, cg[:, 1])
    return float(np.trapezoid(integrand(x * L, tab), x * L))


def test_pitch_bearing_turns_the_blade_as_a_pitched_mesh():
    """Reference: the blade mesh turned by the pitch (another code path).  NREL 5-MW,
    axisymmetric at 11 m/s, 4 elements, pitch 4 deg: the mesh at 0 deg with the pitch bearings
    at 4 deg has the same shaft twist (rotor torque) within 1e-9, the same tip displacement
    (turned into the same frame) within 1e-9 m, and the same eigenvalues within 1e-5
    (relative; the three blades' repeated eigenvalues split by round-off at ~1e-7); without
    the bearings they differ by more than 1e-2.  Undamped structure: the dense QZ of a
    pencil with structural damping (the section loads' rates) carries ~1e-5 noise on the
    high modes compared here (docs/structural_damping.md)."""
    t = axisymmetric(nrel5mw()).without_structural_damping()
    p = np.radians(4.0)
    pitched = TurbineModel(replace(t, rotor=replace(t.rotor, pitch=-p)), elements=4,
                           wind=Wind(11.0))
    flat = lambda: TurbineModel(t, elements=4, wind=Wind(11.0),
                                inductions=pitched.aero.inductions)
    driven = flat()
    driven.set_controls(ControlInputs(3, pitch=p))
    la, ya = turbine_eigenvalues(pitched)
    lb, yb = turbine_eigenvalues(driven)
    l0, _ = turbine_eigenvalues(flat())
    twist = pitched.layout["shaft_twist"]
    assert abs(ya[twist] - yb[twist]) < 1e-9 * abs(ya[twist])
    u = pitched.layout.blade(0).u[-1]
    # both root frames are turned by -p from the hub's (ElastoDyn's BlPitch sign)
    assert np.allclose(ya[u], rot1(-p) @ yb[u], rtol=0, atol=1e-9)
    assert max(mismatch(la, lb), mismatch(lb, la)) < 1e-5
    assert mismatch(la, l0) > 1e-2


def test_pitch_acceleration_needs_the_blade_polar_inertia():
    """Reference: rigid rotation about the pitch axis.  The paper's blade, 100x stiffer, on a
    hub at rest (1e-6 rad/s), no gravity, in a vacuum, pitched as beta = A (1 - cos w t)
    (A = 5 deg, w = 2 rad/s, steps of 0.01 s, the commands ramped per step): over two periods
    the root torsional moment on the hub, projected on cos(w t), is I_p A w^2 with
    I_p = int (i1 + m |cg|^2) ds within 1e-2 (the torsion mode at ~120 rad/s, excited by the
    start, is nearly orthogonal to it); its sin(w t) part is below 1e-2 of that."""
    t = stiff_paper_turbine(1e-6)
    model = TurbineModel(t, elements=4)
    controls = ControlInputs(2, pitch=0.0)
    model.set_controls(controls)
    A, w, h = np.radians(5.0), 2.0, 0.01
    sim = Simulator(model, step_seconds=h, method="step", record=False)
    root = sim._blades[0].root_moment
    times, moments = [], []
    for _ in range(int(round(2 * (2 * np.pi / w) / h))):
        t0 = sim.t
        controls.command(t0, t0 + h, pitch=A * (1 - np.cos(w * (t0 + h))))
        sim.run(h)
        times.append(sim.t)
        moments.append(sim.y[root][0])
    times, moments = np.array(times), np.array(moments)
    Ip = section_integral(t, lambda s, c: c["i1"] + c["mass"] * (c["cg2"] ** 2 + c["cg3"] ** 2))
    basis = np.stack([np.cos(w * times), np.sin(w * times)], 1)
    (a_cos, a_sin), *_ = np.linalg.lstsq(basis, moments, rcond=None)
    expected = Ip * A * w ** 2
    assert abs(a_cos - expected) < 1e-2 * expected
    assert abs(a_sin) < 1e-2 * expected


def test_generator_torque_decelerates_the_rotor_by_newtons_law():
    """Reference: d(Omega)/dt = -N T / (J_rotor + N^2 J_gen), J_rotor = Nb int (m (e + s)^2
    + i3) ds + the hub's polar inertia.  The paper's turbine (blades 100x stiffer, rigid hub,
    no precone or twist), a free generator behind a rigid shaft (N = 20, J_gen = 3 kg m^2),
    T = 40 N m ramped in from t = 0 to 0.2 s: the rotor speed after 2 s, within 1e-3 of the closed form's
    change; the generator speed is N times the rotor's."""
    N, Jg, T = 20.0, 3.0, 40.0
    t = stiff_paper_turbine(6.0, drivetrain={"generator": "free",
                                             "gearbox_ratio": N, "generator_inertia": Jg})
    model = TurbineModel(t, elements=4)
    controls = ControlInputs(2, pitch=-t.rotor.pitch)
    model.set_controls(controls)
    sim = Simulator(model, step_deg=2.0, record=False)   # from the steady state, T = 0
    controls.command(0.0, 0.2, torque=T)                 # ramped in 0.2 s: mean T t - 0.1 T
    sim.run(2.0)
    rate = sim.y[model.layout["generator_rate"]]
    e = t.hub.radius
    J = 2 * section_integral(t, lambda s, c: c["mass"] * (e + s) ** 2 + c["i3"]) \
        + t.hub.inertia_longitudinal
    expected = -N * T / (J + N * N * Jg) * (sim.t - 0.1)
    assert abs(rate - expected) < 1e-3 * abs(expected)


def test_controls_are_checked():
    """Bad controls name the field, the value and what is allowed."""
    t = stiff_paper_turbine(6.0)
    model = TurbineModel(t, elements=2)
    with pytest.raises(ValueError, match="controls: 3 blades"):
        model.set_controls(ControlInputs(3))
    with pytest.raises(ValueError, match="drivetrain.generator: free"):
        model.set_controls(ControlInputs(2, torque=1.0))
    with pytest.raises(ValueError, match=r"pitch: .* \(one per blade\)"):
        ControlInputs(2, pitch=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"within \+-pi/2"):
        ControlInputs(2, pitch=2.0)
    c = ControlInputs(2)
    with pytest.raises(ValueError, match="must be after"):
        c.command(1.0, 1.0, pitch=0.1)
    with pytest.raises(ValueError, match="torque: nan"):
        c.command(0.0, 1.0, torque=float("nan"))
    model.set_controls(c)
    assert model.controls is c
    with pytest.raises(ValueError, match="torque: 5.0 is not allowed; .* prescribed"):
        c.command(0.0, 1.0, torque=5.0)
    model.set_controls(None)
    assert model.controls is None
