"""Hill's method: the characteristic exponents of a linear periodic DAE as the eigenvalues of
its harmonic-balance (Hill) pencil, found by sparse shift-invert in a frequency band.

For ``E(t) x' = A(t) x`` with period ``T = 2 pi / w`` and Fourier coefficients
``E(t) = sum_j E_j e^{i j w t}`` (likewise A), a Floquet solution ``x = e^{eta t} p(t)``,
``p(t) = sum_k p_k e^{i k w t}``, satisfies for every harmonic m

    eta sum_k E_{m-k} p_k = sum_k (A_{m-k} - i k w E_{m-k}) p_k,

a generalized eigenproblem of size n (2H + 1) when the harmonics are truncated at |k| <= H
(Hill 1886; for Floquet analysis of rotors e.g. Lazarus & Thomas, C. R. Mecanique 338, 2010;
Bauchau & Nikishkov, J. Am. Helicopter Soc. 46, 2001).  Every exponent appears once per
harmonic, shifted by ``i m w`` with its vector shifted by m harmonics; the copy whose weighted
vector is dominant in harmonic 0 is the exponent with the dominant-harmonic convention of
hawt_core.floquet (the paper's), so only those "centred" copies are kept.  Truncation: the
vectors of the kept modes must have negligible energy in the outermost harmonics (else H
grows); constant coefficients need H = 0 (one eigenproblem of size n).

The pencil is sparse (the harmonics of E and A are few, J << H); its eigenvalues in a band
``0 <= Im eta <= w_max`` are found with ARPACK on ``(A - sigma E)^{-1} E`` (one sparse LU
per shift), windows split until each holds at most ``MAX_PER_WINDOW`` eigenvalues.  The
infinite eigenvalues of the descriptor pencil (algebraic variables, constraints) map to 0
and never come first.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..numerics.pencil import arpack_start, finite_modes, refine_eigenpairs
from ..numerics.threads import thread_map
from .floquet import FourierCoefficients, LinearPeriodicDAE, dominant_harmonic
from .hill_reduced import BASIS_MARGIN, CORRECTION_TRUST, ReductionFailed, reduced_converged_modes

#: The modal bases tried (|lambda| up to these times the band) before modes whose
#: estimated reduction error is too large are refined on the whole pencil.
BASIS_MARGINS = (BASIS_MARGIN, 2.0 * BASIS_MARGIN)

#: Largest eigenvalue count asked of ARPACK in one window before the window is halved.
MAX_PER_WINDOW = 96
#: Accepted energy share of the outermost harmonics (|k| = H) of a kept vector.
TAIL_TOL = 1e-12
#: Largest harmonic truncation tried.
MAX_HARMONICS = 48
#: Truncation rules of hill_modes: "tail" (the outermost harmonics of every kept vector hold
#: at most tail_tol of its energy) or "converged" (each exponent taken at the first H = 0, 1,
#: 2, ... at which it moved by at most converged_tol, relative to max(|eta|, w), from H - 1).
TRUNCATIONS = ("tail", "converged")
#: Default of "converged": the relative move |eta_H - eta_{H-1}| / max(|eta|, w) at which a
#: mode is taken at H.  The move is the error of the coarser truncation; the finer one kept is
#: far better (NREL 5-MW in multi-blade coordinates, modes below 50 per-rev: H = 0 is off by
#: up to 1.7e-4, H = 1 by 1.1e-6 of H = 2), so the reported move is a conservative error
#: estimate.  Per mode (not the largest move of all, which pushed every mode to the H of the
#: slowest), 5e-4 let a nearly neutral lag mode's real part stray by 1.3e-5 per-rev (4 % of
#: it) from the monodromy's; 5e-5 keeps it within 1e-6.
CONVERGED_TOL = 5e-5
#: The estimated reduction error accepted for a heavily damped mode (|Re| > w, or a damping
#: ratio |Re| / |eta| above HEAVY_RATIO) without a refinement on the whole pencil
#: (hill._reduced_modes): relative to max(|eta|, w).
HEAVY_TOL = 1e-3
#: ... the damping ratio above which a mode is heavily damped whatever its |Re| (IEA 15-MW
#: at 11 m/s, frozen wake: an overdamped-like flap root -2.276 + 0.598i, ratio 0.97 at
#: |Re| = 0.96 w, estimated at 1.1e-4, was refined on the whole pencil at H = 2 and 3 for
#: 33 s of the point's 44 s: a 2.6e-4 rad/s error on a 2.3 1/s decay)
HEAVY_RATIO = 0.5
#: ... and for any mode of a system whose internal lags (the blades' aerodynamic states) the
#: modal basis left out: the whole Hill pencil of such a system factorizes in minutes (IEA
#: 15-MW at 11 m/s with Oye's inflow and Jones's lags: 530 s to refine one mode estimated at
#: 6e-5, i.e. 6e-5 of its damping ratio 0.036); 2e-4 of max(|eta|, w) moves a damping ratio
#: by at most 2e-4.  Such a system's modes above it are kept too, with a warning and their
#: estimate in ``change`` (no whole-pencil refinement)
LAG_TOL = 2e-4
#: Constant coefficients: dense QZ (after deflation) up to this many unknowns.
DENSE_SIZE = 200


class HillError(RuntimeError):
    """Hill's method could not resolve the band (ARPACK failure or truncation too large)."""


