"""Tests of hawt_core.floquet (generic Floquet machinery for linear periodic DAEs).

Every test states its reference and tolerance.  Systems:
- chain_rotor (bench/floquet_generic.py): chains of masses with algebraic spring forces
  (index 1) and a rigid outer link with a Lagrange multiplier (index 3), periodic stiffness,
  optional hub ("teeter", sign (-1)^b for two blades) and blade-relabelling symmetry S;
- the damped Mathieu equation as index-1 and index-3 descriptor systems, and an index-3 system
  with a time-varying constraint q1 = (1 + a sin t) q2;
- an anisotropic oscillator viewed in a rotating frame (dominant-harmonic resolution).
"""
import math
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from hawt_core.solvers.floquet import LinearPeriodicDAE, floquet_analysis, monodromy

sys.path.insert(0, os.path.join(os.path.dirname(__file__), os.pardir, "bench"))
from floquet_generic import chain_rotor  # noqa: E402


# ------------------------------------------------------------------------------------------
# systems
def ode_multipliers(f, T):
    """Monodromy of a 2-state ODE by DOP853, rtol 1e-13 (reference)."""
    cols = [solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
            for y0 in np.eye(2)]
    return np.linalg.eigvals(np.array(cols).T)


MATHIEU = dict(w=1.7, z=0.02, eps=0.3, Om=1.0)


def mathieu_ref(w, z, eps, Om):
    return ode_multipliers(lambda t, y: [y[1], -2 * z * w * y[1]
                                         - w ** 2 * (1 + eps * math.cos(Om * t)) * y[0]],
                           2 * math.pi / Om)


def mathieu_index1(w, z, eps, Om):
    """vars (x, v, f): x' = v, v' = f - 2 z w v, 0 = -f - w^2 (1 + eps cos Om t) x."""
    E = sp.csc_matrix(np.diag([1.0, 1.0, 0.0]))

    def A(t):
        k = w ** 2 * (1 + eps * math.cos(Om * t))
        return sp.csc_matrix(np.array([[0, 1, 0], [0, -2 * z * w, 1], [-k, 0, -1.0]]))
    return LinearPeriodicDAE(lambda t: E, A, 2 * math.pi / Om, [1, 1, 0])


def mathieu_index3(w, z, eps, Om, m1=0.3, m2=0.7):
    """Two masses joined by a rigid link q1 = q2 (multiplier lam), total mass 1, stiffness and
    damping split between them with time-varying shares: vars (q1, q2, v1, v2, lam)."""
    E = sp.csc_matrix(np.diag([1.0, 1.0, m1, m2, 0.0]))
    c1 = 2 * z * w * m1 * 1.5
    c2 = 2 * z * w * (m1 + m2) - c1

    def A(t):
        k = w ** 2 * (1 + eps * math.cos(Om * t))
        k1 = k * (0.2 + 0.1 * math.sin(Om * t))
        return sp.csc_matrix(np.array([[0, 0, 1, 0, 0], [0, 0, 0, 1, 0],
                                       [-k1, 0, -c1, 0, 1], [0, -(k - k1), 0, -c2, -1],
                                       [1, -1, 0, 0, 0.0]]))
    return LinearPeriodicDAE(lambda t: E, A, 2 * math.pi / Om, [1, 1, 1, 1, 0])


TV3 = dict(m1=0.4, m2=0.9, k1=2.0, k2=1.1, c1=0.03, c2=0.05, alpha=0.3, Om=1.0)


def tv3(m1, m2, k1, k2, c1, c2, alpha, Om):
    """Index 3 with a time-varying constraint: q1 = a(t) q2, a = 1 + alpha sin(Om t)."""
    E = sp.csc_matrix(np.diag([1.0, 1.0, m1, m2, 0.0]))

    def A(t):
        a = 1 + alpha * math.sin(Om * t)
        return sp.csc_matrix(np.array([[0, 0, 1, 0, 0], [0, 0, 0, 1, 0],
                                       [-k1, 0, -c1, 0, 1], [0, -k2, 0, -c2, -a],
                                       [1, -a, 0, 0, 0.0]]))
    return LinearPeriodicDAE(lambda t: E, A, 2 * math.pi / Om, [1, 1, 1, 1, 0])


