"""ROS-side subcommands of the ``hawt`` console script: ``record``, ``play``, ``info``,
``call`` and ``echo`` (the ``ros2 bag`` / ``ros2 service call`` / ``ros2 topic echo`` a
PyPI-only ROS 2 installation lacks, for hawt's needs).

plus ``recover`` (a finalized copy of a crashed recording, as ``mcap recover`` /
``ros2 bag reindex``).

``hawt`` finds these through the entry-point group ``hawt.commands`` (hawt_ros/commands.py);
this module imports rclpy only inside the commands that talk to ROS (``hawt info`` works with
the MCAP libraries alone).

    hawt record run.mcap [--topics /joint_states ...] [--duration S]
    hawt play run.mcap [--rate R] [--loop] [--wait-for-subscribers S]
    hawt info run.mcap [--json]
    hawt recover run.mcap [-o run-recovered.mcap] [--force] [--json]
    hawt call modes [--elements N] [--rotor-speed W] [--steps K] [--method M] [--json] [--action]
    hawt echo /joint_states [--count K] [--json]
"""
from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
import time
from typing import Any, Dict, List, Optional

__all__ = ["HELP", "build_parser", "main", "message_to_plain", "modes_to_json",
           "format_modes_table"]

from hawt_core.cli.parser import EXIT_USAGE, CliError, Parser

#: name -> one-line help
HELP = {
    "record": "record live ROS 2 topics into an MCAP file (rosbag2 layout)",
    "play": "republish the messages of an MCAP file with their original timing",
    "info": "summarize an MCAP file (topics, types, counts, duration)",
    "recover": "write a finalized copy of a crashed (unfinalized) MCAP recording",
    "call": "call the hawt node's modal_analysis service (or action) and print the modes",
    "echo": "print the messages arriving on a ROS 2 topic",
}

EXIT_FAIL = 1
DEFAULT_IGNORED = ("/rosout", "/parameter_events")


# ============================================================================ helpers
def message_to_plain(msg: Any) -> Any:
    """An rclpy message as nested dicts/lists of plain Python values."""
    if hasattr(msg, "get_fields_and_field_types"):
        return {f: message_to_plain(getattr(msg, f)) for f in msg.get_fields_and_field_types()}
    if isinstance(msg, (list, tuple)):
        return [message_to_plain(v) for v in msg]
    if hasattr(msg, "tolist"):
        return msg.tolist()
    if isinstance(msg, (bytes, bytearray)):
        return list(msg)
    return msg


def _json_default(x):
    if hasattr(x, "tolist"):
        return x.tolist()
    return str(x)


def _num(x: float) -> Optional[float]:
    return float(x) if math.isfinite(float(x)) else None


def modes_to_json(response) -> Dict[str, Any]:
    """A ModalAnalysis response/result as the JSON of ``hawt modes --json`` (keys ``settings``
    and ``modes``; each mode: family, symmetry (null when none), index, frequency_per_rev,
    real_per_rev, frequency_hz, damping_ratio, and with three or more blades (whirl not
    empty) fixed_frame_per_rev, fixed_frame_hz, fixed_frame_damping_ratio, whirl; null
    otherwise, as ``hawt modes --json``)."""
    s = response.settings
    return {
        "settings": {"turbine": s.turbine, "elements": int(s.elements),
                     "order": int(s.order or 1),
                     "rotor_speed": float(s.rotor_speed), "method": s.method,
                     "steps": int(s.steps)},
        "modes": [{"family": m.family, "symmetry": m.symmetry or None, "index": int(m.index),
                   "frequency_per_rev": float(m.frequency_per_rev),
                   "real_per_rev": float(m.real_per_rev),
                   "frequency_hz": float(m.frequency_hz),
                   "damping_ratio": _num(m.damping_ratio),
                   **{k: (_num(getattr(m, k, 0.0)) if getattr(m, "whirl", "") else None)
                      for k in ("fixed_frame_per_rev", "fixed_frame_hz",
                                "fixed_frame_damping_ratio")},
                   "whirl": getattr(m, "whirl", "") or None}
                  for m in response.modes],
        "compute_time": float(response.compute_time),
        "message": response.message,
    }


def format_modes_table(response) -> str:
    """The modes of a response as a table like ``hawt modes`` prints."""
    from hawt_core.model import order_text
    from hawt_core.results.tables import format_table
    st = response.settings
    header = (f"Dominant frequencies of the turbine '{st.turbine}' (Floquet, {st.method}, "
              f"{st.steps} steps/period), {st.elements} elements{order_text(st.order)} per "
              f"blade, rotor speed {st.rotor_speed:.4g} rad/s")
    return format_table(header, response.modes,
                        [f"{response.message}; computed in {response.compute_time:.2f} s"])


