"""A subscriber in a process of its own, for tests that judge timing (run as a script by
the venv's python; not a test module).

    python tests/ros_listener.py OUT.jsonl TOPIC=TYPE:COUNT [TOPIC=TYPE:COUNT ...] [--timeout S]

Subscribes to each TOPIC (TYPE: ``sensor_msgs/msg/JointState`` or any installed message
type) on the ROS_DOMAIN_ID of its environment, prints ``ready`` on stdout once every
subscription exists, and spins with ``rclpy.spin_once`` (one thread, nothing else to do:
the receive times are the middleware's delivery times, not those of a test process's
executor thread competing with the test) until each topic has received COUNT messages or
the timeout passes.  Then it writes one JSON line per message, in arrival order:
``{"topic", "t": monotonic receive time [s], "msg": the message as a dict}``, and exits 0
(1 if it timed out; the lines received are written all the same).
"""
from __future__ import annotations

import argparse
import importlib
import json
import sys
import time


def _message_class(type_name: str):
    pkg, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)


def _as_dict(value):
    """A message as plain JSON-able data (its fields by name, arrays as lists)."""
    if hasattr(value, "get_fields_and_field_types"):
        return {k: _as_dict(getattr(value, k)) for k in value.get_fields_and_field_types()}
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        return [_as_dict(v) for v in list(value)]
    if isinstance(value, bytes):
        return list(value)
    return value


def main(argv=None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("subs", nargs="+", metavar="TOPIC=TYPE:COUNT")
    p.add_argument("--timeout", type=float, default=30.0)
    args = p.parse_args(argv)

    import rclpy
    from rclpy.qos import QoSProfile

    rclpy.init()
    node = rclpy.create_node("hawt_test_listener")
    received, wanted = [], {}
    for spec in args.subs:
        topic, rest = spec.split("=", 1)
        type_name, count = rest.rsplit(":", 1)
        wanted[topic] = int(count)

        def cb(msg, topic=topic):
            received.append((topic, time.monotonic(), msg))
        node.create_subscription(_message_class(type_name), topic, cb, QoSProfile(depth=1000))
    print("ready", flush=True)
    deadline = time.monotonic() + args.timeout

    def done():
        counts = {t: 0 for t in wanted}
        for t, _, _ in received:
            counts[t] += 1
        return all(counts[t] >= n for t, n in wanted.items())

    while not done() and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    with open(args.out, "w") as f:
        for topic, t, msg in received:
            f.write(json.dumps({"topic": topic, "t": t,
                                "msg": _as_dict(msg)}) + "\n")
    ok = done()
    node.destroy_node()
    rclpy.try_shutdown()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
