"""Benchmark of the MCAP recorder (hawt_ros.bag.BagWriter): messages per second and MB/s for
what the node records per published instant (one JointState, one BladeDeflection per blade,
one MarkerArray), pre-serialized as the node does, with zstd chunks; and the read-back rate
of BagReader (rclpy decoding) and bag_info (summary).

    .venv/bin/python bench/bag.py                  # ~10 s
    .venv/bin/python bench/bag.py --instants 20000 --blades 3 --elements 8
    .venv/bin/python bench/bag.py --writer PATH    # also time another module with a BagWriter
                                                   # (e.g. an older version) in the same run

Run through scripts/test.sh's environment (ROS wheels in .venv).
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from pathlib import Path

from geometry_msgs.msg import Point, Vector3
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from hawt_msgs.msg import BladeDeflection
from hawt_ros.bag import BagReader, BagWriter, bag_info, serialize, type_name_of

T0 = 1_700_000_000_000_000_000


def instant_messages(blades: int, elements: int):
    """[(topic, type, CDR bytes)] of one published instant."""
    js = JointState(header=Header(), name=["yaw", "teeter", "rotor_azimuth"],
                    position=[0.1, 0.02, 1.0], velocity=[0.0, 0.1, 6.0], effort=[1.0, 2.0, 3.0])
    out = [("/joint_states", js)]
    span = [i / elements for i in range(elements + 1)]
    for k in range(blades):
        out.append(("/blade_deflections", BladeDeflection(
            blade=k, span=span, displacement=[Vector3(x=0.1, y=0.2, z=0.3)] * (elements + 1),
            rotation=[Vector3(x=0.01, y=0.02, z=0.03)] * (elements + 1))))
    ma = MarkerArray(markers=[Marker(id=k, type=Marker.LINE_STRIP,
                                     points=[Point(x=1.0, y=2.0, z=3.0)] * (elements + 1))
                              for k in range(blades)])
    out.append(("/blade_markers", ma))
    return [(topic, type_name_of(m), serialize(m)) for topic, m in out]


def time_writer(writer_class, path: Path, instants: int, messages) -> dict:
    t = time.perf_counter()
    w = writer_class(path, turbine_yaml="name: bench\n")
    for i in range(instants):
        stamp = T0 + i * 50_000_000
        for topic, type_name, data in messages:
            w.write_serialized(topic, type_name, data, log_time=stamp)
    w.close()
    wall = time.perf_counter() - t
    n = instants * len(messages)
    raw = instants * sum(len(d) for _, _, d in messages)
    return {"wall": wall, "messages": n, "msg_per_s": n / wall, "MB_per_s": raw / wall / 1e6,
            "file_MB": path.stat().st_size / 1e6}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--instants", type=int, default=5000)
    ap.add_argument("--blades", type=int, default=2)
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--writer", default=None, help="a .py file defining BagWriter, timed too")
    args = ap.parse_args()
    messages = instant_messages(args.blades, args.elements)
    writers = [("hawt_ros.bag", BagWriter)]
    if args.writer:
        spec = importlib.util.spec_from_file_location("other_writer", args.writer)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod           # dataclasses look their module up
        spec.loader.exec_module(mod)
        writers.append((Path(args.writer).name, mod.BagWriter))
    print(f"{args.instants} instants x {len(messages)} messages ({args.blades} blades, "
          f"{args.elements} elements), {sum(len(d) for _, _, d in messages)} bytes per instant")
    print(f"{'writer':<20} {'wall s':>8} {'msg/s':>10} {'MB/s':>7} {'file MB':>8}")
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(2):                   # the second round is the one that counts
            for name, cls in writers:
                r = time_writer(cls, Path(tmp) / f"{name}-{rep}.mcap", args.instants, messages)
                if rep:
                    print(f"{name:<20} {r['wall']:8.2f} {r['msg_per_s']:10.0f} "
                          f"{r['MB_per_s']:7.1f} {r['file_MB']:8.2f}")
        path = Path(tmp) / "hawt_ros.bag-1.mcap"
        t = time.perf_counter()
        count = sum(1 for _ in BagReader(path, decode="rclpy"))
        read = time.perf_counter() - t
        t = time.perf_counter()
        info = bag_info(path)
        summary = time.perf_counter() - t
        print(f"BagReader (rclpy): {count / read:.0f} msg/s; bag_info: {summary * 1e3:.1f} ms "
              f"({info['chunks']} chunks, finalized {info['finalized']})")


if __name__ == "__main__":
    main()
