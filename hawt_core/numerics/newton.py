"""Newton's method with a sparse LU (steady states, harmonic balance, statics)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

__all__ = ["ConvergenceError", "newton"]


class ConvergenceError(RuntimeError):
    """A Newton iteration did not converge."""


def newton(fun, jac, y0, tol=1e-9, max_iter=30, what="steady state", fixed=None,
           linear_solve=None):
    """Newton's method with a sparse LU; ``tol`` is relative to the first residual's scale.

    ``linear_solve(J, r)``: an optional solver of the Newton step ``J dy = r`` (e.g. a
    preconditioned Krylov method); returning None falls back to the sparse LU, which is
    also used whenever ``fixed`` is given.
    ``fixed``: indices of unknowns held at their initial values (ignorable coordinates such
    as a free yaw angle, whose columns of the Jacobian vanish, so J is singular): each step
    solves the bordered system ``[[J, B], [P^T, 0]] [dy; mu] = [r; 0]``, ``P`` selecting the
    fixed unknowns and ``B`` fixed pseudo-random columns (generically outside the range of
    J, which makes the bordered matrix regular); for a consistent system ``mu`` vanishes at
    the solution, which is then the one with the fixed unknowns unchanged.
    Raises ConvergenceError naming ``what``, the iteration count and the residual reached.
    """
    y = np.array(y0, dtype=float)
    r = fun(y)
    scale = max(1.0, np.max(np.abs(r)))
    fixed = np.asarray([] if fixed is None else fixed, int)
    n, k = len(y), len(fixed)
    P = sp.csc_matrix((np.ones(k), (fixed, np.arange(k))), shape=(n, k))
    Bcols = np.random.default_rng(12345).standard_normal((n, k))
    for it in range(max_iter):
        if not np.all(np.isfinite(r)):
            raise ConvergenceError(f"{what}: residual became non-finite at iteration {it}")
        if np.max(np.abs(r)) <= tol * scale:
            return y, it
        J = sp.csc_matrix(jac(y))
        dy = linear_solve(J, r) if linear_solve is not None and not k else None
        if dy is not None:
            y = y - dy
            r = fun(y)
            continue
        if k:
            B = sp.csc_matrix(Bcols * (abs(J).max() / np.sqrt(n)))
            J = sp.bmat([[J, B], [P.T, None]], format="csc")
        try:
            dy = spl.splu(J).solve(np.concatenate([r, np.zeros(k)]))[:n]
        except RuntimeError as exc:  # singular factor
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it} ({exc})") from exc
        y = y - dy
        r = fun(y)
    raise ConvergenceError(f"{what}: Newton did not converge in {max_iter} iterations "
                           f"(max residual {np.max(np.abs(r)):.3e}, tolerance {tol * scale:.3e})")
