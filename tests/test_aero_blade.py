"""One blade of the NREL 5-MW spinning in axial wind with blade-element momentum loads at its
Gauss points (hawt_core/assembly/aero_blade.py): the aeroelastic steady state.

References (each test states its tolerance):
* the rigid-rotor BEM of aero/bem.py (Ning's one-residual solution, itself checked against
  Glauert's optimum rotor and the NREL 5-MW's published Cp in tests/test_bem.py) at the same
  radii: a stiff blade must reach its inductions, the error shrinking with the compliance;
* energy: the shaft power through the blade root (root loads about the shaft axis times the
  rotor speed) equals the aerodynamic power of the distributed driving forces (the inertial
  loads of steady rotation have no moment about the shaft), to the discretization error;
* complex-step Jacobian columns equal central differences.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from hawt_core.aero import BemRotor, StationPolars
from hawt_core.assembly.aero_blade import AeroelasticBlade
from meshes import load_paper_mesh

U, TSR = 8.0, 7.5


def nrel5mw(stiffness=1.0, precone=0.0):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_paper_mesh("nrel5mw")
    sec = t.blade.sections
    kw = {k: getattr(sec, k) * stiffness for k in ("gj", "ei2", "ei3", "ea", "ga2", "ga3")
          if getattr(sec, k) is not None}
    if sec.stiffness_6x6 is not None:
        kw["stiffness_6x6"] = sec.stiffness_6x6 * stiffness
    omega = TSR * U / (t.hub.radius + t.blade.length)
    return replace(t, rotor=replace(t.rotor, precone=precone, speed=omega),
                   blade=replace(t.blade, sections=replace(sec, **kw)))


def rigid_bem(model, turbine, pitch=0.0):
    aero = turbine.aerodynamics
    s = model.beam.xg.ravel() / turbine.blade.length
    r = model.r[..., 0].ravel()
    rotor = BemRotor(turbine.rotor.blades, r, np.interp(s, aero.stations, aero.chord),
                     -np.interp(s, aero.stations, aero.twist), StationPolars(aero, s),
                     model.hub_r, model.tip_r)
    return rotor.solve(U, model.omega, pitch)


def test_stiff_blade_reaches_the_rigid_rotor_bem():
    """A blade 1e4 and 1e6 times stiffer than the NREL 5-MW's: the inductions a, a' at every
    Gauss point equal the rigid-rotor BEM's at those radii within 3e-5 and 3e-7 (the error is
    the deflection's, proportional to the compliance: it falls 100-fold with it)."""
    errors = []
    for k in (1e4, 1e6):
        t = nrel5mw(stiffness=k)
        m = AeroelasticBlade(t, U, elements=8)
        y = m.steady_state()
        d = {}
        m.residual(np.zeros(m.n), y, details=d)
        ref = rigid_bem(m, t)
        errors.append(max(np.max(np.abs(d["a"][..., 0].ravel() - ref.a)),
                          np.max(np.abs(d["ap"][..., 0].ravel() - ref.ap))))
    print(f"\nstiff blade vs rigid BEM: max |da|, |da'| {errors}")
    assert errors[0] < 3e-5 and errors[1] < 3e-7
    assert 50 < errors[0] / errors[1] < 200


def test_pitched_stiff_blade_reaches_the_pitched_rigid_bem():
    """Collective pitch 6 deg towards feather (hawt's rotor.pitch = -6 deg, the mesh turned):
    the stiff blade's inductions equal the rigid BEM's with that pitch (3e-7); the airfoil
    sits in the pitched section frame (a pitch that reached only the structure fails it)."""
    p = np.radians(6.0)
    t = nrel5mw(stiffness=1e6)
    t = replace(t, rotor=replace(t.rotor, pitch=-p))
    m = AeroelasticBlade(t, U, elements=8)
    y = m.steady_state()
    d = {}
    m.residual(np.zeros(m.n), y, details=d)
    ref = rigid_bem(m, t, pitch=p)
    err = max(np.max(np.abs(d["a"][..., 0].ravel() - ref.a)),
              np.max(np.abs(d["ap"][..., 0].ravel() - ref.ap)))
    assert err < 3e-7, err


def shaft_power(m, y):
    """(through the root, of the distributed loads) [W] for one blade."""
    d = {}
    m.residual(np.zeros(m.n), y, details=d)
    torque_root = m.root_loads(y)[0]
    beam = m.beam
    weights = beam.h[:, None] * beam.w[None, :]              # Gauss weights per element
    aero = np.sum(d["drive"][..., 0] * m.r[..., 0] * weights)
    return torque_root * m.omega, aero * m.omega


