"""Pitt and Peters' skewed-wake correction of the axial induction in yawed or tilted flow
(aero/inflow.py skew_angles, skewed_wake_factor; assembly/rotor_aero.py).

References (each test states its tolerance):
* the correction as AeroDyn v15 applies it (SkewRedistr_Mod = 1; D. M. Pitt and D. A.
  Peters, Vertica 5, 1981; Burton et al., Wind Energy Handbook, 2nd ed., section 4.2.6):
  a_skew = a (1 + K (r / R) tan(chi / 2) cos psi), chi = (1 + 0.6 a) chi0, K = 15 pi / 32,
  psi from the most downwind position; written out in the test with the yaw angle and the
  blade azimuth of the rotor's geometry (kinematics conventions of rigid/kane.py: n1 up, the
  wind turned about n1 from n3 by its direction, blade 0 along s1 = cos(psi) n1 +
  sin(psi) n2 without tilt or yaw);
* the physics it stands for: the downwind half of a yawed disk sees more induced velocity
  (Coleman's cylindrical wake), so there the angle of attack and the thrust are smaller, and
  the thrust difference yaws the rotor back towards the wind (a restoring yaw moment);
* complex steps against central differences at axial flow, where psi is undefined and the
  factor's smooth form is used.
"""
from __future__ import annotations

import shutil
from dataclasses import replace

import numpy as np
import pytest

from hawt_core.aero.inflow import skew_angles, skewed_wake_factor
from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel

from test_turbine_aero import _captured_relative_wind, teetering_rotor

ELEMENTS = 3
INDUCTION = 0.3

#: Pitt and Peters' constant as AeroDyn v15 states its default (SkewRedistrFactor "default" =
#: 15 pi / 32, "recommended by R. R. Damiani"; AeroDyn v15 input documentation), written here
#: so that the model's own constant (model.AERODYN_SKEW) is checked, not copied
AERODYN_SKEW = 15.0 * np.pi / 32.0

def _model(turbine, direction_deg, skew=AERODYN_SKEW):
    """The teetering rotor in 8 m/s wind at ``direction_deg`` with the frozen induction 0.3
    everywhere (no swirl) and the skewed-wake constant ``skew``."""
    aero = replace(turbine.aerodynamics, skew_factor=skew)
    shape = (ELEMENTS, 3)
    return TurbineModel(replace(turbine, aerodynamics=aero), elements=ELEMENTS,
                        wind=Wind(8.0, direction=np.radians(direction_deg)),
                        inductions=(np.full(shape, INDUCTION), np.zeros(shape)))


def test_the_induction_is_redistributed_over_the_yawed_disk_as_pitt_and_peters_say():
    """Reference: the formula with the test's own geometry.  The stiff teetering rotor (no
    tilt, precone or pitch), wind 20 deg off the shaft: at azimuth 90 deg blade 0 points along
    +n2, into the in-plane wind -U sin(gamma) n2 (upwind, cos psi = -1) and blade 1 along -n2
    (downwind, cos psi = +1); the relative wind's axial component at every Gauss point is
    U cos(gamma) (1 - a (1 -+ K (r / R) tan(chi / 2))), chi = (1 + 0.6 a) gamma (1e-12).  At
    azimuth 0 the blades are vertical (cos psi = 0): no change.  Yawed by gamma so that the
    shaft faces the wind: axial flow, no redistribution (the blade's actual attitude counts,
    not the wind's direction alone).  K = 0: the plain frozen induction everywhere."""
    t = teetering_rotor()
    gamma = np.radians(20.0)
    model = _model(t, 20.0)
    omega = t.rotor.speed
    y = model.initial_guess()
    x = model.beam.xg
    e, L = t.hub.radius, t.blade.length
    ratio = (e + x) / (e + L)
    U = 8.0
    chi = (1 + 0.6 * INDUCTION) * gamma
    corr = AERODYN_SKEW * ratio * np.tan(chi / 2)
    W = _captured_relative_wind(model, y, 0.5 * np.pi / omega)
    un = U * np.cos(gamma)
    assert np.allclose(W[:, :, 0, 2], un * (1 - INDUCTION * (1 - corr)), rtol=1e-12, atol=0)
    assert np.allclose(W[:, :, 1, 2], un * (1 - INDUCTION * (1 + corr)), rtol=1e-12, atol=0)
    W = _captured_relative_wind(model, y, 0.0)
    assert np.allclose(W[:, :, :, 2], un * (1 - INDUCTION), rtol=1e-12, atol=0)
    plain = _model(t, 20.0, skew=0.0)
    W = _captured_relative_wind(plain, y, 0.5 * np.pi / omega)
    assert np.allclose(W[:, :, :, 2], un * (1 - INDUCTION), rtol=1e-12, atol=0)
    free = _model(replace(t, nacelle=replace(t.nacelle, yaw_free=True)), 20.0)
    yf = free.initial_guess()
    yf[free.layout["yaw"]] = gamma
    W = _captured_relative_wind(free, yf, 0.5 * np.pi / omega)
    # the frozen induced velocity keeps its magnitude a U cos(gamma) (of the built model)
    assert np.allclose(W[:, :, :, 2], U - INDUCTION * un, rtol=1e-12, atol=0)


