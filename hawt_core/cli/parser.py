"""The ``hawt`` parser: one argparse parser class whose errors are one line (CliError, exit
status 2), the subcommand registry (``@command``), and the argument types and groups the
commands share (each error names the field, the text given and what is allowed).
"""

from __future__ import annotations

import argparse
import math
from typing import Callable, Optional

__all__ = ['EXIT_USAGE', 'CliError', 'Parser', 'COMMANDS', 'command', 'positive_int',
           'finite_float', 'checked', 'elements_type', 'order_type', 'rotor_speed_type',
           'step_deg_type',
           'turbine_arg', 'elements_arg', 'model_args', 'load', 'accuracy_type',
           'refined_runner', 'with_accuracy', 'steps_type', 'per_rev', 'marching_args',
           'speeds_type', 'MAX_SPEEDS']


EXIT_USAGE = 2


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
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


def positive_int(text: str) -> int:
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


def checked(validator: Callable):
    """argparse type from one of hawt_core.numerics.checks' validators (the same check, and
    the same allowed range, as the turbine file, the node's parameters and its requests):
    the validator gets the text given; its message loses only its field name, which argparse
    puts back as the option's."""
    def conv(text: str):
        try:
            return validator(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e).split(": ", 1)[-1]) from None
    conv.__name__ = getattr(validator, "__name__", "value")
    return conv


def _checks():
    from ..numerics import checks
    return checks


def elements_type(text: str) -> int:
    return checked(_checks().check_elements)(text)


def rotor_speed_type(text: str) -> float:
    return checked(_checks().check_rotor_speed)(text)


def step_deg_type(text: str) -> float:
    return checked(_checks().check_step_deg)(text)


def turbine_arg(p):
    p.add_argument("turbine", nargs="?", default=None, metavar="TURBINE",
                   help="a hawt turbine file (YAML), an OpenFAST deck (.fst), a HAWC2 "
                        "model (.htc), a WindIO turbine file or the short name of a shipped "
                        "turbine (hawt turbines); default: the paper's Table 1 turbine")


def order_type(text: str) -> int:
    """argparse type of --order: the polynomial degree of the blade's beam elements."""
    from ..numerics.limits import MAX_ORDER
    try:
        v = int(text)
    except ValueError:
        v = None
    if v is None or not 1 <= v <= MAX_ORDER:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need an integer from 1 (the "
                                         f"paper's element) to {MAX_ORDER}")
    return v


def elements_arg(p):
    p.add_argument("--elements", "-n", type=elements_type, default=None, metavar="N",
                   help="finite elements per blade (default: the turbine file's)")
    p.add_argument("--order", type=order_type, default=None, metavar="P",
                   help="polynomial degree of the blade's elements: 1 = the paper's mixed "
                        "element, 2 and more its p-version (default: the turbine file's)")


def accuracy_type(text: str) -> float:
    """argparse type of --accuracy: hawt_core.analyses.accuracy's own check."""
    from ..analyses.accuracy import ACCURACY_RANGE, check_accuracy
    v = finite_float("", unit="relative")(text)
    try:
        return check_accuracy(v)
    except ValueError:
        lo, hi = ACCURACY_RANGE
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need a relative error from "
                                         f"{lo:g} to {hi:g}, e.g. 1e-3") from None


def model_args(p):
    """The arguments every analysis takes: the turbine file and the usual overrides."""
    turbine_arg(p)
    elements_arg(p)
    p.add_argument("--rotor-speed", type=rotor_speed_type, default=None, metavar="RAD_PER_S",
                   help="rotor speed [rad/s] (default: the turbine file's)")
    p.add_argument("--accuracy", type=accuracy_type, default=None, metavar="TOL",
                   help="choose the mesh: raise the elements per blade (from --elements or "
                        "the file's) until the estimated discretization error (Richardson) "
                        "of every mode printed is below TOL, e.g. 1e-3; the mode that "
                        "limits it is named")
    p.add_argument("--error-estimate", action="store_true",
                   help="also run half the elements and report each frequency's estimated "
                        "discretization error")