def tv3_ref(m1, m2, k1, k2, c1, c2, alpha, Om):
    """The same system in the generalized coordinate s = q2 (q1 = a s), Lagrange's equations."""
    def f(t, y):
        s, sd = y
        a = 1 + alpha * math.sin(Om * t)
        ad = alpha * Om * math.cos(Om * t)
        add = -alpha * Om ** 2 * math.sin(Om * t)
        f1 = -k1 * a * s - c1 * (a * sd + ad * s)
        f2 = -k2 * s - c2 * sd
        return [sd, (a * f1 + f2 - 2 * a * ad * m1 * sd - a * add * m1 * s) / (a * a * m1 + m2)]
    return ode_multipliers(f, 2 * math.pi / Om)


SYSTEMS = {
    "mathieu_index1": (lambda: mathieu_index1(**MATHIEU), lambda: mathieu_ref(**MATHIEU)),
    "mathieu_index3": (lambda: mathieu_index3(**MATHIEU), lambda: mathieu_ref(**MATHIEU)),
    "timevarying_index3": (lambda: tv3(**TV3), lambda: tv3_ref(**TV3)),
}


def match_error(lam, ref):
    """Largest distance after matching each reference value to its nearest computed one."""
    lam = np.asarray(lam)
    assert lam.size == len(ref)
    return max(np.min(np.abs(lam - r)) for r in ref)


# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("rigid", [True, False], ids=["index3_rigid_link", "index1_forces"])
def test_time_invariant_equals_generalized_eigenvalues(rigid):
    """Constant coefficients: the resolved Floquet exponents equal the finite generalized
    eigenvalues of (A, E) (scipy.linalg.eig, |lambda| < 1e4 kept) to 1e-6 relative, without any
    integer-per-rev ambiguity; the count equals the dimension of the consistent subspace."""
    dae, info = chain_rotor(N=4, blades=1, hub=False, eps=0.0, rigid=rigid)
    E, A = dae.E(0.0).toarray(), dae.A(0.0).toarray()
    ev = sla.eig(A, E, right=False)
    ref = ev[np.isfinite(ev) & (np.abs(ev) < 1e4)]
    res = floquet_analysis(dae, observed=np.ravel(info["q"]))
    assert res.n_dynamic == info["n_dynamic"] == ref.size
    assert res.exponents.size == ref.size
    err = max(np.min(np.abs(res.exponents - r)) / abs(r) for r in ref)
    print(f"time-invariant ({'index 3' if rigid else 'index 1'}): d = {res.n_dynamic}, "
          f"max rel. exponent error {err:.1e}, max freq {ref.imag.max():.3f}/rev")
    assert err < 1e-6


@pytest.mark.parametrize("name", list(SYSTEMS))
def test_multipliers_match_fine_ode_reference(name):
    """Default method (Radau IIA, default steps): multipliers equal the ODE reference
    (DOP853, rtol 1e-13) to 1e-8; exactly 2 multipliers (the consistent subspace)."""
    mk, mkref = SYSTEMS[name]
    res = floquet_analysis(mk())
    err = match_error(res.multipliers, mkref())
    print(f"{name}: {res.steps} steps, multiplier error {err:.1e}, {res.wall_time * 1e3:.1f} ms")
    assert res.n_dynamic == 2
    assert err < 1e-8


@pytest.mark.parametrize("name", list(SYSTEMS))
@pytest.mark.parametrize("method,steps,order", [("radau", (20, 40), 5.0),
                                                ("paper", (100, 200), 2.0)])
