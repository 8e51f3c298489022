"""Aeroelastic stability in wind, HAWCStab2-like aerodynamics (Oye's dynamic inflow and
Jones's unsteady airfoils) against the frozen wake: wall time of one operating point and of
the Campbell sweep of issue 34 (targets: one IEA 15-MW point < 20 s; `hawt campbell ...
--wind 3:25:23` < 3 min on 2 cores, for both shipped turbines).

Usage: PYTHONPATH=. .venv/bin/python bench/stability_in_wind.py [--wind U] [--campbell]

Prints per shipped turbine (its own mesh: 3 blade elements of order 6) the wall time of
`hawt modes T --wind U` with `--inflow frozen --airfoil quasi-steady` (OpenFAST's
linearization's model) and with Oye + Jones (the default of the stability analyses), the
ratio, and with ``--campbell`` the wall time of `hawt campbell T --wind 3:25:23`
both ways (worker processes: one per CPU).  The analyses print nothing here; their warnings
are counted.
"""
import argparse
import contextlib
import io
import time
import warnings

from hawt_core.cli import main as hawt

HAWCSTAB2_LIKE = ["--inflow", "oye", "--airfoil", "jones"]
FROZEN = ["--inflow", "frozen", "--airfoil", "quasi-steady"]


def timed(argv):
    """(wall time [s], warnings raised) of ``hawt argv`` with its output swallowed."""
    out = io.StringIO()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(out):
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        code = hawt(argv)
        elapsed = time.perf_counter() - t0
    if code:
        raise SystemExit(f"hawt {' '.join(argv)} exited with {code}:\n{out.getvalue()}")
    return elapsed, len(caught)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--wind", default="11", help="wind speed of the single point [m/s]")
    ap.add_argument("--campbell", action="store_true",
                    help="also the 23-point Campbell sweeps (about 10 min)")
    args = ap.parse_args()
    print(f"{'turbine':10s} {'analysis':34s} {'frozen s':>9s} {'oye+jones s':>12s} {'ratio':>6s}"
          f"  warnings")
    for name in ("nrel5mw", "iea15mw"):
        runs = [(f"modes --wind {args.wind}", ["modes", name, "--wind", args.wind])]
        if args.campbell:
            runs.append(("campbell --wind 3:25:23", ["campbell", name, "--wind", "3:25:23"]))
        for what, argv in runs:
            frozen, wf = timed(argv + FROZEN)
            unsteady, wu = timed(argv + HAWCSTAB2_LIKE)
            print(f"{name:10s} {what:34s} {frozen:9.1f} {unsteady:12.1f} "
                  f"{unsteady / frozen:6.2f}  {wf} / {wu}", flush=True)


if __name__ == "__main__":
    main()
