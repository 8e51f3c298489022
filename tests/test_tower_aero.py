"""The flexible tower's aerodynamic drag in the one residual (assembly/tower_aero.py, AeroDyn's
TwrAero tower table as model.TowerAerodynamics).

References (each test states its tolerance):
* static equilibrium: in a steady state the drag's resultant reaches the ground, so the
  tower's root force and moment change by the integrals of 1/2 rho C_d D U(z)^2 (and times
  the height z) over the tower, computed in the test by adaptive quadrature of the deck's
  table (piecewise linear) and the power law, whatever the tower's stiffness;
* the drag's linearization, the aerodynamic damping of a section per unit length:
  rho C_d D U for motion along the wind and 1/2 rho C_d D U across it (d(|W| W)/dW of
  quadratic drag), derived by hand in the test;
* complex steps on the whole residual and central differences (structured Jacobians);
* the OpenFAST deck's own table (TwrElev, TwrDiam, TwrCd) read with numpy in the test.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import quad

from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.assembly.tower_aero import TowerDrag
from hawt_core.solvers.periodic import periodic_steady_state

from test_turbine_aero import check_structured_jacobians, nrel5mw

RHO = 1.225


def upright(t, rpm=12.1, pitch_deg=9.18):
    """``t`` with its flexible tower, no tilt or gravity, yaw locked: axisymmetric in axial
    wind, so the steady state is constant (default: ROSCO's operating point at 15 m/s)."""
    return replace(t, gravity=replace(t.gravity, enabled=False),
                   nacelle=replace(t.nacelle, yaw_free=False, shaft_tilt=0.0),
                   rotor=replace(t.rotor, speed=rpm * np.pi / 30, pitch=-np.radians(pitch_deg)))


def _root_loads(turbine, wind, elements=4):
    """The tower's root force and moment averaged over the periodic steady state's
    collocation times (the deflected tower tilts the shaft out of the wind: periodic), where
    the rates' means vanish and the mean loads balance."""
    model = TurbineModel(turbine, elements=elements, wind=wind)
    y = periodic_steady_state(model, harmonics=2).states.mean(axis=0)
    tl = model.layout.tower()
    return y[tl.root_force], y[tl.root_moment]


def test_the_drag_reaches_the_ground_as_the_integral_of_the_tower_table():
    """Reference: statics.  The NREL 5-MW (its deck's tower table: D 6 to 3.87 m, C_d 1) on
    its flexible tower at its 15 m/s operating point: the root force and moment (means over
    the steady state's period) with the drag minus those without are int 1/2 rho C_d D U^2 dz along the wind and
    int (...) z dz about the lateral axis (quad on the table's linear pieces), within 1e-3
    (the rotor's loads turned by the extra tower-top tilt: 4e-5 and 3e-5 found); no
    lateral force (1e-3 of the drag; 4e-5 found).  In a
    sheared wind each Gauss point feels U (z / z_ref)^0.2 at its own height above the
    ground, N's origin being the tower top at ``origin_height`` (1e-12)."""
    t = upright(nrel5mw())
    ta = t.tower_aerodynamics
    assert ta is not None and t.tower is not None
    H = t.tower.length
    wind = Wind(15.0)
    f1, m1 = _root_loads(t, wind)
    f0, m0 = _root_loads(replace(t, tower_aerodynamics=None), wind)
    z = ta.stations * H

    def q(x):
        return 0.5 * RHO * np.interp(x, z, ta.drag) * np.interp(x, z, ta.diameter) * 15.0 ** 2
    force = sum(quad(q, a, b)[0] for a, b in zip(z[:-1], z[1:]))
    moment = sum(quad(lambda x: q(x) * x, a, b)[0] for a, b in zip(z[:-1], z[1:]))
    dF, dM = f1 - f0, m1 - m0
    assert abs(dF[2]) == pytest.approx(force, rel=1e-3)
    assert abs(dM[1]) == pytest.approx(moment, rel=1e-3)
    assert abs(dF[1]) <= 1e-3 * force
    assert force > 2e4                        # ~30 kN on the NREL 5-MW's tower at 15 m/s
    sheared = Wind(15.0, shear_exponent=0.2, reference_height=90.0, origin_height=H + 2.0)
    model = TurbineModel(t, elements=4, wind=sheared)
    beam = model.tower
    N, G = beam.xg.shape
    pos = np.zeros((N, G, 1, 3))
    pos[..., 0, 0] = beam.xg
    f, _ = model.tower_drag.section_loads(np.zeros(1))(
        {"V": np.zeros((N, G, 1, 3)), "theta": np.zeros((N, G, 1, 3)), "position": pos})
    height = beam.xg + 2.0
    expected = q(beam.xg) * ((height / 90.0) ** 0.2) ** 2
    assert np.allclose(f[..., 0, 2], expected, rtol=1e-12, atol=0)


def test_the_linearized_drag_damps_along_wind_motion_twice_as_much_as_across():
    """Reference: d(|W_perp| W_perp)/dV by hand: per unit length, -rho C_d D U along the
    wind (n3) and -1/2 rho C_d D U across it (n2), no force along the tower axis and none
    from axial motion (1e-12, complex steps on TowerDrag's section loads at an undeformed
    tower in 15 m/s uniform wind)."""
    t = nrel5mw()
    model = TurbineModel(upright(t), elements=4, wind=Wind(15.0))
    drag = model.tower_drag
    beam = model.tower
    N, G = beam.xg.shape
    x = beam.xg
    pos = np.zeros((N, G, 1, 3), complex)
    pos[..., 0, 0] = x
    coef = drag.coefficient[..., 0]
    loads = drag.section_loads(np.zeros(1))
    h = 1e-30
    for axis, expected in ((2, -2 * coef * 15.0), (1, -coef * 15.0), (0, 0 * coef)):
        V = np.zeros((N, G, 1, 3), complex)
        V[..., 0, axis] = 1j * h
        f, m = loads({"V": V, "theta": np.zeros((N, G, 1, 3)), "position": pos})
        df = f[..., 0, :].imag / h
        assert np.allclose(df[..., axis], expected, rtol=1e-12, atol=0)
        others = [a for a in range(3) if a != axis]
        assert np.abs(df[..., others]).max() <= 1e-12 * np.abs(expected).max() + 1e-300
        assert np.all(m == 0)
    f, _ = loads({"V": np.zeros((N, G, 1, 3)), "theta": np.zeros((N, G, 1, 3)),
                  "position": pos.real})
    assert np.allclose(f[..., 0, 2], coef * 225.0, rtol=1e-12)
    assert np.all(f[..., 0, :2] == 0)
    # 1/2 rho C_d D from the deck's table at the Gauss points' heights
    table = t.tower_aerodynamics
    s = x / t.tower.length
    assert np.allclose(coef, 0.5 * RHO * np.interp(s, table.stations, table.drag)
                       * np.interp(s, table.stations, table.diameter), rtol=1e-14)


def test_jacobians_with_tower_drag_equal_complex_steps_and_differences():
    """Reference: plain coloured complex steps on the whole residual (1e-9) and central
    differences (1e-5): the NREL 5-MW with flexible tower and drivetrain in a sheared wind
    with a wind history (the drag at each tower Gauss point's height and time)."""
    t = replace(nrel5mw(), rotor=replace(nrel5mw().rotor, speed=1.0))
    wind = Wind(9.0, shear_exponent=0.2, history=((0.0, 1.0), (1.0, 1.2)))
    model = TurbineModel(t, elements=3, wind=wind)
    assert model.tower_drag is not None
    tl = model.layout.tower()
    check_structured_jacobians(model, np.random.default_rng(11),
                               columns=np.concatenate([tl.V[2], tl.u[3]]))


def test_the_deck_table_is_read_and_the_file_round_trips(tmp_path):
    """Reference: the deck's AeroDyn tower table read with numpy in the test (TwrElev over
    TowerHt, TwrDiam, TwrCd; exact), and hawt's own file: the shipped nrel5mw carries the same
    table, a dump/load round trip keeps it, a rigid tower or a negative diameter is refused
    naming the field; TwrAero = False in an edited deck gives no table."""
    import shutil

    import yaml
    from hawt_core.io import TurbineFileError, dump_turbine, turbine_from_dict
    from test_real_turbines import NREL, _edit, needs_decks

    t = nrel5mw()
    d = yaml.safe_load(dump_turbine(t))
    back = turbine_from_dict(d)
    for k in ("stations", "diameter", "drag"):
        assert np.array_equal(getattr(back.tower_aerodynamics, k),
                              getattr(t.tower_aerodynamics, k))
    bad = dict(d, tower_aerodynamics=dict(d["tower_aerodynamics"], diameter=-1.0))
    with pytest.raises(TurbineFileError, match=r"tower_aerodynamics\.diameter"):
        turbine_from_dict(bad)
    rigid = {k: v for k, v in d.items() if k != "tower"}
    with pytest.raises(TurbineFileError, match=r"tower_aerodynamics.*flexible tower"):
        turbine_from_dict(rigid)
    if needs_decks.args[0]:                      # no rosco wheel: the file part only
        return
    from hawt_core.io.openfast import read_openfast
    rows = []
    text = (NREL.parent / "NRELOffshrBsline5MW_Onshore_AeroDyn15.dat").read_text()
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if "NumTwrNds" in line)
    count = int(lines[start].split()[0])
    rows = np.array([[float(v) for v in lines[start + 3 + i].split()[:3]]
                     for i in range(count)])
    ta = read_openfast(NREL).turbine.tower_aerodynamics
    assert np.array_equal(ta.stations * 87.6, rows[:, 0]) or \
        np.allclose(ta.stations * 87.6, rows[:, 0], rtol=1e-15, atol=1e-12)
    assert np.array_equal(ta.diameter, rows[:, 1]) and np.array_equal(ta.drag, rows[:, 2])
    deck = tmp_path / "deck"
    shutil.copytree(NREL.parent, deck)
    _edit(deck / "NRELOffshrBsline5MW_Onshore_AeroDyn15.dat", "TwrAero", "False")
    assert read_openfast(deck / "NREL-5MW.fst").turbine.tower_aerodynamics is None


