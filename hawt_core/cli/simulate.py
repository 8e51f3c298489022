"""``hawt simulate``: the nonlinear time simulation from the command line (hawt_core.solvers.march;
imported when the command runs, so that ``import hawt_core.cli`` stays cheap).
"""

from __future__ import annotations

from .parser import (command, elements_arg, finite_float, load, rotor_speed_type,
                     step_deg_type, turbine_arg)
from .status import ProgressLine


@command("simulate", help="nonlinear time simulation",
         description="Nonlinear time simulation (implicit midpoint, finite elements in time) "
                     "from the steady state plus perturbations; prints a summary (JSON with "
                     "--json), writes time histories with --output.")
def cmd_simulate(args) -> int:
    import json
    from ..assembly import TurbineModel
    from ..numerics.checks import check_number
    from ..solvers.march import NAMED, Simulator, parse_perturb
    duration = check_number("duration", args.duration, minimum=0.0)
    step_deg = args.step_deg
    perturb = parse_perturb(args.perturb)
    if args.output and not args.output.lower().endswith((".csv", ".npz")):
        raise ValueError(f"output: {args.output!r} is not allowed; need a .csv or .npz file")
    series = None
    if args.wind_series is not None:
        from ..aero.wind import parse_wind_series
        if args.wind is not None:
            raise ValueError("--wind-series: give it instead of --wind (its speed at t = 0 "
                             "sets the operating point)")
        series = parse_wind_series(args.wind_series, "--wind-series")
        args.wind = series.initial_speed
    from .aero import check_wind_args, schedule_given, turbine_in_wind
    check_wind_args(args)
    if args.wind is None and schedule_given(args):
        raise ValueError("--rated-power/--rated-rpm/--min-rpm/--tsr-opt/--efficiency/"
                         "--fine-pitch: only used with --wind U")
    turbine = load(args.turbine, args.order)
    if args.lock_yaw:
        from dataclasses import replace
        turbine = replace(turbine, nacelle=replace(turbine.nacelle, yaw_free=False))
    wind = None
    if args.wind is not None:
        turbine, wind, _ = turbine_in_wind(args, turbine)
        if series is not None:
            from dataclasses import replace
            w = series.for_turbine(turbine)
            wind = replace(wind, history=w.history, gust=w.gust)
    loop = args.controller is not None and args.controller != "none"
    if args.plot and (not loop or not args.plot.lower().endswith(".png")):
        raise ValueError(f"--plot: {args.plot!r} is not allowed; need a .png file, with "
                         "--controller")
    if loop:
        if wind is None:
            raise ValueError(f"--controller {args.controller}: a controller in the loop needs "
                             "--wind U")
        return _closed_loop(args, turbine, wind, duration)
    model = TurbineModel(turbine, elements=args.elements, wind=wind,
                         rotor_speed=None if wind is not None else args.rotor_speed,
                         inflow=args.inflow, airfoil=args.airfoil)
    sim = Simulator(model, step_deg=step_deg, perturb=perturb, record=bool(args.output),
                    method=args.method)
    status = ProgressLine(not args.quiet or args.progress, force=args.progress)
    try:
        summary = sim.run(duration, progress=status if status.enabled else None)
    finally:
        status.close()
    if args.output:
        sim.save(args.output)
        summary["output"] = args.output
    summary["final"] = sim.named()
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"simulated {summary['simulated_seconds']:.4g} s in {summary['wall_seconds']:.3g} s "
              f"(real-time factor {summary['real_time_factor']:.3g}), {summary['steps']} steps, "
              f"{summary['method']} solver, {summary['factorizations']} factorizations")
        fin = summary["final"]
        print("final: " + ", ".join(f"{k} {fin[k]:.6g}" for k in NAMED))
        if args.output:
            print(f"time histories written to {args.output}")
    return 0