def refined_runner(turbine, n0: int, analysis):
    """``run(n, order=None)``: ``analysis(turbine', n)`` with a flexible tower's elements
    scaled like the blades' (n / n0, at least its own count's share) and, given ``order``,
    the blade's elements of that order."""
    from dataclasses import replace
    import math

    def run(n, order=None):
        t = turbine
        if order is not None:
            t = replace(t, blade=replace(t.blade, order=int(order)))
        if t.tower is not None:
            t = replace(t, tower=replace(t.tower, elements=max(
                1, int(math.ceil(t.tower.elements * n / n0)))))
        return analysis(t, n)
    return run


def with_accuracy(args, turbine, analysis, progress=None, scope="the modes printed"):
    """The analysis at the requested mesh, with error estimates (--error-estimate) or at the
    mesh --accuracy chooses (hawt_core.analyses.accuracy) for the modes the analysis
    reports (``scope`` names them in messages)."""
    from ..analyses.accuracy import converge, with_error_estimates
    n0 = int(args.elements or turbine.blade.elements)
    order = int(turbine.blade.order)
    run = refined_runner(turbine, n0, analysis)
    if args.accuracy is not None:
        return converge(run, n0, args.accuracy, progress, scope=scope, order=order)
    if args.error_estimate:
        return with_error_estimates(run, n0, order)
    return run(n0)


def load(path, order=None):
    """The turbine of ``path``: a file, an OpenFAST deck or a shipped name (None: the paper's
    Table 1 turbine); ``order`` (--order) given, its blade's elements of that degree."""
    from ..io.catalog import load_any
    turbine = load_any(path)
    if order is not None:
        from dataclasses import replace
        turbine = replace(turbine, blade=replace(turbine.blade, order=int(order)))
    return turbine


# ---------------------------------------------------------------------------- modes
def steps_type(text: str) -> int:
    """Marching steps per period: the analysis' own range (MIN_STEPS to MAX_STEPS)."""
    from ..analyses.modal import MAX_STEPS, MIN_STEPS
    try:
        v = int(text)
    except ValueError:
        v = None
    if v is None or not MIN_STEPS <= v <= MAX_STEPS:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need an integer from "
                                         f"{MIN_STEPS} to {MAX_STEPS}")
    return v


def per_rev(text: str) -> float:
    v = finite_float("", unit="per-rev")(text)
    if not 0 < v <= 1000:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed; need a number > 0 and "
                                         "<= 1000 [per-rev]")
    return v


def marching_args(p):
    """The Floquet analysis' method options (modes, campbell)."""
    p.add_argument("--steps", type=steps_type, default=None, metavar="K",
                   help="time steps per rotor period of the marching methods (default: 400 "
                        "radau, 1000 paper)")
    p.add_argument("--method", choices=("auto", "radau", "paper", "hill"), default="auto",
                   help="auto (default): Hill's method in multi-blade coordinates where the "
                        "rotor's symmetry allows them (3+ identical blades on a rigid hub: "
                        "one eigenproblem without gravity or tilt, a few harmonics of Nb "
                        "per-rev with them), else radau; radau: Radau IIA monodromy; paper: "
                        "the paper's central differencing; hill: Hill's method (harmonic "
                        "balance eigenproblem)")


# ---------------------------------------------------------------------------- campbell
#: Most rotor speeds of one Campbell sweep.
MAX_SPEEDS = 1000


def speeds_type(text: str):
    """START:STOP:COUNT -> COUNT evenly spaced rotor speeds [rad/s], 0 < START < STOP <=
    MAX_ROTOR_SPEED, 2 <= COUNT <= MAX_SPEEDS; errors name the field."""
    from ..numerics.limits import MAX_ROTOR_SPEED
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
    if not 2 <= count <= MAX_SPEEDS:
        raise argparse.ArgumentTypeError(f"COUNT {parts[2]!r} is not allowed; need an "
                                         f"integer from 2 to {MAX_SPEEDS}")
    if not 0 < start <= MAX_ROTOR_SPEED:
        raise argparse.ArgumentTypeError(f"START {parts[0]!r} is not allowed; need a number "
                                         f"> 0 and <= {MAX_ROTOR_SPEED:g} [rad/s]")
    if not start < stop <= MAX_ROTOR_SPEED:
        raise argparse.ArgumentTypeError(f"STOP {parts[1]!r} is not allowed; need START "
                                         f"({parts[0]}) < STOP <= {MAX_ROTOR_SPEED:g} [rad/s] "
                                         "(COUNT speeds from START to STOP)")
    return [start + (stop - start) * i / (count - 1) for i in range(count)]