def test_observed_temporal_order(name, method, steps, order):
    """Observed order log2(err(K)/err(2K)) of the multipliers: 5 for Radau IIA (also for the
    index-3 systems, time-varying constraint included), 2 for the paper's central
    differencing; tolerance +-0.3."""
    mk, mkref = SYSTEMS[name]
    dae, ref = mk(), mkref()
    errs = [match_error(floquet_analysis(dae, method=method, steps=K, samples=8).multipliers, ref)
            for K in steps]
    p = math.log(errs[0] / errs[1]) / math.log(steps[1] / steps[0])
    print(f"{name} {method}: errors {errs[0]:.2e} (K={steps[0]}), {errs[1]:.2e} "
          f"(K={steps[1]}): order {p:.2f}")
    assert abs(p - order) <= 0.3


@pytest.mark.parametrize("blades", [2, 3])
@pytest.mark.parametrize("method", ["radau", "paper"])
def test_fast_floquet_equals_full_period(blades, method):
    """Peters' Fast Floquet (march T/Nb, Phi(T) = (S^T Phi(T/Nb))^Nb) gives the multipliers
    and the resolved exponents of the full-period monodromy to 1e-8.  Two blades: teeter-like
    hub coordinate whose relabelling flips sign; three blades: cyclic permutation."""
    dae, info = chain_rotor(N=3, blades=blades, eps=0.3)
    assert dae.check_symmetry() < 1e-14
    obs = np.concatenate([np.ravel(info["q"]), info["hub"]]).astype(int)
    steps = 240 if method == "radau" else 600
    full = floquet_analysis(dae, method=method, steps=steps, fast=False, observed=obs)
    fast = floquet_analysis(dae, method=method, steps=steps, fast=True, observed=obs)
    assert fast.fast and not full.fast
    assert full.n_dynamic == fast.n_dynamic == info["n_dynamic"]
    err = match_error(fast.multipliers, full.multipliers)
    a, b = (np.sort_complex(r.exponents[r.representative]) / r.omega for r in (full, fast))
    print(f"Fast Floquet Nb={blades} ({method}): multiplier difference {err:.1e}, exponent "
          f"difference {np.max(np.abs(a - b)):.1e}/rev; time {full.wall_time * 1e3:.0f} -> "
          f"{fast.wall_time * 1e3:.0f} ms")
    assert err < 1e-8
    assert np.max(np.abs(a - b)) < 1e-8


def test_spurious_multipliers_not_reported():
    """The full descriptor monodromy of central differencing (diagnostic full=True) has n
    eigenvalues; the Lagrange multiplier of the rigid link gives a spurious one of modulus 1
    (R(inf) = -1; the algebraic forces, collocated at the nodes, give 0).  The analysis reports
    exactly the d dynamic ones, equal to those of the reduced march to 1e-10."""
    dae, info = chain_rotor(N=3, blades=1, hub=False, eps=0.3)
    m = monodromy(dae, method="paper", steps=400, full=True)
    allmu = np.linalg.eigvals(m.matrix)
    assert allmu.size == dae.n
    assert np.sum(np.abs(np.abs(allmu) - 1) < 1e-9) >= 1
    mu, _ = m.eig()
    red = floquet_analysis(dae, method="paper", steps=400)
    assert mu.size == red.n_dynamic == info["n_dynamic"]
    assert match_error(mu, red.multipliers) < 1e-10


