"""The ``hawt`` console script.

Each subcommand is a small function ``cmd_<name>(args) -> int`` plus an argument-adding
function, registered in one place (``COMMANDS`` below, via ``@command``).  Errors in the input
(bad file, bad arguments, a model that does not converge) print ONE line to stderr and exit
with status 2; no traceback.
"""
from __future__ import annotations

import argparse
import math
import sys
from typing import Callable, Optional

EXIT_USAGE = 2


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line instead of usage + message
        raise CliError(f"{self.prog}: {message}")


#: name -> (help, add_arguments(parser), run(args) -> int)
COMMANDS: dict = {}


def command(name: str, help: str, description: Optional[str] = None):
    """Register ``run(args)`` as subcommand ``name``; the decorated function gets an
    ``arguments`` attribute for its argument definitions (set with ``@run.arguments``)."""
    def deco(run: Callable):
        entry = {"help": help, "description": description or help, "run": run,
                 "arguments": lambda p: None}

        def arguments(add: Callable):
            entry["arguments"] = add
            return add
        run.arguments = arguments
        COMMANDS[name] = entry
        return run
    return deco


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need an integer >= 1")
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} is not allowed; need an integer >= 1")
    return v


def finite_float(field: str = "", minimum=None, unit: str = ""):
    """argparse type: a finite float (>= minimum when given); the error names ``field``, the
    text given and what is allowed."""
    need = "a finite number" + (f" >= {minimum:g}" if minimum is not None else "") + \
        (f" [{unit}]" if unit else "")

    def conv(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            v = float("nan")
        if not math.isfinite(v) or (minimum is not None and v < minimum):
            raise argparse.ArgumentTypeError(
                f"{field + ' ' if field else ''}{text!r} is not allowed; need {need}")
        return v
    return conv


_rotor_speed = finite_float(minimum=0.0, unit="rad/s")


def _turbine_arg(p):
    p.add_argument("turbine", nargs="?", default=None, metavar="TURBINE",
                   help="turbine YAML file (default: the paper's Table 1 turbine)")


def _elements_arg(p):
    p.add_argument("--elements", "-n", type=_positive_int, default=None, metavar="N",
                   help="finite elements per blade (default: the turbine file's)")


def _model_args(p):
    """The arguments every analysis takes: the turbine file and the usual overrides."""
    _turbine_arg(p)
    _elements_arg(p)
    p.add_argument("--rotor-speed", type=_rotor_speed, default=None, metavar="RAD_PER_S",
                   help="rotor speed [rad/s] (default: the turbine file's)")


def _load(path):
    """The turbine of ``path`` (None: the paper's Table 1 turbine)."""
    from .io import load_turbine
    return load_turbine(path)


# ---------------------------------------------------------------------------- blade-modes
@command("blade-modes", help="modes of one blade clamped on the spinning hub",
         description="Steady state, exact linearization and eigen-analysis of one blade "
                     "clamped on the hub spinning at the rotor speed (the symmetric blade "
                     "modes of the paper's Table 2). Prints a table, or JSON with --json.")
def cmd_blade_modes(args) -> int:
    from .blade_modes import blade_modes
    turbine = _load(args.turbine)
    result = blade_modes(turbine, elements=args.elements, rotor_speed=args.rotor_speed,
                         count=args.count, method=args.method)
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


@cmd_blade_modes.arguments
def _blade_modes_args(p):
    _model_args(p)
    p.add_argument("--count", type=_positive_int, default=None,
                   help="number of lowest modes (default: all, or 30 for large models)")
    p.add_argument("--method", choices=("auto", "dense", "sparse"), default="auto",
                   help="eigen-solver: dense QZ with deflation, sparse shift-invert, or auto")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write the mode shapes to this PNG file")


# ---------------------------------------------------------------------------- modes
def _steps(text: str) -> int:
    v = _positive_int(text)
    if not 8 <= v <= 1_000_000:
        raise argparse.ArgumentTypeError(f"{v} is not allowed; need an integer from 8 to 1000000")
    return v


class _StatusLine:
    """A one-line progress display on stderr (only when stderr is a terminal)."""

    def __init__(self, enabled: bool):
        self.enabled = enabled and sys.stderr.isatty()

    def __call__(self, fraction: float, message: str):
        if self.enabled:
            bar = "#" * int(20 * fraction)
            sys.stderr.write(f"\r[{bar:<20}] {100 * fraction:5.1f} % {message:<48}")
            sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\r" + " " * 80 + "\r")
            sys.stderr.flush()


@command("modes", help="Floquet modal analysis of the whole turbine (the paper's Table 2)",
         description="Periodic steady state, exact periodic linearization, Floquet exponents "
                     "(multi-blade coordinates for isotropic rotors with 3+ blades, monodromy "
                     "by time marching with Fast Floquet, or Hill's method), dominant "
                     "frequencies and automatic labels; with 3+ blades also fixed-frame "
                     "frequencies and whirl. Prints a table like the paper's Table 2, or "
                     "JSON with --json.")
def cmd_modes(args) -> int:
    from .modal import modal_analysis
    turbine = _load(args.turbine)
    status = _StatusLine(not args.json)
    try:
        result = modal_analysis(turbine, elements=args.elements, rotor_speed=args.rotor_speed,
                                steps=args.steps, method=args.method,
                                max_per_rev=args.max_per_rev, progress=status)
    finally:
        status.close()
    result.settings["turbine_file"] = args.turbine
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


def _per_rev(text: str) -> float:
    v = finite_float("", unit="per-rev")(text)
    if not 0 < v <= 1000:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need a number > 0 and "
                                         "<= 1000 [per-rev]")
    return v


