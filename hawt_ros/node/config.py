"""Names, quality of service and limits of the hawt node, and the start-up error."""
from __future__ import annotations

import math

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from hawt_core.cli.status import stream_is_tty

from ..params import ParameterError

__all__ = ["NODE_NAME", "JOINT_NAMES", "BLADE_COLORS", "STATE_QOS", "EXECUTOR_THREADS",
           "MAX_BLOCKED", "STATUS_PARAM", "STATUS_TTY_PERIOD", "STATUS_PLAIN_PERIOD",
           "STATUS_DOC", "StartupError", "validate_status", "wrap_pi", "stream_is_tty"]

NODE_NAME = "hawt"
JOINT_NAMES = ("yaw", "teeter", "rotor_azimuth")
BLADE_COLORS = [(0.85, 0.2, 0.2), (0.2, 0.6, 0.9), (0.3, 0.8, 0.3), (0.9, 0.7, 0.1)]
STATE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)
#: Executor threads; at most MAX_BLOCKED of them wait for analyses at any time, so the
#: simulation timer and quick requests always find a free thread.
EXECUTOR_THREADS = 10
MAX_BLOCKED = 6
#: The live status line (parameter ``status``): refreshed in place every STATUS_TTY_PERIOD s
#: on a terminal, else one plain line every STATUS_PLAIN_PERIOD s.
STATUS_PARAM = "status"
STATUS_TTY_PERIOD = 0.5
STATUS_PLAIN_PERIOD = 5.0
STATUS_DOC = ("live status line on stderr (sim time, real-time factor, teeter, yaw, blade-0 tip "
              "deflection, recording, analyses); default true when stderr is a terminal")


class StartupError(RuntimeError):
    """The node cannot start (bad parameter, unreadable turbine file, ...)."""



def validate_status(value):
    """The ``status`` parameter: a bool (ParameterError otherwise)."""
    if isinstance(value, bool):
        return value
    raise ParameterError(STATUS_PARAM, value, "need true or false (default: true when stderr "
                                              "is a terminal)")


def wrap_pi(a: float) -> float:
    """Angle in [-pi, pi) [rad] (the yaw bearing is a continuous joint)."""
    return (a + math.pi) % (2 * math.pi) - math.pi