def rotating_oscillator(nx=2.3, ny=3.55, zeta=0.02, Om=1.0):
    """Anisotropic damped 2-D oscillator (inertial frequencies nx, ny per rev) written in a
    frame rotating at Om: states y (rotating coordinates), w = y', algebraic X = R(Om t) y
    (inertial coordinates).  vars (y1, y2, w1, w2, X1, X2)."""
    K = np.diag([(nx * Om) ** 2, (ny * Om) ** 2])
    C = np.diag([2 * zeta * nx * Om, 2 * zeta * ny * Om])
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    E = sp.csc_matrix(np.diag([1.0, 1, 1, 1, 0, 0]))

    def A(t):
        c, s = math.cos(Om * t), math.sin(Om * t)
        R = np.array([[c, -s], [s, c]])
        Kr, Cr = R.T @ K @ R, R.T @ C @ R
        # y'' = -2 Om J y' + Om^2 y - Cr (y' + Om J y) - Kr y
        M = np.zeros((6, 6))
        M[0:2, 2:4] = np.eye(2)
        M[2:4, 0:2] = Om ** 2 * np.eye(2) - Cr @ (Om * J) - Kr
        M[2:4, 2:4] = -2 * Om * J - Cr
        M[4:6, 4:6] = -np.eye(2)
        M[4:6, 0:2] = R
        return sp.csc_matrix(M)
    ref = []
    for n_, z in ((nx, zeta), (ny, zeta)):
        w = n_ * Om
        ref.append(complex(-z * w, w * math.sqrt(1 - z * z)))
    return LinearPeriodicDAE(lambda t: E, A, 2 * math.pi / Om, [1, 1, 1, 1, 0, 0]), ref


@pytest.mark.parametrize("coefficients", ["fourier", "direct"])
def test_dominant_harmonic_gives_physical_frequency(coefficients):
    """Oscillator at 2.3 and 3.55 per rev (inertial) seen in a rotating frame: observing the
    inertial coordinates X, the reported exponents equal the inertial eigenvalues
    (-zeta w + i w sqrt(1 - zeta^2)) to 1e-8 relative, i.e. the integer ambiguity is resolved
    (2.3/rev, not 0.3 or 1.3 or 3.3), damping ratios 0.02; the Fourier series of the
    coefficients is exact (degree 2) and matches direct evaluation."""
    dae, ref = rotating_oscillator()
    res = floquet_analysis(dae, observed=[4, 5], coefficients=coefficients)
    assert res.n_dynamic == 4
    modes = res.modes()
    got = res.exponents[modes]
    assert np.allclose(res.frequency_per_rev[modes], [r.imag for r in ref], rtol=1e-8)
    assert max(abs(g - r) / abs(r) for g, r in zip(got, ref)) < 1e-8
    assert np.allclose(res.damping_ratio[modes], 0.02, rtol=1e-7)
    assert np.allclose(res.frequency_hz[modes], res.frequency_per_rev[modes] / (2 * math.pi))
    assert np.all(res.harmonic_share[modes] > 0.99)
    if coefficients == "fourier":
        assert res.timings["fourier_error"] < 1e-12
    # conjugate members are kept, with negative frequency
    assert np.sum(~res.representative) == 2
    assert np.allclose(np.sort(res.frequency_per_rev[~res.representative]), [-3.55 * math.sqrt(1 - 4e-4), -2.3 * math.sqrt(1 - 4e-4)])


