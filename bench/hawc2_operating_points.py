"""The IEA 15-MW's HAWC2 aerodynamics (ae/pc files) against HAWCStab2's operating points
(issue 35, item 3): one table.

Data: DTU's ``h2lib_tests`` wheel (PyPI), ``test_files/IEA-15-240-RWT-Onshore`` (the model,
its ``data/IEA_15MW_RWT_Onshore.opt``: HAWCStab2's wind speed, pitch, rotor speed, aero power
and thrust) and ``test_files/IEA-15-240-RWT`` (ae, pc).  The wheel (11 MB) is downloaded with
``pip download --no-deps`` into a cache folder when ``--data`` is not given; it is data, not a
dependency (its own requirements, h2lib and wetb, are not installed).

Columns, at each .opt point (its wind speed, pitch and rotor speed): HAWCStab2's power and
thrust; hawt's steady BEM of the rigid rotor (aero/bem.py: Prandtl tip and hub loss, drag in
the inductions) with the HAWC2 blade aerodynamics (io/hawc2.py: the ae stations, the pc
polars interpolated in thickness) on the shipped iea15mw (the same design's hub radius,
precone, blade length); and the same with the shipped AeroDyn aerodynamics (OpenFAST deck).

The two hawt columns are the same model with two formats of the same data (a consistency
check of the import); against HAWCStab2 the model differences are the elastic blade
(HAWCStab2's operating points are aeroelastic: flap deflection and blade torsion under load,
which unload the rotor above rated by several degrees of effective pitch) and the tilt.
Then like for like: hawt's aeroelastic steady state at the same points.

    PYTHONPATH=. .venv/bin/python bench/hawc2_operating_points.py [--data DIR]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import warnings
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np

CACHE = Path(tempfile.gettempdir()) / "hawt-h2lib-tests"


def test_files(data) -> Path:
    if data:
        return Path(data)
    target = CACHE / "h2lib_tests" / "test_files"
    if not target.is_dir():
        CACHE.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "-q",
                        "h2lib_tests==13.2.2103", "-d", str(CACHE)], check=True)
        wheel = next(CACHE.glob("h2lib_tests-*.whl"))
        with zipfile.ZipFile(wheel) as z:
            z.extractall(CACHE)
    return target


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=None, help="h2lib_tests/test_files folder")
    args = ap.parse_args()
    from hawt_core.aero.bem import BemRotor
    from hawt_core.io.catalog import load_any
    from hawt_core.io.hawc2 import hawc2_aerodynamics
    root = test_files(args.data)
    htc = root / "IEA-15-240-RWT-Onshore" / "htc" / "IEA_15MW_RWT_Onshore.htc"
    aero, notes = hawc2_aerodynamics(htc)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ship = load_any("iea15mw")
    opt = np.loadtxt(root / "IEA-15-240-RWT-Onshore" / "data" / "IEA_15MW_RWT_Onshore.opt",
                     skiprows=1)
    rotors = {"hawc2": BemRotor.from_turbine(replace(ship, aerodynamics=aero)),
              "aerodyn": BemRotor.from_turbine(ship)}
    print(notes[0])
    print(f"{'U':>5} {'pitch':>6} {'rpm':>5} | {'P HS2':>8} {'P h2 ae':>8} {'diff':>7} "
          f"{'P AD':>8} {'diff':>7} | {'T HS2':>7} {'T h2 ae':>7} {'diff':>7} {'T AD':>7} "
          f"{'diff':>7}   [kW, kN]")
    worst = 0.0
    for U, pitch, rpm, P, T in opt:
        if U < 3.0:
            continue
        row = []
        for rot in rotors.values():
            sol = rot.solve(U, rpm * np.pi / 30.0, np.radians(pitch))
            q = 0.5 * 1.225 * np.pi * rot.tip_radius ** 2
            row.append((float(sol.cp) * q * U ** 3 / 1e3, float(sol.ct) * q * U ** 2 / 1e3))
        (ph, th), (pa, ta) = row
        worst = max(worst, abs(ph / pa - 1), abs(th / ta - 1))
        print(f"{U:5.1f} {pitch:6.2f} {rpm:5.2f} | {P:8.0f} {ph:8.0f} {100 * (ph / P - 1):+6.1f}% "
              f"{pa:8.0f} {100 * (pa / P - 1):+6.1f}% | {T:7.0f} {th:7.0f} "
              f"{100 * (th / T - 1):+6.1f}% {ta:7.0f} {100 * (ta / T - 1):+6.1f}%")
    print(f"HAWC2 ae/pc against AeroDyn, same BEM: largest difference {100 * worst:.2f} %")
    # like for like: hawt's aeroelastic steady state (assembly/aero_blade.py: the blade on
    # the spinning hub, BEM at its Gauss points) at the same points, with the HAWC2
    # aerodynamics on the shipped structure (ElastoDyn + BeamDyn blade) and on the HAWC2
    # model's own blade (io/hawc2.py hawc2_body)
    from hawt_core.assembly.aero_blade import AeroelasticBlade
    from hawt_core.io.hawc2 import hawc2_body
    blade, _ = hawc2_body(htc, "blade1")
    cases = {"shipped blade": replace(ship, aerodynamics=aero),
             "HAWC2 blade": replace(ship, aerodynamics=aero, blade=blade)}
    print(f"\naeroelastic steady state, HAWC2 aerodynamics: {'U':>5} | P HS2, hawt (diff) "
          "and T HS2, hawt (diff) per structure; tip flap deflection [m]")
    for name, t0 in cases.items():
        print(f"  {name}")
        y = None
        for U, pitch, rpm, P, T in opt:
            if U < 3.0:
                continue
            om = rpm * np.pi / 30.0
            t = replace(t0, rotor=replace(t0.rotor, speed=om, pitch=-np.radians(pitch)))
            m = AeroelasticBlade(t, U)
            y = m.steady_state(y0=y if y is not None and y.size == m.n else None)
            torque, thrust = m.root_loads(y)
            pe, te = 3 * torque * om / 1e3, 3 * thrust / 1e3
            print(f"    {U:5.1f} | P {P:8.0f} {pe:8.0f} {100 * (pe / P - 1):+6.1f}% | T {T:6.0f} "
                  f"{te:6.0f} {100 * (te / T - 1):+6.1f}% | tip flap {m.tip_deflection(y)[0]:6.2f}")


if __name__ == "__main__":
    main()
