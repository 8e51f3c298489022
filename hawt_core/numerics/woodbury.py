"""Low-rank (Woodbury) updates of a factorized matrix.

``(A0 + U V^T)^-1 = A0^-1 - A0^-1 U (I + V^T A0^-1 U)^-1 V^T A0^-1``.  Two uses in hawt:

* the rigid-body coupling's rows and columns of the simulation's Newton matrix, which turn
  with the azimuth (hawt_core.solvers.march): ``U = [dA[:, cols], E_rows]``,
  ``V^T = [E_cols^T; dR]`` with ``dR`` the change of the coupling rows at the columns ``kc``
  (the blades' root loads), rank len(cols) + len(rows);
* the time-varying rows and columns of the Floquet stage matrices
  (hawt_core.solvers.floquet.lowrank), whose capacitance matrices have blocks of very
  different magnitudes: :func:`equilibrated_solve`.
"""
from __future__ import annotations

import numpy as np

__all__ = ["row_column_capacitance", "row_column_correction", "equilibrate_rows_columns",
           "equilibrated_solve"]


def row_column_capacitance(Z: np.ndarray, dR: np.ndarray, rc: np.ndarray,
                           kc: np.ndarray) -> np.ndarray:
    """Inverse of the capacitance ``I + V^T A0^-1 U = I + [Z[rc]; dR Z[kc]]`` of a
    row/column update (columns ``rc`` replaced, rows changed by ``dR`` at columns ``kc``),
    ``Z = A0^-1 U`` (n, len(rc) + len(dR)); raises numpy's LinAlgError if singular."""
    cap = np.eye(Z.shape[1]) + np.concatenate([Z[rc], dR @ Z[kc]])
    return np.linalg.inv(cap)


def row_column_correction(y0: np.ndarray, Z: np.ndarray, Cinv: np.ndarray, dR: np.ndarray,
                          rc: np.ndarray, kc: np.ndarray) -> np.ndarray:
    """``(A0 + U V^T)^-1 b`` from ``y0 = A0^-1 b`` (vector or matrix of columns)."""
    t = np.concatenate([y0[rc], dR @ y0[kc]])
    return y0 - Z @ (Cinv @ t)


def equilibrate_rows_columns(C: np.ndarray):
    """Row and column scalings r, c with diag(r) C diag(c) of unit max-norm rows/columns."""
    r = 1.0 / np.maximum(np.abs(C).max(axis=1), 1e-300)
    c = 1.0 / np.maximum(np.abs(C * r[:, None]).max(axis=0), 1e-300)
    return r, c


def equilibrated_solve(C: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``C^-1 rhs`` after row and column equilibration of C."""
    r, c = equilibrate_rows_columns(C)
    return c[:, None] * np.linalg.solve(C * r[:, None] * c[None, :], rhs * r[:, None])
