"""hawt_core.numerics.newton: Newton's method and its chord variant (a kept Jacobian).

Reference: scipy.optimize.root (MINPACK's hybrid method, xtol 1e-14) on the same mildly
nonlinear system, y (A + 0.02 diag(y^2)) = b; tolerance 1e-10 of the solution's scale."""
import numpy as np
import scipy.optimize as so
import scipy.sparse as sp

from hawt_core.numerics.newton import newton


def _system(n=40):
    rng = np.random.default_rng(3)
    A = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(n, n)).toarray() + 0.1 * rng.random((n, n))
    b = rng.random(n)
    fun = lambda y: A @ y + 0.02 * y ** 3 - b
    jac = lambda y: sp.csc_matrix(A + np.diag(0.06 * y ** 2))
    return fun, jac, n


def test_chord_newton_reaches_the_root_with_fewer_jacobians():
    fun, jac, n = _system()
    calls = {"newton": 0, "chord": 0}

    def counted(key):
        def j(y):
            calls[key] += 1
            return jac(y)
        return j

    ref = so.root(fun, np.zeros(n), jac=lambda y: jac(y).toarray(), tol=1e-14).x
    y1, _ = newton(fun, counted("newton"), np.zeros(n), tol=1e-13)
    y2, _ = newton(fun, counted("chord"), np.zeros(n), tol=1e-13, reuse_jacobian=True)
    for y in (y1, y2):
        np.testing.assert_allclose(y, ref, atol=1e-10 * np.abs(ref).max())
    assert calls["chord"] < calls["newton"]


def test_chord_newton_takes_a_fresh_jacobian_when_a_step_does_not_contract():
    """A Jacobian that is badly wrong (scaled by 3) contracts by 2/3 per step: the chord
    variant must not keep it forever (each refresh calls jac again), and still converges."""
    fun, jac, n = _system()
    calls = []

    def bad_then_good(y):
        calls.append(1)
        return jac(y) * (3.0 if len(calls) == 1 else 1.0)

    y, _ = newton(fun, bad_then_good, np.zeros(n), tol=1e-13, reuse_jacobian=True)
    assert np.abs(fun(y)).max() < 1e-12 and len(calls) >= 2
