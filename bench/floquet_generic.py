"""Benchmark of hawt_core.floquet on a synthetic turbine-like periodic DAE.

Nb identical "blades", each a chain of N masses whose springs are algebraic force variables
(index 1) with periodic stiffness k_i(t) = k_i (1 + eps cos(Omega t + 2 pi b / Nb)), the outer
link rigid (a Lagrange multiplier: index 3), coupled to a hub coordinate ("teeter") with sign
(-1)^b for two blades.  Blade relabelling S (swap blades, flip the hub for Nb = 2) satisfies
E(t + T/Nb) = S E(t) S^T, A(t + T/Nb) = S A(t) S^T.

    PYTHONPATH=. .venv/bin/python bench/floquet_generic.py [N]
"""
from __future__ import annotations

import sys
import time

import numpy as np
import scipy.sparse as sp

from hawt_core.solvers.floquet import LinearPeriodicDAE, floquet_analysis


def chain_rotor(N=4, blades=2, omega=1.0, eps=0.2, hub=True, rigid=True, damping=0.01,
                coupling=0.3, seed=0):
    """Returns (dae, info).  Variables per blade: q (N), v (N), f (N) where f[N-1] is the
    rigid-link multiplier if `rigid`; then the hub (y, w) if `hub`."""
    rng = np.random.default_rng(seed)
    m = 1.0 + 0.5 * rng.random(N)
    k0 = (3.0 + 2.0 * rng.random(N)) * omega ** 2 * 4.0
    c = damping * np.sqrt(k0 * m)
    nbv = 3 * N
    nh = 2 if hub else 0
    n = blades * nbv + nh
    iq = lambda b, i: b * nbv + i
    iv = lambda b, i: b * nbv + N + i
    jf = lambda b, i: b * nbv + 2 * N + i
    iy, iw = blades * nbv, blades * nbv + 1
    sgn = [(-1) ** b if blades == 2 else 1.0 for b in range(blades)]
    Jh, ky, cy = 2.0, 1.5 * omega ** 2 * 2.0, 0.02

    Ed = np.zeros(n)
    Ar, Ac, Av = [], [], []           # constant part of A
    Pr, Pc, Pv, Pb = [], [], [], []   # periodic part: value * cos(omega t + 2 pi b / Nb)

    def add(r, cidx, v):
        Ar.append(r); Ac.append(cidx); Av.append(v)

    for b in range(blades):
        for i in range(N):
            Ed[iq(b, i)] = 1.0
            Ed[iv(b, i)] = m[i]
            add(iq(b, i), iv(b, i), 1.0)                 # q' = v
            add(iv(b, i), jf(b, i), 1.0)                 # m v' = f_i - f_{i+1} - c v
            if i + 1 < N:
                add(iv(b, i), jf(b, i + 1), -1.0)
            add(iv(b, i), iv(b, i), -c[i])
            # spring i between q_{i-1} (ground for i = 0) and q_i
            r = jf(b, i)
            if rigid and i == N - 1 and N >= 2:          # 0 = q_{i-1} - q_i  (index 3)
                add(r, iq(b, i - 1), 1.0)
                add(r, iq(b, i), -1.0)
            else:                                        # 0 = -f + k(t) (q_{i-1} - q_i)
                add(r, r, -1.0)
                if i > 0:
                    add(r, iq(b, i - 1), k0[i]); Pr.append(r); Pc.append(iq(b, i - 1)); Pv.append(eps * k0[i]); Pb.append(b)
                add(r, iq(b, i), -k0[i]); Pr.append(r); Pc.append(iq(b, i)); Pv.append(-eps * k0[i]); Pb.append(b)
        if hub:
            add(iv(b, 0), iy, coupling * sgn[b])
            add(iw, iq(b, 0), coupling * sgn[b])
    if hub:
        Ed[iy], Ed[iw] = 1.0, Jh
        add(iy, iw, 1.0)
        add(iw, iy, -ky)
        add(iw, iw, -cy)
    E = sp.diags(Ed).tocsc()
    A0 = sp.csc_matrix((Av, (Ar, Ac)), shape=(n, n))
    Pr, Pc, Pv, Pb = map(np.asarray, (Pr, Pc, Pv, Pb))
    ph = 2 * np.pi * Pb / blades

    def A(t):
        P = sp.csc_matrix((Pv * np.cos(omega * t + ph), (Pr, Pc)), shape=(n, n))
        return (A0 + P).tocsc()

    differential = Ed != 0
    S = None
    if blades >= 2:
        # (S x) relabels: new blade b = old blade b+1 (mod Nb); hub sign flips for Nb = 2
        rows, cols, vals = [], [], []
        for b in range(blades):
            for j in range(nbv):
                rows.append(b * nbv + j); cols.append(((b + 1) % blades) * nbv + j); vals.append(1.0)
        for j in range(nh):
            rows.append(blades * nbv + j); cols.append(blades * nbv + j)
            vals.append(-1.0 if blades == 2 else 1.0)
        S = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    dae = LinearPeriodicDAE(lambda t: E, A, 2 * np.pi / omega, differential,
                            S=S, blades=blades if S is not None else None)
    n_dyn = blades * (2 * N - (2 if rigid and N >= 2 else 0)) + nh
    info = dict(n=n, n_dynamic=n_dyn, q=[[iq(b, i) for i in range(N)] for b in range(blades)],
                hub=[iy] if hub else [])
    return dae, info


def main(N=33):
    dae, info = chain_rotor(N=N, blades=2)
    print(f"n = {info['n']}, dynamic states = {info['n_dynamic']}, "
          f"symmetry residual = {dae.check_symmetry():.1e}")
    obs = np.concatenate([np.ravel(info["q"]), info["hub"]]).astype(int)
    ref = floquet_analysis(dae, steps=2048, fast=True, observed=obs)
    ref_f = np.sort(ref.frequency_per_rev[ref.representative])
    for method, steps, fast in [("radau", 256, True), ("radau", 256, False),
                                ("radau", 128, True), ("paper", 1000, True),
                                ("paper", 1000, False)]:
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            r = floquet_analysis(dae, method=method, steps=steps, fast=fast, observed=obs)
            times.append(time.perf_counter() - t0)
        f = np.sort(r.frequency_per_rev[r.representative])
        err = np.max(np.abs(f - ref_f) / np.maximum(ref_f, 1e-3)) if f.size == ref_f.size else np.nan
        print(f"{method:6s} steps={steps:5d} fast={fast!s:5s}  d={r.n_dynamic}  "
              f"best of 3: {min(times) * 1e3:7.1f} ms  (monodromy {r.timings['monodromy'] * 1e3:6.1f} ms, "
              f"{r.timings['factorizations']} LU)  max rel. freq. error {err:.1e}  "
              f"(max freq {ref_f.max():.2f}/rev)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 33)
