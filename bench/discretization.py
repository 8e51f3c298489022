"""Error against unknowns of the blade discretizations: the paper's mixed element (order 1,
fem/beam.py) and its p-version (fem/spectral.py), on the shipped NREL 5-MW and IEA 15-MW
blades, the six lowest modes at standstill and at rated rotor speed (`hawt blade-modes`'s
analysis: one blade clamped on the spinning hub, precone 0).

Reference: the p-version at order 8 with 8 elements (it agrees with order 6 at 6 elements to
< 2e-5 and with an independent Euler-Bernoulli solution of the same tables to < 1e-5,
tests/test_spectral.py).  Prints one table per blade and speed (largest relative error of
the six modes, unknowns per blade, seconds per analysis) and writes a log-log picture.

    .venv/bin/python bench/discretization.py                 # ~1 min on 2 cores
    .venv/bin/python bench/discretization.py --plot /tmp/convergence.png
"""
from __future__ import annotations

import argparse
import dataclasses as dc
import time
import warnings

import numpy as np

from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.io.catalog import load_any

LEGACY = (4, 8, 16, 32, 64, 128)
SPECTRAL = {2: (2, 4, 8, 16), 4: (1, 2, 3, 4, 6, 8), 6: (1, 2, 3, 4, 6)}


def frequencies(turbine, elements, order, speed, count=6):
    t = dc.replace(turbine, blade=dc.replace(turbine.blade, order=order))
    t0 = time.perf_counter()
    r = blade_modes(t, elements=elements, rotor_speed=speed, count=count + 4)
    dt = time.perf_counter() - t0
    f = np.sort([m.frequency_hz for m in r.modes])[:count]
    return f, r.settings["unknowns"], dt


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--plot", default="docs/convergence.png")
    args = p.parse_args(argv)
    warnings.simplefilter("ignore")
    rows = {}
    for name in ("nrel5mw", "iea15mw"):
        t = load_any(name)
        t = dc.replace(t, rotor=dc.replace(t.rotor, precone=0.0))
        for label, speed in (("0 rpm", 0.0), ("rated", float(t.rotor.speed))):
            ref, _, _ = frequencies(t, 8, 8, speed)
            print(f"\n{name}, {label} ({speed * 30 / np.pi:.2f} rpm): reference (order 8, 8 "
                  f"elements) {np.round(ref, 5).tolist()} Hz")
            print(f"{'discretization':<22}{'elements':>9}{'unknowns':>10}{'max error':>12}"
                  f"{'seconds':>9}   errors of the 6 modes [%]")
            out = []
            cases = [(1, n) for n in LEGACY] + [(o, n) for o, ns in SPECTRAL.items() for n in ns]
            for order, n in cases:
                f, unknowns, dt = frequencies(t, n, order, speed)
                err = f / ref - 1
                worst = float(np.nanmax(np.abs(err))) if len(f) == 6 else np.nan
                out.append((order, n, unknowns, worst))
                kind = "paper (order 1)" if order == 1 else f"p-version, order {order}"
                print(f"{kind:<22}{n:>9}{unknowns:>10}{worst:>12.2e}{dt:>9.2f}   "
                      + " ".join(f"{100 * e:+.4f}" for e in err))
            rows[(name, label)] = out
    _plot(rows, args.plot)
    print(f"\nwrote {args.plot}")


def _plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(rows), figsize=(4.2 * len(rows), 4.0), sharey=True)
    for ax, ((name, label), out) in zip(axes, rows.items()):
        for order in sorted({o for o, *_ in out}):
            pts = [(u, e) for o, _, u, e in out if o == order and np.isfinite(e) and e > 0]
            if pts:
                u, e = zip(*pts)
                ax.loglog(u, e, "o-", ms=4, label="paper element" if order == 1
                          else f"order {order}")
        ax.axhline(1e-3, color="0.6", lw=0.8, ls="--")
        ax.set_title(f"{name}, {label}", fontsize=9)
        ax.set_xlabel("unknowns per blade")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("largest relative error, 6 lowest modes")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
