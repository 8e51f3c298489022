"""The ``hawt`` console script.

Each subcommand is a small function ``cmd_<name>(args) -> int`` plus an argument-adding
function, registered with ``@command`` (cli/parser.py) in cli/commands.py, cli/simulate.py,
cli/turbines.py and cli/aero.py.
Errors in the input (bad file, bad arguments, a model that does not converge) print ONE line to
stderr and exit with status 2; no traceback.  Other packages add subcommands through the
entry-point group ``hawt.commands`` (hawt_ros: record, play, info, call, echo): each entry
point is a dict ``{name: {"help": str, "run": callable(argv) -> int}}`` loaded for
``hawt --help`` and when its command is called, so hawt_core never imports them itself.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from importlib.metadata import entry_points

from . import commands as _commands  # noqa: F401  (registers blade-modes, modes, campbell)
from . import aero as _aero  # noqa: F401  (registers aero-table)
from . import simulate as _simulate  # noqa: F401  (registers simulate)
from . import turbines as _turbines  # noqa: F401  (registers turbines, import)
from .parser import COMMANDS, EXIT_USAGE, CliError, Parser

__all__ = ["main", "build_parser", "plugin_commands"]

#: the entry-point group other packages register subcommands under
PLUGIN_GROUP = "hawt.commands"


def plugin_commands() -> dict:
    """{name: {"help", "run"}} of the subcommands registered under PLUGIN_GROUP (a plugin
    that fails to load is left out with a warning on stderr: hawt's own commands keep
    working)."""
    out = {}
    for ep in entry_points(group=PLUGIN_GROUP):
        try:
            out.update(ep.load())
        except Exception as exc:  # noqa: BLE001 - a broken plugin must not break hawt
            print(f"hawt: warning: the subcommands of {ep.value} ({ep.name}) are not "
                  f"available: {type(exc).__name__}: {exc}", file=sys.stderr)
    return out


# ---------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="hawt", description="Structural dynamics and Floquet stability of "
                     "horizontal-axis wind turbines (Patil, Lee & Hodges, AIAA 2001-0064).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for name, entry in COMMANDS.items():
        p = sub.add_parser(name, help=entry["help"], description=entry["description"])
        entry["arguments"](p)
    for name, entry in plugin_commands().items():
        p = sub.add_parser(name, help=entry["help"], description=entry["help"])
        p.add_argument("rest", nargs=argparse.REMAINDER)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings about the input on one line each, as hawt's errors are."""
    text = " ".join(str(message).split())
    print(f"hawt: warning: {text}", file=sys.stderr if file is None else file)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    warnings.showwarning = _show_warning
    plugins = plugin_commands()
    if argv and argv[0] in plugins:        # a plugin (hawt_ros) parses its own arguments
        return int(plugins[argv[0]]["run"](list(argv)) or 0)
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