@dataclass
class HillModes:
    """Centred eigenpairs of the Hill pencil: ``exponents`` (m,) [rad/s, dominant-harmonic
    convention], ``vectors`` (2H+1, n, m) the harmonics p_k (k = -H..H) of the periodic
    vectors, ``tail`` (m,) energy share of the outermost harmonics, ``harmonics`` H,
    ``omega`` the base frequency w [rad/s]."""

    exponents: np.ndarray
    vectors: np.ndarray
    tail: np.ndarray
    harmonics: int
    omega: float
    size: int
    coefficient_harmonics: int
    timings: dict = field(default_factory=dict)
    solves: int = 0
    #: "converged" truncation: the largest relative exponent change from H - 1 to H (see
    #: _converged_modes), a bound on the exponents' truncation error (None for "tail"); on
    #: the modal basis also the modes' estimated reduction errors (_reduced_modes)
    change: Optional[float] = None
    #: how the band was searched: "whole pencil" (sparse shift-invert on Hill's pencils) or
    #: "modal basis" (hill_reduced.py, weakly periodic systems)
    method: str = "whole pencil"
    #: on the modal basis: every state's participation (n, m) in each mode (shares summing
    #: to 1, hill_reduced._participation); None from the whole pencil
    participation: Optional[np.ndarray] = None

    def periodic(self, i: int, times, rows=None) -> np.ndarray:
        """p_i(t) (len(times), rows) from the harmonics."""
        H = self.harmonics
        k = np.arange(-H, H + 1)
        V = self.vectors[:, :, i] if rows is None else self.vectors[:, rows, i]
        ph = np.exp(1j * self.omega * np.outer(np.asarray(times, float), k))
        return ph @ V


def _complex_coefficients(fc: FourierCoefficients):
    """{j: (E_j data, A_j data)} for j = -J..J on fc's patterns (complex)."""
    out = {0: (fc.cE[0].astype(complex), fc.cA[0].astype(complex))}
    K = len(fc.k)
    for i, j in enumerate(fc.k):
        aE, bE = fc.cE[1 + i], fc.cE[1 + K + i]
        aA, bA = fc.cA[1 + i], fc.cA[1 + K + i]
        out[int(j)] = ((aE - 1j * bE) / 2, (aA - 1j * bA) / 2)
        out[-int(j)] = ((aE + 1j * bE) / 2, (aA + 1j * bA) / 2)
    return out


def coefficient_matrices(fc: FourierCoefficients) -> dict:
    """{j: (E_j, A_j)} the complex harmonics j = -J..J of the coefficients as sparse
    matrices."""
    n = fc.dae.n
    return {j: (sp.csc_matrix((Ed, (fc.pE.rows, fc.pE.cols)), shape=(n, n)),
                sp.csc_matrix((Ad, (fc.pA.rows, fc.pA.cols)), shape=(n, n)))
            for j, (Ed, Ad) in _complex_coefficients(fc).items()}


def hill_pencil(fc: FourierCoefficients, H: int):
    """(Ah, Eh) csc, size n (2H+1): unknown (dof i, harmonic k) at index i (2H+1) + k + H
    (dof-major, so that the band structure of E and A is kept)."""
    n = fc.dae.n
    w = fc.dae.omega
    L = 2 * H + 1
    coef = _complex_coefficients(fc)
    rA, cA, vA, rE, cE, vE = [], [], [], [], [], []
    for j, (Ed, Ad) in coef.items():
        for m in range(-H, H + 1):
            k = m - j
            if not -H <= k <= H:
                continue
            ro_E = fc.pE.rows * L + (m + H)
            co_E = fc.pE.cols * L + (k + H)
            rE.append(ro_E), cE.append(co_E), vE.append(Ed)
            rA.append(fc.pA.rows * L + (m + H)), cA.append(fc.pA.cols * L + (k + H))
            vA.append(Ad)
            if k != 0:              # - i k w E_{m-k} on the A side
                rA.append(ro_E), cA.append(co_E), vA.append(-1j * k * w * Ed)
    N = n * L
    cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)
    Ah = sp.csc_matrix((cat(vA), (cat(rA), cat(cA))), shape=(N, N))
    Eh = sp.csc_matrix((cat(vE), (cat(rE), cat(cE))), shape=(N, N))
    Ah.sum_duplicates()
    Eh.sum_duplicates()
    return Ah, Eh


