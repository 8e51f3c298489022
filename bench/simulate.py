"""Real-time factor of hawt.simulate for N = 4, 8, 16 elements, 1 degree azimuth steps.

Usage: PYTHONPATH=. .venv/bin/python bench/simulate.py [--revs R] [--profile]
Prints a table (RTF, ms per step, residual evaluations per step (Newton iterations plus the
complex steps of low-rank updates), full Jacobians, low-rank updates of the rigid rows and
columns) for the yaw-locked and yaw-free paper rotor, and the per-step cost ratios N=8/N=4,
N=16/N=4. docs/simulation.md has the figures.
Timings are the best of --repeat runs (the machine is shared).
"""
import argparse
import cProfile
import pstats
import time

from hawt_core.assembly import TurbineModel
from hawt_core.model import Beam, Hub, Nacelle, Rotor, SectionTable, Turbine
from hawt_core.simulate import Simulator

SEC = SectionTable.uniform(mass=67.5772, i1=5, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6,
                           ei3=21.8e6)


def run(N, yaw_free, revs):
    t = Turbine("paper", Rotor(), Hub(), Nacelle(yaw_free=yaw_free), Beam(8.42, SEC, N))
    m = TurbineModel(t)
    sim = Simulator(m, step_deg=1.0, perturb={"teeter": 0.02}, record=False)
    s = sim.run(revs * m.period)
    s["ms_per_step"] = 1e3 * s["wall_seconds"] / s["steps"]
    return s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--revs", type=float, default=2.0)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--profile", action="store_true")
    a = ap.parse_args()
    if a.profile:
        pr = cProfile.Profile()
        pr.enable()
        run(4, False, a.revs)
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(15)
        return
    print(f"{'yaw':<7}{'N':>4}{'RTF':>8}{'ms/step':>10}{'res/step':>10}{'jac':>6}{'upd':>6}")
    for yaw_free in (False, True):
        base = None
        for N in (4, 8, 16):
            best = min((run(N, yaw_free, a.revs) for _ in range(a.repeat)),
                       key=lambda s: s["wall_seconds"])
            ms = best["ms_per_step"]
            base = base or ms
            print(f"{'free' if yaw_free else 'locked':<7}{N:>4}{best['real_time_factor']:>8.2f}"
                  f"{ms:>10.3f}{best['residual_evaluations'] / best['steps']:>10.2f}"
                  f"{best['jacobian_evaluations']:>6}{best.get('low_rank_updates', 0):>6}"
                  f"   cost ratio vs N=4: {ms / base:.2f}")


if __name__ == "__main__":
    main()
