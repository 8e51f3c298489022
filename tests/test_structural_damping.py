"""Structural damping of the beams (model.BeamDamping, hawt_core/fem/damping.py and
fem/damping_fit.py).

References and tolerances:
- proportional damping of a uniform clamped beam (Caughey: a damping operator proportional
  to the stiffness or to the mass keeps the undamped modes): every mode has ``zeta_n = mu
  omega_n / 2`` (Kelvin-Voigt, ``[F, M]_d = mu S d(strain)/dt``) or ``alpha / (2
  omega_n)`` (mass-proportional), omega_n the undamped frequency, which the damped
  eigenvalue's modulus keeps; four flap modes and the first lag mode within 1e-6 relative,
  through the blade-modes analysis (its assembled Jacobians), for the paper's element and
  the p-version;
- the Rayleigh pair through two modes (Clough & Penzien, Dynamics of Structures, 2nd ed.,
  eq. 12-39): ``alpha = 2 w1 w2 (z1 w2 - z2 w1) / (w2^2 - w1^2)``, ``mu = 2 (z2 w2 - z1 w1) /
  (w2^2 - w1^2)``, and ElastoDyn's rule for one ratio, ``mu = 2 zeta / omega``
  (ElastoDyn.f90, Coeff: ``CBE = 0.01 BldEDamp KBE / (pi FreqBE)``): the modal fit of a
  uniform beam within 1e-6 relative (w1, w2 of the undamped discrete beam);
- the deck's ratios: the shipped NREL 5-MW blade (ElastoDyn BldFlDmp 0.477465 %, BldEdDmp
  0.477465 %) clamped at rest has them in its 1st and 2nd flap and 1st edge modes within
  1e-7 absolute (shift-invert eigenvalues, independent of the fit's own);
- the dense complex-step Jacobian of the whole residual (numerics/jacobian.py): the
  Gauss-point Jacobians (dR/dy and dR/dydot) of both discretizations with both forms on the
  curved, twisted, tapered, offset beam of tests/beam_cases.py, within 1e-12 of the largest
  entry;
- a rigid motion of the root frame is not damped: the damped residual equals the undamped
  one to round-off at a rigidly moving beam;
- time domain (implicit midpoint, tests/test_simulate.py's parked rotor): the free decay
  of the 1st flap mode has the eigenvalue's rate within 1 % and the energy falls at every
  step (a dissipative material).
"""
from __future__ import annotations

import dataclasses as dc
import warnings

import numpy as np
import pytest
import yaml

from beam_cases import every_term_model
from test_beam_jacobian import _case, pointwise_against_dense
from test_real_turbines import quiet_load
from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.fem.beam import BeamElements
from hawt_core.fem.beam_jacobian import PointwiseBeamJacobian
from hawt_core.fem.damping import DampingCoefficients
from hawt_core.fem.damping_fit import (FIT_ELEMENTS, FIT_ORDER, clamped_modes,
                                       clamped_pencil, fit_modal, refine)
from hawt_core.fem.discretization import beam_elements
from hawt_core.fem.energy import FAMILIES, classify_energy
from hawt_core.fem.sections import mesh_beam
from hawt_core.fem.spectral import SpectralBeamElements
from hawt_core.fem.spectral_jacobian import SpectralPointwiseJacobian
from hawt_core.io.turbine_writer import dump_turbine
from hawt_core.io.turbine_yaml import TurbineFileError, turbine_from_dict
from hawt_core.model import Beam, BeamDamping, SectionTable

L_C, M_C, EI_C = 10.0, 50.0, 2e6


def _uniform(elements, order, damping=None):
    """A uniform cantilever (Euler-Bernoulli: rotary inertia 1e-9) with lag 4x stiffer."""
    sec = SectionTable.uniform(mass=M_C, i1=2.0, i2=1e-9, i3=1e-9, gj=1e5, ei2=EI_C,
                               ei3=4 * EI_C)
    return Beam(L_C, sec, elements, order=order, damping=damping)


def _clamped_modes(beam, count=12):
    """(family, omega [rad/s], zeta) of the lowest modes of ``beam`` clamped at rest, from
    the blade-modes analysis (assembled pointwise Jacobians, shift-invert)."""
    t = quiet_load("paper")
    t = dc.replace(t, blade=beam, rotor=dc.replace(t.rotor, precone=0.0))
    modes = blade_modes(t, rotor_speed=0.0, count=count, method="sparse").modes
    return [(m.family, abs(m.eigenvalue), m.damping_ratio) for m in modes]


