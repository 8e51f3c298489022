"""Hill's method on the averaged system's modal basis, for weakly periodic systems: the
multi-blade coordinates of an isotropic rotor, periodic only through gravity, tilt, shear and
the tower (docs/floquet.md, "Hill's method on a modal basis").

Such a system's exponents stay near those of its averaged pencil (A_0, E_0), and its periodic
coupling is small.  The averaged pencil's right and left eigenvectors with |lambda| <=
``BASIS_MARGIN`` times the band (one sparse LU, two ARPACK runs) make modal coordinates in
which the Hill pencil of any truncation H is diagonal (lambda_j - i k w, mode j, harmonic k)
plus the small coupling.  Each exponent of the band is then found on its own by Loewdin
partitioning: the modal coordinates within ``PARTITION_RADIUS`` w of it (near-resonances,
where the periodic coupling mixes modes, cross-harmonic copies included) are kept exactly in
a small dense eigenproblem; the others enter to second order through their diagonal; the
exponent is iterated to a fixed point.  The coupling that leaves the basis (mostly into the
algebraic constraints' subspace: NREL 5-MW at 8 m/s, up to 1.4e-5 of an exponent) enters to
second order too: every harmonic block of the full Hill residual is solved on the
complement of the basis by a short Neumann series of the averaged pencil's LU (exact on the
nilpotent, index-3 part after three terms) and the exponent gets the two-sided Rayleigh
correction.  H grows until every exponent moves by at most the tolerance from H - 1.

Each exponent's two second-order corrections give its error estimate (CORRECTION_TRUST);
hill.py refines the few modes whose estimate exceeds the tolerance on the whole pencil.

Cost: a few sparse solves per mode instead of sparse LUs of the (2H + 1) n Hill pencils
(NREL 5-MW at 8 m/s, 16 elements: 8.5 s -> 1.0 s).  ReductionFailed (and the whole-pencil
search, hill.py) where the reduction does not apply: a defective averaged eigenvalue (a free
yaw's double zero: no modal coordinates), a degenerate cluster or a nearly degenerate one
that the coupling mixes (ambiguous continuation), a strongly periodic system, two modes
continuing into one exponent.

Internal lags (the blades' aerodynamic states: hundreds of nearly equal, nearly parallel
real exponents, which have no modal coordinates) are left out of the basis when the caller
marks them (``internal``); their response enters whole through their modal expansion in the
out-of-basis correction (_internal_tier, _out_of_basis)."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..numerics.pencil import arpack_start
from .floquet import dominant_harmonic

#: The modal basis holds the averaged pencil's eigenvectors with |lambda| <= BASIS_MARGIN x the
#: band (1.5: NREL 5-MW, 68 modes for 25 in the band; 2.5 changes no exponent by > 2e-7).
BASIS_MARGIN = 1.5
#: Modal coordinates (j, k) with |lambda_j - i k w - eta| <= PARTITION_RADIUS w are kept
#: exactly in an exponent's partition; farther ones to second order.
PARTITION_RADIUS = 1.0
#: The error left in an exponent after its second-order corrections, as a share of their
#: size (measured against the whole pencil converged to 1e-7: at most 0.08 on the NREL
#: 5-MW with 6 and 8 elements and the IEA 15-MW with 8; 0.23 with 4 NREL elements, where
#: the corrections reach 7e-3).
CORRECTION_TRUST = 0.25
#: Strongly periodic: more than a quarter of the exponents move by more than this (relative
#: to max(|eta|, w)) from the averaged system at H = 1; the reduction is given up at once
#: (NREL 5-MW at 15 m/s with 4 elements: 13 of 32; at 8 m/s with 8 elements none, IEA
#: 15-MW at 10 m/s with 8 elements 2 of 26).
STRONG_FIRST_MOVE = 3e-3
#: Largest modal Hill pencil (2H + 1) r formed (dense); beyond, ReductionFailed.
MAX_REDUCED_SIZE = 3000
#: An eigenvalue within REAL_TOL x the basis radius of the real axis is real (its vector made
#: real in the basis; Im >= -that is the upper half).
REAL_TOL = 1e-9
#: Complex entries of one chunk of the out-of-basis correction's right-hand sides (n x
#: exponents x harmonic blocks; 64 MB), solved together.
OUT_OF_BASIS_COLUMNS = 4_000_000
#: Two modal coordinates whose averaged exponents (Hill copies included) are nearer than
#: DEGENERATE w form a nearly degenerate cluster: an exponent continues its mode only while
#: its vector keeps CLUSTER_DOMINANCE of its cluster's share on that mode's coordinate (and
#: not at all within DEFECTIVE_SPLIT w, a degenerate pair); else the reduction is not used.
DEGENERATE = 1e-3
CLUSTER_DOMINANCE = 0.9
#: Terms of the Neumann series for the out-of-basis response: the index-3 nilpotent part is
#: exact after three; the finite modes beyond the basis converge like (band / (1.5 band))^p.
NEUMANN_TERMS = 5
#: Largest |cos| of the angle between two eigenvectors of the averaged pencil accepted (a
#: defective eigenvalue, split by round-off, has two nearly parallel ones: the modal basis
#: does not exist).
MAX_PARALLEL = 0.99
#: ... and nearer than this (relative to max(|lambda|, w)): round-off splits a double
#: eigenvalue by ~sqrt(eps) (the three-bladed rotor's free yaw: 3e-9 of w).
DEFECTIVE_SPLIT = 1e-5
#: ... or nearer than this and both near zero (below NEAR_ZERO of w): a free coordinate's
#: pair (a free generator's azimuth and the rotor speed's slow aerodynamic decay, 0 and
#: 0.017 w on the NREL 5-MW) is nearly defective: its modal coordinates mix the pair into
#: every other mode's vector (the azimuth at 2x the blade tip's motion where the whole
#: pencil and the monodromy find 1e-3 of it)
NEAR_ZERO = 0.05


class ReductionFailed(RuntimeError):
    """The modal reduction does not apply (defective averaged pencil, ambiguous exponents)."""


#: ARPACK's share of the spectrum beyond which one dense eigensolution of the shift-inverted
#: operator is cheaper (ARPACK restarts with twice as many vectors each time the basis
#: radius holds more eigenvalues; with dynamic inflow and unsteady airfoil states, half of
#: the IEA 15-MW's 2138 averaged eigenvalues lie inside it: 77 s of ARPACK against one
#: dense solution)
DENSE_SHARE = 0.2


class _Averaged:
    """The averaged pencil's eigenpairs with |lambda| <= the basis radius and Im >= 0:
    ``lam`` (m,), right vectors ``X`` (n, m), left vectors ``Y`` (n, m) (each column the
    partner of X's: the nearest left eigenvalue's, or exact from one dense eigensolution),
    the real LU of A0 - sigma E0 and ``sigma``."""

    def __init__(self, lam, X, Y, lu, sigma: float):
        self.lam, self.X, self.Y, self.lu, self.sigma = lam, X, Y, lu, sigma


class _DenseLU:
    """A dense LU of a real matrix with SuperLU's ``solve(b, trans)``: the dense path's
    solves, with many right-hand sides at once (BLAS-3; SuperLU solves one column at a
    time)."""

    def __init__(self, K: np.ndarray):
        self.factors = sla.lu_factor(K, overwrite_a=True, check_finite=False)

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        return sla.lu_solve(self.factors, b, trans=0 if trans == "N" else 1,
                            check_finite=False)


def _averaged_modes(A0, E0, radius: float, stats: dict, cache: dict,
                    force_dense: bool = False) -> _Averaged:
    """The averaged pencil's eigenpairs with |lambda| <= radius (_Averaged): ARPACK
    shift-invert about a small negative shift with one sparse LU, or, once ARPACK would need
    more than DENSE_SHARE of the spectrum (or ``force_dense``: a system with the blades'
    aerodynamic states, whose lags fill the radius), one dense eigensolution of the
    shift-inverted operator with both sides (exact partners, also within clusters of nearly
    equal eigenvalues).  ``cache`` keeps the LU and a dense solution for wider radii."""
    n = A0.shape[0]
    eps = REAL_TOL * radius
    sigma = cache.setdefault("sigma", -1e-3 * radius)

    def within(lam):
        return (np.abs(lam) <= radius) & (lam.imag >= -eps)

    def partners(keep):
        # the left vectors of the dense solution's eigenvalues ``keep``, each solved once
        # (a wider radius asks for more): y = (A0 - sigma E0)^-T conj(u)
        lu, (lam, X, Ud, Y, solved) = cache["lu"], cache["dense"]
        todo = keep & ~solved
        if todo.any():
            Y[:, todo] = _solve(lu, Ud[:, todo], trans="T")
            solved |= todo
            stats["solves"] = stats.get("solves", 0) + int(todo.sum())
        return _Averaged(lam[keep], X[:, keep], Y[:, keep], lu, sigma)

    if "dense" in cache:
        return partners(within(cache["dense"][0]))

    def count(x):
        stats["solves"] = stats.get("solves", 0) + 1
        return x

    def dense():
        # the shift-inverted operator M = (A0 - sigma E0)^-1 E0 and one dense eigensolution
        # with both sides, cheaper than ARPACK once it would need many vectors.  M's columns
        # outside E0's nonzero ones (d: the algebraic unknowns') are zero, so its nonzero
        # eigenvalues are those of M[d, d] (IEA 15-MW with Oye and Jones: 1866 of 2138, 1.5x
        # fewer flops), whose right vector is x's rows d, the others M[rest, d] x_d / mu; a
        # left vector u (u^H M = mu u^H) is zero outside d and gives y = (A0 - sigma E0)^-T conj(u), one of the
        # pencil's: exact partners, also within clusters of nearly equal eigenvalues.  A
        # dense LU: its solves with hundreds of columns are BLAS-3
        stats["dense"] = stats.get("dense", 0) + 1
        lu = _DenseLU(sp.csc_matrix(A0 - sigma * E0).toarray())
        stats["factorizations"] = stats.get("factorizations", 0) + 1
        Ec = sp.csc_matrix(E0)
        d = np.flatnonzero(np.asarray(abs(Ec).sum(axis=0)).ravel())
        Md = lu.solve(Ec[:, d].toarray())
        stats["solves"] = stats.get("solves", 0) + d.size
        mu, U, V = sla.eig(Md[d], left=True, right=True, check_finite=False)
        finite = np.abs(mu) > 1e-14 * np.abs(mu).max()        # mu = 0: infinite lambda
        lam = sigma + 1.0 / mu[finite]
        up = lam.imag >= -1e-9 * np.abs(lam).max()
        lam, mu, V = lam[up], mu[finite][up], V[:, finite][:, up]
        X = np.zeros((n, lam.size), complex)
        X[d] = V                                    # M[d, d] x_d = mu x_d
        rest = np.setdiff1d(np.arange(n), d)
        X[rest] = (Md[rest] @ V) / mu
        X /= np.linalg.norm(X, axis=0)
        Ud = np.zeros((n, lam.size), complex)
        Ud[d] = U[:, finite][:, up].conj()
        cache["lu"] = lu
        cache["dense"] = (lam, X, Ud, np.zeros_like(Ud), np.zeros(lam.size, bool))
        return partners(within(lam))

    if force_dense:
        return dense()
    if "lu" not in cache:
        cache["lu"] = spla.splu(sp.csc_matrix(A0 - sigma * E0))
        stats["factorizations"] = stats.get("factorizations", 0) + 1
    lu = cache["lu"]
    ET = sp.csc_matrix(E0.T)
    right = spla.LinearOperator((n, n), dtype=float,
                                matvec=lambda x: count(lu.solve(np.asarray(E0 @ x))))
    left = spla.LinearOperator((n, n), dtype=float,
                               matvec=lambda x: count(lu.solve(np.asarray(ET @ x), trans="T")))

    def eigs(op, k):
        k = min(k, n - 2)
        while True:
            if k > DENSE_SHARE * n:
                return None, None, k
            mu, V = spla.eigs(op, k=k, which="LM", tol=1e-13, ncv=min(n - 1, 2 * k + 20),
                              v0=arpack_start(n))
            lam = sigma + 1.0 / mu
            if np.abs(lam - sigma).max() > 1.1 * radius + abs(sigma) or k >= n - 2:
                return lam, V, k
            k = min(2 * k, n - 2)

    lam, X, k = eigs(right, 60)
    if lam is None:
        return dense()
    lamL, Y, _ = eigs(left, k)   # the same spectrum: the count the right side needed
    if lamL is None:
        return dense()
    keep = within(lam)
    lam, X = lam[keep], X[:, keep]
    # each right vector's left partner: the left eigenvalue nearest it or its conjugate (the
    # real basis spans both members of a pair)
    lamL = np.where(lamL.imag < -eps, lamL.conj(), lamL)
    Y = Y[:, [int(np.argmin(np.abs(lamL - l))) for l in lam]]
    return _Averaged(lam, X, Y, lu, sigma)


def _real_basis(lam, V, eps: float) -> np.ndarray:
    """An orthonormal real basis (n, r) of the eigenvectors V (n, m) of a real pencil with
    eigenvalues lam (Im >= 0): a real eigenvalue's vector made real, a complex one's real
    and imaginary parts (they span both members of the pair)."""
    cols = []
    for l, v in zip(lam, V.T):
        if abs(l.imag) <= eps:                    # real eigenvalue: a real vector
            k = int(np.argmax(np.abs(v)))
            cols.append(np.real(v * np.conj(v[k]) / abs(v[k])))
        else:
            cols += [v.real, v.imag]
    return np.linalg.qr(np.column_stack(cols))[0] if cols else np.zeros((V.shape[0], 0))


def _internal_tier(av: _Averaged, mask: np.ndarray, E0, eps: float, w: float):
    """(mask, (lam, X, Y)) of the averaged modes ``mask`` marks (the blades' aerodynamic
    lags: analyses/labels.aerodynamic_lags), widened by their nearly defective twins, both
    members of each complex pair, Y^T E0 X = I: their response enters whole through their
    modal expansion, not as modal coordinates (hundreds of nearly equal lags with nearly
    parallel vectors: no Loewdin partition); (mask, None) when none is marked."""
    mask = np.array(mask, bool)
    if not mask.any():
        return mask, None
    # a mode nearly parallel to an internal one with a nearly equal eigenvalue joins it (a
    # nearly defective pair split between the basis and the expansion would be counted
    # twice: Oye's slow inflow lags, one of them dragging some structure along)
    U = av.X / np.linalg.norm(av.X, axis=0)
    while True:
        rest = np.flatnonzero(~mask)
        cos = np.abs(U[:, rest].conj().T @ U[:, mask])
        near = np.abs(av.lam[rest][:, None] - av.lam[mask][None, :]) <= DEGENERATE * w
        joins = rest[np.any((cos > MAX_PARALLEL) & near, axis=1)]
        if not joins.size:
            break
        mask[joins] = True
    lam, X, Y = av.lam[mask], av.X[:, mask], av.Y[:, mask]
    pair = np.abs(lam.imag) > eps
    lam = np.concatenate([lam, lam[pair].conj()])
    X = np.hstack([X, X[:, pair].conj()])
    Y = np.hstack([Y, Y[:, pair].conj()])
    norm = np.einsum("ij,ij->j", Y, np.asarray(E0 @ X))
    return mask, (lam, X, Y / norm)


def _modal_coordinates(Xr, Yr, A0, E0, scale: float):
    """(mu, Xm, Ym): the eigenpairs of the projected pencil (Yr^T A0 Xr, Yr^T E0 Xr), mapped
    back: Ym^T E0 Xm = I, Ym^T A0 Xm = diag(mu) (``scale``: the base frequency w).  Raises
    ReductionFailed when two vectors are (nearly) parallel and their eigenvalues (nearly)
    equal (a defective eigenvalue)."""
    Ar, Er = Yr.T @ (A0 @ Xr), Yr.T @ (E0 @ Xr)
    mu, VL, VR = sla.eig(Ar, Er, left=True, right=True)
    VR = VR / np.linalg.norm(VR, axis=0)
    VL = VL / np.linalg.norm(VL, axis=0)
    Xm, Ym = Xr @ VR, Yr @ VL.conj()
    # a defective eigenvalue (a free yaw's double zero) shows as two (nearly) equal
    # eigenvalues with (nearly) parallel vectors (in Xr's orthonormal coordinates; a nearly
    # real vector and its conjugate are nearly parallel too, but their eigenvalues differ)
    parallel = np.abs(VR.conj().T @ VR) - np.eye(mu.size) > MAX_PARALLEL
    close = np.abs(mu[:, None] - mu[None, :]) <= DEFECTIVE_SPLIT * np.maximum(
        np.abs(mu)[:, None], scale)
    slow = np.abs(mu) <= NEAR_ZERO * scale
    close |= slow[:, None] & slow[None, :]
    if not np.all(np.isfinite(mu)) or np.any(parallel & close):
        raise ReductionFailed("the averaged pencil has a defective (or infinite) eigenvalue "
                              "among the basis's: no modal coordinates")
    norm = np.einsum("ij,ij->j", Ym, np.asarray(E0 @ Xm))
    return mu, Xm / norm, Ym


class _ModalHill:
    """The Hill pencil of truncation H in modal coordinates (index k * r + j for harmonic
    k = -H..H, mode j): Ah, Eh dense, and the diagonal of Ah."""

    def __init__(self, Ar: dict, Er: dict, mu: np.ndarray, H: int, w: float):
        r = mu.size
        ks = np.arange(-H, H + 1)
        L = ks.size
        self.H, self.r = H, r
        self.Ah = np.zeros((L * r, L * r), complex)
        self.Eh = np.zeros((L * r, L * r), complex)
        for a, m in enumerate(ks):
            for b, k in enumerate(ks):
                j = int(m - k)
                if j in Er:
                    self.Eh[a * r:(a + 1) * r, b * r:(b + 1) * r] = Er[j]
                    self.Ah[a * r:(a + 1) * r, b * r:(b + 1) * r] = Ar[j] - 1j * k * w * Er[j]
        self.diag = np.concatenate([mu - 1j * k * w for k in ks])
        self.w = w

    def exponent(self, i: int, eta0: complex):
        """(eta, c, d): the exponent continuing mode i (harmonic 0), its right and left
        vectors (L r,) in modal coordinates; Loewdin partitioning iterated in eta."""
        Ah, Eh, w = self.Ah, self.Eh, self.w
        target = self.H * self.r + i
        P = np.flatnonzero(np.abs(self.diag - eta0) <= PARTITION_RADIUS * w)
        if target not in P:
            P = np.union1d(P, [target])
        Q = np.setdiff1d(np.arange(self.diag.size), P)
        t = int(np.flatnonzero(P == target)[0])
        gap = np.abs(self.diag[P] - self.diag[target])
        near = gap <= DEGENERATE * w
        if np.count_nonzero(gap <= DEFECTIVE_SPLIT * w) > 1:
            # a degenerate cluster (four blades on a rigid hub: the cyclic modes at +-1
            # per-rev from a blade mode are a base frequency apart): which exponent
            # continues which mode is ambiguous
            raise ReductionFailed("nearly degenerate averaged exponents (Hill copies "
                                  "included): the continuation is ambiguous")
        dA, dE = np.diagonal(Ah)[Q], np.diagonal(Eh)[Q]
        APQ, EPQ = Ah[np.ix_(P, Q)], Eh[np.ix_(P, Q)]
        AQP, EQP = Ah[np.ix_(Q, P)], Eh[np.ix_(Q, P)]
        APP, EPP = Ah[np.ix_(P, P)], Eh[np.ix_(P, P)]
        eta = eta0
        for _ in range(50):
            d = dA - eta * dE
            lam, ZL, ZR = sla.eig(APP - (APQ - eta * EPQ) @ ((AQP - eta * EQP) / d[:, None]),
                                  EPP, left=True, right=True)
            share = np.abs(ZR[t]) / np.linalg.norm(ZR, axis=0)
            best = int(np.argmax(share))
            moved = abs(lam[best] - eta)
            eta = lam[best]
            if moved <= 1e-14 * max(abs(eta), w):
                break
        if near.sum() > 1:
            # a nearly degenerate cluster (two overdamped flap roots 8e-4 w apart on the IEA
            # 15-MW at 22 m/s): the continuation is clear when the exponent's vector stays
            # mostly on its own mode's coordinate within the cluster
            z = np.abs(ZR[near, best]) ** 2
            if abs(ZR[t, best]) ** 2 < CLUSTER_DOMINANCE * z.sum():
                raise ReductionFailed("nearly degenerate averaged exponents (Hill copies "
                                      "included) mixed by the coupling: the continuation "
                                      "is ambiguous")
        d = dA - eta * dE
        c = np.zeros(self.diag.size, complex)
        dl = np.zeros(self.diag.size, complex)
        c[P] = ZR[:, best]
        c[Q] = -((AQP - eta * EQP) @ ZR[:, best]) / d
        yl = ZL[:, best].conj()                       # y^T (A - eta E) = 0
        dl[P] = yl
        dl[Q] = -(yl @ (APQ - eta * EPQ)) / d
        return eta, c, dl


def reduced_converged_modes(mats: dict, n: int, w: float, band: float, obs, wts, stats: dict,
                            tol: float, max_harmonics: int, margin: float = BASIS_MARGIN,
                            internal=None, cache: dict = None):
    """The exponents of the band 0 <= Im <= ``band``, |Re| <= w (Hill's "converged"
    truncation, see hill._converged_modes) on the averaged system's modal basis: (lam, V
    (2H+1, n, m), tails, H, change, corrections, participation); ``corrections`` (m,): the
    size of each exponent's second-order corrections (out of the basis, and among the
    partition's far coordinates) relative to max(|eta|, w): where it exceeds the tolerance,
    the coupling is too strong for the reduction to be trusted (hill.py refines those modes
    on the whole pencil); ``participation`` (n, m): the states' participation in each mode
    (_participation, from its in-basis right and left vectors).  ``mats``: {j: (E_j, A_j)}
    the coefficients' complex harmonics as sparse matrices (hill.coefficient_matrices);
    ``margin``: the basis reaches |lambda| <= margin x band; ``internal``: a test (lam, X)
    -> bool of averaged modes kept out of the basis (the blades' aerodynamic lags: their
    response is taken whole in the out-of-basis correction, and they are not followed as
    exponents); ``cache``: a dict that keeps the averaged pencil's LU and dense spectrum
    for a call with a wider margin.  Raises ReductionFailed when the reduction does not
    apply."""
    E0, A0 = (sp.csc_matrix(m.real) for m in mats[0])
    cache = {} if cache is None else cache
    # internal modes need their exact left partners (the dense solution), and hundreds of
    # them fill the radius (ARPACK would restart until DENSE_SHARE: 2 s on the IEA 15-MW)
    av = _averaged_modes(A0, E0, margin * band, stats, cache,
                         force_dense=internal is not None)
    eps_basis = REAL_TOL * margin * band
    marked = np.zeros(av.lam.size, bool) if internal is None else internal(av.lam, av.X)
    mask, tier = _internal_tier(av, marked, E0, eps_basis, w)
    Xr = _real_basis(av.lam[~mask], av.X[:, ~mask], eps_basis)
    Yr = _real_basis(av.lam[~mask], av.Y[:, ~mask], eps_basis)
    lu, sigma = av.lu, av.sigma
    if Xr.shape[1] != Yr.shape[1] or Xr.shape[1] == 0:
        raise ReductionFailed(f"the right and left bases differ ({Xr.shape[1]} vs "
                              f"{Yr.shape[1]} vectors)")
    mu, Xm, Ym = _modal_coordinates(Xr, Yr, A0, E0, w)
    Er = {j: Ym.T @ (E @ Xm) for j, (E, A) in mats.items()}
    Ar = {j: Ym.T @ (A @ Xm) for j, (E, A) in mats.items()}
    eps = 1e-9 * band
    # candidates: the averaged exponents in the band (and half a base frequency beyond it,
    # where the coupling may bring them in)
    # (and the heavily damped oscillatory ones, |Re| up to the band: aerodynamically damped
    # flap modes; not the real exponents of the aerodynamic states' lags, of which every
    # Gauss point has its own)
    targets = np.flatnonzero((mu.imag >= -eps) & (mu.imag <= band + 0.5 * w)
                             & ((np.abs(mu.real) <= 1.5 * w)
                                | ((np.abs(mu.real) <= band) & (mu.imag > 0.05 * w))))
    eta = mu[targets].copy()
    H_cap = min(max_harmonics, (MAX_REDUCED_SIZE // max(mu.size, 1) - 1) // 2)
    for H in range(1, H_cap + 1):
        hill = _ModalHill(Ar, Er, mu, H, w)
        found = [hill.exponent(int(i), e) for i, e in zip(targets, eta)]
        new = np.array([f[0] for f in found])
        # a real system: a pair's member with Im >= 0 (two real exponents that merge into a
        # complex pair may be followed to either member)
        new = np.where(new.imag < -eps, new.conj(), new)
        move = np.abs(new - eta) / np.maximum(np.abs(new), w)
        if H == 1 and np.count_nonzero(move > STRONG_FIRST_MOVE) > move.size // 4:
            raise ReductionFailed(f"{np.count_nonzero(move > STRONG_FIRST_MOVE)} of "
                                  f"{move.size} exponents move by > {STRONG_FIRST_MOVE:.0e} "
                                  "from the averaged system: strongly periodic")
        eta = new
        if not move.size or move.max() <= tol:
            break
    else:
        raise ReductionFailed(f"the exponents still move by {move.max(initial=0):.1e} at "
                              f"{H_cap} harmonics")
    L = 2 * H + 1
    kk = np.arange(-H, H + 1)
    lam, vectors, tails, sizes, parts = [], [], [], [], []
    for e, p, size, part in _out_of_basis(found, hill, mats, lu, sigma, E0, Xm, Ym, w, tier):
        if e.imag < -eps:           # the conjugate solution: p_k -> conj(p_-k)
            e, p = e.conjugate(), p[::-1].conj()
        if any(abs(e - o) <= 1e-9 * w for o in lam) and abs(e.imag) > eps:
            continue                # two real exponents merged into this pair: once
        energy = np.einsum("r,kr->k", wts, np.abs(p[:, obs]) ** 2)
        m = int(kk[dominant_harmonic(energy, kk, e.imag, w, tie=1e-12)])
        if m:                       # the copy dominant in harmonic 0: eta + i m w
            e = e + 1j * m * w
            shifted = np.zeros_like(p)
            if m > 0:
                shifted[:L - m] = p[m:]
            else:
                shifted[-m:] = p[:L + m]
            p = shifted
            energy = np.einsum("r,kr->k", wts, np.abs(p[:, obs]) ** 2)
        if not (-eps <= e.imag <= band and abs(e.real) <= max(w, band)):
            continue
        if any(abs(e - o) <= 1e-9 * w for o in lam):
            raise ReductionFailed("two averaged modes continue into copies of one exponent")
        lam.append(e)
        vectors.append(p)
        tails.append((energy[0] + energy[-1]) / max(energy.sum(), 1e-300))
        sizes.append(size)
        parts.append(part)
    lam = np.array(lam, complex)
    V = np.array(vectors).transpose(1, 2, 0) if vectors else np.zeros((L, n, 0), complex)
    tails, sizes = np.array(tails), np.array(sizes)
    part = np.array(parts).T if parts else np.zeros((n, 0))
    order = np.lexsort((lam.real, lam.imag))
    change = float(move.max()) if move.size else 0.0
    return lam[order], V[:, :, order], tails[order], H, change, sizes[order], part[:, order]


def _out_of_basis(found, hill: _ModalHill, mats: dict, lu, sigma: float, E0, Xm, Ym,
                  w: float, tier=None):
    """[(eta, p, size)] for every exponent (eta, c, dl) of ``found`` (_ModalHill.exponent)
    with the response outside the modal basis in every harmonic block: the residual blocks
    r_m = sum_k (A_{m-k} - (eta + i k w) E_{m-k}) p_k of the vector p (L, n) in full
    coordinates projected off the basis (Ym^T of it is zero), solved by the Neumann series
    of the averaged pencil's LU about sigma, added to p; eta gets q^T T(eta) f / q^T E_h p
    (two-sided Rayleigh) and the reduced pencil's own Rayleigh correction.  ``tier``: (lam,
    X, Y) of the internal modes left out of the basis (_internal_tier), whose share of the
    residual is solved by their modal expansion instead of the series.  ``size``: the
    larger of the two corrections relative to max(|eta|, w): both are second order in the
    coupling they stand for, so the error left is far smaller while they are small.  The
    exponents go through together, in chunks of OUT_OF_BASIS_COLUMNS columns (one
    multi-column solve per Neumann term for all of them)."""
    H = hill.H
    L = 2 * H + 1
    kk = np.arange(-H, H + 1)
    n = Xm.shape[0]
    step = max(1, OUT_OF_BASIS_COLUMNS // (L * n))
    out = []
    for first in range(0, len(found), step):
        chunk = found[first:first + step]
        m = len(chunk)
        eta = np.array([f[0] for f in chunk])
        C = np.array([f[1] for f in chunk])                # (m, L r) modal coordinates
        D = np.array([f[2] for f in chunk])
        # harmonic blocks as columns (n, m, L): mode i's harmonic k in column (i, k)
        P = (Xm @ C.reshape(m * L, -1).T).reshape(n, m, L)
        Q = (Ym @ D.reshape(m * L, -1).T).reshape(n, m, L)
        R = _hill_apply(mats, P, eta, w).reshape(n, m * L)    # the residual blocks
        B = -(R - E0 @ (Xm @ (Ym.T @ R)))
        shifts = (eta[:, None] + 1j * kk[None, :] * w).ravel()     # (m L,)
        inner = 0.0
        if tier is not None:
            # the internal modes' response whole: x_j (y_j^T b) / (lambda_j - s) (they may
            # lie near s, where the Neumann series about sigma would not converge)
            lt, Xt, Yt = tier
            Ct = Yt.T @ B                                       # (mt, m L)
            inner = Xt @ (Ct / (lt[:, None] - shifts[None, :]))
            B = B - E0 @ (Xt @ Ct)
        s = shifts - sigma

        def beyond(x):
            # x without its components along the internal modes: round-off there would
            # grow by ((s - sigma) / (lambda_j - sigma))^p in the series (Oye's slow lags,
            # 1e-11)
            return x if tier is None else x - Xt @ (Yt.T @ (E0 @ x))

        # the Neumann series of every block of every exponent: one solve per term
        term = beyond(_solve(lu, B))
        total = term.copy()
        for _ in range(NEUMANN_TERMS - 1):
            term = beyond(s * _solve(lu, E0 @ term))
            total += term
        F = (total + inner).reshape(n, m, L)
        # q^T T(eta) f over every block that f reaches
        num = np.einsum("nml,nml->m", Q, _hill_apply(mats, F, eta, w))
        Ec = hill.Eh @ C.T                                      # (L r, m)
        den = np.einsum("mj,jm->m", D, Ec)
        # the reduced pencil's own two-sided Rayleigh correction (the coupling among the far
        # modal coordinates that the partition neglected)
        near = np.einsum("mj,jm->m", D, hill.Ah @ C.T - eta * Ec) / den
        scale = np.maximum(np.abs(eta), w)
        sizes = np.maximum(np.abs(num / den), np.abs(near)) / scale
        new = eta + num / den + near
        part = _participation(E0, P, Q)
        out += [(new[i], (P[:, i] + F[:, i]).T, sizes[i], part[:, i]) for i in range(m)]
    return out


def _participation(E0, P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Every state's participation (n, m) in each of m modes with right and left harmonic
    blocks P, Q (n, m, L) (y^T (A - eta E) = 0): |sum_k (E0^T q_k)_s p_k,s| over the states s,
    normalized to sum 1 per mode (Perez-Arriaga, Verghese and Schweppe, "Selective modal
    analysis", IEEE Trans. PAS-101 (9), 1982: p_s = y_s x_s; for a descriptor pencil y^T E
    takes y's place).  Invariant to the states' scaling: the share of the eigenvalue that a
    group of states (the blades' aerodynamic lags) carries, whatever their units."""
    n, m, L = P.shape
    EQ = np.asarray(E0.T @ Q.reshape(n, m * L)).reshape(n, m, L)
    part = np.abs(np.einsum("nml,nml->nm", EQ, P))
    return part / np.maximum(part.sum(axis=0), 1e-300)


