"""Wall time of the blade-modes pipeline (paper blade, Table 1).

Prints, for N = 4, 16, 64 elements: unknowns, the steady state (Newton), the linearization
(two complex-step Jacobians from the Gauss-point integrands' steps), the eigen-analysis
(dense deflation + QZ for all modes where n <= 600, sparse shift-invert for the lowest 30
beyond), the time per residual and per Jacobian evaluation (median of repeats) and the
number of complex steps per Jacobian.

    PYTHONPATH=. .venv/bin/python bench/blade_modes.py
"""
from __future__ import annotations

import statistics
import time

import numpy as np

from hawt_core.analyses.blade_modes import SPARSE_THRESHOLD
from hawt_core.assembly import SpinningBlade
from hawt_core.fem.energy import frequency_bound
from hawt_core.numerics.pencil import finite_modes, sparse_modes
from hawt_core.model import Beam, Hub, Nacelle, Rotor, SectionTable, Turbine


def paper(N):
    sec = SectionTable.uniform(mass=67.5772, i1=5, i2=1e-4, i3=4.9999, gj=21.8e3,
                               ei2=4.36e6, ei3=21.8e6)
    return Turbine("paper", Rotor(), Hub(), Nacelle(), Beam(8.42, sec, N))


def median_time(fun, repeats):
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fun()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts)


def main():
    rows = []
    for N in (4, 16, 64):
        t0 = time.perf_counter()
        model = SpinningBlade(paper(N), N)
        t_setup = time.perf_counter() - t0
        t0 = time.perf_counter()
        y0 = model.steady_state()
        t_ss = time.perf_counter() - t0
        z = np.zeros(model.n)
        t0 = time.perf_counter()
        Jy, Jd = model.jacobians(z, y0)
        t_lin = time.perf_counter() - t0
        band = 100 * frequency_bound(model.beam.props)
        t0 = time.perf_counter()
        if model.n > SPARSE_THRESHOLD:
            lam, _ = sparse_modes(-Jy, Jd, 30, band=band)
            how = "sparse, 30"
        else:
            lam, _ = finite_modes(-Jy.toarray(), Jd.toarray(), band)
            how = f"dense, {len(lam)}"
        t_eig = time.perf_counter() - t0
        t_res = median_time(lambda: model.residual(z, y0), 50)
        t_jac = median_time(lambda: model.jacobians(z, y0)[0], 7)
        rows.append((N, model.n, t_setup, t_ss, t_lin, t_eig, how, t_res, t_jac,
                     model._pointwise.directions))
    print(f"{'N':>4}{'n':>6}{'setup':>9}{'steady':>9}{'linear.':>9}{'eigen':>9}"
          f"{'(modes)':>14}{'total':>9}{'resid.':>10}{'dR/dy':>9}{'steps':>9}")
    for N, n, ts, tss, tl, te, how, tr, tj, nc in rows:
        print(f"{N:>4}{n:>6}{ts:>8.3f}s{tss:>8.3f}s{tl:>8.3f}s{te:>8.3f}s{how:>14}"
              f"{ts + tss + tl + te:>8.3f}s{tr * 1e3:>8.3f}ms{tj * 1e3:>7.1f}ms{nc:>9}")


if __name__ == "__main__":
    main()
