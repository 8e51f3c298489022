"""End-to-end test of the README's main job, ``bash scripts/run.sh``: the node starts on the
default turbine, the NREL 5-MW operating in 15 m/s wind under ROSCO, with recording on; it
publishes joint states (pitch and generator included) at rated rotor speed, its status line
shows wind, rotor speed, power, pitch and tip deflection, it serves the Floquet modal analysis
on request, and Ctrl-C stops it leaving a finalized MCAP file, which the script summarizes with
``hawt info``.

The script runs in its own session (process group) with its own ROS_DOMAIN_ID,
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_LOG_DIR and HAWT_RUNS_DIR in the test's temporary
folder; Ctrl-C is a SIGINT to the whole process group, as a terminal sends it. The real
simulation and modal analysis are used. Every wait is bounded (the whole test < 120 s).

References: the NREL 5-MW's rated rotor speed 12.1 rpm (Jonkman et al. 2009, NREL/TP-500-38060,
Table 1-1; within 5 %, ROSCO's regulation in the first seconds) and its 1st tower side-side
frequency 0.3120 Hz (FAST, Table 9-1; within 3 % at this coarse mesh of 4 elements per blade,
rotating; tests/test_real_turbines.py checks it converged, at rest); the node's modal analysis
is the aeroelastic one at its operating point, where the rotor's thrust damps the tower's
fore-aft mode (zeta > 2 %) and hardly its side-side mode (< 1 %), as in every operating
turbine (the aerodynamic damping of tower fore-aft motion, e.g. Burton et al., Wind Energy
Handbook)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from ros_support import child_env, domain_id, require_ros

ROOT = Path(__file__).resolve().parents[1]
RUN_SH = ROOT / "scripts" / "run.sh"
BIN = Path(sys.executable).parent
HAWT_EXE = BIN / "hawt"

try:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState
    from hawt_msgs.srv import ModalAnalysis  # noqa: F401 - the service type must be importable
    _ROS_ERROR = None
except Exception as exc:  # noqa: BLE001
    _ROS_ERROR = f"{type(exc).__name__}: {exc}"

pytestmark = pytest.mark.ros

BUDGET = 118.0          # s, the whole test


def _require_ros():
    require_ros(_ROS_ERROR, HAWT_EXE)


def test_run_script_node_modes_ctrl_c(tmp_path):
    _require_ros()
    t_start = time.monotonic()

    def left() -> float:
        return BUDGET - (time.monotonic() - t_start)

    domain = domain_id()
    runs = tmp_path / "runs"
    env = child_env(domain, tmp_path, HAWT_RUNS_DIR=str(runs), HAWT_VENV=str(BIN.parent),
                    PYTHONUNBUFFERED="1")
    for k in ("HAWT_ROS_FAKE", "HAWT_ROS_FAKE_PARTS", "RCUTILS_CONSOLE_OUTPUT_FORMAT"):
        env.pop(k, None)
    log_path = tmp_path / "run.log"
    log = open(log_path, "w")
    proc = subprocess.Popen(["bash", str(RUN_SH), "--ros-args", "-p", "status:=true"],
                            env=env, cwd=str(tmp_path),
                            stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                            start_new_session=True)

    def output() -> str:
        log.flush()
        return log_path.read_text(errors="replace")

    ctx = None
    node = None
    try:
        # ------------------------------------------------ joint states reach a subscriber
        ctx = rclpy.Context()
        rclpy.init(context=ctx, domain_id=domain,
                   signal_handler_options=SignalHandlerOptions.NO)
        node = rclpy.create_node("test_run_script", context=ctx)
        got = []
        node.create_subscription(JointState, "joint_states", got.append, 10)
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(node)
        deadline = time.monotonic() + min(60.0, left())
        while len(got) < 3 and time.monotonic() < deadline:
            assert proc.poll() is None, f"run.sh exited early ({proc.returncode}):\n{output()}"
            executor.spin_once(timeout_sec=0.1)
        assert len(got) >= 3, f"no joint_states within 60 s:\n{output()}"
        assert list(got[-1].name) == ["yaw", "teeter", "rotor_azimuth", "blade_0_pitch",
                                      "blade_1_pitch", "blade_2_pitch", "generator"]
        rpm = got[-1].velocity[2] * 30 / math.pi
        assert abs(rpm - 12.1) < 0.05 * 12.1, (rpm, output())
        executor.shutdown(timeout_sec=1.0)

        out = output()
        assert "hawt call modes" in out and "ros2 service call /modal_analysis" in out, out
        assert "closed loop in 15 m/s wind under rosco" in out, out
        # the plain status line (every 5 s without a terminal)
        wait_until_text = time.monotonic() + min(15.0, left())
        while "hawt | " not in output() and time.monotonic() < wait_until_text:
            time.sleep(0.1)
        status = [ln for ln in output().splitlines() if ln.startswith("hawt | ")]
        assert status, output()
        for part in ("wind 15.0 m/s", "rotor ", "rpm", "power ", "kW", "pitch ", "tip flap"):
            assert part in status[-1], (part, status[-1])
        files = sorted(runs.glob("hawt-*.mcap"))
        assert len(files) == 1, (files, out)
        mcap = files[0]
        assert str(mcap.name) in out

        # ------------------------------------------------ the modal analysis, on request
        timeout = max(10.0, left() - 12.0)
        call = subprocess.run([str(HAWT_EXE), "call", "modes", "--json",
                               "--timeout", f"{timeout:.0f}"],
                              env=env, cwd=str(tmp_path), capture_output=True, text=True,
                              timeout=timeout + 10)
        assert call.returncode == 0, f"{call.stderr}\n--- run.sh:\n{output()}"
        data = json.loads(call.stdout)
        # the shipped file's mesh (the node's default): 3 blade elements of order 6
        assert (data["settings"]["elements"], data["settings"]["order"]) == (3, 6)
        side = [m for m in data["modes"] if m["family"] == "tower"
                and m["symmetry"] == "side-side" and m["index"] == 1]
        assert side, data["modes"]
        f = side[0]["frequency_hz"]
        assert abs(f - 0.3120) / 0.3120 < 0.03, f
        # the analysis is the aeroelastic one at the node's operating point: the thrust damps
        # the tower's fore-aft motion (aerodynamic damping, a few per cent), not its
        # side-side motion (in a vacuum both are undamped, |zeta| < 1e-3)
        fore = [m for m in data["modes"] if m["family"] == "tower"
                and m["symmetry"] == "fore-aft" and m["index"] == 1]
        assert fore and fore[0]["damping_ratio"] > 0.02, fore
        assert abs(side[0]["damping_ratio"]) < 0.01, side
        assert proc.poll() is None, f"run.sh exited during the analysis:\n{output()}"

        # ------------------------------------------------ Ctrl-C: finalized recording
        os.killpg(proc.pid, signal.SIGINT)
        try:
            rc = proc.wait(timeout=max(5.0, min(20.0, left())))
        except subprocess.TimeoutExpired:
            # diagnose: the node's threads' stacks (hawt-node's faulthandler on SIGUSR1)
            ps = subprocess.run(["ps", "-o", "pid,ppid,stat,etime,args", "-g", str(proc.pid)],
                                capture_output=True, text=True).stdout
            for line in ps.splitlines()[1:]:
                if "hawt-node" in line:
                    try:
                        os.kill(int(line.split()[0]), signal.SIGUSR1)
                    except (ProcessLookupError, ValueError):
                        pass
            time.sleep(1.0)
            pytest.fail(f"run.sh did not exit within the wait after SIGINT\n{ps}\n{output()}")
        out = output()
        assert rc == 0, out
        assert "Bag state:" in out and "finalized" in out, out      # the script's `hawt info`

        from hawt_ros.bag import bag_info
        info = bag_info(str(mcap))
        assert info["finalized"] and not info["truncated"], info
        assert info["topics"]["/joint_states"]["type"] == "sensor_msgs/msg/JointState", info
        assert info["topics"]["/joint_states"]["count"] >= 3, info
        assert time.monotonic() - t_start < 90.0
    finally:
        if node is not None:
            node.destroy_node()
        if ctx is not None:
            rclpy.try_shutdown(context=ctx)
        if proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGTERM)
                proc.wait(10)
            except (subprocess.TimeoutExpired, ProcessLookupError):
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait(5)
        log.close()


# ============================================================================ status line
class _Stream:
    def __init__(self, tty: bool):
        self.tty, self.text = tty, ""

    def isatty(self):
        return self.tty

    def write(self, s):
        self.text += s

    def flush(self):
        pass


def _fake_node(**kw):
    from types import SimpleNamespace

    base = dict(last_state=None, recorder=None, record_path="", analyses_served=0,
                analyses_waiting=0, _failed=None, status_enabled=True)
    base.update(kw)
    return SimpleNamespace(**base)


def test_status_line_content_never_nan():
    _require_ros()
    import math
    from types import SimpleNamespace
    from hawt_ros.node import StatusLine

    node = _fake_node()
    st = StatusLine(node, stream=_Stream(False))
    assert "starting" in st.line() and "rec off" in st.line()

    now = time.monotonic()
    node.last_state = (now, 12.5, math.radians(370.0), math.radians(-1.5), 0.0123, -0.0045)
    node.recorder = SimpleNamespace(message_count=42)
    node.record_path = "/x/runs/hawt-1.mcap"
    node.analyses_served, node.analyses_waiting = 2, 1
    st._samples.extend([(now - 2.0, 10.5), (now, 12.5)])
    line = st.line()
    for part in ("t 12.50 s", "rtf 1.00", "teeter -1.50 deg", "yaw +10.00 deg",
                 "tip flap +12.3 mm, lag -4.5 mm", "rec hawt-1.mcap 42 msgs",
                 "analyses 2 (+1 running)"):
        assert part in line, (part, line)

    node.last_state = (now, float("nan"), float("inf"), float("nan"), float("nan"), -0.0)
    node._failed = "boom"
    line = st.line()
    assert "nan" not in line.lower() and "inf" not in line.lower(), line
    assert "t -- s" in line and "lag +0.0 mm" in line and "SIMULATION STOPPED" in line, line

    # in wind: wind, rotor speed, power and pitch, the tip in metres; never nan
    node._failed = None
    node.last_state = (now, 12.5, 0.0, 0.0, 4.123, 0.51)
    node.last_rotor = (15.0, 12.1, 5000.4, 9.21)
    line = st.line()
    for part in ("wind 15.0 m/s", "rotor 12.10 rpm", "power 5000 kW", "pitch 9.21 deg",
                 "tip flap +4.12 m, lag +0.51 m"):
        assert part in line, (part, line)
    node.last_rotor = (float("nan"), 12.1, float("inf"), 9.0)
    assert "nan" not in st.line().lower() and "inf" not in st.line().lower()
    node.last_rotor = None

    # a stalled simulation: the achieved factor heads to 0
    st._samples.clear()
    st._samples.extend([(now - 12.0, 1.0), (now - 10.0, 3.0)])
    assert st.real_time_factor(now) < 0.2


def test_status_line_output_tty_and_plain():
    _require_ros()
    from hawt_ros.node import StatusLine

    node = _fake_node(last_state=(time.monotonic(), 1.0, 0.0, 0.0, 0.0, 0.0))
    tty = _Stream(True)
    st = StatusLine(node, stream=tty)
    assert st.tty and st.period == 0.5
    st.show()
    st.show()
    assert tty.text.count("\r\x1b[K") == 2 and "\n" not in tty.text
    st.close()
    assert tty.text.endswith("\n") and tty.text.count("\n") == 1

    plain = _Stream(False)
    st = StatusLine(node, stream=plain)
    assert not st.tty and st.period == 5.0
    st.show()
    assert plain.text.startswith("hawt | t 1.00 s") and plain.text.endswith("\n")
    assert "\r" not in plain.text and "\x1b" not in plain.text

    class Broken(_Stream):
        def write(self, s):
            raise BrokenPipeError()

    st = StatusLine(node, stream=Broken(True)).start()
    time.sleep(0.7)
    t0 = time.monotonic()
    st.close()
    assert time.monotonic() - t0 < 1.5
