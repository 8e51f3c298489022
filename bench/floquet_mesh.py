"""The NREL 5-MW's aeroelastic Floquet analysis at 8 m/s against the blade mesh: wall time
and accuracy of every mode below --max-hz against a converged reference, in one run.

The shipped turbine (flexible tower on its file mesh, drivetrain, gravity, tilt, frozen-wake
BEM) at ROSCO's 8 m/s operating point, `hawt modes nrel5mw --wind 8`'s analysis
(analyses/modal.py: harmonic balance, then Hill's method in multi-blade coordinates).  The
reference: order 8 with 8 blade elements.  For each mesh (elements x order per blade): the
wall time (best of --repeat; steady state and Floquet apart), the largest relative error of
the frequencies and the largest damping-ratio error |d zeta| / max(|zeta|, 0.01) of the
modes matched by label.

    .venv/bin/python bench/floquet_mesh.py                      # ~1.5 min on 2 cores
    .venv/bin/python bench/floquet_mesh.py --meshes 3x6 4x4 --repeat 3
"""
from __future__ import annotations

import argparse
import dataclasses as dc
import time
import warnings

import numpy as np

from hawt_core.aero.wind import Wind
from hawt_core.analyses.modal import modal_analysis
from hawt_core.analyses.operating_points import operating_points
from hawt_core.io.catalog import load_any, shipped_controller
from hawt_core.io.discon import discon_schedule


def parse_mesh(text):
    n, p = text.lower().split("x")
    return int(n), int(p)


def analysis(turbine, wind, n, p):
    t = dc.replace(turbine, blade=dc.replace(turbine.blade, elements=n, order=p))
    t0 = time.perf_counter()
    r = modal_analysis(t, wind=Wind(wind))
    return r, time.perf_counter() - t0


def by_label(result, max_hz):
    return {m.label: m for m in result.modes if m.frequency_hz <= max_hz}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", type=parse_mesh,
                    default=[(48, 1), (64, 1), (4, 4), (3, 5), (3, 6)],
                    help="ELEMENTSxORDER per blade (default 48x1 64x1 4x4 3x5 3x6)")
    ap.add_argument("--wind", type=float, default=8.0)
    ap.add_argument("--max-hz", type=float, default=3.0)
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    t = load_any("nrel5mw")
    point = operating_points(t, [args.wind], discon_schedule(shipped_controller("nrel5mw"))
                             ).points[0]
    t = dc.replace(t, rotor=dc.replace(t.rotor, speed=point["rotor_speed_rpm"] * np.pi / 30,
                                       pitch=-np.radians(point["pitch_deg"])))
    ref, _ = analysis(t, args.wind, 8, 8)
    ref_modes = by_label(ref, args.max_hz)
    print(f"nrel5mw at {args.wind:g} m/s ({point['rotor_speed_rpm']:.2f} rpm, pitch "
          f"{point['pitch_deg']:.2f} deg): reference order 8 x 8 elements, {len(ref_modes)} "
          f"modes below {args.max_hz:g} Hz")
    print(f"{'mesh (per blade)':<24}{'seconds':>9}{'steady':>8}{'Floquet':>9}"
          f"{'freq err':>10}{'damp err':>10}  worst mode")
    for n, p in args.meshes:
        runs = [analysis(t, args.wind, n, p) for _ in range(args.repeat)]
        r, dt = min(runs, key=lambda x: x[1])
        got = by_label(r, args.max_hz * 1.05)
        ef, ez, worst = 0.0, 0.0, "-"
        for label, m0 in ref_modes.items():
            m = got.get(label)
            if m is None:
                ef, worst = np.inf, f"{label} missing"
                continue
            e = abs(m.frequency_hz / m0.frequency_hz - 1)
            if e > ef:
                ef, worst = e, label
            ez = max(ez, abs(m.damping_ratio - m0.damping_ratio) / max(abs(m0.damping_ratio),
                                                                        1e-2))
        kind = "paper element" if p == 1 else f"order {p}"
        print(f"{f'{n} x {kind}':<24}{dt:>9.2f}"
              f"{r.timings['steady_state']:>8.2f}{r.timings['floquet']:>9.2f}"
              f"{ef:>10.1e}{ez:>10.1e}  {worst}", flush=True)


if __name__ == "__main__":
    main()
