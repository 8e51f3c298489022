"""The aerodynamic subcommands of ``hawt``: ``aero-table`` (rigid-rotor Cp, Ct, Cq surfaces) and
``flutter`` (a cantilever wing's flutter and divergence speeds)."""

from __future__ import annotations

import argparse

from .parser import command, finite_float, load, turbine_arg

#: Most points of one grid axis.
MAX_GRID = 500


def grid_type(name: str, low: float, high: float, unit: str, integer_count: bool = True):
    """argparse type: START:STOP:COUNT -> COUNT evenly spaced values from START to STOP
    (low <= START <= STOP <= high; COUNT 1 to MAX_GRID, START = STOP when COUNT is 1)."""
    allowed = (f"need START:STOP:COUNT with {low:g} <= START <= STOP <= {high:g} [{unit}] and "
               f"COUNT from 1 to {MAX_GRID}")

    def conv(text: str):
        parts = text.split(":")
        if len(parts) == 1:
            parts = [parts[0], parts[0], "1"]
        if len(parts) != 3:
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}")
        try:
            start, stop = (finite_float(name, unit=unit)(p) for p in parts[:2])
            count = int(parts[2])
        except (argparse.ArgumentTypeError, ValueError):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}") from None
        if not (low <= start <= stop <= high and 1 <= count <= MAX_GRID) \
                or (count > 1 and stop == start) or (count == 1 and stop != start):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}")
        if count == 1:
            return [start]
        return [start + (stop - start) * i / (count - 1) for i in range(count)]
    return conv


@command("aero-table", help="rigid-rotor Cp, Ct, Cq against tip-speed ratio and pitch (BEM)",
         description="Steady blade-element momentum theory (Ning 2014; Prandtl tip and hub "
                     "loss, Buhl's high-induction correction) of the rigid rotor over a grid "
                     "of tip-speed ratios and collective pitch angles: the power, thrust and "
                     "torque coefficient surfaces controller tools consume. Prints the "
                     "optimum, JSON with --json, ROSCO's Cp_Ct_Cq file with --rosco.")
def cmd_aero_table(args) -> int:
    from ..analyses.aero_table import aero_table
    turbine = load(args.turbine)
    table = aero_table(turbine, args.tsr, args.pitch, wind_speed=args.wind_speed,
                       tip_loss=not args.no_tip_loss, hub_loss=not args.no_hub_loss,
                       drag_in_induction=not args.no_drag_in_induction)
    if args.rosco:
        table.save_rosco(args.rosco)
    if args.plot:
        table.plot(args.plot)
    if args.json:
        print(table.to_json(indent=None))
        return 0
    opt = table.optimum()
    print(f"{turbine.name}: {len(table.tsr)} tip-speed ratios x {len(table.pitch_deg)} pitch "
          f"angles ({table.settings['stations']} blade stations)")
    print(f"maximum Cp {opt['cp']:.4f} at tip-speed ratio {opt['tsr']:.4g}, pitch "
          f"{opt['pitch_deg']:.4g} deg (Ct {opt['ct']:.4f})")
    for what, path in (("ROSCO table", args.rosco), ("picture", args.plot)):
        if path:
            print(f"{what} written to {path}")
    return 0


@cmd_aero_table.arguments
def _aero_table_args(p):
    from ..analyses.aero_table import MAX_TSR, PITCH_RANGE_DEG
    turbine_arg(p)
    p.add_argument("--tsr", type=grid_type("--tsr", 1e-3, MAX_TSR, "-"), default="2:14:25",
                   metavar="START:STOP:COUNT", help="tip-speed ratios (default 2:14:25)")
    p.add_argument("--pitch", type=grid_type("--pitch", *PITCH_RANGE_DEG, "deg"),
                   default="-5:25:31", metavar="START:STOP:COUNT",
                   help="collective pitch angles [deg, towards feather] (default -5:25:31; "
                        "a negative start needs the = form: --pitch=-5:25:31)")
    p.add_argument("--wind-speed", type=finite_float("--wind-speed", minimum=0.1,
                                                     unit="m/s"),
                   default=10.0, metavar="U", help="wind speed [m/s] (default 10; the "
                   "coefficients do not depend on it)")
    p.add_argument("--no-tip-loss", action="store_true", help="no Prandtl tip loss")
    p.add_argument("--no-hub-loss", action="store_true", help="no Prandtl hub loss")
    p.add_argument("--no-drag-in-induction", action="store_true",
                   help="leave the drag out of the induction equations (AeroDyn's "
                        "AIDrag/TIDrag = False)")
    p.add_argument("--json", action="store_true",
                   help='print {"tsr", "pitch_deg", "cp", "ct", "cq" ([tsr][pitch]), ...}')
    p.add_argument("--rosco", metavar="FILE", default=None,
                   help="write ROSCO's Cp_Ct_Cq text file")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write Cp and Ct contours to this PNG file")