def _marching_args(p):
    """The Floquet analysis' method options (modes, campbell)."""
    p.add_argument("--steps", type=_steps, default=None, metavar="K",
                   help="time steps per rotor period of the marching methods (default: 400 "
                        "radau, 1000 paper)")
    p.add_argument("--method", choices=("auto", "radau", "paper", "hill"), default="auto",
                   help="auto (default): multi-blade coordinates where they make the system "
                        "time-invariant (3+ identical blades on a rigid hub, no gravity), "
                        "else radau; radau: Radau IIA monodromy; paper: the paper's central "
                        "differencing; hill: Hill's method (harmonic balance eigenproblem)")


@cmd_modes.arguments
def _modes_args(p):
    _model_args(p)
    _marching_args(p)
    p.add_argument("--max-per-rev", type=_per_rev, default=None, metavar="F",
                   help="band of Hill's method and multi-blade coordinates: modes below F "
                        "per-rev (default 50)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--plots", metavar="DIR", default=None,
                   help="write mode-shape pictures (PNG) into this folder")


# ---------------------------------------------------------------------------- ROS 2 (lazy)
#: Subcommands implemented in hawt_ros.cli (they need ROS 2). hawt_core never imports rclpy or
#: hawt_ros at import time: main() hands ``hawt <one of these> ...`` to hawt_ros.cli.main,
#: imported only then; the entries below only list them in ``hawt --help``.
ROS_COMMANDS = {
    "record": "record live ROS 2 topics into an MCAP file (rosbag2 layout)",
    "play": "republish the messages of an MCAP file with their original timing",
    "info": "summarize an MCAP file (topics, types, counts, duration)",
    "call": "call the hawt node's modal_analysis service and print the modes",
    "echo": "print the messages arriving on a ROS 2 topic",
}


def _run_ros_command(argv) -> int:
    try:
        from hawt_ros.cli import main as ros_main
    except ImportError as exc:
        print(f"hawt: error: '{argv[0]}' needs the ROS 2 part of hawt (hawt_ros): {exc}",
              file=sys.stderr)
        return EXIT_USAGE
    return int(ros_main(list(argv)) or 0)


def _register_ros_commands():
    for name, help_text in ROS_COMMANDS.items():
        COMMANDS[name] = {"help": f"{help_text} [ROS 2; see hawt {name} -h]",
                          "description": help_text,
                          "run": lambda args, _n=name: _run_ros_command([_n] + args.rest),
                          "arguments": lambda p: p.add_argument("rest", nargs=argparse.REMAINDER)}


_register_ros_commands()