def test_tower_drag_needs_the_table_and_a_flexible_tower():
    """Bad input: TowerDrag without a table names what it needs; a model in a vacuum or on a
    rigid tower has none; the results' description names the tower drag and the skewed
    wake."""
    t = nrel5mw()
    with pytest.raises(ValueError, match="tower_aerodynamics"):
        TowerDrag(replace(t, tower_aerodynamics=None), None, Wind(8.0), RHO)
    assert TurbineModel(t, elements=2).tower_drag is None
    described = TurbineModel(t, elements=2, wind=Wind(8.0)).aero_description
    assert "tower drag" in described and "Pitt-Peters skewed wake" in described
    assert TurbineModel(replace(t, tower=None), elements=2,
                        wind=Wind(8.0)).tower_drag is None


def test_the_drag_of_a_round_tower_does_not_depend_on_the_wind_direction():
    """Reference: a circular cylinder in cross-flow: f = 1/2 rho C_d D |W_perp| W_perp with
    W_perp the flow normal to its axis, whatever its direction in that plane (no preferred
    axis) and whatever the flow along the axis.  At wind directions 0, 30, 90 and 200 deg
    about the tower axis the force per length has the magnitude 1/2 rho C_d D U^2 and the
    wind's direction (1e-12); a section tilted 10 deg (theta about b2) sees a flow component
    along its axis that adds no force along it and only W_perp's magnitude (1e-12).  A
    drag written with one component's magnitude (|W3| for |W_perp|) fails the 30 and 90 deg
    cases."""
    t = upright(nrel5mw())
    ta = t.tower_aerodynamics
    H = t.tower.length
    z = ta.stations * H
    model = TurbineModel(t, elements=4, wind=Wind(15.0))
    for deg in (0.0, 30.0, 90.0, 200.0):
        wind = Wind(15.0, direction=np.radians(deg))
        model.tower_drag.set_wind(wind)           # the tower's drag alone, in that wind
        beam = model.tower
        N, G = beam.xg.shape
        pos = np.zeros((N, G, 1, 3))
        pos[..., 0, 0] = beam.xg
        coef = 0.5 * RHO * np.interp(beam.xg, z, ta.drag) * np.interp(beam.xg, z, ta.diameter)
        zero = np.zeros((N, G, 1, 3))
        for tilt in (0.0, np.radians(10.0)):
            theta = zero.copy()
            theta[..., 0, 1] = 2 * np.tan(tilt / 2)      # Rodrigues parameters
            f, m = model.tower_drag.section_loads(np.zeros(1))(
                {"V": zero, "theta": theta, "position": pos})
            assert np.all(f[..., 0, 0] == 0) and np.all(m == 0)
            if tilt == 0.0:
                assert np.allclose(np.linalg.norm(f[..., 0, :], axis=-1), coef * 15.0 ** 2,
                                   rtol=1e-12, atol=0), deg
                U = wind.velocity(np.zeros((N, G)), pos[..., 0, :] - [H, 0.0, 0.0])
                cosine = np.sum(f[..., 0, :] * U, -1) / (np.linalg.norm(f[..., 0, :], axis=-1)
                                                         * np.linalg.norm(U, axis=-1))
                assert np.allclose(cosine, 1.0, rtol=0, atol=1e-12), deg
            else:
                # the flow in the tilted section's frame, by the rotation written here
                c, s = np.cos(tilt), np.sin(tilt)
                R2 = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])    # frame turned about b2
                U = wind.velocity(np.zeros((N, G)), pos[..., 0, :] - [H, 0.0, 0.0])
                Ws = U @ R2.T
                perp = np.linalg.norm(Ws[..., 1:], axis=-1)
                assert np.allclose(np.linalg.norm(f[..., 0, :], axis=-1), coef * perp ** 2,
                                   rtol=1e-12, atol=0), deg