def report(args, run) -> int:
    """Run ``run(progress)`` with a status line (none with --json), write --plot, print the
    result's JSON (--json) or table."""
    from .status import ProgressLine
    status = ProgressLine(not args.json)
    try:
        result = run(status)
    finally:
        status.close()
    if args.plot:
        result.plot(args.plot)
    if args.json:
        print(result.to_json())
        return 0
    print(result.table())
    if args.plot:
        print(f"picture written to {args.plot}")
    return 0


#: Wing cases shipped with hawt: name -> file in hawt_core/data.
SHIPPED_WINGS = {"goland": "goland_wing.yaml"}


def load_wing_case(spec: str):
    """A model.Wing from a wing file or a shipped wing name, or None when ``spec`` is
    neither (then it names a turbine)."""
    from pathlib import Path
    from ..io.wing_yaml import is_wing_file, load_wing
    p = Path(spec)
    if not p.exists() and spec in SHIPPED_WINGS:
        p = Path(__file__).resolve().parent.parent / "data" / SHIPPED_WINGS[spec]
    elif not p.exists() or not is_wing_file(p):
        return None
    return load_wing(p)


@command("flutter", help="flutter speed of a cantilever wing, or overspeed flutter of a turbine",
         description="Aeroelastic modes of a cantilever wing in a uniform stream (hawt's beam "
                     "elements, Theodorsen's strip loads with Wagner's lag as states) against "
                     "the flow speed: the lowest speed at which a mode's damping crosses "
                     "zero, with its frequency, and the static divergence speed. CASE: a wing "
                     "file or a shipped case (goland); or a turbine with --wind U --rpm "
                     "A:B:N: its aeroelastic Floquet modes (BEM; --inflow, --airfoil) over rotor "
                     "speeds, "
                     "and the lowest speed where a mode's damping crosses zero.")
def cmd_flutter(args) -> int:
    from ..analyses.flutter import flutter
    wing = load_wing_case(args.case)
    if wing is None:
        return _turbine_flutter(args)
    if args.wind is not None or args.rpm is not None:
        raise ValueError("--wind, --rpm: only for a turbine CASE (a wing sweeps --speeds)")
    check_aero_model_args(args)         # a wing's lag is --quasi-steady's
    return report(args, lambda status: flutter(
        wing, args.speeds, elements=args.elements, modes=args.modes,
        unsteady=not args.quasi_steady, progress=status))


def _turbine_flutter(args) -> int:
    """``hawt flutter TURBINE --wind U --rpm A:B:N``: the overspeed sweep in wind."""
    import math
    from ..analyses.turbine_flutter import turbine_flutter
    from .executors import sweep_executor
    from .parser import load
    if args.wind is None or args.rpm is None:
        raise ValueError(f"CASE: {args.case!r} is not a wing file nor a shipped wing case "
                         f"({', '.join(SHIPPED_WINGS)}); for a turbine give --wind U and "
                         "--rpm START:STOP:COUNT (the overspeed sweep)")
    if args.rpm[0] <= 0 or len(args.rpm) < 2:
        raise ValueError("--rpm: need COUNT >= 2 rotor speeds > 0 [rpm]")
    turbine = load(args.case)
    args.turbine = args.case        # the shipped turbine's DISCON.IN gives the pitch at --wind
    args.rotor_speed = args.rpm[0] * math.pi / 30       # the operating point's pitch only
    check_wind_args(args)
    turbine, wind, point = turbine_in_wind(args, turbine)
    speeds = [n * math.pi / 30 for n in args.rpm]
    with sweep_executor(args.scheduler, None) as (pool, where):
        def run(status):
            r = turbine_flutter(turbine, wind, speeds, elements=args.elements,
                                executor=pool, progress=status, inflow=args.inflow,
                                airfoil=args.airfoil)
            r.campbell.settings.update(executor=where, operating_point=point)
            return r
        return report(args, run)


