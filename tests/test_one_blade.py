"""One-bladed rotors (periodic steady states of an unbalanced rotor on a free yaw bearing).

References and tolerances (each test says which):
- the residual R(ydot, y, t) of the harmonic-balance steady state, evaluated at times that
  are not collocation points (an independent check of the periodic solution);
- static balance in closed form: a counterweight m_c at R_c opposite the blade balances it
  when m_c R_c = int m (e + x) dx; the steady state is then constant in the rotating frame;
- continuity: as the counterweight approaches balance the periodic steady state tends to the
  constant one, so the Floquet multipliers tend to the balanced rotor's.
"""
import dataclasses as dc

import numpy as np
import pytest

from hawt_core.assembly import TurbineModel
from hawt_core.numerics.newton import ConvergenceError
from hawt_core.io import load_turbine
from hawt_core.analyses.modal import modal_analysis
from hawt_core.solvers.periodic import periodic_steady_state

PAPER = load_turbine()
#: first moment of the Table 1 blade about the shaft axis, m (e l + l^2 / 2) [kg m]
BLADE_MOMENT = 67.5772 * (1.8 * 8.42 + 8.42 ** 2 / 2)
RC = 1.8


def one_blade(balance=0.0, teeter=False):
    """One Table 1 blade, free yaw, a counterweight of ``balance`` times the static balance."""
    return dc.replace(PAPER, rotor=dc.replace(PAPER.rotor, blades=1),
                      hub=dc.replace(PAPER.hub, teeter=teeter, counterweight_radius=RC,
                                     counterweight_mass=balance * BLADE_MOMENT / RC))


def test_balanced_one_blade_rotor_has_a_constant_steady_state():
    """m_c R_c = the blade's first moment: the steady state is constant (hub loads cancel;
    closed form), zero yaw; 1 % off balance it is periodic."""
    for teeter in (False, True):
        st = periodic_steady_state(TurbineModel(one_blade(1.0, teeter), elements=3))
        assert st.constant
        st = periodic_steady_state(TurbineModel(one_blade(0.99, teeter), elements=3))
        assert not st.constant


@pytest.mark.parametrize("teeter", [False, True], ids=["rigid-hub", "teetering-hub"])
def test_unbalanced_one_blade_periodic_steady_state_satisfies_the_residual(teeter):
    """10 % below balance, free yaw: the rotating imbalance swings the nacelle (yaw amplitude
    above 0.01 rad); the harmonic-balance state satisfies R(ydot, y, t) = 0 at 13 times that
    are not collocation points to 1e-8 of the load scale (the interpolation tolerance)."""
    model = TurbineModel(one_blade(0.9, teeter), elements=3)
    st = periodic_steady_state(model)
    assert not st.constant
    yaw = st.states[:, model.layout["yaw"]]
    assert np.ptp(yaw) / 2 > 0.01
    scale = max(1.0, np.abs(model.residual(np.zeros(model.n), model.initial_guess(), 0.0)).max())
    times = model.period * (np.arange(13) + 0.37) / 13
    worst = max(np.abs(model.residual(st.rate_at(t), st.at(t), t)).max() for t in times)
    assert worst <= 1e-8 * scale, worst


def test_floquet_multipliers_are_continuous_as_the_counterweight_reaches_balance():
    """Counterweight at 98, 99, 99.5 % of balance and at balance (rigid hub, free yaw, N = 3):
    every multiplier of the balanced rotor's modes below 8 per-rev has a partner in the
    unbalanced analyses whose distance shrinks at least linearly with the imbalance (by 2x
    per halving of it; measured 2.9x) and is below 2e-2 at 99.5 % (measured 1.0e-2: the
    nearly coincident flap-lag-yaw pair at 4.80 and 4.88 per-rev is the most sensitive)."""
    fracs = (0.98, 0.99, 0.995)
    runs = {f: modal_analysis(one_blade(f), elements=3, max_per_rev=10) for f in fracs + (1.0,)}
    assert runs[1.0].steady.constant and not runs[0.98].steady.constant
    fl0 = runs[1.0].floquet
    ref = [fl0.multipliers[m.column] for m in runs[1.0].modes
           if m.family != "yaw" and m.frequency_per_rev < 8]
    assert len(ref) >= 4
    dist = {}
    for f in fracs:
        mu = runs[f].floquet.multipliers
        dist[f] = max(np.min(np.abs(mu - r)) for r in ref)
    print("multiplier distance to the balanced rotor:", dist)
    assert dist[0.98] > 2 * dist[0.99] > 4 * dist[0.995]
    assert dist[0.995] < 2e-2


def test_no_periodic_state_is_reported_with_the_reason():
    """No counterweight at all: the continuation from a weakly forced turbine stalls (the
    family of periodic states folds before the true yaw inertia); the error says so and
    names the remedies (ConvergenceError, not a NaN or an overflow traceback)."""
    with pytest.raises(ConvergenceError, match="continuation.*stalled.*counterweight"):
        periodic_steady_state(TurbineModel(one_blade(0.0), elements=2))