class _ShiftInvert:
    """The eigenvalues of the pencil (A, E) nearest ``sigma``: ARPACK on (A - sigma E)^-1 E
    with one sparse LU (counted in ``stats``, with the solves)."""

    def __init__(self, A, E, sigma, stats: dict, what: str):
        self.N = A.shape[0]
        self.sigma = sigma
        self.what = what
        lu = spla.splu(sp.csc_matrix(A - sigma * E))
        stats["factorizations"] = stats.get("factorizations", 0) + 1

        def mv(x):
            stats["solves"] = stats.get("solves", 0) + 1
            return lu.solve(np.asarray(E @ x))
        self.op = spla.LinearOperator((self.N, self.N), matvec=mv,
                                      dtype=complex if np.iscomplexobj(sigma) else float)

    def nearest(self, k: int):
        """(lam, X) of the k eigenvalues nearest sigma (infinite ones excluded)."""
        N = self.N
        ncv = min(N - 1, max(2 * k + 1, 40))
        for attempt in range(3):
            # fixed start vectors (reproducible whatever ran before); LAPACK's Schur
            # reordering inside ARPACK can fail for some starts (widely spread
            # eigenvalues): retry from other ones
            v0 = arpack_start(N, self.op.dtype == complex, seed=attempt)
            try:
                mu, X = spla.eigs(self.op, k=k, which="LM", ncv=min(N - 1, ncv + 10 * attempt),
                                  tol=1e-13, v0=v0)
                break
            except spla.ArpackNoConvergence as err:
                mu, X = err.eigenvalues, err.eigenvectors
                if len(mu) < k // 2:
                    raise HillError(f"{self.what}: ARPACK did not converge for the {k} "
                                    f"eigenvalues nearest {self.sigma:.4g}") from err
                break
            except spla.ArpackError as err:
                if attempt == 2:
                    raise HillError(f"{self.what}: ARPACK failed for the {k} eigenvalues "
                                    f"nearest {self.sigma:.4g}: {err}") from err
        ok = np.abs(mu) > 0
        return self.sigma + 1.0 / mu[ok], X[:, ok]


def _window_eigs(Ah, Eh, lo: float, hi: float, stats: dict, depth: int = 0,
                 re_lo: Optional[float] = None, re_hi: Optional[float] = None):
    """Eigenpairs of the pencil (Ah, Eh) in the box lo <= Im <= hi, re_lo <= Re <= re_hi
    (default |Re| <= (hi - lo) / 2): ARPACK's k eigenvalues nearest the box centre, k doubled
    until the farthest of them lies outside the box's circumscribed circle; a window that
    needs more than MAX_PER_WINDOW is halved across its longer side (both halves searched;
    in Re the left half open at its right edge): many non-oscillatory exponents on the real
    axis (the blades' inflow and lag states and their Hill copies at Im = k w) fill a window
    that only a split in Re thins."""
    N = Ah.shape[0]
    c = 0.5 * (lo + hi)
    r = 0.5 * (hi - lo)
    if re_lo is None:
        re_lo, re_hi = -r, r
    cr = 0.5 * (re_lo + re_hi)
    radius = 0.5 * math.hypot(hi - lo, re_hi - re_lo)
    # a shift just off the imaginary axis: undamped modes (and a free angle's zero) are
    # never exactly at it
    si = _ShiftInvert(Ah, Eh, complex(cr - 1e-3 * r, c), stats,
                      f"Hill's method in the band [{lo:.4g}, {hi:.4g}] rad/s")
    k = min(32, N - 2)
    while True:
        lam, X = si.nearest(k)
        if (lam.size and np.abs(lam - si.sigma).max() > radius) or k >= N - 2:
            eps = 1e-9 * max(abs(lo), abs(hi), r)     # real exponents sit on Im = 0
            sel = ((lam.imag >= lo - eps) & (lam.imag <= hi) & (lam.real >= re_lo)
                   & (lam.real <= re_hi))
            return lam[sel], X[:, sel]
        if 2 * k > MAX_PER_WINDOW and depth < 12:
            del si
            if re_hi - re_lo > hi - lo:      # split in Re, the left half open on the right
                m = 0.5 * (re_lo + re_hi)
                a = _window_eigs(Ah, Eh, lo, hi, stats, depth + 1, re_lo, m)
                keep = a[0].real < m
                a = (a[0][keep], a[1][:, keep])
                b = _window_eigs(Ah, Eh, lo, hi, stats, depth + 1, m, re_hi)
            else:
                a = _window_eigs(Ah, Eh, lo, c, stats, depth + 1, re_lo, re_hi)
                b = _window_eigs(Ah, Eh, c, hi, stats, depth + 1, re_lo, re_hi)
            return np.concatenate([a[0], b[0]]), np.concatenate([a[1], b[1]], axis=1)
        k = min(2 * k, N - 2)