@cmd_flutter.arguments
def _flutter_args(p):
    from .parser import elements_type, positive_int
    p.add_argument("case", metavar="CASE", help="a wing file (docs/aerodynamics.md), a "
                   f"shipped case ({', '.join(SHIPPED_WINGS)}), or a turbine (with --wind "
                   "and --rpm: its overspeed flutter in wind)")
    p.add_argument("--wind", type=finite_float("--wind", unit="m/s"), default=None,
                   metavar="U", help="turbine: the wind speed [m/s]")
    p.add_argument("--rpm", type=grid_type("--rpm", 1e-3, 1000.0, "rpm"), default=None,
                   metavar="START:STOP:COUNT", help="turbine: rotor speeds [rpm] to sweep")
    p.add_argument("--pitch", type=finite_float("--pitch", unit="deg"), default=None,
                   metavar="DEG", help="turbine: collective pitch [deg] towards feather "
                                       "(default: the schedule's at --wind, else the file's)")
    p.add_argument("--controller", default=None, metavar="DISCON.IN",
                   help="turbine: controller file whose schedule gives the pitch at --wind")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="turbine: run the speeds on this Dask scheduler's workers")
    aero_model_args(p, stability=True)
    p.set_defaults(wind_direction=0.0, rotor_speed=None)
    p.add_argument("--speeds", type=grid_type("--speeds", 1e-3, 1e4, "m/s"),
                   default="20:200:19", metavar="START:STOP:COUNT",
                   help="flow speeds [m/s] (default 20:200:19)")
    p.add_argument("--elements", "-n", type=elements_type, default=None, metavar="N",
                   help="finite elements (default: the case file's)")
    p.add_argument("--modes", type=positive_int, default=4, metavar="K",
                   help="lowest oscillatory modes to follow (default 4)")
    p.add_argument("--quasi-steady", action="store_true",
                   help="no Wagner lag (C(k) = 1); the added-mass loads remain")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write frequency and damping against speed to this PNG file")


def _schedule_defaults(s: dict) -> dict:
    """What a schedule without these entries assumes: no minimum speed, a lossless
    generator, fine pitch 0, pitch up to 90 deg."""
    import math
    s.setdefault("min_speed", 0.0)
    s.setdefault("efficiency", 1.0)
    s.setdefault("fine_pitch", 0.0)
    s.setdefault("max_pitch", math.radians(90.0))
    return s


#: --controller values that name a controller rather than a DISCON.IN file: "rosco" (the
#: rosco wheel's DISCON.IN of a shipped turbine), "builtin" (hawt's own, control/builtin.py,
#: on that file's schedule), "none" (no controller in the loop)
CONTROLLER_NAMES = ("rosco", "builtin", "none")


def controller_file(args):
    """The DISCON.IN of --controller (a file, or "rosco"/"none"/absent: the shipped
    turbine's from the rosco wheel), or None."""
    from ..io.catalog import shipped_controller
    name = args.controller
    if name is not None and name not in CONTROLLER_NAMES:
        return name
    path = shipped_controller(args.turbine)
    if path is None and name == "rosco":
        raise ValueError(f"--controller {name}: the rosco wheel ships no DISCON.IN for "
                         f"{args.turbine!r}; give --controller DISCON.IN, or --controller "
                         "builtin with --rated-power, --rated-rpm and --tsr-opt")
    return path


def controller_schedule(args):
    """(path, schedule) of --controller or the shipped turbine's DISCON.IN, or (None, None)."""
    from ..io.discon import discon_schedule
    path = controller_file(args)
    if path is None:
        return None, None
    return path, _schedule_defaults(discon_schedule(path))


