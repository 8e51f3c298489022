"""The drivetrain (hawt_core.model.Drivetrain, hawt_core.rigid.kane): shaft torsion between
the rotor and the gearbox, and the generator behind it, prescribed or free.

References:
- closed forms of a rigid rotor (blades 1e4 times stiffer than the paper's) on a torsion
  spring: sqrt(K / J_rotor) with the generator held, sqrt(K (1/J_rotor + 1/(N^2 J_gen)))
  with it free, J_rotor = hub + blades' inertia about the shaft (integrated here);
  tolerance 2e-5 (the blades' remaining flexibility), at rest and turning;
- an independent route: multi-blade coordinates (one eigenproblem) against Radau IIA
  monodromy with Fast Floquet on a flexible-blade rotor with the drivetrain, 1e-7;
- the YAML round trip and its errors.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hawt_core.analyses.modal import modal_analysis
from hawt_core.io import TurbineFileError, dump_turbine, load_turbine, turbine_from_dict
from hawt_core.io import turbines_equal
from hawt_core.io.catalog import load_any
from hawt_core.model import Drivetrain

K, J_GEN, RATIO = 1.0e6, 2.0, 20.0


def stiff_rotor(drivetrain, tower=False):
    """The three-blade rotor with stiff blades, yaw locked; ``tower``: on a very stiff
    flexible tower (the flexible-tower equations of the rigid system, same closed form)."""
    from hawt_core.model import Beam, SectionTable
    t = load_any("three-blade")
    s = t.blade.sections
    stiff = replace(s, ei2=s.ei2 * 1e4, ei3=s.ei3 * 1e4, gj=s.gj * 1e4)
    beam = Beam(length=10.0, elements=2, sections=SectionTable.uniform(
        mass=500.0, i1=20.0, i2=10.0, i3=10.0, gj=1e14, ei2=1e14, ei3=1e14)) if tower else None
    return replace(t, blade=replace(t.blade, sections=stiff), drivetrain=drivetrain,
                   nacelle=replace(t.nacelle, yaw_free=False), tower=beam)


def rotor_inertia(t) -> float:
    s, L, e = t.blade.sections, t.blade.length, t.hub.radius
    x = np.linspace(0.0, L, 20001)
    per_blade = np.trapezoid(np.interp(x / L, s.stations, s.mass) * (e + x) ** 2
                             + np.interp(x / L, s.stations, s.i3), x)
    return t.hub.inertia_longitudinal + t.rotor.blades * per_blade


@pytest.mark.parametrize("generator", ["prescribed", "free"])
@pytest.mark.parametrize("speed", [0.0, 6.02])
@pytest.mark.parametrize("tower", [False, True])
def test_rigid_rotor_on_a_shaft_spring_has_the_closed_form_frequency(generator, speed, tower):
    t = stiff_rotor(Drivetrain(stiffness=K, generator_inertia=J_GEN, gearbox_ratio=RATIO,
                               generator=generator), tower)
    J = rotor_inertia(t)
    inv = 1.0 / J + (1.0 / (RATIO ** 2 * J_GEN) if generator == "free" else 0.0)
    want = np.sqrt(K * inv) / (2 * np.pi)
    r = modal_analysis(t, rotor_speed=speed, elements=4,
                       max_per_rev=10.0 if speed == 0 else 60.0)
    drive = [m for m in r.modes if m.family == "drivetrain" and m.frequency_hz > 1e-6]
    assert len(drive) == 1, [(m.label, m.frequency_hz) for m in r.modes]
    assert drive[0].frequency_hz == pytest.approx(want, rel=2e-5)
    if generator == "free":                      # the free rotation: a zero exponent
        assert any(m.family == "drivetrain" and m.frequency_hz < 1e-9 for m in r.modes)


def test_shaft_damper_gives_the_damping_ratio_of_the_equivalent_oscillator():
    """J phi'' + C phi' + K phi = 0: zeta = C / (2 sqrt(K J)), generator held; 1e-4."""
    J = rotor_inertia(stiff_rotor(None))
    C = 0.04 * 2 * np.sqrt(K * J)
    t = stiff_rotor(Drivetrain(stiffness=K, damping=C))
    m = [m for m in modal_analysis(t, rotor_speed=0.0, elements=4, max_per_rev=10.0).modes
         if m.family == "drivetrain"][0]
    assert m.damping_ratio == pytest.approx(0.04, rel=1e-4)


def test_multiblade_coordinates_agree_with_the_monodromy_with_a_drivetrain():
    """Flexible paper blades, 3 on a rigid hub, free yaw, drivetrain with a free generator:
    time-invariant in multi-blade coordinates; both routes give the same exponents below
    20 per-rev: frequencies to 1e-7 per-rev, real parts to 1e-6 (Radau IIA's own damping at
    600 steps); the zero exponents of the free rotation and the free yaw (Jordan blocks, a
    few split by round-off into a 1e-7 pair, depending on the LAPACK build) are counted
    apart: at least two near zero (|eta| < 1e-5 per-rev) in each."""
    t = replace(load_any("three-blade"),
                drivetrain=Drivetrain(stiffness=2e6, damping=500.0, generator_inertia=3.0,
                                      gearbox_ratio=15.0, generator="free"))
    a = modal_analysis(t, elements=3, method="auto", max_per_rev=20.0)
    b = modal_analysis(t, elements=3, method="radau", steps=600)
    assert a.settings["frame"] == "multi-blade"
    def exponents(r, zero):
        return sorted((m.frequency_per_rev, m.real_per_rev) for m in r.modes
                      if m.frequency_per_rev < 19.0
                      and (abs(complex(m.real_per_rev, m.frequency_per_rev)) < 1e-5) == zero)

    assert min(len(exponents(a, True)), len(exponents(b, True))) >= 2
    fa, fb = exponents(a, False), exponents(b, False)
    assert len(fa) == len(fb)
    np.testing.assert_allclose(np.array(fa)[:, 0], np.array(fb)[:, 0], atol=1e-7)
    np.testing.assert_allclose(np.array(fa)[:, 1], np.array(fb)[:, 1], atol=1e-6)
    assert any(m.family == "drivetrain" and m.frequency_per_rev > 0 for m in a.modes)


def test_drivetrain_round_trip_and_errors(tmp_path):
    t = replace(load_any("three-blade"), drivetrain=Drivetrain(
        stiffness=3e7, damping=1e4, generator_inertia=5.0, gearbox_ratio=50.0,
        generator="free"))
    f = tmp_path / "d.yaml"
    f.write_text(dump_turbine(t))
    assert turbines_equal(replace(load_turbine(f), name=t.name), t)
    base = {k: v for k, v in __import__("yaml").safe_load(dump_turbine(t)).items()}
    for bad, words in (({"stiffness": -1.0}, ["drivetrain.stiffness", "> 0"]),
                       ({"generator": "locked"}, ["drivetrain.generator", "prescribed, free"]),
                       ({"gearbox": 9}, ["drivetrain.gearbox", "gearbox_ratio"]),
                       ({"stiffness": None, "generator": "prescribed"}, ["rigid shaft"])):
        d = dict(base, drivetrain={**base["drivetrain"], **bad})
        if d["drivetrain"].get("stiffness", 0) is None:
            d["drivetrain"].pop("stiffness")
        with pytest.raises(TurbineFileError) as e:
            turbine_from_dict(d)
        for w in words:
            assert w in str(e.value), (w, str(e.value))
