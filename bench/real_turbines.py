"""Wall time and size of the analyses of the shipped real turbines (NREL 5-MW, IEA 15-MW).

Each case runs in its own process (``hawt ...``, one BLAS thread, the default): the command
line a user types, timed end to end, plus the model's unknowns.  Cases:

- ``hawt blade-modes nrel5mw`` / ``iea15mw`` (one blade, the shipped mesh: 64 elements);
- ``hawt modes nrel5mw --rotor-speed 0`` (at rest: one eigenproblem about the static
  equilibrium, gravity included);
- ``hawt modes nrel5mw`` with the deck's gravity (the default: a periodic steady state by
  harmonic balance, then Hill's method in multi-blade coordinates, a few harmonics of
  3 per-rev), at 32 and 64 (the shipped) elements per blade; and with gravity off
  (multi-blade coordinates: one eigenproblem);
- ``hawt campbell nrel5mw --speeds 0.2:1.4:15`` without gravity, and (full run) with it.

Goals of issue 11: ``hawt modes nrel5mw`` < 10 s, ``hawt campbell nrel5mw`` < 60 s.

    PYTHONPATH=. .venv/bin/python bench/real_turbines.py [--quick]
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HAWT = [sys.executable, "-c", "import sys; from hawt_core.cli import main; sys.exit(main())"]


def unknowns(name: str, gravity: bool = True) -> int:
    import warnings
    from hawt_core.assembly import TurbineModel
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_any(name)
    return TurbineModel(t).layout.n


def no_gravity_file(name: str, folder: str) -> str:
    import warnings
    from hawt_core.io import dump_turbine
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_any(name)
    t = replace(t, gravity=replace(t.gravity, enabled=False))
    path = os.path.join(folder, f"{name}_no_gravity.yaml")
    Path(path).write_text(dump_turbine(t))
    return path


def run(label: str, args: list, timeout: float = 600.0):
    t0 = time.perf_counter()
    try:
        p = subprocess.run(HAWT + args, cwd=ROOT, capture_output=True, text=True,
                           timeout=timeout, env=dict(os.environ, PYTHONPATH=str(ROOT)))
        status = "ok" if p.returncode == 0 else f"exit {p.returncode}: {p.stderr[-200:]}"
    except subprocess.TimeoutExpired:
        status = f"timed out after {timeout:.0f} s"
    print(f"{label:58s} {time.perf_counter() - t0:8.1f} s  {status}", flush=True)


def main():
    quick = "--quick" in sys.argv
    with tempfile.TemporaryDirectory() as d:
        ng = no_gravity_file("nrel5mw", d)
        print(f"nrel5mw: {unknowns('nrel5mw')} unknowns (3 blades x 64 elements, tower 16, "
              "drivetrain)")
        run("hawt blade-modes nrel5mw", ["blade-modes", "nrel5mw"])
        run("hawt blade-modes iea15mw", ["blade-modes", "iea15mw"])
        run("hawt modes nrel5mw --rotor-speed 0 --max-per-rev 3 (at rest, Hz)",
            ["modes", "nrel5mw", "--rotor-speed", "0", "--max-per-rev", "3"])
        run("hawt modes nrel5mw (no gravity: multi-blade, one eigenproblem)", ["modes", ng])
        run("hawt modes nrel5mw --max-per-rev 8 --elements 32 (gravity)",
            ["modes", "nrel5mw", "--max-per-rev", "8", "--elements", "32"])
        run("hawt modes nrel5mw --max-per-rev 8 (gravity, 64 elements)",
            ["modes", "nrel5mw", "--max-per-rev", "8"])
        run("hawt campbell nrel5mw --speeds 0.2:1.4:15 (no gravity)",
            ["campbell", ng, "--speeds", "0.2:1.4:15"])
        if not quick:
            run("hawt modes nrel5mw (gravity, 64 elements, default band 50 per-rev)",
                ["modes", "nrel5mw"], timeout=1200)
            # the default band (50 per-rev at the top speed, 11 Hz) is 350 per-rev at
            # 0.2 rad/s: ~60 Hill windows per low speed; 2 Hz is the band people plot
            run("hawt campbell nrel5mw --speeds 0.2:1.4:15 --elements 32 --max-hz 2 (gravity)",
                ["campbell", "nrel5mw", "--speeds", "0.2:1.4:15", "--elements", "32",
                 "--max-hz", "2"], timeout=1800)


if __name__ == "__main__":
    main()