def turbine_in_wind(args, turbine):
    """(turbine at its operating point, Wind, settings) for ``--wind U``: the rotor speed
    and pitch given (--rotor-speed, --pitch), else those of the controller's schedule at U
    (--controller, or the shipped turbine's DISCON.IN: the operating point of
    ``hawt operating-points``), else the turbine file's."""
    import math
    from dataclasses import replace
    from ..aero.wind import Wind
    from ..analyses.operating_points import operating_points
    U = float(args.wind)
    wind = Wind(U, direction=math.radians(args.wind_direction))
    if getattr(args, "shear", 0.0):
        if turbine.tower is None:
            raise ValueError("--shear: the turbine has no tower, so no height above the "
                             "ground; the power law needs one")
        top = float(turbine.tower.length)          # N's origin: the tower top
        wind = Wind(U, direction=wind.direction, shear_exponent=float(args.shear),
                    origin_height=top, reference_height=top + turbine.nacelle.shaft_height)
    speed = args.rotor_speed
    pitch = None if args.pitch is None else math.radians(args.pitch)
    source = "given"
    if speed is None or pitch is None:
        path, schedule = controller_schedule(args)
        if path is None and schedule_given(args):
            path, schedule = "the given schedule", schedule_from_args(args)
        if path is not None:
            point = operating_points(turbine, [U], schedule).points[0]
            if not point["converged"]:
                raise ValueError(f"--wind: no operating point at {U:g} m/s under the schedule "
                                 f"of {path}: {point.get('error')}")
            speed = point["rotor_speed_rpm"] * math.pi / 30 if speed is None else speed
            pitch = math.radians(point["pitch_deg"]) if pitch is None else pitch
            source = f"the schedule of {path} (hawt operating-points)"
        else:
            speed = turbine.rotor.speed if speed is None else speed
            pitch = -turbine.rotor.pitch if pitch is None else pitch
            source = "the turbine file's rotor speed and pitch"
    if not speed > 0:
        raise ValueError(f"--rotor-speed: {speed!r} is not allowed in wind; need a rotor speed "
                         "> 0 [rad/s]")
    turbine = replace(turbine, rotor=replace(turbine.rotor, speed=float(speed),
                                             pitch=-float(pitch)))
    return turbine, wind, {"rotor_speed_rpm": speed * 30 / math.pi,
                           "pitch_deg": math.degrees(pitch), "source": source}


#: The blades' aerodynamic model of the stability analyses (modes, campbell, flutter) in wind
#: unless --inflow/--airfoil say otherwise: HAWCStab2's kind, dynamic inflow and an unsteady
#: (attached-flow) airfoil; the frozen-wake quasi-steady model is OpenFAST's linearization's
#: (MBC3 comparisons) and the other commands' default.
STABILITY_AERODYNAMICS = ("oye", "jones")
#: ... and of every other command: the inductions frozen, quasi-steady airfoils
DEFAULT_AERODYNAMICS = ("frozen", "quasi-steady")


def aero_model_args(p, stability: bool = False):
    """``--inflow`` and ``--airfoil``: the blades' aerodynamic model in wind
    (assembly/rotor_aero.py); ``stability``: the command is a stability analysis, whose
    default is STABILITY_AERODYNAMICS."""
    from ..assembly.rotor_aero import AIRFOIL_MODELS, INFLOW_MODELS
    inflow, airfoil = STABILITY_AERODYNAMICS if stability else DEFAULT_AERODYNAMICS
    p.set_defaults(stability=stability)
    p.add_argument("--inflow", choices=INFLOW_MODELS, default=None,
                   help="with --wind: the inductions frozen at the operating point's BEM "
                        "state, or Oye's dynamic inflow (four states per blade element: the "
                        f"induction lags the loads) (default {inflow}" + (
                            "; frozen is OpenFAST's linearization's, for MBC3 comparisons)"
                            if stability else "; with a controller in the loop oye)"))
    p.add_argument("--airfoil", choices=AIRFOIL_MODELS, default=None,
                   help="with --wind: polars at the quasi-steady angle of attack, or "
                        "Theodorsen's attached-flow airfoil with Jones's two-state lag of the "
                        "circulatory lift, the three-quarter-chord downwash and the "
                        f"added-mass loads (default {airfoil})")


