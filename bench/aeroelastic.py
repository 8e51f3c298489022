"""Aerodynamics figures: the rigid-rotor coefficient table (hawt aero-table) of the shipped
NREL 5-MW and IEA 15-MW, and the cost per BEM operating point.

Usage: PYTHONPATH=. .venv/bin/python bench/aeroelastic.py [--repeat K]

Prints for each turbine: stations, the default 25 x 31 table's wall time (best of K), the
time per operating point (all stations solved together by vectorized bisection), and the
optimum found. One core (OPENBLAS_NUM_THREADS=1 does not matter here: no linear algebra).
The aeroelastic figures of the issue (operating points, aeroelastic Floquet, simulation with
aerodynamics) are added here as those analyses land.
"""
import argparse
import time
import warnings

import numpy as np

from hawt_core.analyses.aero_table import aero_table
from hawt_core.io.catalog import load_any


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    tsr, pitch = np.linspace(2, 14, 25), np.linspace(-5, 25, 31)
    print(f"{'turbine':10s} {'stations':>8s} {'table s':>8s} {'us/point':>9s}  optimum")
    for name in ("nrel5mw", "iea15mw"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            turbine = load_any(name)
        best = np.inf
        for _ in range(max(1, args.repeat)):
            t0 = time.perf_counter()
            table = aero_table(turbine, tsr, pitch)
            best = min(best, time.perf_counter() - t0)
        opt = table.optimum()
        print(f"{name:10s} {table.settings['stations']:8d} {best:8.3f} "
              f"{1e6 * best / table.cp.size:9.1f}  Cp {opt['cp']:.4f} at TSR {opt['tsr']:.3g}, "
              f"pitch {opt['pitch_deg']:.3g} deg")


if __name__ == "__main__":
    main()