def _hill_apply(mats: dict, v: np.ndarray, eta: np.ndarray, w: float) -> np.ndarray:
    """Hill's pencil T(eta_i) applied to the harmonic blocks ``v`` (n, m, L) of m vectors,
    the same shape out: block m of vector i is sum_k (A_{m-k} - (eta_i + i k w) E_{m-k})
    v_ik, ``mats`` {d: (E_d, A_d)}; one sparse product per coefficient harmonic d."""
    n, m, L = v.shape
    H = (L - 1) // 2
    kk = np.arange(-H, H + 1)
    out = np.zeros((n, m, L), complex)
    for d, (E, A) in mats.items():                      # k = m - d inside -H..H
        k = kk[(kk + d >= -H) & (kk + d <= H)]
        if k.size:
            V = v[:, :, k + H].reshape(n, -1)
            shift = (eta[:, None] + 1j * k[None, :] * w).ravel()
            out[:, :, k + d + H] += (A @ V - (E @ V) * shift).reshape(n, m, k.size)
    return out


def _solve(lu, b: np.ndarray, trans: str = "N") -> np.ndarray:
    """lu^{-1} b (or lu^{-T} b) for a complex b (n,) or (n, k) with a real LU (one
    multi-column solve)."""
    k = 1 if b.ndim == 1 else b.shape[1]
    x = lu.solve(np.column_stack([b.real, b.imag]), trans=trans)
    x = x[:, :k] + 1j * x[:, k:]
    return x[:, 0] if b.ndim == 1 else x
