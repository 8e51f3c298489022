"""No steady state, refused up front (hawt_core.solvers.equilibrium).

References:
- the free generator's unbalanced torque against an independent route to the same number:
  the same turbine with the generator held (prescribed) has a constant steady state whose
  shaft carries the rotor's aerodynamic torque, k_shaft x twist; both must agree to 1e-9
  (the check starts from the blades' own aeroelastic steady state, which the held turbine's
  Newton solve reaches too; the shaft twist does not change the loads in steady rotation);
- the decision rule |G| > pi |K| on a linear one-degree-of-freedom stand-in whose G and K
  are set exactly (refused on one side of the rule, passed on the other);
- no false refusal: a balanced rotor and an unbalanced one-bladed rotor in a vacuum (a
  1 per-rev gravity torque of zero mean) with a free generator pass.
"""
from __future__ import annotations

import dataclasses as dc
import math
from types import SimpleNamespace

import numpy as np
import pytest

from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.io.catalog import load_any
from hawt_core.model import Drivetrain
from hawt_core.solvers import periodic as periodic_module
from hawt_core.solvers.equilibrium import (NoEquilibrium, check_equilibrium_exists,
                                           unbalanced_forces)
from meshes import load_paper_mesh

RPM9 = 9.0 * math.pi / 30.0


def nrel5mw(generator="free", simple=False):
    t = load_paper_mesh("nrel5mw")
    t = dc.replace(t, rotor=dc.replace(t.rotor, pitch=0.0),
                   drivetrain=dc.replace(t.drivetrain, generator=generator))
    if simple:    # a constant steady state: no gravity, tilt or tower
        t = dc.replace(t, gravity=dc.replace(t.gravity, enabled=False), tower=None,
                       nacelle=dc.replace(t.nacelle, shaft_tilt=0.0))
    return t


def test_free_generator_torque_equals_the_held_shaft_torque():
    from hawt_core.solvers.steady import constant_steady_state
    held = TurbineModel(nrel5mw("prescribed", simple=True), elements=6, rotor_speed=RPM9,
                        wind=Wind(8.0))
    y = constant_steady_state(held)
    shaft_torque = held.turbine.drivetrain.stiffness * y[held.layout["shaft_twist"]]
    free = TurbineModel(nrel5mw("free", simple=True), elements=6, rotor_speed=RPM9,
                        wind=Wind(8.0))
    forces = {name: (G, K) for name, G, K, _ in unbalanced_forces(free)}
    G, K = forces["generator_azimuth"]
    assert shaft_torque > 1e6                      # ~2 MN m at 8 m/s, 9 rpm, pitch 0
    assert abs(G) == pytest.approx(shaft_torque, rel=1e-9)
    assert abs(K) * math.pi < 1e-6 * abs(G)        # nothing restores a free drivetrain
    with pytest.raises(NoEquilibrium, match="drivetrain.generator"):
        check_equilibrium_exists(free)


def test_free_generator_in_wind_with_its_own_controls_refused_before_any_newton(monkeypatch):
    """The shipped NREL 5-MW (flexible tower, gravity, tilt, yaw bearing with its spring)
    with the generator free and controls of its own holding no torque (a closed loop whose
    controller gives none; without controls the steady state trims the torque instead:
    tests/test_generator_trim.py): the periodic steady state refuses before the harmonic
    balance or any Newton solve runs, naming the field, the torque and the remedy, and no
    free-yaw advice."""
    from hawt_core.rigid.actuators import ControlInputs
    from hawt_core.solvers.periodic import periodic_steady_state

    def forbidden(*a, **k):
        raise AssertionError("a steady-state solve ran before the equilibrium check")
    monkeypatch.setattr(periodic_module, "_harmonic_balance", forbidden)
    monkeypatch.setattr(periodic_module, "constant_steady_state", forbidden)
    model = TurbineModel(nrel5mw(), elements=8, rotor_speed=RPM9, wind=Wind(8.0))
    model.set_controls(ControlInputs(3, pitch=-float(model.turbine.rotor.pitch), torque=0.0))
    with pytest.raises(NoEquilibrium) as ei:
        periodic_steady_state(model)
    msg = str(ei.value)
    for words in ("drivetrain.generator", "kN m", "at 9 rpm in 8 m/s wind", "prescribed",
                  "GenDOF"):
        assert words in msg, msg
    assert "yaw" not in msg


def test_balanced_and_unbalanced_rotors_in_a_vacuum_pass():
    """A free generator with no torque in a vacuum: a balanced rotor (NREL 5-MW, gravity and
    tilt) and an unbalanced one-bladed rotor (gravity torque 1 per-rev, zero mean) both have
    a periodic steady state: the check must not refuse them."""
    check_equilibrium_exists(TurbineModel(nrel5mw(), elements=4, rotor_speed=RPM9))
    paper = load_any("paper")
    one = dc.replace(paper, rotor=dc.replace(paper.rotor, blades=1),
                     hub=dc.replace(paper.hub, teeter=False),
                     gravity=dc.replace(paper.gravity, enabled=True),
                     drivetrain=Drivetrain(generator="free", generator_inertia=1.0))
    check_equilibrium_exists(TurbineModel(one, elements=4))


class _LinearDof:
    """A stand-in model with one rigid angle q (the yaw) and its speed: the speed row's
    residual is ``G + K q`` (K < 0 restores), the kinematic row ``qdot - u``."""

    def __init__(self, G, K):
        self.G, self.K = G, K
        self.nq = self.nu = 1
        self.n = 2
        self.period = 1.0
        self.rotor_speed = 2 * math.pi
        self.wind, self.controls = None, None
        self.rigid = SimpleNamespace(coordinates=("yaw",))
        self.turbine = SimpleNamespace(hub=SimpleNamespace(radius=1.0),
                                       blade=SimpleNamespace(length=9.0),
                                       nacelle=SimpleNamespace(yaw_stiffness=-K))

    def initial_guess(self):
        return np.zeros(2)

    def load_scale(self):
        return 1.0

    def residual(self, ydot, y, t):
        q, u = y[..., 0], y[..., 1]
        return np.stack([ydot[..., 0] - u, self.G + self.K * q], -1)


@pytest.mark.parametrize("K, refused", [(-1.0e4, True), (-0.99 * 1e5 / math.pi, True),
                                        (-1.01 * 1e5 / math.pi, False), (-1.0e6, False)])
def test_refused_exactly_when_no_angle_within_half_a_turn_balances(K, refused):
    model = _LinearDof(1.0e5, K)
    if refused:
        with pytest.raises(NoEquilibrium, match=r"nacelle.yaw_free.*yaw_stiffness"):
            check_equilibrium_exists(model)
    else:
        check_equilibrium_exists(model)


def test_round_off_is_not_a_force():
    check_equilibrium_exists(_LinearDof(1e-9, 0.0))


def test_continuation_advice_fits_the_turbine():
    """No free-yaw advice for a locked yaw (the old message gave it to every turbine)."""
    t = load_paper_mesh("nrel5mw")
    locked = dc.replace(t, nacelle=dc.replace(t.nacelle, yaw_free=False))
    assert "yaw" not in periodic_module._continuation_hint(locked)
    assert "yaw" not in periodic_module._homotopy_description(locked)
    free = dc.replace(t, nacelle=dc.replace(t.nacelle, yaw_stiffness=0.0))
    assert "free yaw bearing" in periodic_module._continuation_hint(free)
