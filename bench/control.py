"""Control-in-the-loop figures: the NREL 5-MW under ROSCO (its DISCON library through ctypes) and
under hawt's built-in controller, in one run.

Usage: PYTHONPATH=. OMP_NUM_THREADS=1 .venv/bin/python bench/control.py [--duration S]
       [--plot F.png]

Prints, for a 15 m/s wind stepping to 17 m/s over 0.5 s at t = 1 s (4 elements, 1 deg steps,
controller every 0.055 s, Oye's inflow): the set-up time (operating point and initial
periodic state) and the real-time factor of the closed loop, with the flexible tower and on a
rigid tower, ROSCO and built-in; the last two seconds' mean rotor speed and power. The
issue's goal for the live node: real-time factor >= 1 on one core. ``--plot`` writes the
ROSCO run on the flexible tower as a picture (results/plotting.py plot_time_history).
"""
import argparse
import time
import warnings
from dataclasses import replace

from hawt_core.aero.wind import Wind
from hawt_core.analyses.closed_loop import closed_loop
from hawt_core.io.catalog import load_any, shipped_controller
from hawt_core.results.plotting import plot_time_history


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--plot", default=None)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    path = shipped_controller("nrel5mw")
    base = load_any("nrel5mw")
    wind = Wind(15.0, history=((0.0, 1.0), (1.0, 1.0), (1.5, 17 / 15), (1e3, 17 / 15)))
    print(f"{'tower':9s} {'controller':10s} {'set-up s':>8s} {'RTF':>6s} {'rpm':>7s} "
          f"{'MW':>6s} {'pitch':>6s}")
    for tower in ("flexible", "rigid"):
        t = base if tower == "flexible" else replace(base, tower=None)
        for kind in ("rosco", "builtin"):
            w0 = time.perf_counter()
            # from the schedule's operating point at 15 m/s (analyses/closed_loop.py)
            loop = closed_loop(t, wind, kind, discon=path, elements=4)
            setup = time.perf_counter() - w0
            try:
                s = loop.run(args.duration)
            finally:
                loop.close()
            H = loop.history()
            last = H["time"] > H["time"][-1] - 2.0
            print(f"{tower:9s} {kind:10s} {setup:8.1f} {s['real_time_factor']:6.2f} "
                  f"{H['rotor_speed_rpm'][last].mean():7.3f} "
                  f"{H['generator_power_kw'][last].mean() / 1e3:6.3f} "
                  f"{H['pitch1_deg'][-1]:6.2f}", flush=True)
            if args.plot and tower == "flexible" and kind == "rosco":
                plot_time_history(H, args.plot, title="NREL 5-MW under ROSCO, wind step "
                                                      "15 -> 17 m/s")


if __name__ == "__main__":
    main()
