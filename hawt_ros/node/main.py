"""Entry point ``hawt-node``: ROS arguments, signals, the executor, the status line and an
orderly shutdown (recording finalized)."""
from __future__ import annotations

import os
import signal
import sys
import threading
from typing import List, Optional

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

from ..bag import close_all_writers
from ..params import PARAMETERS, RUNTIME_CHANGEABLE
from ..analysis_workers import AnalysisRunner
from .config import (EXECUTOR_THREADS, STATUS_DOC, STATUS_PARAM, STATUS_PLAIN_PERIOD,
                     STATUS_TTY_PERIOD, StartupError, stream_is_tty)
from .status import StatusLine
from .turbine_node import HawtNode

__all__ = ["main"]


def _log_format_for_tty() -> None:
    """On a terminal, start every rcutils log line with 'carriage return, clear line' so a log
    message replaces the status line being redrawn instead of being appended to it (the next
    redraw then starts on a fresh line). Only when the user has not chosen a format."""
    if stream_is_tty() and "RCUTILS_CONSOLE_OUTPUT_FORMAT" not in os.environ:
        os.environ["RCUTILS_CONSOLE_OUTPUT_FORMAT"] = \
            "\r\x1b[K[{severity}] [{time}] [{name}]: {message}"


# ====================================================================== entry point
USAGE = """usage: hawt-node [-h] [--ros-args -p NAME:=VALUE ...]

ROS 2 node of hawt: simulates the turbine, publishes joint_states, blade_deflections,
blade_markers (and /clock when real_time_factor is 0), serves the modal_analysis service
and action. Parameters (see docs/ros.md):
"""


def _usage() -> str:
    lines = [USAGE]
    for name, (default, doc) in PARAMETERS.items():
        flag = "" if name in RUNTIME_CHANGEABLE else " [restart to change]"
        lines.append(f"  {name} (default {default!r}){flag}\n      {doc}")
    lines.append(f"  {STATUS_PARAM} (default: {stream_is_tty()!r} here)\n      {STATUS_DOC}; "
                 f"redrawn every {STATUS_TTY_PERIOD:g} s on a terminal, else a line every "
                 f"{STATUS_PLAIN_PERIOD:g} s")
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    args = list(sys.argv if argv is None else argv)
    # before anything calls into rcl/rcutils (remove_ros_args does): rcutils reads its log
    # format once, at its first use
    _log_format_for_tty()
    from rclpy.utilities import remove_ros_args

    rest = remove_ros_args(args)[1:]
    if any(a in ("-h", "--help") for a in rest):
        sys.stdout.write(_usage())
        return 0
    if rest:
        sys.stderr.write(f"hawt-node: unexpected arguments {rest}; parameters go after "
                         "--ros-args as -p name:=value\n" + _usage())
        return 2

    stop = threading.Event()
    received = []
    starting = [True]

    def on_signal(signum, _frame):
        received.append(signum)
        stop.set()
        if starting[0]:      # interrupt a long start-up (a big turbine's mesh and steady state)
            raise KeyboardInterrupt

    # `kill -USR1 <pid>` prints every thread's Python stack to stderr (diagnosing a hang)
    import faulthandler
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    # Start the analysis forkserver before any DDS thread exists.
    AnalysisRunner.prepare_forkserver()
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    node = None
    executor = None
    status = None
    try:
        try:
            node = HawtNode()
            starting[0] = False
        except StartupError as exc:
            sys.stderr.write(f"hawt-node: {exc}\n")
            return 2
        except KeyboardInterrupt:
            starting[0] = False
            name = signal.Signals(received[0]).name if received else "SIGINT"
            sys.stderr.write(f"hawt-node: {name} during start-up: stopped\n")
            return 130
        executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
        executor.add_node(node)

        def spin():
            try:
                executor.spin()
            except (ExternalShutdownException, KeyboardInterrupt):
                pass
            finally:
                stop.set()

        spinner = threading.Thread(target=spin, name="hawt-executor", daemon=True)
        spinner.start()
        status = StatusLine(node).start()
        while not stop.wait(0.5):
            pass
        status.close()
        if received:
            node.get_logger().info(f"signal {signal.Signals(received[0]).name}: shutting down")
    finally:
        if status is not None:
            status.close()
        if node is not None:
            node.shutdown()
        if executor is not None:
            executor.shutdown(timeout_sec=2.0)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for s, h in old.items():
            signal.signal(s, h)
    # Everything is finalized (recording closed by node.shutdown, writers closed below).
    # Leave without running the interpreter's teardown: middleware threads that are still
    # joinable while C++ static destructors run make libstdc++ call std::terminate (an abort,
    # status -6, seen under load); os._exit skips that race.
    close_all_writers()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())