@pytest.mark.parametrize("elements,order", [(24, 1), (4, 5)])
def test_proportional_damping_of_a_uniform_cantilever(elements, order):
    undamped = _clamped_modes(_uniform(elements, order))
    mu, alpha = 2e-3, 0.4
    stiff = _clamped_modes(_uniform(elements, order, BeamDamping(stiffness=(0, 0, 0, mu, mu,
                                                                            mu))))
    mass = _clamped_modes(_uniform(elements, order, BeamDamping(mass=(alpha,) * 6)))
    flap = [i for i, m in enumerate(undamped) if m[0] == "flap"][:4]
    lag = [i for i, m in enumerate(undamped) if m[0] == "lag"][:1]
    assert len(flap) == 4 and len(lag) == 1
    for i in flap + lag:
        w = undamped[i][1]
        assert undamped[i][2] == pytest.approx(0.0, abs=1e-9)
        assert stiff[i][1] == pytest.approx(w, rel=1e-9)
        assert stiff[i][2] == pytest.approx(mu * w / 2, rel=1e-6)
        assert mass[i][2] == pytest.approx(alpha / (2 * w), rel=1e-6)
    # the closed-form frequency too (beta_1 L = 1.87510407), so w is the beam's
    w1 = 1.87510407 ** 2 * np.sqrt(EI_C / (M_C * L_C ** 4))
    assert undamped[flap[0]][1] == pytest.approx(w1, rel=2e-3 if order == 1 else 1e-6)


@pytest.mark.parametrize("elements,order", [(24, 1), (4, 5)])
def test_uniform_mu_on_a_shear_flexible_extensible_cantilever_is_proportional(elements,
                                                                               order):
    """Reference: Caughey.  The same mu on all six strains of a Timoshenko cantilever
    (axial and shear rigidities given: EA, GA as for a real blade section) is C = mu K, so
    every mode has zeta = mu w / 2 exactly, flap, lag and the shear's effect on them
    included (1e-6).  The viscous shear force must act on the shear strain rate: before
    its moment (t x F_d) was in the moment rows, it did work on the slope rate and every
    bending mode came out with zeta 1.98-1.99 x mu w / 2 (HAWC2's DTU 10-MW blade showed
    it: the 1st flap at 0.0097 against HAWC2's 0.0048)."""
    sec = SectionTable.uniform(mass=M_C, i1=2.0, i2=0.5, i3=1.5, gj=1e5, ei2=EI_C,
                               ei3=4 * EI_C, ea=1e9, ga2=1e7, ga3=2e7)
    mu = 2e-3
    plain = _clamped_modes(Beam(L_C, sec, elements, order=order), count=8)
    damped = _clamped_modes(Beam(L_C, sec, elements, order=order,
                                 damping=BeamDamping(stiffness=(mu,) * 6)), count=8)
    bending = [i for i, m in enumerate(plain) if m[0] in ("flap", "lag")][:4]
    assert len(bending) == 4
    for i in bending:
        w = plain[i][1]
        assert damped[i][1] == pytest.approx(w, rel=1e-9)
        assert damped[i][2] == pytest.approx(mu * w / 2, rel=1e-6)