def test_periodic_eigenvector_samples():
    """x(t) = p(t) exp(eta t): the periodic samples reproduce a direct march of the eigenvector
    (1e-7), p is periodic, and the dominant harmonic of p is the constant term."""
    dae, _ = rotating_oscillator()
    res = floquet_analysis(dae, observed=[4, 5], samples=64, store_all=True)
    i = res.modes()[0]
    P = res.periodic_sample(i)
    M = P.shape[0]
    assert M >= 64 and P.shape[1] == dae.n
    # march the eigenvector directly with a fine reference (ODE in the rotating frame)
    x0 = res.eigenvectors[:, i]
    eta = res.exponents[i]
    A = dae.A

    def f(t, y):
        Am = A(t).toarray()
        return (Am[:4, :4] @ y[:4].reshape(4))
    for m in (M // 4, M // 2):
        t = res.sample_times[m]
        sol = solve_ivp(lambda tt, y: f(tt, y), (0, t), x0[:4].astype(complex), method="DOP853",
                        rtol=1e-12, atol=1e-14)
        y = sol.y[:, -1]
        c, s = math.cos(t), math.sin(t)
        X = np.array([[c, -s], [s, c]]) @ y[:2]
        assert np.allclose(np.concatenate([y, X]), P[m] * np.exp(eta * t), atol=1e-7 * np.abs(P).max())
    C = np.fft.fft(P[:, 4:6], axis=0)
    assert np.argmax(np.sum(np.abs(C) ** 2, axis=1)) == 0


def test_zero_exponents_free_angle():
    """A free angle (zero column, multiplier exactly 1) and a free, undamped rotation (defective
    double multiplier 1) report frequency 0 and |eta| < 1e-6 per rev, as real modes."""
    n = 4
    E = sp.identity(n, format="csc")
    # psi' = r ; r' = -0.1 r + 0.2 q ; q' = p ; p' = -4 q   (psi free)  -> single multiplier 1
    # plus a decoupled free rotation would give a Jordan block: tested separately below
    A0 = sp.csc_matrix(np.array([[0, 1, 0, 0], [0, -0.1, 0.2, 0], [0, 0, 0, 1], [0, 0, -4, 0.0]]))
    dae = LinearPeriodicDAE(lambda t: E, lambda t: A0, 2 * math.pi, [1] * n)
    res = floquet_analysis(dae)
    z = np.flatnonzero(np.abs(res.exponents) < 1e-6)
    assert z.size == 1 and res.representative[z[0]] and res.frequency_per_rev[z[0]] == 0.0
    assert res.multipliers[z[0]] == pytest.approx(1.0, abs=1e-12)
    # Jordan block: psi' = r, r' = 0
    A1 = sp.csc_matrix(np.array([[0, 1.0], [0, 0]]))
    dae1 = LinearPeriodicDAE(lambda t: sp.identity(2, format="csc"), lambda t: A1, 2 * math.pi,
                             [1, 1])
    r1 = floquet_analysis(dae1)
    assert np.all(r1.frequency_per_rev == 0.0) and np.all(np.abs(r1.exponents) < 1e-6)


def test_fourier_series_reproduces_coefficients():
    """FFT of the sparse data on the union pattern: a degree-2 trigonometric polynomial is
    reproduced exactly (1e-13) at arbitrary times; a non-polynomial periodic coefficient
    (exp(cos t)) triggers more harmonics until the check error is below tol."""
    dae, _ = rotating_oscillator()
    fc = dae.fourier()
    for t in (0.123, 2.5, 5.9):
        assert abs(fc.A(t) - dae.A(t)).max() < 1e-13
    assert fc.harmonics_kept == 2
    E = sp.identity(2, format="csc")
    dae2 = LinearPeriodicDAE(lambda t: E, lambda t: sp.csc_matrix(
        np.array([[0, 1], [-(1 + 0.5 * math.exp(math.cos(t))), 0]])), 2 * math.pi, [1, 1])
    fc2 = dae2.fourier(tol=1e-12)
    assert fc2.error < 1e-12
    assert abs(fc2.A(1.234) - dae2.A(1.234)).max() < 1e-11


def test_fourier_levels_are_nested_and_exact_for_polynomials():
    """Reference: a trigonometric polynomial of degree 10 in A(t) (entries with one sparse
    pattern at some times and another at others: a time-varying zero), and the sampling
    rule of FourierCoefficients' nested grids 5, 15, 30 (every check time of a level lies on
    the next grid): the series reproduces A at arbitrary times to 1e-13 of its size, with
    10 harmonics kept, from exactly 30 + 4 evaluations (the last level's 4 check times are
    the only samples off its grid; separate grids would take 5 + 15 + 30 + 12)."""
    E = sp.identity(3, format="csc")
    calls = []

    def A(t):
        calls.append(t)
        c = [math.cos(k * t + 0.3 * k) / (1 + k) for k in range(11)]
        a = np.array([[0.0, 1.0, 0.2 * math.sin(3 * t)],     # exactly 0 at t = 0: the
                      [-2.0 - sum(c), 0.1 * c[10], 0.0],        # sample there has a smaller
                      [c[2], 0.0, -1.0 + c[7] - c[3]]])         # pattern (the union's job)
        return sp.csc_matrix(a)
    dae = LinearPeriodicDAE(lambda t: E, A, 2 * math.pi, [1, 1, 1])
    fc = dae.fourier(tol=1e-12)
    assert fc.samples == 30 and fc.harmonics_kept == 10
    assert fc.evaluations == 34 and len(set(round(t / (2 * math.pi), 12) for t in calls)) == 34
    for t in (0.123, 2.5, 5.9):
        ref = A(t).toarray()
        assert np.abs(fc.A(t).toarray() - ref).max() < 1e-13 * np.abs(ref).max()


def test_default_method_needs_far_fewer_steps():
    """Steps per period for <= 1e-6 relative frequency error (reference: Radau with 2048 steps)
    on the chain rotor (highest mode ~7/rev): Radau IIA needs at least 8x fewer steps than the
    paper's central differencing."""
    dae, info = chain_rotor(N=3, blades=2, eps=0.3)
    obs = np.concatenate([np.ravel(info["q"]), info["hub"]]).astype(int)
    ref = floquet_analysis(dae, steps=2048, observed=obs)
    fr = np.sort(ref.frequency_per_rev[ref.representative])

    def needed(method, candidates):
        for K in candidates:
            r = floquet_analysis(dae, method=method, steps=K, observed=obs, samples=32)
            f = np.sort(r.frequency_per_rev[r.representative])
            err = np.max(np.abs(f - fr) / np.maximum(np.abs(fr), 1e-12))
            if err <= 1e-6:
                return K, err, r.wall_time
        return None, err, r.wall_time
    kr, er, tr = needed("radau", [32, 48, 64, 96, 128, 192, 256])
    kp, ep, tp = needed("paper", [1000, 2000, 4000, 8000, 16000, 32000])
    print(f"steps for 1e-6 (max freq {fr.max():.2f}/rev): radau {kr} ({er:.1e}, {tr * 1e3:.0f} ms), "
          f"paper {kp} ({ep:.1e}, {tp * 1e3:.0f} ms)")
    assert kr is not None and kp is not None
    assert kp >= 8 * kr


# ------------------------------------------------------------------------------------------
# low-rank stage update (one factorization of the mean stage matrix + Woodbury per step)
def lowrank_rotor(N=12, alpha=0.4):
    """chain_rotor without periodic stiffness (eps = 0) whose time variation is confined to
    the hub: the hub row (yaw-like equation: coupling to the blade roots and an inertia
    varying at 2/rev) and the hub columns (the blades see the hub angle and acceleration
    through azimuth-dependent terms).  The variations keep the blade relabelling symmetry:
    per-blade phases pi b for 1/rev terms, sign sgn_b = (-1)^b with the hub."""
    base, info = chain_rotor(N=N, blades=2, eps=0.0, hub=True, seed=3)
    n, nbv = base.n, 3 * N
    iy, iw = 2 * nbv, 2 * nbv + 1
    iq = lambda b, i: b * nbv + i
    iv = lambda b, i: b * nbv + N + i
    E0, A0 = base.E(0.0).tocsc(), base.A(0.0).tocsc()
    Om = 2 * math.pi / base.period

    def E(t):
        d = sp.lil_matrix((n, n))
        d[iw, iw] = E0[iw, iw] * 0.3 * math.cos(2 * Om * t)
        for b in range(2):
            d[iv(b, 1), iw] = 0.05 * (-1) ** b * math.sin(Om * t + math.pi * b)
        return (E0 + d.tocsc()).tocsc()

    def A(t):
        d = sp.lil_matrix((n, n))
        for b in range(2):
            s, f = (-1) ** b, math.cos(Om * t + math.pi * b)
            d[iw, iq(b, 0)] = 0.3 * s * alpha * f
            d[iw, iq(b, 2)] = 0.2 * s * math.sin(2 * Om * t)
            d[iv(b, 0), iy] = 0.3 * s * alpha * f
            d[iv(b, 2), iw] = 0.1 * s * math.cos(2 * Om * t)
        return (A0 + d.tocsc()).tocsc()

    dae = LinearPeriodicDAE(E, A, base.period, base.differential, S=base.S, blades=2)
    return dae, info


@pytest.mark.parametrize("fast", [False, True], ids=["full_period", "fast_floquet"])
@pytest.mark.parametrize("method,steps", [("radau", 96), ("paper", 400)])
def test_lowrank_stage_update_equals_factorized_steps(method, steps, fast):
    """Time variation confined to the hub row and columns: the low-rank path (one LU of the
    mean stage matrix, Woodbury update of rank 3 (|rows| + |cols|) per step) gives the
    multipliers of the per-step factorization to 1e-10, and the same periodic eigenvector
    samples; the automatic choice takes it, with one factorization per step size."""
    dae, info = lowrank_rotor()
    assert dae.check_symmetry() < 1e-14
    obs = np.concatenate([np.ravel(info["q"]), info["hub"]]).astype(int)
    kw = dict(method=method, steps=steps, fast=fast, observed=obs)
    ref = floquet_analysis(dae, lowrank=False, **kw)
    got = floquet_analysis(dae, lowrank=True, **kw)
    auto = floquet_analysis(dae, **kw)
    assert not ref.timings["lowrank"] and got.timings["lowrank"] and auto.timings["lowrank"]
    assert got.n_dynamic == ref.n_dynamic == info["n_dynamic"]
    err = match_error(got.multipliers, ref.multipliers)
    err_auto = match_error(auto.multipliers, ref.multipliers)
    print(f"low-rank {method} fast={fast}: multiplier difference {err:.1e} "
          f"(auto {err_auto:.1e}); factorizations {ref.timings['factorizations']} -> "
          f"{got.timings['factorizations']}; monodromy {ref.timings['monodromy'] * 1e3:.1f} -> "
          f"{got.timings['monodromy'] * 1e3:.1f} ms")
    assert err < 1e-10 and err_auto < 1e-10
    assert got.timings["factorizations"] < ref.timings["factorizations"] / 4
    a, b = (np.sort_complex(r.exponents[r.representative]) for r in (ref, got))
    assert np.max(np.abs(a - b)) / ref.omega < 1e-9
    i = int(np.argmax(np.abs(ref.multipliers)))
    j = int(np.argmin(np.abs(got.multipliers - ref.multipliers[i])))
    Pa, Pb = ref.periodic_sample(i), got.periodic_sample(j)
    assert np.max(np.abs(Pa - Pb)) < 1e-7 * np.max(np.abs(Pa))
    # the variation matters: the mean system's multipliers are far from these
    ts = dae.period * np.arange(16) / 16
    E0, A0 = (sum(f(t) for t in ts) / 16 for f in (dae.E, dae.A))
    mean = LinearPeriodicDAE(lambda t: E0, lambda t: A0, dae.period, dae.differential)
    m0 = floquet_analysis(mean, method=method, steps=steps, lowrank=False)
    assert match_error(m0.multipliers, ref.multipliers) > 1e-3


def test_lowrank_is_declined_when_everything_varies():
    """Periodic stiffness in every blade (the chain rotor with eps > 0, like a periodic steady
    state with gravity): the automatic choice keeps the per-step factorization; forcing the
    low-rank path still gives the same multipliers (rank ~ n, 1e-10)."""
    dae, _ = chain_rotor(N=3, blades=2, eps=0.3)
    auto = floquet_analysis(dae, steps=64)
    assert not auto.timings["lowrank"]
    forced = floquet_analysis(dae, steps=64, lowrank=True)
    assert forced.timings["lowrank"]
    assert match_error(forced.multipliers, auto.multipliers) < 1e-10


def test_lowrank_needs_fourier_coefficients():
    """lowrank=True with directly evaluated coefficients is an error; None falls back."""
    dae, _ = lowrank_rotor(N=3)
    with pytest.raises(ValueError, match="lowrank"):
        floquet_analysis(dae, steps=32, coefficients="direct", lowrank=True)
    assert not floquet_analysis(dae, steps=32, coefficients="direct").timings["lowrank"]


def test_lowrank_stage_update_on_the_turbine(monkeypatch):
    """The paper's turbine (no gravity: constant steady state; only the yaw equation and the
    yaw-rate column vary with azimuth): modal_analysis with the low-rank path forced on and
    off (floquet_analysis(..., lowrank=True/False)) reports the same modes; multipliers of the
    reported modes agree to 2e-7 (the free-yaw pair, a defective double multiplier at 1 with
    sqrt(eps) sensitivity: 1e-6).  Tolerance: round-off of the per-step path itself; another
    valid fill-reducing ordering of its stage matrices (permc_spec='MMD_AT_PLUS_A') moves these
    multipliers by 3e-8 (N = 3, 4) .. 5e-7 (N = 2); the low-rank path differs from the default
    ordering by 6e-9 .. 4e-8 at N = 4."""
    import functools

    import hawt_core.analyses.modal as modal
    from hawt_core.io import load_turbine

    tb = load_turbine()
    res = {}
    for lr in (False, True):
        monkeypatch.setattr(modal, "floquet_analysis",
                            functools.partial(floquet_analysis, lowrank=lr))
        res[lr] = modal.modal_analysis(tb, elements=4)
    a, b = res[False], res[True]
    assert not a.floquet.timings["lowrank"] and b.floquet.timings["lowrank"]
    assert [m.label for m in a.modes] == [m.label for m in b.modes]

    def mult(r, m):
        fl = r.floquet
        i = np.argmin(np.abs(fl.frequency_per_rev - m.frequency_per_rev)
                      + np.abs(fl.real_per_rev - m.real_per_rev))
        return fl.multipliers[i]
    worst = {True: 0.0, False: 0.0}
    for ma, mb in zip(a.modes, b.modes):
        yaw = ma.family == "yaw"
        worst[yaw] = max(worst[yaw], abs(mult(a, ma) - mult(b, mb)))
    print(f"turbine N=4: multiplier difference {worst[False]:.1e} (yaw {worst[True]:.1e}); "
          f"Floquet {a.timings['floquet']:.2f} -> {b.timings['floquet']:.2f} s, "
          f"{a.floquet.timings['factorizations']} -> {b.floquet.timings['factorizations']} LU")
    assert worst[False] < 2e-7
    assert worst[True] < 1e-6


def test_weights_decide_the_dominant_harmonic():
    """periodic_modes: the dominant harmonic maximises the WEIGHTED energy sum_r w_r |c_k,r|^2
    (so units do not decide).  A solution whose row A is harmonic 0 (amplitude 1) and row B
    harmonic 2 (amplitude 3): weights (100, 1) report the exponent's own frequency (energy 100
    against 9), weights (1, 1) report it 2 per-rev higher (9 against 1); exact."""
    from hawt_core.solvers.floquet import periodic_modes
    T, M = 2 * math.pi, 64
    t = np.arange(M) * T / M
    eta0 = complex(-0.01, 0.3)
    x = np.stack([np.ones(M), 3 * np.exp(2j * t)], axis=1) * np.exp(eta0 * t)[:, None]

    def freq(w):
        X = x[:, :, None].astype(complex).copy()
        r = periodic_modes(np.array([eta0]), X, X[0].copy(), 1, period=T,
                           sample_rows=np.array([0, 1]), observed=np.array([0, 1]),
                           weights=np.array(w, float), method="test", steps=0, fast=False,
                           blades=1, n_dynamic=1)
        return r.frequency_per_rev[0]
    assert freq([100.0, 1.0]) == pytest.approx(0.3, abs=1e-12)
    assert freq([1.0, 1.0]) == pytest.approx(2.3, abs=1e-12)
