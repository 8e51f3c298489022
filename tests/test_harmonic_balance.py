"""The periodic steady state's harmonic balance over 1/Nb of the period (solvers/periodic.py):
identical, equally spaced blades (an odd number of them) repeat each other's motion a blade
spacing later, ``y(t + T/Nb) = S y(t)``, so only the first 1/Nb of the samples are unknowns.

References and tolerances (each test says which):
- the harmonic balance over the whole period at the same truncation (every sample an unknown,
  the residual imposed at every one; the route the reduced one replaces): the same samples to
  1e-8 of each unknown's own scale plus 1e-7 SI units (both converge Newton to 1e-10 of the
  load scale);
- the residual at the samples the reduced solve never imposed (the last (Nb - 1)/Nb of the
  period, reconstructed by the symmetry): at most 1e-8 of the load scale, as at the imposed
  ones;
- a residual that breaks the symmetry (a load on blade 0 only), two and four blades: the
  reduction is refused and the whole period collocated.
"""
import dataclasses as dc
import warnings

import numpy as np
import pytest

from hawt_core.aero.wind import Wind
from hawt_core.assembly import TurbineModel
from hawt_core.io import load_turbine
from hawt_core.solvers import periodic
from hawt_core.solvers.periodic import (_harmonic_balance, _relabelling_symmetry,
                                        periodic_steady_state)
from meshes import load_paper_mesh

PAPER = load_turbine()