class _Stop:
    """SIGINT/SIGTERM -> a flag (the loops below poll it)."""

    def __init__(self):
        self.event = threading.Event()
        self.signum = None
        self._old = {}

    def __enter__(self):
        for s in (signal.SIGINT, signal.SIGTERM):
            self._old[s] = signal.signal(s, self._handler)
        return self

    def _handler(self, signum, _frame):
        self.signum = signum
        self.event.set()

    def __exit__(self, *exc):
        for s, h in self._old.items():
            signal.signal(s, h)

    def __bool__(self):
        return self.event.is_set()


def _ros_init(name: str):
    try:
        import rclpy
        from rclpy.signals import SignalHandlerOptions
    except ImportError as exc:
        raise CliError(f"hawt: ROS 2 (rclpy) is not available in this Python: {exc}; "
                       "run scripts/bootstrap.sh and use .venv/bin/hawt") from None
    rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
    return rclpy, rclpy.create_node(name)


def _ros_done(rclpy, node) -> None:
    try:
        node.destroy_node()
    finally:
        rclpy.try_shutdown()


def _qos_for(node, topic: str, depth: int = 100):
    """A subscription QoS compatible with every publisher of ``topic``."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    infos = node.get_publishers_info_by_topic(topic)
    reliable = all(i.qos_profile.reliability == ReliabilityPolicy.RELIABLE for i in infos) \
        if infos else True
    transient = bool(infos) and all(
        i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos)
    return QoSProfile(depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable
                      else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if transient
                      else DurabilityPolicy.VOLATILE), infos


# ============================================================================ info
def cmd_info(args) -> int:
    from .bag import bag_info, format_bag_info

    try:
        info = bag_info(args.file)
    except FileNotFoundError as exc:
        raise CliError(f"hawt info: {args.file}: no such file or bag folder ({exc})") from None
    if args.json:
        print(json.dumps(info, indent=1, default=_json_default))
    else:
        print(format_bag_info(info))
    return 0


def _info_args(p):
    p.add_argument("file", metavar="FILE.mcap", help="MCAP file or rosbag2 folder")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


# ============================================================================ recover
def cmd_recover(args) -> int:
    from .bag.recover import format_report, recover

    try:
        report = recover(args.file, args.output, overwrite=args.force)
    except (FileNotFoundError, FileExistsError, ValueError, IsADirectoryError) as exc:
        raise CliError(f"hawt recover: {exc}") from None
    if args.json:
        print(json.dumps(report.as_dict(), indent=1))
    else:
        print(format_report(report))
    return 0


def _recover_args(p):
    p.add_argument("file", metavar="FILE.mcap", help="the crashed MCAP file (or bag folder)")
    p.add_argument("--output", "-o", default=None, metavar="OUT.mcap",
                   help="where to write the finalized copy (default: FILE-recovered.mcap "
                        "beside FILE; never FILE itself)")
    p.add_argument("--force", action="store_true", help="overwrite OUT.mcap if it exists")
    p.add_argument("--json", action="store_true", help="print the report as JSON")


# ============================================================================ record
def cmd_record(args) -> int:
    from .bag import BagWriter, DefinitionNotFound, message_class

    wanted = None
    if args.topics:
        wanted = {t if t.startswith("/") else "/" + t for t in args.topics}
    if args.duration is not None and not (args.duration > 0 and math.isfinite(args.duration)):
        raise CliError(f"hawt record: --duration: {args.duration!r} is not allowed; need a "
                       "number of seconds > 0")
    rclpy, node = _ros_init("hawt_record")
    writer = None
    subs: Dict[str, Any] = {}
    skipped: Dict[str, str] = {}
    lock = threading.Lock()
    try:
        try:
            writer = BagWriter(args.output, settings={"recorded_by": "hawt record",
                                                      "topics": sorted(wanted or [])})
        except (OSError, ValueError) as exc:
            raise CliError(f"hawt record: {args.output}: {exc}") from None

        def make_cb(topic: str, type_name: str):
            def cb(data: bytes):
                with lock:
                    if writer is not None and not writer.closed:
                        writer.write_serialized(topic, type_name, data,
                                                log_time=node.get_clock().now().nanoseconds)
            return cb

        def discover():
            for name, types in node.get_topic_names_and_types():
                if name in subs or name in skipped:
                    continue
                if wanted is not None:
                    if name not in wanted:
                        continue
                elif name in DEFAULT_IGNORED or "/_" in name:
                    continue
                type_name = types[0]
                try:
                    cls = message_class(type_name)
                except (ImportError, DefinitionNotFound, ValueError) as exc:
                    skipped[name] = f"type {type_name} not importable ({exc})"
                    print(f"hawt record: skipping {name}: {skipped[name]}", file=sys.stderr)
                    continue
                qos, infos = _qos_for(node, name)
                try:
                    writer.add_topic(name, type_name,
                                     qos=[i.qos_profile for i in infos] or None)
                except Exception as exc:  # noqa: BLE001 - e.g. no .msg definition
                    skipped[name] = f"cannot record type {type_name}: {exc}"
                    print(f"hawt record: skipping {name}: {skipped[name]}", file=sys.stderr)
                    continue
                subs[name] = node.create_subscription(cls, name, make_cb(name, type_name), qos,
                                                      raw=True)
                print(f"hawt record: recording {name} ({type_name})", file=sys.stderr)

        from rclpy.executors import SingleThreadedExecutor

        ex = SingleThreadedExecutor()
        ex.add_node(node)
        t0 = time.monotonic()
        next_discovery = 0.0
        with _Stop() as stop:
            while not stop:
                now = time.monotonic()
                if args.duration is not None and now - t0 >= args.duration:
                    break
                if now >= next_discovery:
                    discover()
                    next_discovery = now + 0.5
                ex.spin_once(timeout_sec=0.05)
        ex.shutdown(timeout_sec=1.0)
    finally:
        with lock:
            if writer is not None:
                writer.close()
        _ros_done(rclpy, node)
    missing = sorted((wanted or set()) - set(subs))
    print(f"hawt record: wrote {writer.message_count} messages on {len(subs)} topics to "
          f"{writer.path}" + (f"; never seen: {', '.join(missing)}" if missing else ""),
          file=sys.stderr)
    return 0


def _record_args(p):
    p.add_argument("output", metavar="FILE.mcap",
                   help="output: a .mcap file, or a rosbag2 folder (any other name)")
    p.add_argument("--topics", nargs="+", metavar="TOPIC", default=None,
                   help="topics to record (default: all but /rosout, /parameter_events and "
                        "hidden ones), subscribed as soon as they are discovered")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="stop after S seconds (default: until Ctrl-C / SIGTERM)")


# ============================================================================ play
def cmd_play(args) -> int:
    from .bag import BagReader, bag_info, message_class

    if not (args.rate > 0 and math.isfinite(args.rate)):
        raise CliError(f"hawt play: --rate: {args.rate!r} is not allowed; need a number > 0")
    try:
        info = bag_info(args.file)
    except FileNotFoundError as exc:
        raise CliError(f"hawt play: {args.file}: no such file ({exc})") from None
    if not info["message_count"]:
        raise CliError(f"hawt play: {args.file} holds no messages")
    rclpy, node = _ros_init("hawt_play")
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
    pubs = {}
    count = 0
    try:
        only = set(args.topics) if args.topics else None
        for topic, t in info["topics"].items():
            if only is not None and topic not in only:
                continue
            try:
                pubs[topic] = node.create_publisher(message_class(t["type"]), topic, qos)
            except Exception as exc:  # noqa: BLE001
                print(f"hawt play: skipping {topic}: type {t['type']} not importable ({exc})",
                      file=sys.stderr)
        with _Stop() as stop:
            if args.wait_for_subscribers:
                deadline = time.monotonic() + args.wait_for_subscribers
                while not stop and time.monotonic() < deadline:
                    if all(p.get_subscription_count() > 0 for p in pubs.values()):
                        # the graph shows a subscriber once this side has discovered it; its
                        # side may match our writers later, and a reliable reader then gets
                        # the first samples repaired in one burst (seen in CI: median gap
                        # 6 ms instead of 50): settle
                        time.sleep(PLAY_SETTLE_S)
                        break
                    time.sleep(0.02)
            while not stop:
                first = None
                start = time.monotonic()
                for item in BagReader(args.file, topics=list(pubs), decode="raw"):
                    if stop:
                        break
                    if first is None:
                        first = item.log_time
                    target = start + (item.log_time - first) / 1e9 / args.rate
                    while not stop:
                        delay = target - time.monotonic()
                        if delay <= 0:
                            break
                        time.sleep(min(delay, 0.05))
                    if stop:
                        break
                    pubs[item.topic].publish(item.message)
                    count += 1
                if not args.loop:
                    break
            # let reliable deliveries finish before the publishers go away
            time.sleep(0.2)
    finally:
        _ros_done(rclpy, node)
    print(f"hawt play: published {count} messages", file=sys.stderr)
    return 0


#: Seconds ``hawt play --wait-for-subscribers`` waits after every topic has a subscriber,
#: for the subscribers' side of the discovery to match the player's writers.
PLAY_SETTLE_S = 0.5


def _play_args(p):
    p.add_argument("file", metavar="FILE.mcap", help="MCAP file or rosbag2 folder")
    p.add_argument("--rate", type=float, default=1.0, help="playback speed factor (default 1)")
    p.add_argument("--loop", action="store_true", help="start again at the end")
    p.add_argument("--topics", nargs="+", metavar="TOPIC", default=None,
                   help="only these topics (default: all)")
    p.add_argument("--wait-for-subscribers", type=float, default=0.0, metavar="S",
                   help="before starting, wait up to S seconds until every topic has a "
                        "subscriber, then 0.5 s for them to match (default: start at once)")


# ============================================================================ call
def cmd_call(args) -> int:
    if args.what != "modes":
        raise CliError(f"hawt call: {args.what!r} is not allowed; choose modes")
    from .params import ParameterError, validate_request

    try:  # same checks as the node (a clear message without a round trip)
        validate_request(rotor_speed=args.rotor_speed, elements=args.elements,
                         steps=args.steps, method=args.method)
    except ParameterError as exc:
        raise CliError(f"hawt call modes: {exc}") from None
    rclpy, node = _ros_init("hawt_call")
    try:
        if args.action:
            resp = _call_action(rclpy, node, args)
        else:
            resp = _call_service(rclpy, node, args)
    finally:
        _ros_done(rclpy, node)
    if resp is None:
        return EXIT_FAIL
    if not resp.success:
        print(f"hawt call modes: the node answered: {resp.message}", file=sys.stderr)
        return EXIT_FAIL
    if args.json:
        print(json.dumps(modes_to_json(resp), indent=1))
    else:
        print(format_modes_table(resp))
    return 0


def _fill_request(req, args):
    req.rotor_speed = float(args.rotor_speed)
    req.elements = int(args.elements)
    req.steps = int(args.steps)
    req.method = args.method
    return req


def _spin_until(rclpy, node, fut, stop, timeout: Optional[float]) -> bool:
    deadline = None if timeout is None else time.monotonic() + timeout
    while not fut.done() and not stop:
        if deadline is not None and time.monotonic() > deadline:
            return False
        rclpy.spin_once(node, timeout_sec=0.05)
    return fut.done()


def _call_service(rclpy, node, args):
    from hawt_msgs.srv import ModalAnalysis

    client = node.create_client(ModalAnalysis, args.service)
    if not client.wait_for_service(timeout_sec=args.wait):
        print(f"hawt call modes: service {args.service} not available after {args.wait:g} s "
              "(is hawt-node running, with the same ROS_DOMAIN_ID?)", file=sys.stderr)
        return None
    fut = client.call_async(_fill_request(ModalAnalysis.Request(), args))
    with _Stop() as stop:
        ok = _spin_until(rclpy, node, fut, stop, args.timeout)
    if not ok:
        print("hawt call modes: " + ("interrupted" if fut and not fut.done() and stop
                                     else f"no answer within {args.timeout:g} s"),
              file=sys.stderr)
        return None
    return fut.result()


def _call_action(rclpy, node, args):
    from rclpy.action import ActionClient
    from hawt_msgs.action import ModalAnalysis

    client = ActionClient(node, ModalAnalysis, args.service)
    if not client.wait_for_server(timeout_sec=args.wait):
        print(f"hawt call modes: action {args.service} not available after {args.wait:g} s",
              file=sys.stderr)
        return None
    goal = _fill_request(ModalAnalysis.Goal(), args)

    def feedback(msg):
        fb = msg.feedback
        print(f"[{100 * fb.progress:5.1f} %] {fb.stage}", file=sys.stderr)

    with _Stop() as stop:
        fut = client.send_goal_async(goal, feedback_callback=feedback)
        if not _spin_until(rclpy, node, fut, stop, args.wait) or not fut.result().accepted:
            print("hawt call modes: the goal was not accepted", file=sys.stderr)
            return None
        handle = fut.result()
        res_fut = handle.get_result_async()
        ok = _spin_until(rclpy, node, res_fut, stop, args.timeout)
        if not ok:
            print("hawt call modes: cancelling the analysis", file=sys.stderr)
            cfut = handle.cancel_goal_async()
            stop.event.clear()
            _spin_until(rclpy, node, cfut, stop, 5.0)
            _spin_until(rclpy, node, res_fut, stop, 5.0)
            if not res_fut.done():
                return None
    return res_fut.result().result


def _call_args(p):
    p.add_argument("what", metavar="modes", help="what to call: modes (the modal analysis)")
    p.add_argument("--elements", "-n", type=int, default=0, metavar="N",
                   help="beam elements per blade (default 0: the node's)")
    p.add_argument("--rotor-speed", type=float, default=0.0, metavar="RAD_PER_S",
                   help="rotor speed [rad/s] (default 0: the turbine's nominal speed)")
    p.add_argument("--steps", type=int, default=0, metavar="K",
                   help="marching steps per period (default 0: the method's default)")
    p.add_argument("--method", default="", metavar="M",
                   help="radau or paper (default '': radau)")
    p.add_argument("--json", action="store_true",
                   help="print the JSON of `hawt modes --json` instead of a table")
    p.add_argument("--action", action="store_true",
                   help="use the modal_analysis action: progress on stderr, Ctrl-C cancels")
    p.add_argument("--service", default="/modal_analysis", help="service/action name")
    p.add_argument("--wait", type=float, default=10.0, metavar="S",
                   help="wait up to S seconds for the node (default 10)")
    p.add_argument("--timeout", type=float, default=600.0, metavar="S",
                   help="give up after S seconds (default 600)")


# ============================================================================ echo
def cmd_echo(args) -> int:
    import yaml
    from .bag import message_class

    topic = args.topic if args.topic.startswith("/") else "/" + args.topic
    if args.count is not None and args.count < 1:
        raise CliError(f"hawt echo: --count: {args.count} is not allowed; need an integer >= 1")
    rclpy, node = _ros_init("hawt_echo")
    received = 0
    try:
        with _Stop() as stop:
            type_name = None
            deadline = time.monotonic() + args.wait
            while not stop and type_name is None:
                for name, types in node.get_topic_names_and_types():
                    if name == topic:
                        type_name = types[0]
                if type_name is None:
                    if time.monotonic() > deadline:
                        print(f"hawt echo: topic {topic} not found after {args.wait:g} s",
                              file=sys.stderr)
                        return EXIT_FAIL
                    rclpy.spin_once(node, timeout_sec=0.1)
            if stop:
                return 0
            cls = message_class(type_name)
            qos, _ = _qos_for(node, topic, depth=10)
            out = sys.stdout

            def cb(msg):
                nonlocal received
                if args.count is not None and received >= args.count:
                    return
                received += 1
                plain = message_to_plain(msg)
                if args.json:
                    out.write(json.dumps(plain, default=_json_default) + "\n")
                else:
                    out.write(yaml.safe_dump(plain, sort_keys=False, default_flow_style=None))
                    out.write("---\n")
                out.flush()

            node.create_subscription(cls, topic, cb, qos)
            while not stop and (args.count is None or received < args.count):
                rclpy.spin_once(node, timeout_sec=0.1)
    finally:
        _ros_done(rclpy, node)
    return 0


def _echo_args(p):
    p.add_argument("topic", metavar="TOPIC")
    p.add_argument("--count", type=int, default=None, metavar="K",
                   help="exit after K messages (default: until Ctrl-C)")
    p.add_argument("--json", action="store_true", help="one JSON object per line")
    p.add_argument("--wait", type=float, default=10.0, metavar="S",
                   help="wait up to S seconds for the topic to appear (default 10)")


# ============================================================================ main
_RUN = {"record": (cmd_record, _record_args), "play": (cmd_play, _play_args),
        "info": (cmd_info, _info_args), "recover": (cmd_recover, _recover_args),
        "call": (cmd_call, _call_args),
        "echo": (cmd_echo, _echo_args)}


def build_parser(prog: str = "hawt") -> argparse.ArgumentParser:
    parser = Parser(prog=prog, description="ROS 2 tools of hawt")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for name, help_text in HELP.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        _RUN[name][1](p)
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    """``argv``: e.g. ``["record", "out.mcap", "--duration", "5"]``."""
    parser = build_parser()
    try:
        args = parser.parse_args(sys.argv[1:] if argv is None else list(argv))
        if args.command is None:
            parser.print_help()
            return EXIT_USAGE
        return int(_RUN[args.command][0](args) or 0)
    except CliError as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("hawt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `hawt echo ... | head`
        try:
            sys.stdout = open(__import__("os").devnull, "w")
        except OSError:
            pass
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
