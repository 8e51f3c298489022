"""The live node's turbine at candidate blade meshes: accuracy against converged, and speed.

The node's default (hawt_ros/params.py): the shipped NREL 5-MW in 15 m/s wind under ROSCO,
flexible tower, Oye's dynamic inflow, quasi-steady airfoils.  For each mesh (elements x
order per blade) this prints, in one run:

- the first 3 blade frequencies at rated rotor speed (12.1 rpm, `hawt blade-modes`'s
  analysis) against the converged reference (order 8 x 8 elements, < 1e-5 from an
  independent Euler-Bernoulli solution, tests/test_spectral.py): largest relative error;
- the steady tip flap deflection of the operating point at 11 and 15 m/s (`hawt
  operating-points`) against the same reference mesh;
- the closed loop's real-time factor (`hawt simulate nrel5mw --wind 15 --controller rosco
  --duration D`) at 5 and 1 deg azimuth steps, one process pinned to one core with one
  BLAS thread, the model's construction (start-up) timed apart; best of --repeat runs.

    OPENBLAS_NUM_THREADS=1 taskset -c 0 .venv/bin/python bench/live_default.py   # ~4 min
    .venv/bin/python bench/live_default.py --meshes 4x1 3x6 --duration 10
"""
from __future__ import annotations

import argparse
import dataclasses as dc
import time
import warnings

import numpy as np

from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.analyses.closed_loop import closed_loop
from hawt_core.analyses.operating_points import operating_points
from hawt_core.aero.wind import Wind
from hawt_core.io.catalog import load_any, shipped_controller
from hawt_core.io.discon import discon_schedule

REFERENCE = (8, 8)                      # elements, order


def with_mesh(turbine, elements, order):
    return dc.replace(turbine, blade=dc.replace(turbine.blade, elements=elements, order=order))


def blade_frequencies(turbine, count=3):
    r = blade_modes(turbine, elements=turbine.blade.elements, rotor_speed=turbine.rotor.speed,
                    count=count + 3)
    return np.sort([m.frequency_hz for m in r.modes])[:count]


def tip_flaps(turbine, schedule, winds=(11.0, 15.0)):
    pts = operating_points(turbine, list(winds), schedule).points
    return np.array([p["tip_flap_m"] for p in pts], float)


def real_time_factor(turbine, discon, wind_speed, step_deg, duration):
    t0 = time.perf_counter()
    loop = closed_loop(turbine, Wind(wind_speed), "rosco", discon=discon, step_deg=step_deg)
    try:
        setup = time.perf_counter() - t0
        s = loop.run(duration)
    finally:
        loop.close()
    return s["real_time_factor"], setup


def parse_mesh(text):
    n, p = text.lower().split("x")
    return int(n), int(p)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turbine", default="nrel5mw")
    ap.add_argument("--meshes", nargs="+", type=parse_mesh,
                    default=[(4, 1), (32, 1), (4, 4), (3, 6), (4, 6)],
                    help="ELEMENTSxORDER per blade (default 4x1 32x1 4x4 3x6 4x6)")
    ap.add_argument("--wind", type=float, default=15.0)
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds per run")
    ap.add_argument("--steps", type=float, nargs="+", default=[5.0, 1.0],
                    help="azimuth steps [deg] (default 5 1)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--compare-undamped", action="store_true",
                    help="also each mesh with the structure undamped (the cost of the "
                         "deck's structural damping, in the same run)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    base = load_any(args.turbine)
    discon = shipped_controller(args.turbine)
    schedule = discon_schedule(discon)
    ref = with_mesh(base, *REFERENCE)
    f_ref = blade_frequencies(ref)
    d_ref = tip_flaps(ref, schedule)
    print(f"{args.turbine}: reference (order {REFERENCE[1]}, {REFERENCE[0]} elements): blade "
          f"frequencies at {base.rotor.speed * 30 / np.pi:.2f} rpm {np.round(f_ref, 5).tolist()}"
          f" Hz; tip flap at 11 / 15 m/s {d_ref[0]:.4f} / {d_ref[1]:.4f} m")
    head = (f"{'mesh (per blade)':<24}{'unknowns':>9}{'freq err':>10}{'tip 11':>9}"
            f"{'tip 15':>9}" + "".join(f"{f'rtf {s:g}deg':>11}" for s in args.steps)
            + f"{'start-up':>10}")
    print(head)
    cases = [(n, p, False) for n, p in args.meshes]
    if args.compare_undamped:
        cases = [c for n, p in args.meshes for c in ((n, p, False), (n, p, True))]
    for n, p, undamped in cases:
        t = with_mesh(base, n, p)
        if undamped:
            t = t.without_structural_damping()
        r = blade_modes(t, elements=n, rotor_speed=t.rotor.speed, count=6)
        unknowns = r.settings["unknowns"]
        f = np.sort([m.frequency_hz for m in r.modes])[:3]
        ef = float(np.max(np.abs(f / f_ref - 1)))
        ed = tip_flaps(t, schedule) / d_ref - 1
        rtfs, setup = [], np.inf
        for step in args.steps:
            best = 0.0
            for _ in range(args.repeat):
                rtf, s = real_time_factor(t, discon, args.wind, step, args.duration)
                best, setup = max(best, rtf), min(setup, s)
            rtfs.append(best)
        kind = ("paper element" if p == 1 else f"order {p}") + (" undamped" if undamped
                                                                else "")
        print(f"{f'{n} x {kind}':<24}{unknowns:>9}{100 * ef:>9.3f}%{100 * ed[0]:>+8.2f}%"
              f"{100 * ed[1]:>+8.2f}%" + "".join(f"{x:>11.2f}" for x in rtfs)
              + f"{setup:>9.1f}s", flush=True)


if __name__ == "__main__":
    main()