def test_shaft_power_equals_aerodynamic_power():
    """The flexible NREL 5-MW blade (its own stiffness and precone): the power through the
    root equals that of the aerodynamic driving forces on the deformed blade, to the
    discretization error (1e-3 at N = 16, shrinking with the mesh)."""
    gaps = []
    for N in (8, 16):
        t = nrel5mw(precone=-0.04363323129985824)
        m = AeroelasticBlade(t, U, elements=N)
        y = m.steady_state()
        root, aero = shaft_power(m, y)
        gaps.append(abs(root / aero - 1))
        print(N, gaps[-1])
        print(f"\nN = {N}: shaft power {root / 1e3:.2f} kW through the root, "
              f"{aero / 1e3:.2f} kW of the driving forces")
    assert gaps[-1] < 1e-3 and gaps[-1] < gaps[0]


def test_complex_step_jacobian_equals_central_differences():
    """The sparse Jacobian (the Gauss-point integrands' steps, fem/beam_jacobian.py) equals
    the dense complex-step one (1e-12: it misses no entry); 40 columns of it at the flexible blade's steady state: against central
    differences (step 1e-5 of the unknown's scale), 1e-5 of the column's largest entry plus
    the differences' own cancellation error (the residual's root rows are ~1e6 N)."""
    t = nrel5mw()
    m = AeroelasticBlade(t, U, elements=4)
    y = m.steady_state()
    J = m.jacobian(y).toarray()
    dense = m.dense_jacobian(y)                               # the steps lose nothing
    assert np.allclose(J, dense, rtol=1e-12, atol=1e-12 * np.max(np.abs(dense)))
    scale = np.maximum(np.abs(y), 1.0)
    z = np.zeros(m.n)
    big = np.max(np.abs(m.residual(z, y + 0.0)) + np.abs(y))     # round-off scale of R
    cols = np.linspace(0, m.n - 1, 40).astype(int)
    for j in cols:
        h = 1e-5 * scale[j]
        e = np.zeros(m.n)
        e[j] = h
        cd = (m.residual(z, y + e) - m.residual(z, y - e)) / (2 * h)
        # truncation (h^2) and cancellation (|R| eps / h) of the central difference
        tol = 1e-5 * max(1.0, np.max(np.abs(J[:, j]))) + 1e3 * np.finfo(float).eps * big / h
        assert np.max(np.abs(cd - J[:, j])) < tol, j


def test_oye_dynamic_inflow_keeps_the_steady_state():
    """With Oye's dynamic inflow (four differential unknowns per Gauss point) the steady state
    is the quasi-steady one (the filters pass a constant: 1e-8 in the inductions, 1e-9 of the
    beam unknowns), z = (1 - k) a, and tau1 = 1.1 R / ((1 - 1.3 a_mean) U) from the state's
    area-weighted mean induction; the rate coefficients of the filter rows are tau2 and tau1
    (dR/dydot, complex step)."""
    from hawt_core.aero.inflow import OYE_K
    t = nrel5mw(precone=-0.04363323129985824)
    q = AeroelasticBlade(t, U, elements=8)
    o = AeroelasticBlade(t, U, elements=8, inflow="oye")
    yq, yo = q.steady_state(), o.steady_state()
    nb, ns = q.n_beam, q.n_stations
    assert np.max(np.abs(yq[:nb] - yo[:nb])) < 1e-9 * np.max(np.abs(yq[:nb]))
    assert np.max(np.abs(yq[nb:] - yo[nb:nb + 2 * ns])) < 1e-8
    # Oye's weight k = 0.6 (Snel & Schepers, ECN-C--94-107, 1995; Hansen, Aerodynamics of
    # Wind Turbines, 3rd ed., section 10.1), stated here, not read from the module
    assert OYE_K == 0.6
    assert np.allclose(yo[nb + 2 * ns:], (1 - 0.6) * yo[nb:nb + 2 * ns], atol=1e-14)
    a = yo[nb:nb + ns].reshape(o.beam.xg.shape)
    w = o.r[..., 0] * o.beam.h[:, None] * o.beam.w[None, :]
    a_mean = np.sum(a * w) / np.sum(w)
    assert o.tau1 == pytest.approx(1.1 * o.rotor_radius / ((1 - 1.3 * a_mean) * U), rel=1e-12)
    h = 1e-30
    rows = nb + np.arange(4 * ns)
    E = np.array([o.residual(1j * h * np.eye(o.n)[j], yo).imag / h for j in rows]).T
    diag = E[rows, np.arange(4 * ns)]
    tau2 = np.broadcast_to(o.tau2[..., 0], o.beam.xg.shape).ravel()
    assert np.allclose(diag[:ns], tau2, rtol=1e-12) and np.allclose(diag[ns:2 * ns], tau2)
    assert np.allclose(diag[2 * ns:], o.tau1, rtol=1e-12)
    with pytest.raises(ValueError, match="inflow"):
        AeroelasticBlade(t, U, inflow="pitt-peters")