# ---------------------------------------------------------------------------- simulate
# `hawt simulate`: defined in hawt_core.simulate (cmd_simulate, add_arguments), imported only
# when the command runs or its arguments are added (build_parser), so that importing this
# module stays cheap (hawt_core.simulate pulls in numpy and scipy: ~0.25 s).
@command("simulate", help="nonlinear time simulation",
         description="Nonlinear time simulation (implicit midpoint, finite elements in time) "
                     "from the steady state plus perturbations; prints a summary (JSON with "
                     "--json), writes time histories with --output.")
def cmd_simulate(args) -> int:
    from .simulate import cmd_simulate as run
    return run(args)


@cmd_simulate.arguments
def _simulate_args(p):
    from .simulate import add_arguments
    add_arguments(p)


# ---------------------------------------------------------------------------- campbell
def _speeds(text: str):
    """START:STOP:COUNT -> COUNT evenly spaced rotor speeds [rad/s]; errors name the field."""
    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not allowed; need START:STOP:COUNT [rad/s], e.g. 3:9:30")
    start, stop = (finite_float(name, unit="rad/s")(part)
                   for name, part in zip(("START", "STOP"), parts[:2]))
    try:
        count = int(parts[2])
    except ValueError:
        count = 0
    if count < 2:
        raise argparse.ArgumentTypeError(f"COUNT {parts[2]!r} is not allowed; need an "
                                         "integer >= 2")
    if start <= 0:
        raise argparse.ArgumentTypeError(f"START {parts[0]!r} is not allowed; need a number "
                                         "> 0 [rad/s]")
    if stop < start:
        raise argparse.ArgumentTypeError(f"STOP {parts[1]!r} is not allowed; need STOP >= "
                                         f"START ({parts[0]})")
    return [start + (stop - start) * i / (count - 1) for i in range(count)]


@command("campbell", help="Campbell diagram: Floquet modes over a range of rotor speeds",
         description="Floquet modal analysis (as `hawt modes`) at COUNT rotor speeds from START "
                     "to STOP rad/s, run in parallel worker processes, modes tracked from speed "
                     "to speed by MAC (Hungarian assignment). Prints the frequency table; "
                     "--plot writes the diagram (Hz vs rpm with 1P..nP rays, damping), --csv "
                     "the data.")
def cmd_campbell(args) -> int:
    import concurrent.futures as cf
    import os
    from .campbell import campbell
    turbine = _load(args.turbine)
    status = _StatusLine(True)
    workers = args.workers or os.cpu_count() or 1
    with cf.ProcessPoolExecutor(max_workers=workers) as pool:
        try:
            result = campbell(turbine, args.speeds, elements=args.elements, steps=args.steps,
                              method=args.method, executor=pool, progress=status,
                              frame=args.frame, max_hz=args.max_hz)
        finally:
            status.close()
    result.settings["workers"] = workers
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
    _turbine_arg(p)
    p.add_argument("--speeds", type=_speeds, required=True, metavar="START:STOP:COUNT",
                   help="rotor speeds [rad/s]: COUNT (>= 2) evenly spaced from START (> 0) to "
                        "STOP")
    _elements_arg(p)
    _marching_args(p)
    p.add_argument("--workers", type=_positive_int, default=None, metavar="W",
                   help="worker processes (default: one per CPU)")
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
                        "resolves, 50 per-rev with the default steps)")
    p.add_argument("--all-modes", action="store_true",
                   help="plot every track (default: the Table 2 ones: yaw, teeter and the "
                        "first two of each family and symmetry)")


# ---------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="hawt", description="Structural dynamics and Floquet stability of "
                     "horizontal-axis wind turbines (Patil, Lee & Hodges, AIAA 2001-0064).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, entry in COMMANDS.items():
        p = sub.add_parser(name, help=entry["help"], description=entry["description"])
        entry["arguments"](p)
    return parser


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in ROS_COMMANDS:  # hawt_ros.cli parses its own arguments
        return _run_ros_command(argv)
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return EXIT_USAGE
        return int(COMMANDS[args.command]["run"](args) or 0)
    except CliError as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_USAGE
    except (OSError, ValueError, RuntimeError) as exc:
        msg = " ".join(str(exc).split()) or type(exc).__name__
        print(f"hawt: error: {msg}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("hawt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