def _band_eigs(Ah, Eh, hi: float, width: float, stats: dict):
    """Eigenpairs with 0 <= Im <= hi, in windows of at most ``width`` (see _window_eigs);
    a small pencil (at most DENSE_SIZE unknowns) by dense QZ at once."""
    N = Ah.shape[0]
    if N <= DENSE_SIZE:
        import scipy.linalg as sla
        stats["factorizations"] = stats.get("factorizations", 0) + 1
        (al, be), X = sla.eig(Ah.toarray(), Eh.toarray(), homogeneous_eigvals=True)
        fin = np.abs(be) > 1e-10 * np.abs(al)
        lam = np.full(al.shape, np.inf, complex)
        lam[fin] = al[fin] / be[fin]
        r = 0.5 * width
        sel = fin & (lam.imag >= -1e-9 * max(hi, 1.0)) & (lam.imag <= hi) & \
            (np.abs(lam.real) <= r)
        return refine_eigenpairs(Ah, Eh, lam[sel], X[:, sel])
    count = max(1, int(math.ceil(hi / width)))
    edges = np.linspace(0.0, hi, count + 1)

    def window(edge):          # one window, counting its own factorizations and solves
        own: dict = {}
        return (*_window_eigs(Ah, Eh, edge[0], edge[1], own), own)

    # the windows are independent: searched on the solver threads (numerics/threads.py)
    parts = thread_map(window, list(zip(edges[:-1], edges[1:])))
    _add_stats(stats, [p[2] for p in parts])
    return (np.concatenate([p[0] for p in parts]),
            np.concatenate([p[1] for p in parts], axis=1))


def _add_stats(stats: dict, parts) -> None:
    """Add the counts of ``parts`` (dicts) into ``stats``."""
    for part in parts:
        for key, value in part.items():
            stats[key] = stats.get(key, 0) + value


def _real_pencil_band(A, E, max_frequency: float, stats: dict):
    """Finite eigenpairs of a real pencil with |eta| <= max_frequency, Im >= 0: dense
    (deflation of the infinite eigenvalues + QZ) for small systems, otherwise real
    shift-invert ARPACK about a small negative shift, k doubled until the farthest
    eigenvalue found lies beyond the band."""
    N = A.shape[0]
    if N <= DENSE_SIZE:
        stats["factorizations"] = stats.get("factorizations", 0) + 1
        lam, X = finite_modes(A.toarray().real, E.toarray().real)
        keep = np.abs(lam) <= max_frequency
        return refine_eigenpairs(A, E, lam[keep], X[:, keep])
    A = sp.csc_matrix(A.real)
    E = sp.csc_matrix(E.real)
    si = _ShiftInvert(A, E, -1e-3 * max_frequency, stats, "multi-blade eigenproblem")
    k = min(40, N - 2)
    while True:
        lam, X = si.nearest(k)
        if (lam.size and np.abs(lam - si.sigma).max() > max_frequency + abs(si.sigma)) \
                or k >= N - 2:
            keep = (np.abs(lam) <= max_frequency) & (lam.imag >= -1e-9 * max_frequency)
            return refine_eigenpairs(A, E, lam[keep], X[:, keep])
        k = min(2 * k, N - 2)


