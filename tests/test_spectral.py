"""The p-version of the mixed beam element (hawt_core/fem/spectral.py) and its Gauss-point
Jacobian (hawt_core/fem/spectral_jacobian.py).

References and tolerances:
- order 1 on uniform properties is the paper's element (fem/beam.py, an independent
  implementation): the residual of both at random states with gravity and root motion
  equal to 1e-13 of its scale;
- the dense complex-step Jacobian of the whole residual (numerics/jacobian.py): the
  Gauss-point Jacobian equal to 1e-12 of the largest entry on a curved, twisted, tapered
  beam with offsets, flexible axial and shear directions, a tip body, loads reading every
  Gauss-point input and two unknowns per Gauss point (dR/dy and dR/dydot);
- closed forms of a uniform cantilever (Euler-Bernoulli bending, beta_n L = 1.87510407,
  4.69409113, 7.85475744, 10.99554073; torsion (2n - 1) pi / 2L sqrt(GJ / i1)): four flap
  and two torsion frequencies within 1e-7 at order 6 with 4 elements (the rotary inertia
  is set to 1e-9 so that the closed form applies), and the observed order of convergence
  2p (within 0.4) for p = 1, 2, 3 from 4 to 8 elements;
- an independent solution of the shipped NREL 5-MW and IEA 15-MW blades (tests/
  test_real_turbines.py: Euler-Bernoulli, 200 Hermite elements with the deck's tables,
  converged to 2e-5): the five lowest bending frequencies at standstill within 5e-5 at
  order 6 with 4 elements (observed <= 2.3e-5; the paper's element needs ~128 elements
  for 1e-4);
- a curved blade (prebend and sweep) against the paper's element's polygon mesh refined to
  128 and 256 elements and Richardson-extrapolated (an independent treatment of the
  curvature: straight chords with their own frames): within 2e-6.
"""
from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

from beam_cases import every_term_model
from test_beam_jacobian import _case, pointwise_against_dense
from test_real_turbines import euler_bernoulli_blade, quiet_load
from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.fem.beam import BeamElements
from hawt_core.fem.sections import mesh_beam
from hawt_core.fem.spectral import SpectralBeamElements, gll_points, lagrange_basis
from hawt_core.fem.spectral_jacobian import SpectralPointwiseJacobian
from hawt_core.model import Beam, SectionTable


def test_bases():
    """GLL points (p = 4: 0, (1 -+ sqrt(3/7)) / 2, 1/2, 1) and the Lagrange basis: nodal
    (identity at its nodes), a partition of unity, derivatives summing to zero."""
    x = gll_points(4)
    assert x == pytest.approx([0.0, (1 - np.sqrt(3 / 7)) / 2, 0.5, (1 + np.sqrt(3 / 7)) / 2,
                               1.0], abs=1e-15)
    val, der = lagrange_basis(x, x)
    assert val == pytest.approx(np.eye(5), abs=1e-14)
    z = np.linspace(0, 1, 7)
    val, der = lagrange_basis(x, z)
    assert val.sum(1) == pytest.approx(1.0, abs=1e-14)
    assert der.sum(1) == pytest.approx(0.0, abs=1e-12)
    # derivative of x^3 interpolated exactly (degree 4 basis)
    assert der @ x ** 3 == pytest.approx(3 * z ** 2, abs=1e-12)


def _uniform(L=10.0):
    return SectionTable.uniform(mass=50.0, i1=2.0, i2=0.3, i3=1.7, gj=1e5, ei2=2e6, ei3=8e6)


def test_order_one_on_uniform_properties_is_the_papers_element():
    beam = Beam(10.0, _uniform(), 4)
    old = BeamElements(mesh_beam(beam))
    new = SpectralBeamElements(beam, 4, 1)
    rng = np.random.default_rng(3)
    y = 0.1 * rng.standard_normal((3, old.n))
    yd = rng.standard_normal((3, old.n))
    v, w, g = (rng.standard_normal((3, 3)) for _ in range(3))
    r0 = old.residual(yd, y, v, w, g)
    r1 = new.residual(yd, y, v, w, g)
    assert np.abs(r1 - r0).max() <= 1e-13 * np.abs(r0).max()


@pytest.mark.parametrize("states", [0, 2])
def test_gauss_point_jacobian_equals_dense_complex_step(states):
    rng = np.random.default_rng(11 + states)
    beam = SpectralBeamElements(every_term_model(2), 2, 3)
    pw = SpectralPointwiseJacobian(beam, states)
    fun = _case(beam, states, rng)
    for ref in pointwise_against_dense(beam, pw, fun, states, rng):
        assert np.count_nonzero(ref) > 500
    # the clamped root's element and the tip body are exercised
    assert beam._has_tip_body and np.abs(ref[:, 12 + 6:12 + 12]).max() > 0


def _modes(beam, count=20):
    t = quiet_load("paper")
    t = dc.replace(t, blade=beam, rotor=dc.replace(t.rotor, precone=0.0))
    return blade_modes(t, rotor_speed=0.0, count=count).modes


L_C, M_C, EI_C, GJ_C, I1_C = 10.0, 50.0, 2e6, 1e5, 2.0
BETA_L = np.array([1.87510407, 4.69409113, 7.85475744, 10.99554073])