@pytest.mark.parametrize("order", [1, 4])
def test_modal_fit_is_rayleigh_through_two_modes_and_elastodyn_rule_for_one(order):
    """(The beam's own mesh does not matter: the fit is on its converged discretization.)"""
    z1, z2, ze = 0.01, 0.02, 0.005
    beam = _uniform(16, order, BeamDamping(modal={"flap": (z1, z2), "edge": (ze,)}))
    c = fit_modal(beam)
    bare = beam_elements(dc.replace(beam, damping=None, elements=FIT_ELEMENTS,
                                    order=FIT_ORDER))
    A, E = clamped_pencil(bare)
    lam, vr, _ = clamped_modes(A, E, 8)
    fam = [FAMILIES[int(np.argmax(classify_energy(bare, vr[:, j])))]
           for j in range(vr.shape[1])]
    flap_w = [abs(lam[j]) for j in range(len(lam)) if fam[j] == "flap"][:2]
    edge_w = [abs(lam[j]) for j in range(len(lam)) if fam[j] == "lag"][:1]
    w1, w2 = flap_w
    alpha = 2 * w1 * w2 * (z1 * w2 - z2 * w1) / (w2 ** 2 - w1 ** 2)
    mu = 2 * (z2 * w2 - z1 * w1) / (w2 ** 2 - w1 ** 2)
    assert c.mu[4] == pytest.approx(mu, rel=1e-6)
    assert c.alpha[2] == pytest.approx(alpha, rel=1e-6)
    assert c.alpha[4] == pytest.approx(alpha, rel=1e-6)       # the plane's rotation too
    assert c.mu[5] == pytest.approx(2 * ze / edge_w[0], rel=1e-6)
    assert c.mu[[0, 1, 2, 3]] == pytest.approx(0.0) and c.alpha[[0, 1, 3, 5]] == \
        pytest.approx(0.0)


def test_unreachable_ratios_are_fitted_non_negative_and_warned():
    """A second flap ratio above omega2/omega1 times the first needs a negative mass term
    (it would drive slow motions unstable): refused by the non-negative fit, warned."""
    beam = _uniform(4, 4, BeamDamping(modal={"flap": (0.001, 0.05)}))
    with pytest.warns(UserWarning, match="no non-negative Rayleigh damping"):
        c = fit_modal(beam)
    assert np.all(c.mu >= 0) and np.all(c.alpha >= 0)


def test_shipped_nrel5mw_blade_has_the_decks_ratios_clamped_at_rest():
    t = quiet_load("nrel5mw")
    assert t.blade.damping.modal == {"flap": (0.00477465, 0.00477465),
                                     "edge": (0.00477465,)}
    el = beam_elements(t.blade)                      # the file's mesh, fitted on it
    A, E = clamped_pencil(el)
    lam, vr, _ = clamped_modes(A, E, 6)
    lam = refine(A, E, lam)
    fam = [FAMILIES[int(np.argmax(classify_energy(el, vr[:, j])))] for j in range(6)]
    zeta = -lam.real / abs(lam)
    named = [j for j in range(6) if fam[j] == "flap"][:2] + \
        [j for j in range(6) if fam[j] == "lag"][:1]
    assert zeta[named] == pytest.approx(0.00477465, abs=1e-7)
    # the blade-modes analysis of the shipped file reports them (its dense QZ: 1e-5)
    modes = blade_modes(t, rotor_speed=0.0, count=6).modes
    for fam_name, k in (("flap", 1), ("flap", 2), ("lag", 1)):
        m = [m for m in modes if m.family == fam_name][k - 1]
        assert m.damping_ratio == pytest.approx(0.00477465, rel=1e-3), (fam_name, k)


@pytest.mark.parametrize("spectral", [False, True])
def test_damped_gauss_point_jacobians_equal_dense_complex_step(spectral):
    rng = np.random.default_rng(5)
    coeffs = DampingCoefficients(np.array([1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 6e-3]),
                                 np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6]))
    model = every_term_model(3)
    if spectral:
        beam = SpectralBeamElements(model, 2, 3, pitch=0.2, damping=coeffs)
        pw = SpectralPointwiseJacobian(beam, 0)
    else:
        beam = BeamElements(mesh_beam(model), damping=coeffs)
        pw = PointwiseBeamJacobian(beam, 0)
    fun = _case(beam, 0, rng)
    ref = pointwise_against_dense(beam, pw, fun, 0, rng)[1]          # dR/dydot
    # the damping is in them: the loads' rates are read, and they are differential
    fm = 12 + np.arange(6)
    assert np.abs(ref[:, fm]).max() > 0
    assert beam.differential[fm].all()