def hill_modes(dae: LinearPeriodicDAE, max_frequency: float, harmonics: Optional[int] = None,
               observed=None, weights=None, fourier_tol: float = 1e-10,
               coefficients: Optional[FourierCoefficients] = None,
               tail_tol: float = TAIL_TOL, truncation: str = "tail",
               converged_tol: float = CONVERGED_TOL, modal_basis: bool = True,
               internal=None) -> HillModes:
    """Hill eigenpairs with the dominant-harmonic frequency in ``[0, max_frequency]`` [rad/s].

    Constant coefficients (H = 0): the eigenpairs of the real pencil (A_0, E_0) with
    |eta| <= max_frequency.  Periodic ones: the band is searched in windows of width 2 w
    (halved when crowded); every copy ``eta + i m w`` in the band is found and the centred
    one (dominant harmonic 0 of the weighted vector) kept.  ``harmonics``: the truncation H
    (default: automatic, from ``max(4, 2 J)`` with J the highest of the coefficients'
    harmonics above 1e-3 of the largest, grown by half while a kept vector holds more than
    ``tail_tol`` of its energy in the outermost harmonics |k| = H; measured on the paper's
    turbine, the relative exponent error is about sqrt(tail)/10 there).  ``truncation=
    "converged"`` instead takes each exponent at the first H = 0, 1, 2, ... at which it moved
    by at most ``converged_tol`` relative to max(|eta|, w) (_converged_modes): for weakly
    periodic systems (an isotropic rotor's multi-blade coordinates, whose periodicity is only
    gravity and tilt), where the tail of a vector mixed by a near-resonance stays large
    although its exponent has converged (NREL 5-MW: tail 2.6e-2 at H = 1, exponents already
    within 3e-8 w of H = 4).  ``change`` of the result is the largest such move of the kept
    exponents; ``harmonics`` the largest H used.  ``observed``, ``weights``: rows and weights
    (on squared amplitudes)
    of the dominant-harmonic test (default: the differential rows, weight 1).  An exponent
    whose real part exceeds half the width of the window that finds it (at least w / 2^8) is
    missed: heavily damped modes need their own search.  ``modal_basis`` (truncation
    "converged"): try the averaged system's modal basis first (hill_reduced.py; False: the
    whole pencil at once, as a reference); ``internal``: a test (lam, X) -> bool of the
    averaged system's modes the modal basis leaves out, their response taken whole (the
    blades' aerodynamic lags: analyses/labels.aerodynamic_lags); they are not followed."""
    t0 = time.perf_counter()
    fc = coefficients if coefficients is not None else dae.fourier(tol=fourier_tol)
    t1 = time.perf_counter()
    n, w = dae.n, dae.omega
    J = int(max(fc.k, default=0)) if len(fc.k) else 0
    # the harmonics that matter for the start of the truncation: those above 1e-3 of the
    # largest (a periodic steady state with gravity keeps ~20 tiny ones)
    K = len(fc.k)
    amp = [max(np.abs(fc.cE[[1 + i, 1 + K + i]]).max(), np.abs(fc.cA[[1 + i, 1 + K + i]]).max())
           for i in range(K)]
    big = max(amp, default=0.0)
    J_eff = max([int(j) for j, a in zip(fc.k, amp) if a >= 1e-3 * big], default=0)
    obs = (np.flatnonzero(dae.differential) if observed is None
           else np.asarray(observed, int))
    wts = np.ones(obs.size) if weights is None else np.asarray(weights, float)
    if truncation not in TRUNCATIONS:
        raise ValueError(f"truncation: {truncation!r} is not one of {TRUNCATIONS}")
    if harmonics is not None:
        H_list = [int(harmonics)]
    elif J == 0:
        H_list = [0]
    elif truncation == "converged":
        H_list = list(range(0, MAX_HARMONICS + 1))
    else:
        H_list, H = [], max(4, 2 * J_eff)
        while H <= MAX_HARMONICS:
            H_list.append(H)
            H = int(math.ceil(1.5 * H))
    stats: dict = {}
    if truncation == "converged" and len(H_list) > 1:
        found = None
        if modal_basis:     # weakly periodic: the averaged system's modal basis
            try:
                found = _reduced_modes(fc, n, w, float(max_frequency), obs, wts, stats,
                                       converged_tol, internal)
            except (ReductionFailed, spla.ArpackError, np.linalg.LinAlgError):
                pass        # it does not apply here: the whole pencil
        method = "whole pencil" if found is None else "modal basis"
        lam, V, tails, H, change, part = found if found is not None else (*_converged_modes(
            fc, n, w, float(max_frequency), obs, wts, stats, converged_tol), None)
        return HillModes(exponents=lam, vectors=V, tail=tails, harmonics=H, omega=w,
                         size=n * (2 * H + 1), coefficient_harmonics=J,
                         timings={"coefficients": t1 - t0,
                                  "eigen": time.perf_counter() - t1,
                                  "factorizations": stats.get("factorizations", 0),
                                  # dense eigensolutions of the averaged pencil
                                  "dense": stats.get("dense", 0)},
                         solves=stats.get("solves", 0), change=change, method=method,
                         participation=part)
    change = None
    for attempt, H in enumerate(H_list):
        Ah, Eh = hill_pencil(fc, H)
        L = 2 * H + 1
        if H == 0:
            lam, X = _real_pencil_band(Ah, Eh, float(max_frequency), stats)
        else:
            lam, X = _band_eigs(Ah, Eh, float(max_frequency), 2.0 * w, stats)
        lam, V, tails = _centred(lam, X, H, n, obs, wts, w)
        if H == 0 or tails.size == 0 or tails.max() <= tail_tol or \
                attempt == len(H_list) - 1:
            if H and tails.size and tails.max() > tail_tol:
                warnings.warn(f"Hill's method: the outermost of {H} harmonics still holds "
                              f"{tails.max():.1e} of a mode's energy (tolerance "
                              f"{tail_tol:.0e})", RuntimeWarning, stacklevel=2)
        else:
            continue
        return HillModes(exponents=lam, vectors=V, tail=tails, harmonics=H, omega=w,
                         size=n * L, coefficient_harmonics=J,
                         timings={"coefficients": t1 - t0,
                                  "eigen": time.perf_counter() - t1,
                                  "factorizations": stats.get("factorizations", 0)},
                         solves=stats.get("solves", 0),
                         change=change)
    raise HillError("Hill's method: no truncation tried")  # pragma: no cover


