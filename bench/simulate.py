"""Real-time factor of hawt.simulate for N = 4, 8, 16 elements, 1 degree azimuth steps.

Usage: PYTHONPATH=. .venv/bin/python bench/simulate.py [--revs R] [--repeat K] [--profile]

For the paper's rotor with the yaw locked and free, after a 0.02 rad teeter release, prints
for each N: the real-time factor and ms per step of the default window solver
(hawt_core.window: 24 steps solved together, one batched residual evaluation per
iteration) and of the step-by-step solver (sparse LU per step), their ratio, the window
solver's iterations per window and full Jacobians, and its per-step cost relative to N = 4.
One core (run with OPENBLAS_NUM_THREADS=1). The wall time counts everything the steps do,
including the first Jacobian and its inverse. Timings are the best of several runs (the
machine is shared): --repeat runs of the window solver, max(1, --repeat - 1) of the slower
step-by-step solver. docs/simulation.md has the figures.
"""
import argparse
import cProfile
import pstats

from hawt_core.assembly import TurbineModel
from hawt_core.model import Beam, Hub, Nacelle, Rotor, SectionTable, Turbine
from hawt_core.solvers.march import Simulator

SEC = SectionTable.uniform(mass=67.5772, i1=5, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6,
                           ei3=21.8e6)


def run(N, yaw_free, revs, method):
    t = Turbine("paper", Rotor(), Hub(), Nacelle(yaw_free=yaw_free), Beam(8.42, SEC, N))
    m = TurbineModel(t)
    sim = Simulator(m, step_deg=1.0, perturb={"teeter": 0.02}, record=False, method=method)
    s = sim.run(revs * m.period)
    s["ms_per_step"] = 1e3 * s["wall_seconds"] / s["steps"]
    return s


def best(N, yaw_free, revs, method, repeat):
    return min((run(N, yaw_free, revs, method) for _ in range(repeat)),
               key=lambda s: s["wall_seconds"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--revs", type=float, default=3.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--profile", action="store_true")
    a = ap.parse_args()
    if a.profile:
        pr = cProfile.Profile()
        pr.enable()
        run(4, True, a.revs, "window")
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(15)
        return
    print(f"{a.revs:g} revolutions, 1 deg steps, best of {a.repeat} (window) and "
          f"{max(1, a.repeat - 1)} (step) runs")
    print(f"{'yaw':<7}{'N':>4}{'RTF window':>12}{'ms/step':>9}{'RTF step':>10}{'ms/step':>9}"
          f"{'speed-up':>10}{'it/window':>11}{'jac':>5}{'cost vs N=4':>13}")
    for yaw_free in (False, True):
        base = None
        for N in (4, 8, 16):
            w = best(N, yaw_free, a.revs, "window", a.repeat)
            s = best(N, yaw_free, a.revs, "step", max(1, a.repeat - 1))
            base = base or w["ms_per_step"]
            print(f"{'free' if yaw_free else 'locked':<7}{N:>4}{w['real_time_factor']:>12.2f}"
                  f"{w['ms_per_step']:>9.3f}{s['real_time_factor']:>10.2f}{s['ms_per_step']:>9.3f}"
                  f"{s['ms_per_step'] / w['ms_per_step']:>10.2f}"
                  f"{w['window_iterations'] / w['windows']:>11.2f}{w['jacobian_evaluations']:>5}"
                  f"{w['ms_per_step'] / base:>13.2f}")


if __name__ == "__main__":
    main()