@pytest.mark.parametrize("spectral", [False, True])
def test_rigid_motion_is_not_damped(spectral):
    coeffs = DampingCoefficients(np.full(6, 3e-3), np.full(6, 0.7))
    model = every_term_model(3)
    if spectral:    # straight: a rigid velocity field on a curved line is not polynomial
        model = dc.replace(model, sections=dc.replace(model.sections, prebend=None,
                                                      sweep=None))
    make = (lambda c: SpectralBeamElements(model, 2, 3, damping=c)) if spectral else \
        (lambda c: BeamElements(mesh_beam(model), damping=c))
    damped, plain = make(coeffs), make(None)
    rng = np.random.default_rng(2)
    v, w = rng.normal(size=3), rng.normal(size=3)
    y = plain.rigid_body_state(v, w)
    args = (np.zeros((1, plain.n)), y[None], v[None], w[None])
    r0, r1 = plain.residual(*args), damped.residual(*args)
    assert np.abs(r1 - r0).max() <= 1e-12 * np.abs(r0).max()
    # a deformed state with rates is damped (the test can fail)
    y2 = y + 0.01 * rng.normal(size=plain.n)
    yd2 = rng.normal(size=plain.n)
    args = (yd2[None], y2[None], v[None], w[None])
    assert np.abs(damped.residual(*args) - plain.residual(*args)).max() > 1e-3


def test_free_decay_in_time_matches_the_eigenvalue_and_energy_falls():
    from test_simulate import blade_hub_energy, decay_rate, paper
    from hawt_core.assembly import TurbineModel
    from hawt_core.solvers.march import Simulator
    base = paper(N=6, teeter=False)
    w_flap = [m for m in blade_modes(base, rotor_speed=0.0).modes if m.family == "flap"][0]
    mu = 2 * 0.02 / (2 * np.pi * w_flap.frequency_hz)          # 2 % in the 1st flap mode
    t = dc.replace(base, blade=dc.replace(base.blade, damping=BeamDamping(
        stiffness=(0, 0, 0, mu, mu, mu))))
    model = TurbineModel(t, rotor_speed=0.0)
    flap = [m for m in blade_modes(t, rotor_speed=0.0).modes if m.family == "flap"][0]
    rate = -flap.eigenvalue.real
    assert flap.damping_ratio == pytest.approx(0.02, rel=1e-6)
    period = 1.0 / flap.frequency_hz
    dt = period / 80
    sim = Simulator(model, step_seconds=dt, y0=model.initial_guess(), mode=flap,
                    mode_amplitude=0.02, newton_tol=1e-11)
    E = [blade_hub_energy(model, sim.y, 0.0)]
    for _ in range(int(4 * period / dt)):
        sim.step()
        E.append(blade_hub_energy(model, sim.y, sim.t))
    h = sim.history()
    found, peaks = decay_rate(h["time"], h["blade0_u"][:, -1, 2])
    assert peaks >= 3
    print(f"\nfree decay {found:.5f} 1/s, eigenvalue {rate:.5f} 1/s")
    assert found == pytest.approx(rate, rel=1e-2)
    assert np.all(np.diff(E) < 0)


def test_damping_in_the_turbine_file_round_trips_and_bad_values_are_named():
    t = quiet_load("nrel5mw")
    tower = dc.replace(t.tower, damping=BeamDamping(stiffness=(0, 0, 0, 1e-2, 2e-3, 2e-3),
                                                    mass=(0, 0.1, 0, 0, 0, 0)))
    t2 = dc.replace(t, tower=tower)
    text = dump_turbine(t2)
    assert "flap: [0.477465, 0.477465]" in text
    back = turbine_from_dict(yaml.safe_load(text))
    assert back.blade.damping == t2.blade.damping
    assert back.tower.damping == t2.tower.damping
    d = yaml.safe_load(text)
    d["blade"]["damping"] = {"modal_percent": {"flap": [1, 2, 3], "twist": 1},
                             "stiffness": [1, 2]}
    d["tower"]["damping"] = {"modal_percent": {"fore_aft": [120]}}
    with pytest.raises(TurbineFileError) as err:
        turbine_from_dict(d)
    text = str(err.value)
    assert "blade.damping.stiffness = [1, 2]: must be a list of six numbers >= 0 [s]" in text
    assert "blade.damping.modal_percent.twist: unknown key (allowed: flap, edge)" in text
    assert "blade.damping.modal_percent.flap = [1, 2, 3]: must be one or two numbers" in text
    assert "tower.damping.modal_percent.fore_aft = [120]: must be below 100" in text
    d["blade"]["damping"] = {"modal_percent": {"flap": 1}, "mass": [0] * 6}
    d["tower"].pop("damping")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(TurbineFileError, match="give modal_percent or stiffness/mass"):
            turbine_from_dict(d)