def _centred(lam, X, H: int, n: int, obs, wts, w: float):
    """(lam, V (2H+1, n, m), tails) of the eigenpairs (lam, X) of the Hill pencil with H
    harmonics whose weighted vectors are dominant in harmonic 0 (the others are copies of
    modes centred elsewhere), sorted by frequency then real part; ``tails`` the energy share
    of the outermost harmonics."""
    L = 2 * H + 1
    V = X.reshape(n, L, -1).transpose(1, 0, 2)            # (L, n, m)
    energy = np.einsum("r,krm->km", wts, np.abs(V[:, obs, :]) ** 2)
    kk = np.arange(-H, H + 1)
    keep, tails = [], []
    for i in range(lam.size):
        e = energy[:, i]
        if H and kk[dominant_harmonic(e, kk, lam[i].imag, w, tie=1e-12)] != 0:
            continue                            # a copy of a mode centred elsewhere
        keep.append(i)
        tails.append((e[0] + e[-1]) / max(e.sum(), 1e-300) if H else 0.0)
    keep = np.array(keep, int)
    lam, V, tails = lam[keep], V[:, :, keep], np.array(tails)
    order = np.lexsort((lam.real, lam.imag))
    return lam[order], V[:, :, order], tails[order]


#: "converged" truncation: at most this many (or a quarter of the modes) still moving are
#: refined one by one at the next truncation; more, and the whole band is searched again.
TARGETED_MODES = 12
#: Eigenvalues asked of ARPACK about each mode refined one by one (its Hill copies are a
#: base frequency apart, other modes may lie nearer).
TARGETED_K = 8