def _closed_loop(args, turbine, wind, duration) -> int:
    """``simulate --wind U --controller rosco|builtin|FILE``: a controller in the loop
    (analyses/closed_loop.py)."""
    import json
    from ..analyses.closed_loop import closed_loop
    from .aero import controller_file, schedule_from_args
    if args.perturb:
        raise ValueError("--perturb: not used with a controller in the loop (the run starts "
                         "from the operating point)")
    path = controller_file(args)           # (it refuses "rosco" without a DISCON.IN)
    kind = "builtin" if args.controller == "builtin" else "rosco"
    schedule = schedule_from_args(args) if kind == "builtin" else None
    status = ProgressLine(not args.quiet or args.progress, force=args.progress)
    loop = None
    try:
        # the turbine is already at the schedule's operating point (turbine_in_wind)
        loop = closed_loop(turbine, wind, kind, discon=path, schedule=schedule,
                           dt=args.controller_step, elements=args.elements,
                           inflow=args.inflow if args.inflow_given else "oye",
                           airfoil=args.airfoil, step_deg=args.step_deg, method=args.method,
                           operating_point=False)
        summary = loop.run(duration, progress=status if status.enabled else None)
    finally:
        status.close()
        if loop is not None:
            loop.close()
        if loop is not None and args.output and loop.rows:
            loop.save(args.output)           # what was simulated is kept, also on errors
        if loop is not None and args.plot and len(loop.rows) > 1:
            from ..results.plotting import plot_time_history
            plot_time_history(loop.history(), args.plot,
                              title=f"{turbine.name} under {args.controller}")
    if args.plot:
        summary["plot"] = args.plot
    summary["controller"] = "builtin" if kind == "builtin" else str(path)
    if args.output:
        summary["output"] = args.output
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        fin = summary["final"]
        print(f"simulated {summary['simulated_seconds']:.4g} s in {summary['wall_seconds']:.3g} s "
              f"(real-time factor {summary['real_time_factor']:.3g}) under {summary['controller']}, "
              f"{summary['controller_calls']} controller calls of {summary['controller_step']:.4g} s")
        print(f"final: wind {fin['wind_speed']:.3g} m/s, rotor {fin['rotor_speed_rpm']:.4g} rpm, "
              f"power {fin['generator_power_kw']:.5g} kW, pitch {fin['pitch1_deg']:.3g} deg, "
              f"tip flap {fin['tip1_flap_m']:.3g} m")
        if any(summary["clipped"].values()):
            print("clipped demands: " + ", ".join(f"{k} {v}" for k, v in
                                                   summary["clipped"].items()))
        if args.output:
            print(f"time histories written to {args.output}")
        if args.plot:
            print(f"summary plot written to {args.plot}")
    return 0


@cmd_simulate.arguments
def _simulate_args(p):
    from .aero import schedule_args, wind_args
    turbine_arg(p)
    wind_args(p)
    p.add_argument("--wind-series", default=None, metavar="T0:U0,T1:U1,...",
                   help="instead of --wind: the hub-height wind speed [m/s] against time "
                        "[s], linear between the points, constant beyond (e.g. "
                        "0:15,10:15,10.5:17, a step at 10 s; eog@T adds the IEC extreme "
                        "operating gust from T); the operating point is that of its speed "
                        "at t = 0")
    p.add_argument("--rotor-speed", type=rotor_speed_type, default=None, metavar="RAD_PER_S",
                   help="rotor speed [rad/s] (default: the file's; with --wind the "
                        "schedule's)")
    p.add_argument("--duration", type=finite_float(), required=True, metavar="S",
                   help="simulated time [s]")
    p.add_argument("--step-deg", type=step_deg_type, default=1.0, metavar="DEG",
                   help="time step in rotor azimuth [deg] (default 1, at most 10)")
    elements_arg(p)
    p.add_argument("--perturb", default=None, metavar="NAME=VALUE,...",
                   help="initial perturbations of yaw, yaw_rate, teeter, teeter_rate "
                        "[rad, rad/s], e.g. teeter=0.02,yaw_rate=0.01")
    p.add_argument("--lock-yaw", action="store_true", help="lock the yaw bearing")
    p.add_argument("--method", choices=("auto", "window", "step"), default="auto",
                   help="Newton organization: 24 steps solved together (window, the default "
                        "for small and medium meshes) or one step at a time (step); the "
                        "results agree to the Newton tolerance")
    schedule_args(p)
    p.add_argument("--controller-step", type=finite_float("--controller-step", unit="s"),
                   default=0.05, metavar="S",
                   help="with --controller: the controller's time step [s] (rounded to whole "
                        "simulation steps; default 0.05)")
    p.add_argument("--output", "-o", default=None, metavar="FILE.csv|FILE.npz",
                   help="write the time histories (CSV with a header row, or NPZ)")
    p.add_argument("--plot", default=None, metavar="FILE.png",
                   help="with --controller: a summary plot (wind, rotor speed, power, pitch, "
                        "torque, tip deflections against time)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--progress", action="store_true",
                   help="show the status line even when stderr is not a terminal")
    p.add_argument("--quiet", "-q", action="store_true", help="no status line")
