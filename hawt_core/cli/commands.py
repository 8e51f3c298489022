"""The analysis subcommands of ``hawt``: ``blade-modes``, ``modes`` and ``campbell``."""

from __future__ import annotations

from .parser import (command, elements_arg, finite_float, load, marching_args, model_args,
                     with_accuracy,
                     per_rev, positive_int, speeds_type, turbine_arg)
from .status import ProgressLine


# ---------------------------------------------------------------------------- blade-modes
@command("blade-modes", help="modes of one blade clamped on the spinning hub",
         description="Steady state, exact linearization and eigen-analysis of one blade "
                     "clamped on the hub spinning at the rotor speed (the symmetric blade "
                     "modes of the paper's Table 2). Prints a table, or JSON with --json.")
def cmd_blade_modes(args) -> int:
    from ..analyses.blade_modes import blade_modes
    turbine = load(args.turbine, args.order)
    count = args.count
    if args.accuracy is not None and count is None and args.max_hz is None:
        count = ACCURACY_COUNT
    scope = " and ".join(([f"the {count} lowest modes"] if count else [])
                         + ([f"the modes below {args.max_hz:g} Hz"] if args.max_hz else [])) \
        or "every mode"
    result = with_accuracy(args, turbine, lambda t, n: blade_modes(
        t, elements=n, rotor_speed=args.rotor_speed, count=count, method=args.method,
        max_hz=args.max_hz), scope=scope)
    result.settings["turbine_file"] = args.turbine
    if args.plot:
        result.plot(args.plot)
    if args.json:
        print(result.to_json(indent=1))
    else:
        print(result.table())
        if args.plot:
            print(f"mode shapes written to {args.plot}")
    return 0


#: Modes blade-modes reports (and converges) with --accuracy and neither --count nor --max-hz.
ACCURACY_COUNT = 10


@cmd_blade_modes.arguments
def _blade_modes_args(p):
    model_args(p)
    p.add_argument("--count", type=positive_int, default=None,
                   help="number of lowest modes (default: all, or 30 for large models; "
                        f"{ACCURACY_COUNT} with --accuracy)")
    p.add_argument("--max-hz", type=finite_float("--max-hz", minimum=1e-9, unit="Hz"),
                   default=None, metavar="F",
                   help="only the modes at or below F Hz (with --accuracy: the modes it "
                        "applies to)")
    p.add_argument("--method", choices=("auto", "dense", "sparse"), default="auto",
                   help="eigen-solver: dense QZ with deflation, sparse shift-invert, or auto")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write the mode shapes to this PNG file")


@command("modes", help="Floquet modal analysis of the whole turbine (the paper's Table 2)",
         description="Periodic steady state, exact periodic linearization, Floquet exponents "
                     "(multi-blade coordinates for isotropic rotors with 3+ blades, monodromy "
                     "by time marching with Fast Floquet, or Hill's method), dominant "
                     "frequencies and automatic labels; with 3+ blades also fixed-frame "
                     "frequencies and whirl. Prints a table like the paper's Table 2, or "
                     "JSON with --json.")
def cmd_modes(args) -> int:
    from ..analyses.modal import modal_analysis
    from .aero import check_wind_args, turbine_in_wind
    check_wind_args(args)
    turbine = load(args.turbine, args.order)
    wind, point = None, None
    if args.wind is not None:
        turbine, wind, point = turbine_in_wind(args, turbine)
    status = ProgressLine(not args.json)
    try:
        result = with_accuracy(args, turbine, lambda t, n: modal_analysis(
            t, elements=n, rotor_speed=None if wind is not None else args.rotor_speed,
            steps=args.steps, method=args.method, max_per_rev=args.max_per_rev,
            progress=status, wind=wind, inflow=args.inflow, airfoil=args.airfoil),
            progress=lambda msg: status(0.0, msg))
    finally:
        status.close()
    result.settings["turbine_file"] = args.turbine
    if point is not None:
        result.settings["operating_point"] = point
    written = []
    if args.plots:
        import os
        os.makedirs(args.plots, exist_ok=True)
        written = result.plot(args.plots)
    if args.json:
        print(result.to_json(indent=1))
    else:
        print(result.table())
        for w in written or []:
            print(f"wrote {w}")
    return 0


@cmd_modes.arguments
def _modes_args(p):
    from .aero import wind_args
    model_args(p)
    marching_args(p)
    wind_args(p, stability=True)
    p.add_argument("--max-per-rev", type=per_rev, default=None, metavar="F",
                   help="band of Hill's method and multi-blade coordinates: modes below F "
                        "per-rev (default 50); with --rotor-speed 0 (a standing rotor) F is "
                        "in Hz (default 10)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--plots", metavar="DIR", default=None,
                   help="write mode-shape pictures (PNG) into this folder")


@command("campbell", help="Campbell diagram: Floquet modes over rotor speeds or wind speeds",
         description="Floquet modal analysis (as `hawt modes`) at COUNT rotor speeds from START "
                     "to STOP rad/s, run in parallel worker processes, modes tracked from speed "
                     "to speed by MAC (Hungarian assignment). Prints the frequency table; "
                     "--plot writes the diagram (Hz vs rpm with 1P..nP rays, damping), --csv "
                     "the data. With --wind instead of --speeds: the aeroelastic diagram "
                     "against wind speed at the controller schedule's operating points.")
