"""Benchmark of the hawt ROS 2 node: publishing rate achieved vs requested, end-to-end latency
(simulation instant's header stamp -> subscriber receive time), publishing gaps, and the
modal_analysis service latency for N = 4 elements (cold, cached, invalid request), on the
paper's turbine in a vacuum; then the node's default, the NREL 5-MW in 15 m/s wind under
ROSCO, on the turbine file's mesh: the real-time factor it achieves as fast as possible (the
goal: >= 1 with margin on one core), the in-wind modal analysis at the node's mesh, and its
publishing rate at real_time_factor 1 while 5 modal analyses (2..6 elements of the blade's
order, all computed) are requested at once.

    .venv/bin/python bench/node.py                 # ~1.5 min on 2 cores
    .venv/bin/python bench/node.py --duration 3 --configs 10:0.25
    .venv/bin/python bench/node.py --fake-sim      # the node's plumbing with a 1 ms stand-in
                                                   # simulator (tests/ros_fakes.py)

Each configuration starts ``hawt-node`` (the venv's console script) in a subprocess on its own
ROS domain (localhost only) and subscribes from this process. Latency is only meaningful with
real_time_factor > 0, where stamps are ROS (wall-clock) time; with real_time_factor = 0 the
table shows the achieved real-time factor instead.
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _stamp(s) -> int:
    return s.sec * 1_000_000_000 + s.nanosec


class Node:
    def __init__(self, params: dict, domain: int, tmp: Path, fake: str = "", env=None):
        e = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                 ROS_LOG_DIR=str(tmp / "roslog"))
        e.pop("HAWT_ROS_FAKE", None)
        if fake:
            e.update(HAWT_ROS_FAKE=str(ROOT / "tests" / "ros_fakes.py"), HAWT_ROS_FAKE_PARTS=fake)
        e.update(env or {})
        args = [str(BIN / "hawt-node"), "--ros-args"]
        for k, v in params.items():
            args += ["-p", f"{k}:={v}"]
        self.log = tmp / f"node-{domain}.log"
        with open(self.log, "w") as out:      # the child keeps its own copy of the descriptor
            self.proc = subprocess.Popen(args, env=e, stdout=out, stderr=subprocess.STDOUT)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)


class Client:
    def __init__(self, domain: int):
        import rclpy
        from rclpy.executors import MultiThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.rclpy = rclpy
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=domain,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node("hawt_bench", context=self.ctx)
        self.ex = MultiThreadedExecutor(num_threads=2, context=self.ctx)
        self.ex.add_node(self.node)
        self.items = []
        self.lock = threading.Lock()
        threading.Thread(target=self._spin, daemon=True).start()

    def _spin(self):
        try:
            self.ex.spin()
        except Exception:  # noqa: BLE001
            pass

    def subscribe_joint_states(self):
        from sensor_msgs.msg import JointState

        def cb(msg):
            now = time.time_ns()
            with self.lock:
                self.items.append((time.monotonic(), now, _stamp(msg.header.stamp)))
        self.node.create_subscription(JointState, "/joint_states", cb, 1000)

    def call(self, client, req, timeout=600.0):
        done = threading.Event()
        fut = client.call_async(req)
        fut.add_done_callback(lambda f: done.set())
        t0 = time.perf_counter()
        if not done.wait(timeout):
            raise RuntimeError("no answer")
        return fut.result(), time.perf_counter() - t0

    def close(self):
        self.ex.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.ctx)


def wait_for(cond, timeout):
    t = time.monotonic() + timeout
    while time.monotonic() < t:
        if cond():
            return True
        time.sleep(0.02)
    return False


def _collect(node, domain: int, duration: float, first_timeout: float):
    """(joint-state items received over ``duration`` s after the first one, seconds to the
    first one); the node is stopped at the end."""
    cli = Client(domain)
    try:
        cli.subscribe_joint_states()
        t0 = time.monotonic()
        if not wait_for(lambda: len(cli.items) > 0, first_timeout):
            raise RuntimeError(f"no messages; node log:\n{node.log.read_text()}")
        start_up = time.monotonic() - t0
        n0 = len(cli.items)
        time.sleep(duration)   # the measurement window (a benchmark, not a test)
        with cli.lock:
            items = cli.items[n0:]
    finally:
        node.stop()
        cli.close()
    return items, start_up


def bench_publishing(rate: float, rtf: float, duration: float, domain: int, tmp: Path,
                     step_deg: float, fake: bool) -> dict:
    node = Node({"turbine": "paper", "wind": 0.0, "publish_rate": rate,
                 "real_time_factor": rtf, "step_deg": step_deg, "perturb": "teeter=0.02"},
                domain, tmp, fake="simulate" if fake else "",
                env={"HAWT_FAKE_STEP_COST": "0.001"} if fake else None)
    items, _ = _collect(node, domain, duration, 60.0)
    mono = np.array([i[0] for i in items])
    wall = np.array([i[1] for i in items], float)
    st = np.array([i[2] for i in items], float)
    span = mono[-1] - mono[0]
    out = {"rate_req": rate, "rtf": rtf, "n": len(items), "rate": (len(items) - 1) / span,
           "gap_max": float(np.diff(mono).max()) * 1e3, "gap_mean": float(np.diff(mono).mean()) * 1e3}
    if rtf > 0:
        lat = (wall - st) / 1e6
        out.update(lat_med=float(np.median(lat)), lat_p95=float(np.percentile(lat, 95)),
                   lat_max=float(lat.max()))
        out["sim_rate"] = (len(items) - 1) / ((st[-1] - st[0]) / 1e9) if st[-1] > st[0] else 0
    else:
        out["achieved_rtf"] = ((st[-1] - st[0]) / 1e9) / span
        out["sim_rate"] = (len(items) - 1) / ((st[-1] - st[0]) / 1e9)
    return out


def bench_service(domain: int, tmp: Path, repeats: int) -> list:
    from hawt_msgs.srv import ModalAnalysis

    node = Node({"turbine": "paper", "wind": 0.0, "publish_rate": 10.0,
                 "real_time_factor": 0.25}, domain, tmp)
    cli = Client(domain)
    rows = []
    try:
        client = cli.node.create_client(ModalAnalysis, "/modal_analysis")
        if not client.wait_for_service(timeout_sec=60.0):
            raise RuntimeError(f"no service; node log:\n{node.log.read_text()}")
        cli.subscribe_joint_states()
        wait_for(lambda: len(cli.items) > 0, 60)
        t0 = time.monotonic()
        resp, t = cli.call(client, ModalAnalysis.Request(elements=4))
        t1 = time.monotonic()
        with cli.lock:
            times = [i[0] for i in cli.items if t0 <= i[0] <= t1]
        gaps = np.diff([t0] + times + [t1])
        rows.append(("N=4, cold (computed)", t, resp.compute_time, resp.success, len(resp.modes)))
        rows.append((f"  (publishing at 10 Hz meanwhile: {len(times)} msgs, largest gap "
                     f"{gaps.max() * 1e3:.0f} ms)", None, None, None, None))
        for _ in range(repeats):
            resp, t = cli.call(client, ModalAnalysis.Request(elements=4))
            rows.append(("N=4, cached", t, resp.compute_time, resp.success, len(resp.modes)))
        for _ in range(repeats):
            resp, t = cli.call(client, ModalAnalysis.Request(elements=4, method="euler"))
            rows.append(("invalid (method)", t, 0.0, resp.success, 0))
    finally:
        node.stop()
        cli.close()
    return rows


def bench_wind_fast(domain: int, tmp: Path, duration: float, step_deg=None) -> dict:
    """The default node (NREL 5-MW, 15 m/s, ROSCO) as fast as possible: achieved real-time
    factor from the stamps (simulation time) over ``duration`` s of wall time (``step_deg``
    given: at that step)."""
    params = {"real_time_factor": 0.0, "publish_rate": 20.0}
    if step_deg is not None:
        params["step_deg"] = float(step_deg)
    node = Node(params, domain, tmp)
    items, start_up = _collect(node, domain, duration, 120.0)
    mono = np.array([i[0] for i in items])
    st = np.array([i[2] for i in items], float)
    return {"start_up": start_up, "rtf": ((st[-1] - st[0]) / 1e9) / (mono[-1] - mono[0])}


def bench_wind_analyses(domain: int, tmp: Path, count: int = 5) -> dict:
    """The default node at real_time_factor 1, 20 Hz: publishing rate and largest gap before
    and while ``count`` modal analyses (elements 2, 3, ...) are requested at once."""
    from hawt_msgs.srv import ModalAnalysis

    node = Node({"real_time_factor": 1.0, "publish_rate": 20.0}, domain, tmp)
    cli = Client(domain)
    try:
        client = cli.node.create_client(ModalAnalysis, "/modal_analysis")
        cli.subscribe_joint_states()
        if not wait_for(lambda: len(cli.items) > 0, 120) or \
                not client.wait_for_service(timeout_sec=60.0):
            raise RuntimeError(f"no messages or service; node log:\n{node.log.read_text()}")
        n0 = len(cli.items)
        time.sleep(5.0)
        with cli.lock:
            quiet = [i[0] for i in cli.items[n0:]]
        # one analysis at the node's own mesh (elements 0: the turbine file's) first
        t_one = time.monotonic()
        one = client.call_async(ModalAnalysis.Request())
        wait_for(one.done, 900.0)
        one_wall = time.monotonic() - t_one
        one_res = one.result() if one.done() else None
        t0 = time.monotonic()
        futures = [client.call_async(ModalAnalysis.Request(elements=2 + k))
                   for k in range(count)]
        wait_for(lambda: all(f.done() for f in futures), 900.0)
        t1 = time.monotonic()
        ok = sum(1 for f in futures if f.done() and f.result().success)
        with cli.lock:
            busy = [i[0] for i in cli.items if t0 <= i[0] <= t1]
    finally:
        node.stop()
        cli.close()

    def rate(ts):
        return (len(ts) - 1) / (ts[-1] - ts[0]) if len(ts) > 1 else 0.0

    return {"one_wall": one_wall, "one_compute": float(one_res.compute_time) if one_res else
            float("nan"), "one_ok": bool(one_res and one_res.success),
            "one_modes": len(one_res.modes) if one_res else 0,
            "quiet_rate": rate(quiet), "quiet_gap": float(np.diff(quiet).max()) * 1e3,
            "busy_rate": rate(busy), "busy_gap": float(np.diff(busy).max()) * 1e3
            if len(busy) > 1 else float("nan"), "seconds": t1 - t0, "ok": ok, "count": count}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--duration", type=float, default=5.0, help="seconds per configuration")
    ap.add_argument("--configs", nargs="+", default=["10:0.25", "20:0.5", "20:1.0", "20:0"],
                    help="RATE:REAL_TIME_FACTOR pairs")
    ap.add_argument("--step-deg", type=float, default=5.0)
    ap.add_argument("--fake-sim", action="store_true",
                    help="stand-in simulator (1 ms per step): the node's own overhead")
    ap.add_argument("--repeats", type=int, default=5, help="cached/invalid service calls")
    ap.add_argument("--no-service", action="store_true")
    ap.add_argument("--no-wind", action="store_true", help="skip the NREL 5-MW in wind")
    ap.add_argument("--wind-steps", type=float, nargs="*", default=[],
                    help="also run the default node as fast as possible at these step_deg")
    ap.add_argument("--only-wind-steps", action="store_true",
                    help="only the --wind-steps runs")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="hawt-bench-node-"))
    os.environ.setdefault("ROS_LOG_DIR", str(tmp / "roslog"))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    base = (os.getpid() * 7) % 90 + 1
    print(f"hawt-node benchmark ({'stand-in' if args.fake_sim else 'real'} simulator, step "
          f"{args.step_deg:g} deg, {args.duration:g} s per configuration, "
          f"{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f})")
    print(f"{'rate req':>9} {'rtf':>5} {'msgs':>5} {'rate':>7} {'gap max':>8} {'latency med':>12} "
          f"{'p95':>7} {'max':>7} {'sim-time rate / achieved rtf':>30}")
    if args.only_wind_steps:
        for i, step in enumerate(args.wind_steps):
            r = bench_wind_fast(base + i, tmp, max(args.duration, 10.0), step)
            print(f"default node, step_deg {step:g}: real-time factor {r['rtf']:.2f} as fast as "
                  f"possible (first message {r['start_up']:.1f} s)")
        return 0
    for i, cfg in enumerate(args.configs):
        rate, rtf = (float(x) for x in cfg.split(":"))
        r = bench_publishing(rate, rtf, args.duration, base + i, tmp, args.step_deg, args.fake_sim)
        if rtf > 0:
            lat = f"{r['lat_med']:>9.1f} ms {r['lat_p95']:>5.1f} {r['lat_max']:>7.1f}"
            extra = f"{r['sim_rate']:.2f} Hz of stamps"
        else:
            lat = f"{'-':>12} {'-':>7} {'-':>7}"
            extra = f"{r['sim_rate']:.2f} Hz sim / rtf {r['achieved_rtf']:.3f}"
        print(f"{rate:>7.1f}Hz {rtf:>5.2f} {r['n']:>5d} {r['rate']:>5.2f}Hz "
              f"{r['gap_max']:>6.0f}ms {lat} {extra:>30}")
    if not args.no_service:
        print("\nmodal_analysis service (round trip from this process)")
        print(f"{'request':<24}{'latency':>10}{'compute':>10}{'ok':>6}{'modes':>7}")
        rows = bench_service(base + len(args.configs), tmp, args.repeats)
        for name, t, ct, ok, n in rows:
            if t is None:
                print(name)
                continue
            print(f"{name:<24}{t * 1e3:>8.1f}ms{ct:>9.2f}s{str(ok):>6}{n:>7}")
    if not args.no_wind:
        base += len(args.configs) + 1
        print("\nthe default node: NREL 5-MW in 15 m/s under ROSCO (the file's mesh: 3 blade "
              "elements of order 6; its default step_deg)")
        r = bench_wind_fast(base, tmp, max(args.duration, 10.0))
        print(f"  as fast as possible: real-time factor {r['rtf']:.2f} (start-up to the first "
              f"message {r['start_up']:.1f} s)")
        for i, step in enumerate(args.wind_steps):
            r = bench_wind_fast(base + 2 + i, tmp, max(args.duration, 10.0), step)
            print(f"  step_deg {step:g}: real-time factor {r['rtf']:.2f} as fast as possible")
        r = bench_wind_analyses(base + 1, tmp)
        print(f"  the in-wind modal analysis at the node's mesh (one request, elements 0): "
              f"{r['one_wall']:.1f} s round trip, {r['one_compute']:.1f} s compute, success "
              f"{r['one_ok']}, {r['one_modes']} modes")
        print(f"  real_time_factor 1, 20 Hz: {r['quiet_rate']:.1f} Hz (largest gap "
              f"{r['quiet_gap']:.0f} ms); with {r['count']} modal analyses requested at once "
              f"({r['ok']} answered with success in {r['seconds']:.0f} s): {r['busy_rate']:.1f} Hz "
              f"(largest gap {r['busy_gap']:.0f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
