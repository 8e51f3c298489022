"""dR/dy from steps of the Gauss-point integrands (hawt_core/fem/beam_jacobian.py).

Reference: the dense complex-step Jacobian of the whole residual (numerics/jacobian.py
dense_complex_step: one step per unknown, exact to round-off), and central differences.
Every term is exercised: a curved (prebent, swept), twisted, tapered beam with mass-centre
and tension-centre offsets, flexible axial and shear directions, gravity, root motion, tip
loads, a rigid tip body, distributed loads that read every Gauss-point input (velocities,
position, rotation, a rotated wind) and, in the second test, two unknowns per Gauss point
whose rows read the point's velocities and whose values enter its loads.  The turbine-level
tests (tests/test_assembly.py, tests/test_turbine_aero.py) compare the assembled turbine
Jacobians (blades with aerodynamic states, tower with drag) the same way.
Both dR/dy and dR/dydot (the same steps applied to the rates).
Tolerance: 1e-12 of the largest entry (round-off; a wrong chain-rule weight or a missed
term is O(1) of its entries), and central differences within 1e-6.
"""
from __future__ import annotations

import numpy as np

from beam_cases import every_term_beam
from hawt_core.fem.beam_jacobian import PointwiseBeamJacobian
from hawt_core.numerics.jacobian import STEP, dense_complex_step
from hawt_core.numerics.rotations import rot_apply


def _loads(sec, X=None):
    """Distributed loads reading every Gauss-point input, nonlinearly; with states X
    (k, N, G, B) a load proportional to them."""
    V, Om, pos, th, wind = sec["V"], sec["Omega"], sec["position"], sec["theta"], sec["wind"]
    rel = wind - V
    speed = np.sqrt(np.sum(rel * rel, axis=-1, keepdims=True) + 1.0)
    f = 0.3 * speed * rel + 0.1 * np.sin(pos) + 0.05 * rot_apply(th, pos)
    m = 0.02 * speed * Om + 0.01 * np.cos(th) * rel
    if X is not None:
        f = f + np.stack([X[0], X[1], X[0] * X[1]], -1)
        m = m + 0.1 * np.stack([X[1], X[0] ** 2, X[0]], -1)
    return f, m


def _case(beam, k, rng):
    """fun(ydot, y) of one beam (+ k states per Gauss point), with a capture argument."""
    N, G = beam.N, len(beam.eta)
    v, w = rng.normal(size=(1, 3)), rng.normal(size=(1, 3))
    g = np.array([[-9.81, 1.0, 2.0]])
    tf, tm = rng.normal(size=(1, 3)), rng.normal(size=(1, 3))
    wind = rng.normal(size=(1, 3)) * 5

    def fun(yd, y, capture=None):
        yd, y = np.atleast_2d(yd), np.atleast_2d(y)
        B = y.shape[0]
        rep = lambda a: np.repeat(a, B, axis=0)                    # noqa: E731
        X = y[:, beam.n:].reshape(B, k, N, G).transpose(1, 2, 3, 0) if k else None
        Xd = yd[:, beam.n:].reshape(B, k, N, G).transpose(1, 2, 3, 0) if k else None
        rows = {}

        def loads(sec):
            if k:   # states relax towards a function of the point's velocity and position
                target = np.stack([np.sum(sec["V"] ** 2, -1) * 0.01,
                                   np.tanh(sec["position"][..., 2] + sec["Omega"][..., 0])])
                r = Xd - 2.0 * (target - X)
                rows["r"] = r.transpose(3, 0, 1, 2).reshape(B, -1)
            return _loads(sec, X)

        out = beam.residual(yd[:, :beam.n], y[:, :beam.n], rep(v), rep(w), rep(g), rep(tf),
                            rep(tm), wind=rep(wind), section_loads=loads, capture=capture)
        return np.concatenate([out, rows["r"]], axis=1) if k else out
    return fun


def pointwise_against_dense(beam, pw, fun, states, rng):
    """Compare ``pw``'s dR/dy and dR/dydot of ``fun`` (from :func:`_case`) at a random state
    with the dense complex step of the whole residual (1e-12 of the largest entry); returns
    the dense references (dR/dy, dR/dydot)."""
    y = rng.normal(size=pw.n) * 0.3
    yd = rng.normal(size=pw.n)
    D = pw.directions
    refs = []
    for rates in (False, True):
        cap = {}
        if rates:
            r = fun(yd[None] + 1j * STEP * pw.seeds, np.tile(y, (D, 1)), cap)
            ref = dense_complex_step(lambda z: fun(z, y)[0], yd)
        else:
            r = fun(np.tile(yd, (D, 1)), y[None] + 1j * STEP * pw.seeds, cap)
            ref = dense_complex_step(lambda z: fun(yd, z)[0], y)
        rows, cols, vals = pw.values(cap, r[:, beam.n:] if states else None, STEP, 1,
                                     rates=rates)
        J = np.zeros((pw.n, pw.n))
        np.add.at(J, (rows, cols), vals[0])
        assert np.abs(J - ref).max() <= 1e-12 * np.abs(ref).max(), rates
        refs.append(ref)
    return refs


def _check(k):
    rng = np.random.default_rng(11 + k)
    beam = every_term_beam(4)
    pw = PointwiseBeamJacobian(beam, k)
    fun = _case(beam, k, rng)
    y = rng.normal(size=pw.n) * 0.3
    yd = rng.normal(size=pw.n)
    D = pw.directions
    assert D == 18 + k
    cap = {}
    r = fun(np.tile(yd, (D, 1)), y[None] + 1j * STEP * pw.seeds, cap)
    rows, cols, vals = pw.values(cap, r[:, beam.n:] if k else None, STEP, 1)
    J = np.zeros((pw.n, pw.n))
    np.add.at(J, (rows, cols), vals[0])
    Jd = dense_complex_step(lambda yy: fun(yd, yy)[0], y)
    scale = np.abs(Jd).max()
    assert np.abs(J - Jd).max() <= 1e-12 * scale
    hstep = 1e-6 * np.maximum(1.0, np.abs(y))
    Jf = np.stack([(fun(yd, y + hstep[j] * e)[0] - fun(yd, y - hstep[j] * e)[0]) / (2 * hstep[j])
                   for j, e in enumerate(np.eye(pw.n))], -1)
    assert np.abs(J - Jf).max() <= 1e-6 * scale
    # the first element's u, theta (clamped left node) and the tip body are exercised
    assert np.abs(Jd[:, 12 + 6:12 + 12]).max() > 0 and beam._has_tip_body
    # dR/dydot from the same steps applied to the rates
    cap = {}
    r = fun(yd[None] + 1j * STEP * pw.seeds, np.tile(y, (D, 1)), cap)
    rows, cols, vals = pw.values(cap, r[:, beam.n:] if k else None, STEP, 1, rates=True)
    J = np.zeros((pw.n, pw.n))
    np.add.at(J, (rows, cols), vals[0])
    Jr = dense_complex_step(lambda ydd: fun(ydd, y)[0], yd)
    assert np.abs(J - Jr).max() <= 1e-12 * np.abs(Jr).max()
    assert np.count_nonzero(Jr) > 100


def test_pointwise_jacobian_of_a_beam_equals_dense_complex_step():
    _check(0)


def test_pointwise_jacobian_with_states_per_gauss_point():
    _check(2)