def _cantilever(elements, order):
    sec = SectionTable.uniform(mass=M_C, i1=I1_C, i2=1e-9, i3=1e-9, gj=GJ_C, ei2=EI_C,
                               ei3=4 * EI_C)
    modes = _modes(Beam(L_C, sec, elements, order=order))
    flap = np.array([m.frequency_hz for m in modes if m.family == "flap"][:4])
    torsion = np.array([m.frequency_hz for m in modes if m.family == "torsion"][:2])
    return flap, torsion


def test_uniform_cantilever_closed_forms():
    flap_ref = BETA_L ** 2 * np.sqrt(EI_C / (M_C * L_C ** 4)) / (2 * np.pi)
    tors_ref = np.array([1, 3]) * np.pi / (2 * L_C) * np.sqrt(GJ_C / I1_C) / (2 * np.pi)
    flap, torsion = _cantilever(4, 6)
    assert flap == pytest.approx(flap_ref, rel=1e-7)
    assert torsion == pytest.approx(tors_ref, rel=1e-7)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_observed_order_of_convergence_is_2p(order):
    flap_ref = BETA_L ** 2 * np.sqrt(EI_C / (M_C * L_C ** 4)) / (2 * np.pi)
    e4 = np.abs(_cantilever(4, order)[0][1:3] / flap_ref[1:3] - 1)
    e8 = np.abs(_cantilever(8, order)[0][1:3] / flap_ref[1:3] - 1)
    observed = np.log2(e4 / e8)
    assert np.all(np.abs(observed - 2 * order) < 0.4), observed


@pytest.mark.parametrize("name", ["nrel5mw", "iea15mw"])
def test_real_blades_at_four_elements_against_an_independent_solution(name):
    t = quiet_load(name).without_structural_damping()      # undamped, as the reference
    t = dc.replace(t, rotor=dc.replace(t.rotor, precone=0.0))
    ref = euler_bernoulli_blade(t, 0.0)[:5]
    modes = _modes(dc.replace(t.blade, elements=4, order=6), count=8)
    got = np.array([m.frequency_hz for m in modes if m.family in ("flap", "lag")][:5])
    assert got == pytest.approx(ref, rel=5e-5)


def test_curved_blade_against_the_papers_element_refined():
    """Prebend and sweep (no twist or offsets: the paper's element interpolates the mass
    matrix between stations, the p-version the properties, as the file format says; the
    two continua differ where the matrix is nonlinear in them)."""
    b = every_term_model(4)
    sec = dc.replace(b.sections, twist=None, cg_offset=None, tension_offset=None, ea=None,
                     ga2=None, ga3=None)
    beam = dc.replace(b, sections=sec, tip_mass=0.0, tip_inertia=(0.0, 0.0, 0.0))
    f = lambda bm: np.array([m.frequency_hz for m in _modes(bm, 8)])    # noqa: E731
    p6 = f(dc.replace(beam, elements=4, order=6))
    f1, f2 = f(dc.replace(beam, elements=128)), f(dc.replace(beam, elements=256))
    assert p6 == pytest.approx(f2 + (f2 - f1) / 3, rel=2e-6)
    assert np.abs(f2 / p6 - 1).max() > 1e-5         # the refined polygon is still off


@pytest.mark.parametrize("name", ["nrel5mw", "iea15mw"])
def test_coarse_meshes_of_real_blades_have_no_spurious_or_unstable_mode(name):
    """A cell across the blade root's steep stiffness change gets an indefinite property
    moment at a point (the product-integration weights change sign): before the guard in
    fem/spectral.py property_moments, the NREL 5-MW at order 4 with one element had a
    real eigenvalue pair (a static instability) and with two a spurious flap mode at
    2.84 Hz.  Reference: positive semi-definite section matrices at every Gauss point, a
    spectrum with neither real nor growing eigenvalues (1e-6 of |lambda|), and, from 6
    cells, the first two modes (flap 1, lag 1) within 0.5 % of the converged ones (order
    6, 4 elements)."""
    t = quiet_load(name)
    t = dc.replace(t, rotor=dc.replace(t.rotor, precone=0.0))
    ref = np.array([m.frequency_hz for m in _modes(dc.replace(t.blade, elements=4, order=6),
                                                   4)])[:2]
    for order, elements in ((4, 1), (4, 2), (6, 1), (3, 2)):
        beam = SpectralBeamElements(t.blade, elements, order)
        for M in (beam.R, beam.mass):
            sym = 0.5 * (M + np.swapaxes(M, -1, -2))
            eig = np.linalg.eigvalsh(sym.reshape(-1, 6, 6))
            assert eig.min() >= -1e-12 * np.abs(eig).max(), (order, elements)
        tt = dc.replace(t, blade=dc.replace(t.blade, elements=elements, order=order))
        modes = blade_modes(tt, rotor_speed=0.0, method="dense").modes
        lam = np.array([m.eigenvalue for m in modes])
        assert np.all(np.abs(lam.imag) > 1e-6 * np.abs(lam)), (order, elements)
        assert lam.real.max() <= 1e-6 * np.abs(lam).max(), (order, elements)
        if order * elements >= 6:   # (4, 1) is simply too coarse for the IEA 15-MW's lag 1
            f = np.array([m.frequency_hz for m in modes])[:2]
            assert f == pytest.approx(ref, rel=5e-3), (order, elements)