def check_aero_model_args(args):
    """--inflow/--airfoil other than the defaults need --wind.  An absent one becomes the
    command's default (STABILITY_AERODYNAMICS in wind for a stability analysis, else frozen
    and quasi-steady); ``args.inflow_given`` says whether --inflow was given."""
    args.inflow_given = getattr(args, "inflow", None) is not None
    stable = getattr(args, "stability", False) and args.wind is not None
    chosen = STABILITY_AERODYNAMICS if stable else DEFAULT_AERODYNAMICS
    for key, default in zip(("inflow", "airfoil"), chosen):
        if hasattr(args, key) and getattr(args, key) is None:
            setattr(args, key, default)
    if args.wind is None:
        for key, plain in zip(("inflow", "airfoil"), DEFAULT_AERODYNAMICS):
            if getattr(args, key, plain) != plain:
                raise ValueError(f"--{key}: only used with --wind")


def wind_args(p, stability: bool = False):
    """``--wind U`` and what goes with it (modes, simulate at one wind speed; ``stability``:
    aero_model_args's)."""
    p.add_argument("--wind", type=finite_float("--wind", unit="m/s"), default=None,
                   metavar="U", help="analyse in a steady wind of U m/s (at hub height): "
                   "blade-element momentum loads (the model: --inflow, --airfoil) "
                   "(rotor speed and pitch from --rotor-speed/--pitch, else the controller's "
                   "schedule, else the turbine file)")
    p.add_argument("--wind-direction", type=finite_float("--wind-direction", unit="deg"),
                   default=0.0, metavar="DEG",
                   help="the wind's direction about the yaw axis (yaw misalignment) [deg]")
    p.add_argument("--pitch", type=finite_float("--pitch", unit="deg"), default=None,
                   metavar="DEG", help="collective pitch [deg], positive towards feather "
                                       "(ElastoDyn's BlPitch)")
    p.add_argument("--shear", type=finite_float("--shear", minimum=0.0), default=0.0,
                   metavar="ALPHA", help="vertical power-law shear exponent (U at hub height; "
                   "heights from the tower's length), e.g. 0.2")
    p.add_argument("--controller", default=None, metavar="DISCON.IN|rosco|builtin|none",
                   help="ROSCO controller file whose schedule sets the rotor speed and pitch "
                        "at --wind (default for nrel5mw and iea15mw, or 'rosco': the rosco "
                        "wheel's); simulate: also runs that controller in the loop (a file or "
                        "'rosco'; 'builtin': hawt's baseline controller on that schedule; "
                        "'none': the rotor at the schedule's speed)")
    aero_model_args(p, stability)


def check_wind_args(args):
    """The --wind options' ranges (ValueError naming the flag)."""
    check_aero_model_args(args)
    if args.wind is None:
        for flag, v in (("--wind-direction", args.wind_direction != 0.0),
                        ("--shear", getattr(args, "shear", 0.0) != 0.0),
                        ("--pitch", args.pitch is not None),
                        ("--controller", args.controller is not None)):
            if v:
                raise ValueError(f"{flag}: only used with --wind U")
        return
    if not 0.1 <= args.wind <= 100.0:
        raise ValueError(f"--wind: {args.wind!r} is not allowed; need a number from 0.1 to "
                         "100 [m/s]")
    if not abs(args.wind_direction) < 90.0:
        raise ValueError(f"--wind-direction: {args.wind_direction!r} is not allowed; need "
                         "-90 < DEG < 90 (the rotor faces the wind)")
    if not 0.0 <= getattr(args, "shear", 0.0) <= 1.0:
        raise ValueError(f"--shear: {args.shear!r} is not allowed; need 0 to 1")
    if args.pitch is not None and not -90.0 <= args.pitch <= 90.0:
        raise ValueError(f"--pitch: {args.pitch!r} is not allowed; need -90 to 90 [deg]")