def _converged_modes(fc, n: int, w: float, band: float, obs, wts, stats: dict, tol: float):
    """The "converged" truncation: (lam, V, tails, H, change).  H = 0 and H = 1 search the
    whole band; a mode is accepted at the first H at which it moved by at most ``tol``
    (relative to max(|eta|, w)) from H - 1 (modes above 0.9 of the band, whose partners may
    have left it, are accepted as found).  The few still moving are
    then refined one by one at H + 1, H + 2, ...: shift-invert about each one's last value on
    the larger pencil, the nearest centred eigenvalue taken, and accepted by the same rule;
    when many move, or a refinement is ambiguous (no centred eigenvalue near, two modes on
    the same one), the whole band is searched at that H instead.  Vectors of modes accepted
    at a lower H are padded with zero harmonics (exactly their truncated expansion).
    ``change``: the largest last move of the accepted modes below 0.9 of the band."""
    edge = 0.9 * band
    Ah, Eh = hill_pencil(fc, 0)
    lam, X = _real_pencil_band(Ah, Eh, band, stats)
    previous = _centred(lam, X, 0, n, obs, wts, w)[0]
    accepted: list = []                       # (eta, V (2H+1, n), tail, H, move)
    pending: list = []                        # the same, still moving
    full = True
    for H in range(1, MAX_HARMONICS + 1):
        Ah, Eh = hill_pencil(fc, H)
        found = None if full else _refine(Ah, Eh, pending, H, n, obs, wts, w, stats)
        if found is None:                     # the whole band at this truncation
            lam, V, tails = _centred(*_band_eigs(Ah, Eh, band, 2.0 * w, stats), H, n, obs,
                                     wts, w)
            lost = _lost(previous, lam, edge, w)
            # each exponent against the nearest of the coarser truncation's
            candidates = [(eta, v, tail, previous) for eta, v, tail in
                          zip(lam, V.transpose(2, 0, 1), tails)]
            accepted, pending = [], []
        else:
            lost = False
            # each refined exponent against its own last value
            candidates = [(eta, v, tail, np.array([p[0]])) for (eta, v, tail), p in
                          zip(found, pending)]
            pending = []
        for eta, v, tail, reference in candidates:
            if eta.imag > edge:
                accepted.append((eta, v, tail, H, 0.0))
                continue
            move = (np.abs(reference - eta).min() / max(abs(eta), w) if reference.size
                    else math.inf)
            if move <= tol:
                accepted.append((eta, v, tail, H, move))
            else:
                pending.append((eta, v, tail, H, move))
        if not pending and not lost:
            break
        previous = np.array([a[0] for a in accepted] + [p[0] for p in pending])
        full = lost or len(pending) > max(TARGETED_MODES, len(previous) // 4)
    else:
        worst = math.inf if lost else max((p[4] for p in pending), default=0.0)
        warnings.warn(f"Hill's method: the exponents still move by {worst:.1e} (relative) "
                      f"at {H} harmonics (tolerance {tol:.0e})", RuntimeWarning, stacklevel=3)
        accepted += pending
    Hmax = max([a[3] for a in accepted], default=H)
    V = _stack_harmonics([(v, Hi) for _, v, _, Hi, _ in accepted], n, Hmax)
    lam = np.array([a[0] for a in accepted], dtype=complex)
    tails = np.array([a[2] for a in accepted])
    change = max([a[4] for a in accepted if a[0].imag <= edge], default=0.0)
    order = np.lexsort((lam.real, lam.imag))
    return lam[order], V[:, :, order], tails[order], Hmax, change


def _reduced_modes(fc, n: int, w: float, band: float, obs, wts, stats: dict, tol: float,
                   internal=None):
    """The "converged" truncation on the averaged system's modal basis
    (hill_reduced.reduced_converged_modes): (lam, V, tails, H, change, participation)
    (participation (n, m): a refined mode keeps its basis mode's).  Modes whose
    estimated reduction error (CORRECTION_TRUST x their second-order corrections) exceeds
    ``tol`` (a coupling too strong for the reduction) are refined one by one on the whole
    pencil (_refine) at H, H + 1, ... until they move by at most ``tol``; ``change`` is the
    largest of the truncation moves and the kept modes' error estimates.  ReductionFailed
    when more than max(TARGETED_MODES, a quarter) need it or a refinement is ambiguous (the
    caller then searches the whole band)."""
    mats = coefficient_matrices(fc)
    best = None
    cache: dict = {}            # the averaged pencil's LU (and dense spectrum) for every margin
    # with the aerodynamic lags the wider basis did not lower the weak modes' estimates (IEA
    # 15-MW, Oye and Jones, at 14, 15 and 25 m/s: 9.0e-4, 9.2e-4, 1.3e-3 -> 9.0e-4, 9.3e-4,
    # 1.2e-3) and cost 5-14 s a point: the first basis only
    margins = BASIS_MARGINS if internal is None else BASIS_MARGINS[:1]
    for margin in margins:
        try:
            lam, V, tails, H, change, corrections, part = reduced_converged_modes(
                mats, n, w, band, obs, wts, stats, tol, MAX_HARMONICS, margin=margin,
                internal=internal, cache=cache)
        except ReductionFailed:
            if best is None:
                raise
            break                   # the wider basis does not apply: keep the first one's
        estimate = CORRECTION_TRUST * corrections
        # a heavily damped mode (|Re| > w: an aerodynamically damped flap mode, damping
        # ratio ~0.4 and more; or a damping ratio above HEAVY_RATIO) is kept at HEAVY_TOL:
        # refining it on the whole pencil costs a factorization of the whole Hill pencil
        # per mode (IEA 15-MW at 8 m/s: 50 s instead of 3.5 s) for digits its damping does
        # not have; its estimate is reported in ``change``
        heavy = (np.abs(lam.real) > w) | (np.abs(lam.real) > HEAVY_RATIO * np.abs(lam))
        allowed = np.where(heavy, max(tol, HEAVY_TOL),
                           tol if internal is None else max(tol, LAG_TOL))
        weak = np.flatnonzero(estimate > allowed)
        if best is None or weak.size < best[-1].size:
            best = (lam, V, tails, H, change, part, estimate, allowed, weak)
        if not weak.size:
            break
    # a narrow band's basis may leave out the modes a damped mode couples with (NREL 5-MW
    # at 11 m/s, band 3.4 Hz: two flap modes refined on the whole pencil, 28 s; with the
    # wider basis none, 4 s): the wider basis is tried before any refinement
    lam, V, tails, H, change, part, estimate, allowed, weak = best
    if weak.size and internal is not None:
        # with the aerodynamic lags the whole pencil factorizes in minutes per mode: the
        # modes are kept at their estimate, reported in ``change`` and said
        warnings.warn(f"Hill's modal basis: {weak.size} mode(s) kept at an estimated "
                      f"reduction error up to {estimate[weak].max():.1e} (above "
                      f"{LAG_TOL:.0e}; not refined on the whole pencil, which the "
                      "aerodynamic states make too large)", RuntimeWarning, stacklevel=3)
        return lam, V, tails, H, max(change, float(estimate.max())), part
    change = max([change, *estimate[estimate <= allowed]])
    if not weak.size:
        return lam, V, tails, H, change, part
    if weak.size > max(TARGETED_MODES, lam.size // 4):
        raise ReductionFailed(f"{weak.size} of {lam.size} modes are coupled too strongly for "
                              "the modal basis")
    pending = [(lam[i], None, None, H, math.inf) for i in weak]
    results = {}
    for Hr in range(H, MAX_HARMONICS + 1):
        Ah, Eh = hill_pencil(fc, Hr)
        found = _refine(Ah, Eh, pending, Hr, n, obs, wts, w, stats)
        if found is None:
            raise ReductionFailed("a refinement on the whole pencil is ambiguous")
        still = []
        for i, (eta, v, tail), p in zip(weak, found, pending):
            move = abs(eta - p[0]) / max(abs(eta), w)
            if Hr > H and move <= tol:
                results[i] = (eta, v, tail, Hr, move)
            else:
                still.append((i, (eta, v, tail, Hr, move)))
        if not still:
            break
        weak = np.array([i for i, _ in still], int)
        pending = [p for _, p in still]
    else:
        raise ReductionFailed("a refined mode does not converge in the harmonics")
    Hmax = max(H, *(r[3] for r in results.values()))
    for i, (eta, _, tail, _, move) in results.items():
        lam[i], tails[i] = eta, tail
        change = max(change, move)
    W = _stack_harmonics([(results[i][1], results[i][3]) if i in results else (V[:, :, i], H)
                          for i in range(lam.size)], n, Hmax)
    order = np.lexsort((lam.real, lam.imag))
    return lam[order], W[:, :, order], tails[order], Hmax, change, part[:, order]


def _stack_harmonics(parts, n: int, H: int) -> np.ndarray:
    """V (2H+1, n, m) from m vectors (v (2Hi+1, n), Hi) of truncations Hi <= H: each padded
    with zero outer harmonics (exactly its truncated expansion)."""
    V = np.zeros((2 * H + 1, n, len(parts)), dtype=complex)
    for i, (v, Hi) in enumerate(parts):
        V[H - Hi:H + Hi + 1, :, i] = v
    return V


def _refine(Ah, Eh, pending, H, n, obs, wts, w, stats):
    """[(eta, V (2H+1, n), tail)] of each pending mode at truncation H: the centred
    eigenvalue nearest its last value among the TARGETED_K nearest a shift beside it; None
    when one is not found within w / 4 or two modes land on the same one."""
    def nearest(eta):          # one mode: its own factorization (on the solver threads)
        own: dict = {}
        si = _ShiftInvert(Ah, Eh, complex(eta) + 1e-4 * w, own,
                          f"Hill's method refining the exponent {eta:.4g}")
        lam, X = si.nearest(min(TARGETED_K, Ah.shape[0] - 2))
        return _centred(lam, X, H, n, obs, wts, w), own

    found = thread_map(nearest, [p[0] for p in pending])
    _add_stats(stats, [f[1] for f in found])
    out = []
    for (eta, *_), ((cl, cV, ct), _) in zip(pending, found):
        if not cl.size:
            return None
        j = int(np.argmin(np.abs(cl - eta)))
        if abs(cl[j] - eta) > 0.25 * w or any(abs(cl[j] - o[0]) <= 1e-9 * w for o in out):
            return None
        out.append((cl[j], cV[:, :, j], ct[j]))
    return out


def _lost(previous, lam, edge: float, w: float) -> bool:
    """True when an exponent of ``previous`` below ``edge`` has nothing of ``lam`` within
    w / 4: a mode of the coarser truncation the finer one does not have (it cannot be
    followed one by one; the whole band is searched again)."""
    # the windows of the periodic truncations reach |Re| <= w: more heavily damped modes
    # of the constant one (searched in a circle) are not followed
    a = previous[(previous.imag <= edge) & (np.abs(previous.real) <= 0.9 * w)]
    if not a.size:
        return False
    if not lam.size:
        return True
    return bool((np.abs(a[:, None] - lam[None, :]).min(axis=1) > 0.25 * w).any())
