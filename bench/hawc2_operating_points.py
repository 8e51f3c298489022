"""The IEA 15-MW's HAWC2 model against HAWCStab2's operating points (issue 35, item 3): one
table.

Data: DTU's ``h2lib_tests`` wheel 13.2.2103 (PyPI), its ``test_files/IEA-15-240-RWT-Onshore``
model with ``data/IEA_15MW_RWT_Onshore.opt`` (HAWCStab2's wind speed, pitch, rotor speed, aero
power and thrust) and ``test_files/IEA-15-240-RWT`` (bodies, ae, pc), committed unchanged in
tests/data/hawc2 (``--data`` names another copy of the wheel's test_files).

First, at each .opt point (its wind speed, pitch and rotor speed), HAWCStab2's power and
thrust against hawt's steady BEM of the rigid rotor (aero/bem.py: Prandtl tip and hub loss,
drag in the inductions) with the HAWC2 blade aerodynamics (io/hawc2.py: the ae stations, the
pc polars interpolated in thickness) on the shipped iea15mw (the same design's hub radius,
precone, blade length), and with the shipped AeroDyn aerodynamics (OpenFAST deck): two
formats of the same data in one model (a consistency check of the import); against
HAWCStab2 the difference is the elastic blade (HAWCStab2's points are aeroelastic).

Then like for like: hawt's aeroelastic steady state (assembly/aero_blade.py: the blade on the
spinning hub, BEM at its Gauss points; no tilt, gravity or tower, as HAWCStab2's steady
states) at the same points, of the turbine ``hawt import hawc2`` makes of the model (its
blade: the c2_def line and Timoshenko sections; its loads at the quarter chord), and of the
shipped structure (ElastoDyn + BeamDyn blade, reference line at the pitch axis) with the
HAWC2 aerodynamics acting at that line.  Last, ``hawt operating-points`` on the imported
turbine with HAWCStab2's schedule settings: hawt's rotor speed and pitch against HAWCStab2's;
and the DTU 10-MW model at its operation.dat's points (no power given: hawt's is shown).

    PYTHONPATH=. .venv/bin/python bench/hawc2_operating_points.py [--data DIR]
"""
from __future__ import annotations

import argparse
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "hawc2"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DATA), help="h2lib_tests/test_files folder "
                    "(default: the files committed in tests/data/hawc2)")
    args = ap.parse_args()
    from hawt_core.aero.bem import BemRotor
    from hawt_core.io.catalog import load_any
    from hawt_core.io.hawc2 import hawc2_aerodynamics
    root = Path(args.data)
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
    # like for like: hawt's aeroelastic steady state at the same points
    from hawt_core.assembly.aero_blade import AeroelasticBlade
    from hawt_core.io.hawc2_turbine import read_hawc2
    cases = {"hawt import hawc2 (the HAWC2 model's blade, loads at the quarter chord)":
             read_hawc2(htc).turbine,
             "shipped structure, HAWC2 aerodynamics at its reference line (pitch axis)":
             replace(ship, aerodynamics=replace(aero, ac_chordwise=None))}
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
    schedule_table(htc, opt)
    dtu_table(root / "DTU_10_MW" / "htc" / "DTU_10MW_RWT.htc")


