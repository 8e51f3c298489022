"""Eigen-analysis of regular descriptor pencils (A, E): equilibration, exact deflation of the
infinite eigenvalues (index-3 beams), dense and sparse (shift-invert) finite eigenpairs, and
their refinement by inverse iteration."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from .newton import ConvergenceError

__all__ = ["RANK_TOL", "SingularPencilError", "arpack_start", "equilibrate", "deflate_infinite",
           "finite_modes", "sparse_modes", "refine_eigenpairs"]



def arpack_start(n: int, complex_: bool = False, seed: int = 0) -> np.ndarray:
    """A fixed generic start vector for ARPACK (scipy's eigs).  Without one ARPACK draws its
    start from a generator whose state lives in the process and advances with every call, so
    an analysis' last digits (1e-8 of an exponent on the index-3 Hill pencils) depended on
    what ran before it in the same process; with this one they do not."""
    rng = np.random.default_rng(seed)
    v = rng.standard_normal(n)
    return v + 1j * rng.standard_normal(n) if complex_ else v

def equilibrate(A: np.ndarray, E: np.ndarray):
    """Row and column scalings of the pencil (A, E) (eigenvalues are unchanged).

    Returns ``(A_s, E_s, c)`` with ``A_s = R^-1 A C^-1`` (likewise E) and ``c`` the column
    scales: an eigenvector ``z`` of the scaled pencil is ``x = z / c`` of the original one.
    """
    big = np.maximum(np.abs(A), np.abs(E))
    r = big.max(1)
    r[r == 0] = 1.0
    big = big / r[:, None]
    c = big.max(0)
    c[c == 0] = 1.0
    return (A / r[:, None]) / c[None, :], (E / r[:, None]) / c[None, :], c


#: Relative singular-value threshold for the rank decisions of the deflation.
RANK_TOL = 1e-12


class SingularPencilError(RuntimeError):
    """det(A - lambda E) vanishes identically: the linearized model is not well posed."""


_SINGULAR = ("the linearized blade equations are singular (det(A - lambda E) = 0 for all "
             "lambda): check the section data (zero mass or inertia with zero compliance?)")


def deflate_infinite(A: np.ndarray, E: np.ndarray, rank_tol: float = RANK_TOL):
    """Remove the infinite eigenvalues of the regular pencil ``(A, E)``.

    Returns ``(Ar, Er, X)`` with ``Er`` nonsingular, such that the eigenvalues of
    ``Ar z = lam Er z`` are exactly the finite eigenvalues of ``A x = lam E x`` and
    ``x = X z`` their eigenvectors.

    Why: with rigid axial/shear directions the blade is a DAE of index 3.  QZ returns its
    infinite eigenvalues partly as huge finite numbers: a Jordan block of size k at infinity,
    perturbed by round-off, splits into k eigenvalues of size ~ eps^(-1/k), e.g. a +-6e6 per-rev
    real (or imaginary!) pair at N = 32, and no band separates those from the genuine but
    ill-conditioned top of the discrete spectrum in every case.  Deflating is exact instead:
    with ``W`` spanning the left null space of E, every finite eigenvector satisfies
    ``W^T A x = 0``; restricting x to that null space (basis ``N``) and the rows to the
    complement ``P`` of ``W`` gives the smaller pencil ``(P^T A N, P^T E N)`` with the same
    finite eigenpairs and an index lowered by one.  Repeat until E is nonsingular.  The first
    step uses the exact zero rows of E (the algebraic equations); later ones an SVD after
    re-equilibration.
    """
    n = A.shape[0]
    X = np.eye(n)
    first = True
    for _ in range(n + 1):
        A, E, c = equilibrate(A, E)
        X = X / c[None, :]
        m = A.shape[0]
        if m == 0:
            break
        # the constraint rows C = W^T A and the kept rows P^T A, P^T E of this step
        if first:
            first = False
            nonzero = np.any(E != 0, axis=1)
            if nonzero.sum() == m:
                break
            C, PA, PE = A[~nonzero], A[nonzero], E[nonzero]
        else:
            U, s, _ = sl.svd(E)
            r = int((s > s[0] * rank_tol).sum()) if s.size and s[0] > 0 else 0
            if r == m:
                break
            P, W = U[:, :r], U[:, r:]
            C, PA, PE = W.T @ A, P.T @ A, P.T @ E
        _, sc, Vh = sl.svd(C)
        rc = int((sc > sc[0] * rank_tol).sum()) if sc.size and sc[0] > 0 else 0
        if rc < C.shape[0]:
            raise SingularPencilError(_SINGULAR)
        N = Vh[rc:].conj().T
        A, E, X = PA @ N, PE @ N, X @ N
    return A, E, X


def finite_modes(A: np.ndarray, E: np.ndarray, band: float = np.inf):
    """Finite eigenpairs of ``A x = lam E x`` with 0 <= Im(lam) and |lam| < band.

    The infinite eigenvalues are deflated first (:func:`deflate_infinite`); QZ on the reduced
    pencil then keeps ``|beta| > 1e-8 |alpha|`` (after equilibration) and the band (an upper
    bound of the discrete spectrum, see :func:`frequency_bound`) as safety nets.  Returns
    ``(lam, X)`` with X's columns in the unscaled variables.
    """
    Ar, Er, T = deflate_infinite(np.asarray(A, float), np.asarray(E, float))
    if Ar.shape[0] == 0:
        return np.zeros(0, complex), np.zeros((A.shape[0], 0), complex)
    As, Es, c = equilibrate(Ar, Er)
    (alpha, beta), Z = sl.eig(As, Es, homogeneous_eigvals=True)
    ok = np.abs(beta) > 1e-8 * np.abs(alpha)
    lam = np.full(alpha.shape, np.inf, complex)
    lam[ok] = alpha[ok] / beta[ok]
    keep = ok & (np.abs(lam) < band) & (lam.imag >= -1e-9 * np.maximum(1, np.abs(lam)))
    X = T @ (Z[:, keep] / c[:, None])
    return lam[keep], X


def sparse_modes(A, E, count: int, band: float = np.inf, sigma: float = 0.0):
    """The ``count`` finite eigenpairs of ``A x = lam E x`` nearest ``sigma`` with Im >= 0
    (lowest frequencies for sigma = 0), by shift-invert Arnoldi: the largest eigenvalues
    ``mu = 1/(lam - sigma)`` of ``(A - sigma E)^-1 E`` (sparse LU).  Infinite eigenvalues map
    to ``mu = 0`` and never come first."""
    A = sp.csc_matrix(A)
    E = sp.csc_matrix(E)
    n = A.shape[0]
    for s in (sigma, sigma - 1e-3, sigma - 1.0):
        try:
            lu = spl.splu(sp.csc_matrix(A - s * E))
            break
        except RuntimeError:
            continue
    else:
        raise SingularPencilError("A - sigma E is singular for every shift tried")
    op = spl.LinearOperator((n, n), matvec=lambda x: lu.solve(np.asarray(E @ x)),
                            dtype=float)
    k = int(min(2 * count + 6, n - 2))
    mu = None
    for ncv in (3 * k, 5 * k):
        try:
            mu, X = spl.eigs(op, k=k, which="LM", ncv=int(min(n - 1, max(ncv, 40))),
                             v0=arpack_start(n))
            break
        except spl.ArpackNoConvergence as err:
            if len(err.eigenvalues) >= min(k, 2 * count):
                mu, X = err.eigenvalues, err.eigenvectors
                break
    if mu is None:
        raise ConvergenceError(f"sparse eigen-solver: ARPACK did not converge for the lowest "
                               f"{count} modes; try method='dense'")
    ok = np.abs(mu) > 0
    lam = np.full(mu.shape, np.inf, complex)
    lam[ok] = s + 1.0 / mu[ok]
    keep = ok & (np.abs(lam) < band) & (lam.imag >= -1e-9 * np.maximum(1, np.abs(lam)))
    lam, X = lam[keep], X[:, keep]
    order = np.argsort(np.abs(lam - s), kind="stable")[:count]
    return lam[order], X[:, order]


def refine_eigenpairs(A, E, lam: np.ndarray, X: np.ndarray, iterations: int = 3):
    """Inverse iteration on the sparse pencil (A, E) at each eigenvalue estimate (one sparse
    LU per eigenvalue, ``iterations`` solves), then the least-squares Rayleigh quotient
    ``lam = (Ex)^H A x / |Ex|^2``.  Shift-invert Arnoldi and QZ leave errors of ~1e-8 to
    1e-6 relative in some eigenvalues of these index-3 pencils (the nilpotent part of
    (A - sigma E)^-1 E pollutes the Krylov space; QZ rounds in the deflated dense pencil);
    two or three steps bring them to round-off."""
    A = sp.csc_matrix(A)
    E = sp.csc_matrix(E)
    lam = np.array(lam, complex)
    X = np.array(X, complex)
    for i in range(lam.size):
        mu = lam[i] * (1 + 1e-10)              # near, not at, the eigenvalue
        try:
            lu = spl.splu(sp.csc_matrix(A - mu * E, dtype=complex))
        except RuntimeError:            # exactly singular: the estimate is exact
            continue
        x = X[:, i] / max(np.linalg.norm(X[:, i]), 1e-300)
        for _ in range(iterations):
            y = lu.solve(np.asarray(E @ x, complex))
            nrm = np.linalg.norm(y)
            if not np.isfinite(nrm) or nrm == 0:
                break
            x = y / nrm
        Ex = E @ x
        den = np.vdot(Ex, Ex)
        if abs(den) > 0:
            lam[i] = np.vdot(Ex, A @ x) / den
            X[:, i] = x
    return lam, X