def test_inductions_do_not_depend_on_the_air_density():
    """Reference: the momentum balance of an annulus equates the blade-element thrust and
    torque to rho U^2-proportional momentum fluxes, so the density cancels: at rho = 1.0 and
    1.225 a (stiff: x 1e4) blade in the same wind has the same inductions, quasi-steady and
    with Oye's filters (1e-5: what is left is the stiff blade's deflection, which the loads
    change; 1.7e-6 found at the tip), and its root torque and thrust scale with rho (1e-5).
    A density written into the momentum balance instead of the model's (22 % off at
    rho = 1.0) would fail it."""
    t = nrel5mw(stiffness=1e4)
    for inflow in ("quasi-steady", "oye"):
        kw = {} if inflow == "quasi-steady" else {"inflow": "oye"}
        m1 = AeroelasticBlade(t, U, elements=8, rho=1.0, **kw)
        m2 = AeroelasticBlade(t, U, elements=8, rho=1.225, **kw)
        y1, y2 = m1.steady_state(), m2.steady_state()
        a1, ap1 = m1.inductions(y1)
        a2, ap2 = m2.inductions(y2)
        assert np.max(np.abs(a1 - a2)) < 1e-5 and np.max(np.abs(ap1 - ap2)) < 1e-5, inflow
        assert 0.2 < np.max(a1) < 0.6                      # a loaded rotor, not a trivial one
        (q1, T1), (q2, T2) = m1.root_loads(y1), m2.root_loads(y2)
        assert q2 / q1 == pytest.approx(1.225, rel=1e-5) and T2 / T1 == pytest.approx(1.225,
                                                                                     rel=1e-5)


def test_aerodynamic_centre_ahead_of_the_line_adds_its_moment():
    """``ac_chordwise`` = a: the loads act a distance a ahead of the reference line along the
    chord, d = a (0, cos tau, sin tau) in the section frame (aero/strip.py).  Reference,
    statics of a cantilever: on a blade 1e4 times stiffer than the NREL 5-MW's (so that
    the loads do not move it) the root's moment about b1 grows by the integral of the
    distributed moment d x F, a (cos tau F3 - sin tau F2), with F3 and F2 the thrust and
    driving force per length at the Gauss points (quadrature weights of the beam), within
    1e-4 (found 1.5e-6); the forces, hence the shaft torque and thrust, stay within 1e-4
    (found 1.2e-5: the blade twists 1e-4 times the NREL 5-MW's)."""
    from hawt_core.fem.beam import ROOT_M
    t = nrel5mw(stiffness=1e4)
    a = t.aerodynamics
    out = []
    for ac in (None, 0.25 * a.chord):
        m = AeroelasticBlade(replace(t, aerodynamics=replace(a, ac_chordwise=ac)), U,
                             elements=8)
        y = m.steady_state()
        d = {}
        m.residual(np.zeros(m.n), y, details=d)
        out.append((m, y, d))
    (m0, y0, _), (m, y, d) = out
    b = m.beam
    s = b.xg / t.blade.length
    tau = np.interp(s, a.stations, a.twist)
    arm = np.interp(s, a.stations, 0.25 * a.chord)
    want = np.sum(b.h[:, None] * b.w[None, :] * arm
                  * (np.cos(tau) * d["thrust"][..., 0] - np.sin(tau) * d["drive"][..., 0]))
    assert want > 1e4                                      # lift ahead of the line: nose up
    assert y[ROOT_M][0] - y0[ROOT_M][0] == pytest.approx(want, rel=1e-4)
    np.testing.assert_allclose(m.root_loads(y), m0.root_loads(y0), rtol=1e-4)
