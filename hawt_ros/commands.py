"""The ROS 2 subcommands of the ``hawt`` console script, registered through the entry-point
group ``hawt.commands`` (pyproject.toml): hawt_core lists them in ``hawt --help`` and hands
``hawt <name> ...`` to :func:`run`.  hawt_ros.cli imports rclpy only inside the commands that
talk to ROS, so listing them is cheap.  hawt_core never imports hawt_ros."""
from __future__ import annotations

from .cli import HELP, main


def run(argv) -> int:
    """``hawt <name> ...`` (argv starts with the command name)."""
    return int(main(list(argv)) or 0)


#: the entry point's value: {name: {"help", "run"}}
COMMANDS = {name: {"help": f"{text} [ROS 2; see hawt {name} -h]", "run": run}
            for name, text in HELP.items()}
