"""Floquet exponents from the monodromy (or from any method's solutions): the conjugate
structure, the dominant harmonic that resolves the integer-per-rev ambiguity, the periodic
eigenvector samples and their normalisation; FloquetResult.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .coefficients import LinearPeriodicDAE
from .monodromy import monodromy

__all__ = ['FloquetResult', 'dominant_harmonic', 'floquet_analysis', 'periodic_modes']


# --------------------------------------------------------------------------------------------
@dataclass
class FloquetResult:
    """Floquet modal results; arrays have one entry per dynamic multiplier (length d).

    ``exponents`` are resolved (dominant harmonic moved into the exponent), in rad/s;
    ``frequency_per_rev = Im(eta)/Omega0``, ``real_per_rev = Re(eta)/Omega0``,
    ``frequency_hz = Im(eta)/(2 pi)``, ``damping_ratio = -Re(eta)/|eta|`` (0 for eta = 0).
    Conjugate pairs: both members are kept, ``representative`` marks the member with
    frequency >= 0 (and every real multiplier).  ``eigenvectors[:, i]`` is the Floquet
    eigenvector x(0) (full state); ``periodic_samples[m, :, i]`` is p_i(t_m) on the rows
    ``sample_rows`` with x_i(t) = p_i(t) exp(eta_i t).
    """
    multipliers: np.ndarray
    exponents: np.ndarray
    exponents_principal: np.ndarray
    frequency_per_rev: np.ndarray
    real_per_rev: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    harmonic: np.ndarray
    harmonic_share: np.ndarray
    representative: np.ndarray
    eigenvectors: np.ndarray
    sample_times: np.ndarray
    sample_rows: np.ndarray
    _p_unique: np.ndarray = field(repr=False)
    _n_upper: int = field(repr=False)
    omega: float
    period: float
    method: str
    steps: int
    fast: bool
    blades: int
    n_dynamic: int
    wall_time: float
    timings: dict = field(default_factory=dict)
    #: positions in ``sample_rows`` and weights (on squared amplitudes) of the rows that
    #: decided the dominant harmonic and the normalisation
    observed: Optional[np.ndarray] = field(default=None, repr=False)
    weights: Optional[np.ndarray] = field(default=None, repr=False)

    def recombine(self, columns, Q: np.ndarray) -> None:
        """Replace the modes ``columns`` (members of one cluster of equal exponents, all with
        a positive-frequency upper member or all real) by the combinations ``V Q`` of their
        eigenvectors and periodic samples (in place; the conjugate members follow), then
        normalise them like :func:`periodic_modes`.  Used to turn an arbitrary basis of a
        degenerate eigenspace into one of the symmetry classes."""
        nu = self._n_upper
        cols = [int(c) for c in columns]
        conj = [nu <= c < 2 * nu for c in cols]
        if any(conj) and not all(conj):
            raise ValueError("recombine: mixed upper and conjugate members")
        slot = [c - nu if c >= nu else c for c in cols]              # in _p_unique
        Qe = np.conj(Q) if conj[0] else Q
        P = self._p_unique[:, :, slot] @ Qe
        V = self.eigenvectors[:, cols] @ Q
        w = np.ones(len(self.sample_rows)) if self.weights is None else self.weights
        obs = slice(None) if self.observed is None else self.observed
        nrm = np.sqrt(np.einsum("r,mrk->k", w, np.abs(P[:, obs, :]) ** 2) / P.shape[0])
        nrm[nrm == 0] = 1.0
        P /= nrm
        V /= (np.conj(nrm) if conj[0] else nrm)[None, :]
        self._p_unique[:, :, slot] = P
        self.eigenvectors[:, cols] = V
        for c, s_ in zip(cols, slot):      # the partner members
            if c < nu:
                self.eigenvectors[:, c + nu] = np.conj(self.eigenvectors[:, c])
            elif c < 2 * nu:
                self.eigenvectors[:, c - nu] = np.conj(self.eigenvectors[:, c])
        self.__dict__.pop("_periodic_samples_cache", None)

    @property
    def periodic_samples(self) -> np.ndarray:
        """(M, len(sample_rows), d) complex: p_i(t_m), built on first use and cached
        (conjugate members are the conjugates of their partners); do not modify in place."""
        cached = self.__dict__.get("_periodic_samples_cache")
        if cached is None:
            P, nu = self._p_unique, self._n_upper
            cached = np.concatenate([P[:, :, :nu], np.conj(P[:, :, :nu]), P[:, :, nu:]], axis=2)
            self.__dict__["_periodic_samples_cache"] = cached
        return cached

    def periodic_sample(self, i: int) -> np.ndarray:
        """(M, len(sample_rows)) samples of the periodic eigenvector of mode i."""
        nu = self._n_upper
        if i < nu:
            return self._p_unique[:, :, i]
        if i < 2 * nu:
            return np.conj(self._p_unique[:, :, i - nu])
        return self._p_unique[:, :, i - nu]

    def modes(self, sort: bool = True) -> np.ndarray:
        """Indices of the representative members, sorted by frequency then real part."""
        idx = np.flatnonzero(self.representative)
        if sort:
            idx = idx[np.lexsort((self.real_per_rev[idx], self.frequency_per_rev[idx]))]
        return idx

    def summary(self) -> str:
        lines = [f"Floquet: {self.n_dynamic} multipliers, method={self.method}, "
                 f"steps/period={self.steps}, fast={self.fast}, {self.wall_time * 1e3:.1f} ms",
                 "   freq/rev     real/rev      freq Hz    damping   |lambda|   k  share"]
        for i in self.modes():
            lines.append(f"{self.frequency_per_rev[i]:11.6f} {self.real_per_rev[i]:12.4e} "
                         f"{self.frequency_hz[i]:12.6f} {self.damping_ratio[i]:10.3e} "
                         f"{abs(self.multipliers[i]):10.6f} {self.harmonic[i]:3d} "
                         f"{self.harmonic_share[i]:6.3f}")
        return "\n".join(lines)


def _real_tol(lam: np.ndarray) -> float:
    """Multipliers with |Im mu| below this are treated as real: 1e-7 (relative) covers the
    O(sqrt(eps)) splitting of a defective double multiplier at 1 (free yaw angle with a
    conserved yaw momentum), which would otherwise appear as a spurious tiny frequency."""
    return 1e-7 * max(1.0, float(np.max(np.abs(lam), initial=1.0)))


def dominant_harmonic(energy: np.ndarray, k: np.ndarray, freq0: float, w0: float,
                       tie: float) -> int:
    """Position in ``k`` (integer harmonics) of the dominant harmonic: the largest ``energy``;
    candidates within 1e-6 (relative) of it tie, and ties (real eigenvectors) prefer the
    non-negative frequency ``freq0 + k w0`` (negative: below ``-tie * w0``), then the
    smallest |frequency|."""
    cand = np.flatnonzero(energy >= energy.max() * (1.0 - 1e-6))
    freqs = freq0 + k[cand] * w0
    best = min(range(cand.size), key=lambda j: (freqs[j] < -tie * w0, abs(freqs[j])))
    return int(cand[best])


def floquet_analysis(dae: LinearPeriodicDAE, method: str = "radau", steps: Optional[int] = None,
                     fast: Optional[bool] = None, samples: int = 128, observed=None,
                     weights=None, coefficients="fourier", harmonics="auto",
                     fourier_tol: float = 1e-10, dynamic_dim: Optional[int] = None,
                     store_all: bool = False, lowrank: Optional[bool] = None) -> FloquetResult:
    """Floquet multipliers, resolved characteristic exponents and periodic eigenvectors.

    observed : indices of the variables used for the dominant-harmonic analysis (default: all
        differential variables); weights : per observed variable (default 1), applied to the
        squared Fourier amplitudes, so that units do not decide.
    lowrank : low-rank stage update (see :func:`monodromy`); None automatic.
    """
    t0 = time.perf_counter()
    mono = monodromy(dae, method=method, steps=steps, fast=fast, coefficients=coefficients,
                     harmonics=harmonics, fourier_tol=fourier_tol, samples=samples,
                     observed=observed, dynamic_dim=dynamic_dim, store_all=store_all,
                     lowrank=lowrank)
    t1 = time.perf_counter()
    T, w0, nb = dae.period, dae.omega, mono.blades
    d = mono.n_dynamic
    mu, V = mono.eig()
    # --- canonical conjugate structure: upper members, their conjugates, real ones
    tol = _real_tol(mu)
    upper = np.flatnonzero(mu.imag > tol)
    real = np.flatnonzero(np.abs(mu.imag) <= tol)
    nlow = int(np.sum(mu.imag < -tol))
    if nlow != upper.size:     # should not happen for a real matrix
        upper = np.flatnonzero(mu.imag > 0)
        real = np.flatnonzero(mu.imag == 0)
    mus = list(mu[upper]) + [complex(np.real(mu[i]), 0.0) for i in real]
    vecs = [V[:, i] for i in upper]
    for i in real:
        v = V[:, i]
        j = np.argmax(np.abs(v))
        vecs.append(np.real(v * np.conj(v[j]) / abs(v[j])))
    mus = np.array(mus, dtype=complex)
    Vc = np.column_stack(vecs).astype(complex) if vecs else np.zeros((V.shape[0], 0), complex)
    nu = upper.size
    # --- samples of x over the full period: x(t + j tau) = mu^j S^j x(t)
    obs_rows = mono.sample_rows
    if observed is None:
        obs_local = np.flatnonzero(dae.differential[obs_rows])
    else:
        pos = {r: i for i, r in enumerate(obs_rows)}
        obs_local = np.array([pos[int(r)] for r in np.asarray(observed, dtype=int)])
    w = np.ones(obs_local.size) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.size != obs_local.size:
        raise ValueError("weights must have one entry per observed variable")
    Xs = np.array(mono.samples)                     # (M/nb, rows, d) real
    Mb = Xs.shape[0]
    Xm = np.empty((Mb * nb, Xs.shape[1], len(mus)), dtype=complex)   # (M, rows, modes)
    np.matmul(Xs, Vc, out=Xm[:Mb])
    if nb > 1:
        Srr = dae.S[obs_rows][:, obs_rows].tocsr()
        Srr.sum_duplicates()
        perm = None
        if Srr.nnz == Srr.shape[0] and np.all(np.diff(Srr.indptr) == 1):
            perm, sgn = Srr.indices, Srr.data          # a signed permutation: gather rows
        else:
            Srr = Srr.toarray()
        for j in range(1, nb):
            prev, cur = Xm[(j - 1) * Mb:j * Mb], Xm[j * Mb:(j + 1) * Mb]
            if perm is not None:
                np.multiply(prev[:, perm, :], sgn[None, :, None], out=cur)
            else:
                np.matmul(Srr, prev, out=cur)
            cur *= mus[None, None, :]
    lam = mus ** nb
    eta0 = np.log(mus) * nb / T                     # e^{eta0 T} = lambda
    t2 = time.perf_counter()
    return periodic_modes(
        eta0, Xm, mono.basis @ Vc, nu, period=T, sample_rows=obs_rows, observed=obs_local,
        weights=w, multipliers=lam, method=method, steps=mono.steps, fast=mono.fast,
        blades=nb, n_dynamic=d, start_time=t0,
        timings={"monodromy": t1 - t0, "eigen": t2 - t1,
                 "factorizations": mono.factorizations, "lowrank": mono.lowrank,
                 "coefficient_evaluations": getattr(mono.coefficients, "evaluations", None),
                 "fourier_harmonics": getattr(mono.coefficients, "harmonics", None),
                 "fourier_error": getattr(mono.coefficients, "error", None)})


def periodic_modes(eta0: np.ndarray, X: np.ndarray, x0: np.ndarray, n_upper: int, *,
                   period: float, sample_rows: np.ndarray, observed: np.ndarray,
                   weights: np.ndarray, multipliers: Optional[np.ndarray] = None,
                   method: str, steps: int, fast: bool, blades: int, n_dynamic: int,
                   start_time: Optional[float] = None, timings: Optional[dict] = None
                   ) -> FloquetResult:
    """A FloquetResult from solutions ``x_i(t) = p_i(t) exp(eta0_i t)`` (p periodic).

    ``X`` (M, len(sample_rows), m): samples x_i(t_m) at ``t_m = m period / M`` over one full
    period (any method: monodromy marching, Hill's method, multi-blade coordinates);
    ``x0`` (n, m): x_i(0) on every state row; the first ``n_upper`` columns are the members
    with a positive imaginary multiplier part (their conjugates are added), the rest real
    ones.  ``observed`` (positions in ``sample_rows``) and ``weights`` (per observed row,
    applied to squared amplitudes) decide the dominant harmonic k, which moves into the
    exponent (eta = eta0 + i k Omega); p is shifted accordingly and normalised (weighted RMS
    over the period 1, largest observed component real positive).  ``X`` is overwritten."""
    T = float(period)
    w0 = 2.0 * math.pi / T
    nu = int(n_upper)
    if start_time is None:
        start_time = time.perf_counter()
    eta0 = np.asarray(eta0, complex)
    lam = np.exp(eta0 * T) if multipliers is None else np.asarray(multipliers, complex)
    obs_local = np.asarray(observed, dtype=int)
    w = np.asarray(weights, dtype=float).ravel()
    M = X.shape[0]
    tm = np.arange(M) * T / M
    P = X
    P *= np.exp(-eta0[None, None, :] * tm[:, None, None])
    # the observed rows as a slice when they are all the sample rows in order (no copies)
    obs_sel = (slice(None) if np.array_equal(obs_local, np.arange(len(sample_rows)))
               else obs_local)
    C = np.fft.fft(P[:, obs_sel, :], axis=0) / M    # (M, obs, modes)
    energy = np.einsum("r,krm->km", w, np.abs(C) ** 2)
    kk = np.fft.fftfreq(M, 1.0 / M).astype(int)
    nm = eta0.size
    harm = np.zeros(nm, dtype=int)
    share = np.zeros(nm)
    for i in range(nm):
        e = energy[:, i]
        harm[i] = kk[dominant_harmonic(e, kk, eta0[i].imag, w0, tie=1e-12)]
        share[i] = e.max() / max(e.sum(), 1e-300)
    eta = eta0 + 1j * harm * w0
    # build the full list: uppers, their conjugates, reals
    idx_up = np.arange(nu)
    idx_re = np.arange(nu, nm)
    all_eta = np.concatenate([eta[idx_up], np.conj(eta[idx_up]), eta[idx_re]])
    all_eta0 = np.concatenate([eta0[idx_up], np.conj(eta0[idx_up]), eta0[idx_re]])
    all_lam = np.concatenate([lam[idx_up], np.conj(lam[idx_up]), lam[idx_re]])
    all_h = np.concatenate([harm[idx_up], -harm[idx_up], harm[idx_re]])
    all_share = np.concatenate([share[idx_up], share[idx_up], share[idx_re]])
    rep = np.concatenate([eta[idx_up].imag >= 0, eta[idx_up].imag < 0,
                          np.ones(idx_re.size, bool)])
    all_V = np.concatenate([x0[:, idx_up], np.conj(x0[:, idx_up]), x0[:, idx_re]], axis=1)
    Pm = P
    Pm *= np.exp(-1j * harm[None, None, :] * w0 * tm[:, None, None])
    # normalise: weighted RMS of p over the observed rows = 1, largest component real > 0
    Po = Pm[:, obs_sel, :]
    nrm = np.sqrt(np.einsum("r,mrk->k", w, np.abs(Po) ** 2) / M)
    nrm[nrm == 0] = 1.0
    Pm /= nrm
    Po = Pm[:, obs_sel, :]
    flat = np.abs(Po).reshape(-1, nm)
    jmax = np.argmax(flat, axis=0)
    mi, ri = np.unravel_index(jmax, Po.shape[:2])
    big = Po[mi, ri, np.arange(nm)]
    ph = np.where(np.abs(big) > 0, np.conj(big) / np.where(np.abs(big) > 0, np.abs(big), 1.0), 1.0)
    ph[nu:] = np.where(np.real(ph[nu:]) < 0, -1.0, 1.0)     # real eigenvectors stay real
    Pm *= ph[None, None, :]
    scale = ph / nrm
    Vn = all_V * np.concatenate([scale[:nu], np.conj(scale[:nu]), scale[nu:]])[None, :]
    absn = np.abs(all_eta)
    zeta = np.where(absn > 0, -all_eta.real / np.where(absn > 0, absn, 1.0), 0.0)
    t_end = time.perf_counter()
    timings = dict(timings or {})
    wall = t_end - start_time
    if "monodromy" in timings:
        timings["analysis"] = wall - timings["monodromy"]
    return FloquetResult(
        multipliers=all_lam, exponents=all_eta, exponents_principal=all_eta0,
        frequency_per_rev=all_eta.imag / w0, real_per_rev=all_eta.real / w0,
        frequency_hz=all_eta.imag / (2 * math.pi), damping_ratio=zeta, harmonic=all_h,
        harmonic_share=all_share, representative=rep, eigenvectors=Vn, sample_times=tm,
        sample_rows=np.asarray(sample_rows), _p_unique=Pm, _n_upper=nu, omega=w0, period=T,
        method=method, steps=steps, fast=fast, blades=blades, n_dynamic=n_dynamic,
        wall_time=wall, timings=timings, observed=obs_local, weights=w)