def schedule_table(htc: Path, opt: np.ndarray) -> None:
    """``hawt operating-points`` on the imported turbine: hawt picks the rotor speed and
    pitch from a schedule with HAWCStab2's settings (the .opt's largest aerodynamic power as
    the rated power at 100 % efficiency, its minimum and rated rotor speed, its region-2
    tip-speed ratio at 8 m/s, fine pitch 0): the pitch that holds rated power against
    HAWCStab2's."""
    from hawt_core.analyses.operating_points import operating_points
    from hawt_core.io.hawc2_turbine import read_hawc2
    t = read_hawc2(htc).turbine
    U, pitch, rpm, P, T = opt.T
    R = t.hub.radius + t.blade.length
    k8 = int(np.argmin(abs(U - 8.0)))
    sched = {"rated_power": float(P.max()) * 1e3, "efficiency": 1.0,
             "rated_speed": float(rpm.max()) * np.pi / 30, "min_speed": float(rpm.min()) * np.pi / 30,
             "tsr": float(rpm[k8] * np.pi / 30 * R / U[k8]), "fine_pitch": 0.0,
             "max_pitch": np.radians(90.0)}
    keep = U >= 3.0
    res = operating_points(t, U[keep], sched)
    print(f"\nhawt operating-points on the imported turbine (rated {sched['rated_power'] / 1e3:.0f} "
          f"kW aero, {rpm.min():.3f}-{rpm.max():.3f} rpm, TSR {sched['tsr']:.3f}, fine pitch 0)")
    print(f"{'U':>5} | {'rpm HS2':>7} {'hawt':>6} | {'pitch HS2':>9} {'hawt':>6} {'diff':>6} | "
          f"{'P HS2':>7} {'hawt':>7} {'diff':>7} | {'T HS2':>6} {'hawt':>6} {'diff':>7}")
    for p, u, pi, r, pw, th in zip(res.points, U[keep], pitch[keep], rpm[keep], P[keep],
                                   T[keep]):
        print(f"{u:5.1f} | {r:7.3f} {p['rotor_speed_rpm']:6.3f} | {pi:9.2f} {p['pitch_deg']:6.2f} "
              f"{p['pitch_deg'] - pi:+6.2f} | {pw:7.0f} {p['aero_power_kw']:7.0f} "
              f"{100 * (p['aero_power_kw'] / pw - 1):+6.1f}% | {th:6.0f} {p['thrust_kn']:6.0f} "
              f"{100 * (p['thrust_kn'] / th - 1):+6.1f}%")


def dtu_table(htc: Path) -> None:
    """The DTU 10-MW model's operation.dat (HAWCStab2's wind speed, pitch and rotor speed, no
    power or thrust): hawt's aeroelastic power and thrust of the imported turbine at each
    point.  HAWCStab2 computed the pitch above rated to hold its rated aerodynamic power, so
    hawt's power there should be flat: its spread says how differently the two codes' blades
    unload with pitch."""
    from hawt_core.assembly.aero_blade import AeroelasticBlade
    from hawt_core.io.hawc2_files import read_opt
    from hawt_core.io.hawc2_turbine import read_hawc2
    if not htc.is_file():
        return
    t0 = read_hawc2(htc).turbine
    op = read_opt(htc.parent.parent / "data" / "operation.dat")
    print("\nDTU 10-MW, hawt import hawc2, at operation.dat's points (HAWCStab2 gives no power)")
    print(f"{'U':>5} {'pitch':>6} {'rpm':>5} | {'P hawt kW':>9} {'T hawt kN':>9} {'tip flap m':>10}")
    y, above = None, []
    for U, pitch, rpm in zip(op["wind_speed"], op["pitch"], op["rpm"]):
        om = rpm * np.pi / 30.0
        t = replace(t0, rotor=replace(t0.rotor, speed=om, pitch=-np.radians(pitch)))
        m = AeroelasticBlade(t, U)
        y = m.steady_state(y0=y if y is not None and y.size == m.n else None)
        torque, thrust = m.root_loads(y)
        p = 3 * torque * om / 1e3
        if rpm >= op["rpm"].max() * (1 - 1e-6) and pitch > 0:
            above.append(p)
        print(f"{U:5.1f} {pitch:6.2f} {rpm:5.2f} | {p:9.0f} {3 * thrust / 1e3:9.0f} "
              f"{m.tip_deflection(y)[0]:10.2f}")
    if above:
        a = np.array(above)
        print(f"above rated (pitched, rated speed): hawt's power {a.min():.0f} .. {a.max():.0f} kW "
              f"(spread {100 * (a.max() - a.min()) / a.mean():.1f} % of its mean)")


if __name__ == "__main__":
    main()