def test_the_downwind_blade_loses_thrust_and_the_rotor_yaws_back_into_the_wind():
    """Reference: the physics of the skewed wake.  Blades horizontal in a 15 deg yawed wind:
    without the correction both carry the same thrust (the cross-flow is radial for both;
    1e-12); with it the downwind blade (more induction) carries less, and the difference,
    acting at +-r along n2, is a yaw moment about n1 of the sign that turns the shaft towards
    the wind (+ yaw for a wind turned by + direction, kane.py's y3 = cos q n3 - sin q n2).
    The thrust difference is first order in K: it doubles (within 2 %) when K doubles."""
    t = teetering_rotor()
    tq = 0.5 * np.pi / t.rotor.speed
    thrust = {}
    for k in (0.0, AERODYN_SKEW, 2 * AERODYN_SKEW):
        model = _model(t, 15.0, skew=k)
        force, _ = model.aero_loads(model.initial_guess(), tq)
        thrust[k] = force[:, 2]                          # along b3 = s3 (no precone)
    assert abs(thrust[0.0][0] - thrust[0.0][1]) <= 1e-12 * abs(thrust[0.0][0])
    upwind, downwind = thrust[AERODYN_SKEW]
    assert upwind > downwind > 0
    # blade 0 at +n2 (upwind), blade 1 at -n2: yaw moment n1 . sum(r x T s3) ~ T0 - T1 > 0
    assert upwind - downwind > 1e-2 * upwind
    doubled = thrust[2 * AERODYN_SKEW]
    assert (doubled[0] - doubled[1]) / (upwind - downwind) == pytest.approx(2.0, rel=2e-2)


def test_axial_flow_is_an_ordinary_point_of_the_residual_and_its_jacobian():
    """Reference: central differences (step 1e-3 rad, where the exact branch of the factor
    is used) against the complex-step Jacobian column of the yaw angle at exact axial flow
    (the series branch; sin^2(chi0) = 0), 1e-6 of the column's largest entry; and the factor
    is 1 there.  The smooth form against the plain one at 10 deg (1e-13)."""
    t = teetering_rotor(stiffness=1.0, yaw_free=True)
    model = _model(t, 0.0)
    y = model.initial_guess()
    yd = np.zeros(model.n)
    tt = 0.21
    Jy, _ = model.jacobians(yd, y, tt)
    c = model.layout["yaw"]
    column = Jy.toarray()[:, c]
    h = 1e-3
    yp, ym = y.copy(), y.copy()
    yp[c] += h
    ym[c] -= h
    fd = (model.residual(yd, yp, tt) - model.residual(yd, ym, tt)) / (2 * h)
    assert np.abs(fd - column).max() <= 1e-6 * np.abs(column).max()
    s3 = np.array([0.0, 0.0, 1.0])
    along, sin2 = skew_angles(np.array([0.0, 0.0, 8.0]), s3)
    assert skewed_wake_factor(along, sin2, 0.3, 0.7, AERODYN_SKEW) == 1.0
    g = np.radians(10.0)
    psi = np.radians(35.0)
    s3 = np.array([np.sin(0.05), 0.0, np.cos(0.05)])            # precone-like b1 . s3
    b1p = np.array([1.0, 0.0, 0.0]) - s3[0] * s3
    b1p /= np.linalg.norm(b1p)
    side = np.cross(s3, b1p)
    wind = 8.0 * (np.cos(g) * s3 + np.sin(g) * (np.cos(psi) * b1p + np.sin(psi) * side))
    along, sin2 = skew_angles(wind, s3)
    chi = 1.18 * g
    plain = 1 + AERODYN_SKEW * 0.7 * np.tan(chi / 2) * np.cos(psi)
    assert skewed_wake_factor(along, sin2, 0.3, 0.7, AERODYN_SKEW) == pytest.approx(
        plain, rel=1e-13)


def test_the_constant_comes_from_the_turbine_file_and_the_aerodynamic_deck(tmp_path):
    """Reference: AeroDyn v15's input description (Skew_Mod 1 = skew model active,
    SkewRedistr_Mod 1 or "default" = Pitt/Peters, SkewRedistrFactor "default" = 15 pi / 32;
    Skew_Mod 0 = no skew model).  The rosco wheel's NREL 5-MW deck gives 15 pi / 32 (the
    shipped file, which has no key, the same); an edited deck with Skew_Mod 0 gives 0 and one
    with SkewRedistrFactor 1.2 gives 1.2; the hawt turbine file's ``aerodynamics.skew_factor``
    round-trips and a negative one is refused naming the field and the value."""
    import yaml
    from hawt_core.io import TurbineFileError, dump_turbine, turbine_from_dict
    from test_real_turbines import NREL, _edit, needs_decks, quiet_load

    t = teetering_rotor()
    assert t.aerodynamics.skew_factor == AERODYN_SKEW
    assert quiet_load("nrel5mw").aerodynamics.skew_factor == AERODYN_SKEW
    d = yaml.safe_load(dump_turbine(replace(t, aerodynamics=replace(t.aerodynamics,
                                                                     skew_factor=0.5))))
    assert d["aerodynamics"]["skew_factor"] == 0.5
    assert turbine_from_dict(d).aerodynamics.skew_factor == 0.5
    d["aerodynamics"]["skew_factor"] = -1.0
    with pytest.raises(TurbineFileError, match=r"aerodynamics\.skew_factor.*>= 0"):
        turbine_from_dict(d)
    if needs_decks.args[0]:                      # no rosco wheel: the file part only
        return
    from hawt_core.io.openfast import read_openfast
    assert read_openfast(NREL).turbine.aerodynamics.skew_factor == AERODYN_SKEW
    for key, value, expected in (("Skew_Mod", "0", 0.0), ("SkewRedistrFactor", "1.2", 1.2)):
        deck = tmp_path / key
        shutil.copytree(NREL.parent, deck)
        _edit(deck / "NRELOffshrBsline5MW_Onshore_AeroDyn15.dat", key, value)
        got = read_openfast(deck / "NREL-5MW.fst").turbine.aerodynamics.skew_factor
        assert got == pytest.approx(expected, abs=0), key