def cmd_campbell(args) -> int:
    import math
    from ..analyses.campbell import campbell, campbell_in_wind
    from .aero import controller_schedule
    from .executors import sweep_executor
    if (args.speeds is None) == (args.wind is None):
        raise ValueError("campbell: give either --speeds START:STOP:COUNT (rotor speeds, in a "
                         "vacuum) or --wind START:STOP:COUNT (wind speeds, at the operating "
                         "points)")
    if args.wind is None and (args.controller is not None or args.wind_direction):
        raise ValueError("--controller, --wind-direction: only used with --wind")
    from .aero import check_aero_model_args
    check_aero_model_args(args)
    if not abs(args.wind_direction) < 90.0:
        raise ValueError(f"--wind-direction: {args.wind_direction!r} is not allowed; need "
                         "-90 < DEG < 90 (the rotor faces the wind)")
    turbine = load(args.turbine, args.order)
    schedule = None
    if args.wind is not None:
        path, schedule = controller_schedule(args)
        if schedule is None:
            raise ValueError("--wind: no controller file for this turbine; give --controller "
                             "DISCON.IN (its schedule sets the rotor speed and pitch)")
    status = ProgressLine(True)
    common = dict(elements=args.elements, steps=args.steps, method=args.method,
                  progress=status, frame=args.frame, max_hz=args.max_hz)
    with sweep_executor(args.scheduler, args.workers) as (pool, where):
        status(0.0, f"running on {where}")
        try:
            if schedule is not None:
                result = campbell_in_wind(turbine, args.wind, schedule, executor=pool,
                                          direction=math.radians(args.wind_direction),
                                          inflow=args.inflow, airfoil=args.airfoil,
                                          **common)
            else:
                result = campbell(turbine, args.speeds, executor=pool, **common)
        finally:
            status.close()
    result.settings["executor"] = where
    print(result.table())
    if args.csv:
        result.to_csv(args.csv)
        print(f"wrote {args.csv}")
    if args.plot:
        result.plot(args.plot, tracks="all" if args.all_modes else "table2")
        print(f"wrote {args.plot}")
    return 0


@cmd_campbell.arguments
def _campbell_args(p):
    # let "--speeds -1:9:3" reach _speeds (and its one-line error naming START) instead of
    # argparse taking "-1:9:3" for an option
    import re
    p._negative_number_matcher = re.compile(r"^-\d+$|^-\d*\.\d+$|^-[\d.eE+-]*:")
    turbine_arg(p)
    from .aero import grid_type
    p.add_argument("--speeds", type=speeds_type, default=None, metavar="START:STOP:COUNT",
                   help="rotor speeds [rad/s]: COUNT (>= 2) evenly spaced from START (> 0) to "
                        "STOP (in a vacuum)")
    p.add_argument("--wind", type=grid_type("--wind", 0.1, 100.0, "m/s"), default=None,
                   metavar="START:STOP:COUNT",
                   help="wind speeds [m/s] instead: the aeroelastic diagram (BEM) "
                        "at the operating points of the controller's schedule, frequency and "
                        "damping against wind speed")
    p.add_argument("--controller", default=None, metavar="DISCON.IN",
                   help="with --wind: ROSCO controller file with the schedule (default for "
                        "nrel5mw and iea15mw: the rosco wheel's)")
    p.add_argument("--wind-direction", type=finite_float("--wind-direction", unit="deg"),
                   default=0.0, metavar="DEG", help="with --wind: yaw misalignment [deg]")
    from .aero import aero_model_args
    aero_model_args(p, stability=True)
    elements_arg(p)
    marching_args(p)
    p.add_argument("--workers", type=positive_int, default=None, metavar="W",
                   help="worker processes (default: one per CPU)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="run the points on this Dask distributed scheduler's workers "
                        "(default: $HAWT_SCHEDULER, else local processes)")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write the Campbell diagram to this PNG file")
    p.add_argument("--csv", metavar="FILE", default=None,
                   help="write speed, track, frequency, real part and damping rows to FILE")
    p.add_argument("--frame", choices=("fixed", "rotating"), default=None,
                   help="frequencies in the fixed frame (multi-blade coordinates; the default "
                        "for 3+ blades) or the rotating frame (the default for 1 and 2)")
    p.add_argument("--max-hz", type=finite_float("--max-hz", minimum=0.0, unit="Hz"),
                   default=None, metavar="HZ",
                   help="band [Hz] reported at every speed (default: what the highest speed "
                        "resolves, 50 per-rev with the default steps; with --wind 1.5 x the "
                        "clamped blade's 2nd flap + 1P, a few modes per blade family)")
    p.add_argument("--all-modes", action="store_true",
                   help="plot every track (default: the Table 2 ones: yaw, teeter and the "
                        "first two of each family and symmetry; a second mode of one name, "
                        "'#2', only when damped below 30 %% somewhere)")