def schedule_from_args(args) -> dict:
    """The operating-point schedule: --controller FILE, the shipped turbine's DISCON.IN from
    the rosco wheel, or the values given; each given value overrides the file's."""
    import math
    from ..io.discon import discon_schedule
    path = controller_file(args)
    s = discon_schedule(path) if path is not None else {}
    _schedule_defaults(s)
    given = {"rated_power": None if args.rated_power is None else 1e3 * args.rated_power,
             "rated_speed": None if args.rated_rpm is None else args.rated_rpm * math.pi / 30,
             "min_speed": None if args.min_rpm is None else args.min_rpm * math.pi / 30,
             "tsr": args.tsr_opt,
             "efficiency": None if args.efficiency is None else args.efficiency / 100,
             "fine_pitch": None if args.fine_pitch is None else math.radians(args.fine_pitch)}
    s.update({k: v for k, v in given.items() if v is not None})
    missing = [k for k in ("rated_power", "rated_speed", "tsr") if k not in s]
    if missing:
        flags = {"rated_power": "--rated-power", "rated_speed": "--rated-rpm",
                 "tsr": "--tsr-opt"}
        raise ValueError(f"{args.command}: no controller file for this turbine; give "
                         "--controller DISCON.IN or " + ", ".join(flags[k] for k in missing))
    return s


@command("operating-points", help="aeroelastic steady states against wind speed",
         description="The rotor's aeroelastic steady state at each wind speed (blades on the "
                     "spinning hub with BEM loads at the beams' Gauss points, axial wind) "
                     "under a region-2 optimal-TSR / region-3 constant-power pitch schedule "
                     "read from ROSCO's DISCON.IN (for the shipped nrel5mw and iea15mw, the "
                     "rosco wheel's) or given: rotor speed, pitch, power, thrust, Cp, Ct, tip "
                     "deflections.")
def cmd_operating_points(args) -> int:
    from ..analyses.operating_points import operating_points
    turbine = load(args.turbine, args.order)
    schedule = schedule_from_args(args)
    return report(args, lambda status: operating_points(
        turbine, args.wind, schedule, elements=args.elements, progress=status))


SCHEDULE_FLAGS = ("rated_power", "rated_rpm", "min_rpm", "tsr_opt", "efficiency", "fine_pitch")


def schedule_given(args) -> bool:
    """Whether any schedule flag (schedule_args) was given."""
    return any(getattr(args, k, None) is not None for k in SCHEDULE_FLAGS)


def schedule_args(p):
    """The schedule's values as flags (operating-points; simulate's built-in controller)."""
    for flag, unit, what in (("--rated-power", "kW", "rated generator power"),
                             ("--rated-rpm", "rpm", "rated rotor speed"),
                             ("--min-rpm", "rpm", "minimum rotor speed"),
                             ("--tsr-opt", "-", "region-2 tip-speed ratio"),
                             ("--efficiency", "%", "generator efficiency"),
                             ("--fine-pitch", "deg", "below-rated pitch")):
        # argparse %-formats help strings: a literal "%" is written "%%"
        p.add_argument(flag, type=finite_float(flag, unit=unit), default=None,
                       metavar={"-": "X", "%": "PERCENT"}.get(unit, unit.upper()),
                       help=f"{what} [{unit.replace('%', '%%')}] (overrides the controller "
                            "file's)")


@cmd_operating_points.arguments
def _operating_points_args(p):
    from .parser import elements_arg
    turbine_arg(p)
    p.add_argument("--wind", type=grid_type("--wind", 0.1, 100.0, "m/s"), default="3:25:23",
                   metavar="START:STOP:COUNT", help="wind speeds [m/s] (default 3:25:23)")
    p.add_argument("--controller", default=None, metavar="DISCON.IN",
                   help="ROSCO controller file with the schedule (default for nrel5mw and "
                        "iea15mw: the rosco wheel's)")
    schedule_args(p)
    elements_arg(p)
    p.add_argument("--json", action="store_true",
                   help='print {"points": [{"wind_speed", "rotor_speed_rpm", "pitch_deg", ...}]}')
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write the operating-point curves to this PNG file")
