"""The ROS 2 subcommands of the ``hawt`` console script, registered through the entry-point
group ``hawt.commands`` (pyproject.toml): hawt_core lists them in ``hawt --help`` and hands
``hawt <name> ...`` to :func:`run`, which imports hawt_ros.cli (and so rclpy, where a command
needs it) only then.  hawt_core never imports hawt_ros."""
from __future__ import annotations

import sys

#: name -> one-line help
HELP = {
    "record": "record live ROS 2 topics into an MCAP file (rosbag2 layout)",
    "play": "republish the messages of an MCAP file with their original timing",
    "info": "summarize an MCAP file (topics, types, counts, duration)",
    "call": "call the hawt node's modal_analysis service (or action) and print the modes",
    "echo": "print the messages arriving on a ROS 2 topic",
}


def run(argv) -> int:
    """``hawt <name> ...`` (argv starts with the command name)."""
    try:
        from .cli import main
    except ImportError as exc:
        print(f"hawt: error: '{argv[0]}' needs the ROS 2 part of hawt (hawt_ros): {exc}",
              file=sys.stderr)
        return 2
    return int(main(list(argv)) or 0)


#: the entry point's value: {name: {"help", "run"}}
COMMANDS = {name: {"help": f"{text} [ROS 2; see hawt {name} -h]", "run": run}
            for name, text in HELP.items()}
