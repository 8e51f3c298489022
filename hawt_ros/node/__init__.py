"""The hawt ROS 2 node (console script ``hawt-node``).

Steps the nonlinear turbine simulation (hawt_core Simulator; in wind the closed loop under a
controller, hawt_core.control.ClosedLoop) and publishes

* ``joint_states``       sensor_msgs/JointState: joints ``yaw``, ``teeter``, ``rotor_azimuth``
                         (position, velocity, effort = moments from the blade root loads);
* ``blade_deflections``  hawt_msgs/BladeDeflection, one message per blade per publish;
* ``blade_markers``      visualization_msgs/MarkerArray: each deformed blade as a LINE_STRIP
                         in frame ``nacelle`` (or ``hub``, parameter ``marker_frame``);
* ``rotor_state``        hawt_msgs/RotorState, in wind only: wind, speeds, power, pitch per
                         blade, overrides, tower-top motion;
* ``/clock``             rosgraph_msgs/Clock, only when ``real_time_factor`` is 0;

and serves the Floquet modal analysis of its turbine as service ``modal_analysis``
(hawt_msgs/srv/ModalAnalysis) and action ``modal_analysis`` (hawt_msgs/action/ModalAnalysis,
progress feedback, cancellable). Analyses run in worker processes
(hawt_ros.analysis_workers), so the simulation timer keeps its cadence. Parameters, frames, time stamps and recording:
docs/ros.md.

    hawt-node --ros-args -p publish_rate:=20.0 -p real_time_factor:=1.0 -p record:=run.mcap

Modules: config (names, QoS, limits) -> publishers, pacing, recording, analysis_server
(parts of the node) -> turbine_node (HawtNode) -> status (the live status line) -> main.
"""
from .config import JOINT_NAMES, NODE_NAME, StartupError
from .main import main
from .status import StatusLine
from .turbine_node import HawtNode

__all__ = ["HawtNode", "main", "StatusLine", "StartupError", "JOINT_NAMES", "NODE_NAME"]