def nrel_in_sheared_yawed_wind(elements=4, tower_shadow=True):
    """NREL 5-MW (tower, drivetrain, tilt, precone, gravity) at 9.09 rpm in an 8 m/s wind with
    shear exponent 0.2, 10 deg yaw misalignment and (optionally) the tower's shadow: strongly
    periodic."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_paper_mesh("nrel5mw")
    t = dc.replace(t, rotor=dc.replace(t.rotor, speed=9.09 * np.pi / 30, pitch=0.0))
    wind = Wind(8.0, direction=np.radians(10.0), shear_exponent=0.2,
                tower_radius=3.0 if tower_shadow else 0.0)
    return TurbineModel(t, elements=elements, wind=wind)


def five_blade_rotor(yaw_free=False):
    """Five Table 1 blades (the paper's) at 72 deg on a rigid hub, gravity on, shaft tilted
    5 deg, in a vacuum: an odd blade count other than three; yaw locked, or free (an
    ignorable yaw angle)."""
    T = dc.replace(PAPER, rotor=dc.replace(PAPER.rotor, blades=5),
                   hub=dc.replace(PAPER.hub, teeter=False),
                   nacelle=dc.replace(PAPER.nacelle, yaw_free=yaw_free,
                                      shaft_tilt=np.radians(5.0)),
                   gravity=dc.replace(PAPER.gravity, enabled=True))
    return TurbineModel(T, elements=4)


def residual_at_every_sample(model, ps) -> float:
    """Largest residual over all samples of the period, relative to the load scale (the
    rates from the samples' own Fourier series)."""
    D = periodic.fourier_differentiation(len(ps.times), ps.period)
    rates = D @ ps.states
    return max(np.abs(model.residual(rates[j], ps.states[j], ps.times[j])).max()
               for j in range(len(ps.times))) / model.load_scale()


@pytest.mark.parametrize("build, H", [(nrel_in_sheared_yawed_wind, 7), (five_blade_rotor, 7)],
                         ids=["nrel5mw-shear-yaw-shadow", "five-blades"])
def test_reduced_harmonic_balance_equals_the_whole_period(build, H):
    """Reference: the whole-period harmonic balance at the same H (2H + 1 = 15 samples,
    divisible by 3 and 5). Tolerances: samples 1e-8 of each unknown's scale + 1e-7; residual at the
    samples never imposed 1e-8 of the load scale."""
    model = build()
    symmetry = _relabelling_symmetry(model)
    assert symmetry is not None and symmetry[1] == model.n_blades
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reduced = _harmonic_balance(model, H, 1e-10, 25, None, None, symmetry)
        whole = _harmonic_balance(model, H, 1e-10, 25, None, None, None)
    # unknowns that vanish by symmetry (a lateral root force in a vacuum...) are round-off
    # either way: 1e-7 in SI units (N, N m, m, rad, m/s) on top of the relative 1e-8
    scale = np.abs(whole.states).max(axis=0)
    excess = np.abs(reduced.states - whole.states) / (1e-7 + 1e-8 * scale)
    assert excess.max() <= 1.0, f"unknown {np.unravel_index(excess.argmax(), excess.shape)}"
    # the periodic part is not negligible (the comparison is not one of constants)
    assert (np.ptp(whole.states, axis=0) / np.maximum(scale, 1e-3)).max() > 1e-3
    assert residual_at_every_sample(model, reduced) < 1e-8


def test_free_yaw_five_blades_reduced_state_solves_the_whole_period():
    """Five blades on a free yaw bearing in a vacuum: the whole-period harmonic balance is
    ill-posed here (its Jacobian nearly singular: two solutions 1e-5 apart in the blades'
    unknowns both have residuals below 1e-11), so the reference is the residual itself: at
    every sample of the period, including those never imposed, at most 1e-10 of the load
    scale; and the state repeats a blade spacing later (y(t + T/5) = S y(t), 1e-12)."""
    model = five_blade_rotor(yaw_free=True)
    S, Nb = _relabelling_symmetry(model)
    ps = _harmonic_balance(model, 7, 1e-10, 25, None, None, (S, Nb))
    assert residual_at_every_sample(model, ps) < 1e-10
    m = len(ps.times) // Nb
    shifted = ps.states[m:2 * m]                     # the samples at t_j + T/5
    assert np.abs(shifted - (S @ ps.states[:m].T).T).max() <= 1e-12 * np.abs(ps.states).max()


class BladeZeroLoaded:
    """A model whose residual has a constant load on blade 0's first row only: the blades are
    no longer interchangeable."""

    def __init__(self, model):
        self._model = model
        self.row = model.layout.blade_offset(0)

    def __getattr__(self, name):
        return getattr(self._model, name)

    def residual(self, ydot, y, t):
        r = self._model.residual(ydot, y, t)
        r[self.row] += 1e-3 * self._model.load_scale()
        return r


def test_the_reduction_is_refused_without_the_symmetry():
    """Reference: the symmetry's definition. A load on one blade only (1e-3 of the load
    scale, far above SYMMETRY_CHECK_TOL), and even blade counts (2H + 1 is odd): None."""
    model = five_blade_rotor()
    assert _relabelling_symmetry(model) is not None
    assert _relabelling_symmetry(BladeZeroLoaded(model)) is None
    for blades in (2, 4):
        T = dc.replace(PAPER, rotor=dc.replace(PAPER.rotor, blades=blades),
                       hub=dc.replace(PAPER.hub, teeter=False))
        assert _relabelling_symmetry(TurbineModel(T, elements=2)) is None


def test_steady_state_with_the_reduction_meets_its_tolerance_over_the_whole_period():
    """periodic_steady_state as the analyses call it (the truncation chosen by the residual
    between collocation times). Reference: the residual at every sample of the period
    (tolerance 1e-8 of the load scale) and between them (the model's interpolation tolerance,
    1e-6 in wind); the truncation's sample count divisible by the three blades. (Without the
    tower's shadow, whose sharp dip needs more harmonics than the 48 allowed for 1e-6.)"""
    model = nrel_in_sheared_yawed_wind(tower_shadow=False)
    ps = periodic_steady_state(model)
    assert len(ps.times) % 3 == 0
    assert residual_at_every_sample(model, ps) < 1e-8
    assert ps.interpolation_error <= model.interpolation_tol


def test_the_constant_attempt_is_skipped_only_where_no_constant_state_exists():
    """periodic_steady_state skips the constant steady state where gravity turns in the
    blades' frames (periodic._gravity_turns).  Reference: the constant solver itself
    (Newton on the time-invariant equations, then its own check of R(0, y, t) = 0 over a
    revolution at the solution, 1e-9): the Table 1 rotor without gravity has a constant
    state, with gravity (and with a 0.1 rad tilt) none, and the NREL 5-MW deck (gravity on)
    none; a one-bladed rotor 1 % off balance (no gravity) has none either but is not skipped
    (its constant attempt fails as before)."""
    from test_one_blade import one_blade

    from hawt_core.numerics.newton import ConvergenceError
    from hawt_core.solvers.steady import constant_steady_state
    P = load_turbine("hawt_core/data/three_blade_rotor.yaml")
    G = dc.replace(P, gravity=dc.replace(P.gravity, enabled=True))
    models = [TurbineModel(P, elements=2), TurbineModel(G, elements=2),
              TurbineModel(dc.replace(G, nacelle=dc.replace(G.nacelle, shaft_tilt=0.1)),
                           elements=2),
              nrel_in_sheared_yawed_wind(tower_shadow=False), TurbineModel(one_blade(0.99),
                                                                          elements=3)]
    skipped, constant = [], []
    for model in models:
        try:
            constant_steady_state(model)
            constant.append(True)
        except (ValueError, ConvergenceError):
            constant.append(False)
        skipped.append(periodic._gravity_turns(model))
    assert constant == [True, False, False, False, False]
    assert skipped == [False, True, True, True, False]
    assert not any(s and c for s, c in zip(skipped, constant))
