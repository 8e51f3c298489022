"""Newton's method with a sparse LU (steady states, harmonic balance, statics)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

__all__ = ["ConvergenceError", "newton"]


class ConvergenceError(RuntimeError):
    """A Newton iteration did not converge."""


#: A step with a reused Jacobian must shrink the residual by this factor, else the next
#: step takes a fresh one (``newton(reuse_jacobian=True)``).
CHORD_CONTRACTION = 0.05


def newton(fun, jac, y0, tol=1e-9, max_iter=30, what="steady state", fixed=None,
           linear_solve=None, reuse_jacobian: bool = False, scale=None,
           min_scale: float = 1.0, border=None):
    """Newton's method with a sparse LU; ``tol`` is relative to the first residual's scale
    (or to ``scale`` when given: a warm start's small first residual would otherwise ask for
    a tolerance below the residual's round-off; an array gives each row its own scale, for
    rows of different units, and the solve converges on the rows divided by it).
    ``min_scale``: a floor under the first residual's scale (the loads a warm start must
    still balance to round-off), when ``scale`` is not given.

    ``reuse_jacobian``: keep the Jacobian (and its factors) while each step shrinks the
    largest residual by at least CHORD_CONTRACTION (the chord method; a weakly nonlinear
    problem, such as a harmonic balance started from the rigid rotation, then needs one
    Jacobian instead of one per step); a step that does not takes a fresh Jacobian next.

    ``linear_solve(J, r)``: an optional solver of the Newton step ``J dy = r`` (e.g. a
    preconditioned Krylov method); returning None falls back to the sparse LU, which is
    also used whenever ``fixed`` is given.
    ``fixed``: indices of unknowns held at their initial values (ignorable coordinates such
    as a free yaw angle, whose columns of the Jacobian vanish, so J is singular): each step
    solves the bordered system ``[[J, B], [P^T, 0]] [dy; mu] = [r; 0]``, ``P`` selecting the
    fixed unknowns and ``B`` fixed pseudo-random columns (generically outside the range of
    J, which makes the bordered matrix regular); for a consistent system ``mu`` vanishes at
    the solution, which is then the one with the fixed unknowns unchanged.
    ``border``: {j: (column (n,), update)} for some fixed unknowns ``fixed[j]``: their
    border is that column instead, the derivative of the residual with respect to a
    parameter ``p`` it is linear in, and ``update(mu)`` is called with each step's ``mu``
    to set ``p -= mu``: the parameter is then solved for with the others (a trim: the
    generator torque that balances a free drivetrain, its azimuth held).  Row scales
    apply to the column as to the rows.
    Raises ConvergenceError naming ``what``, the iteration count and the residual reached.
    """
    y = np.array(y0, dtype=float)
    r = fun(y)
    r_unit = None
    if scale is None:
        scale = max(1.0, float(min_scale), np.max(np.abs(r)))
    elif np.ndim(scale):                  # one scale per row: rows of different units
        r_unit = np.maximum(np.asarray(scale, float), 1e-300)
        base_fun = fun
        fun = lambda y: base_fun(y) / r_unit      # noqa: E731 - converge on scaled rows
        base_jac = jac
        jac = lambda y: sp.diags(1.0 / r_unit) @ sp.csc_matrix(base_jac(y))  # noqa: E731
        r = r / r_unit
        scale = 1.0
    else:
        scale = max(1.0, float(scale))
    fixed = np.asarray([] if fixed is None else fixed, int)
    n, k = len(y), len(fixed)
    P = sp.csc_matrix((np.ones(k), (fixed, np.arange(k))), shape=(n, k))
    Bcols = np.random.default_rng(12345).standard_normal((n, k))
    border = {j: (np.asarray(col, float) / (r_unit if r_unit is not None else 1.0), up)
              for j, (col, up) in (border or {}).items()}
    J, lu = None, None
    for it in range(max_iter):
        if not np.all(np.isfinite(r)):
            raise ConvergenceError(f"{what}: residual became non-finite at iteration {it}")
        if np.max(np.abs(r)) <= tol * scale:
            return y, it
        if J is None:
            J, lu = sp.csc_matrix(jac(y)), None
        dy = linear_solve(J, r) if linear_solve is not None and not k else None
        if dy is None:
            if lu is None:
                A = J
                if k:
                    Bd = Bcols * (abs(J).max() / np.sqrt(n))
                    for j, (col, _) in border.items():
                        Bd[:, j] = col
                    A = sp.bmat([[J, sp.csc_matrix(Bd)], [P.T, None]], format="csc")
                try:
                    lu = spl.splu(A)
                except RuntimeError as exc:  # singular factor
                    raise ConvergenceError(f"{what}: singular Jacobian at iteration {it} "
                                           f"({exc})") from exc
            sol = lu.solve(np.concatenate([r, np.zeros(k)]))
            dy = sol[:n]
            for j, (_, update) in border.items():
                update(sol[n + j])
        r_old = np.max(np.abs(r))
        y = y - dy
        r = fun(y)
        if not reuse_jacobian or not np.max(np.abs(r)) <= CHORD_CONTRACTION * r_old:
            J = None                             # a fresh Jacobian for the next step
    raise ConvergenceError(f"{what}: Newton did not converge in {max_iter} iterations "
                           f"(max residual {np.max(np.abs(r)):.3e}, tolerance {tol * scale:.3e})")
