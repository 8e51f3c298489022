"""hawt_msgs interfaces and the MCAP layer (hawt_ros/bag.py).

These need the ROS 2 wheels and the built msg_defs/hawt_msgs package, which
scripts/bootstrap.sh installs. Without rclpy they are skipped with the reason, unless
HAWT_REQUIRE_ROS=1 (set by scripts/test.sh and so in CI), where a missing ROS is an error.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import yaml

from ros_support import require_ros

pytestmark = pytest.mark.ros

try:
    import rclpy  # noqa: F401
    from rclpy.serialization import deserialize_message, serialize_message

    from geometry_msgs.msg import Point, Vector3
    from hawt_msgs.action import ModalAnalysis as ModalAnalysisAction
    from hawt_msgs.msg import AnalysisSettings, BladeDeflection, Mode, ModeShape
    from hawt_msgs.srv import ModalAnalysis
    from sensor_msgs.msg import JointState
    from visualization_msgs.msg import Marker, MarkerArray
    _ROS_ERROR = None
except Exception as exc:  # ImportError, or a missing shared library of the ROS wheels
    _ROS_ERROR = (f"{type(exc).__name__}: {exc}; the ROS tests need the venv that "
                  "scripts/bootstrap.sh sets up")
require_ros(_ROS_ERROR)      # skips the module, or fails it when HAWT_REQUIRE_ROS=1

from hawt_ros import bag  # noqa: E402
from hawt_ros.bag import serialization as bag_serialization  # noqa: E402
from hawt_ros.bag import writer as bag_writer  # noqa: E402
from hawt_ros.bag import BagReader, BagWriter, bag_info, format_bag_info  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
T0 = 1_700_000_000_000_000_000  # ns
DT = 10_000_000                  # 10 ms
N_STEPS = 40
TURBINE_YAML = "name: test turbine\nblades: 2\n"


# ----------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------

def stamp(msg, t_ns):
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t_ns, 1_000_000_000)
    return msg


def joint_state(i, t):
    # Odd steps have empty float64[] arrays: the case rclpy serializes with extra padding.
    return stamp(JointState(name=["yaw", "teeter"], position=[0.01 * i, -0.02 * i],
                            velocity=[] if i % 2 else [1.0, 2.0], effort=[]), t)


def blade_deflection(i, b, t, stations=5):
    n = 0 if i == 3 else stations  # one message with all arrays empty
    d = BladeDeflection(
        blade=b,
        span=[float(j) for j in range(n)],
        displacement=[Vector3(x=0.0, y=0.001 * i * j, z=0.01 * i * j + b) for j in range(n)],
        rotation=[Vector3(x=1e-3 * j, y=0.0, z=-1e-3 * i) for j in range(n)],
        root_force=Vector3(x=100.0 * i, y=1.0, z=-2.0),
        root_moment=Vector3(x=0.0, y=50.0 * b, z=3.0),
    )
    d.header.frame_id = f"blade_{b}_root"
    return stamp(d, t)


def marker_array(i, t):
    markers = []
    for k in range(3):
        m = Marker(id=k, type=Marker.LINE_STRIP, action=Marker.ADD, ns="blades",
                   points=[Point(x=float(j), y=0.1 * i, z=float(k)) for j in range(4)])
        m.header.frame_id = "hub"
        m.scale.x = 0.05
        m.color.a = 1.0
        markers.append(stamp(m, t))
    return MarkerArray(markers=markers)


def mode(i):
    return Mode(family="flap", symmetry="anti-symmetric", index=i + 1,
                frequency_per_rev=7.321 + i, real_per_rev=-0.01, frequency_hz=1.2,
                damping_ratio=0.002,
                shape=ModeShape(blades=2, span=[] if i == 0 else [0.0, 1.0],
                                displacement_real=[Vector3(z=1.0)] * (0 if i == 0 else 4),
                                displacement_imag=[Vector3()] * (0 if i == 0 else 4),
                                teeter_real=0.5))


def expected_messages():
    """(topic, type, log_time, msg) in the order written."""
    out = []
    for i in range(N_STEPS):
        t = T0 + i * DT
        out.append(("/joint_states", "sensor_msgs/msg/JointState", t, joint_state(i, t)))
        for b in range(2):
            out.append((f"/blade_{b}/deflection", "hawt_msgs/msg/BladeDeflection", t + 1 + b,
                        blade_deflection(i, b, t)))
        out.append(("/markers", "visualization_msgs/msg/MarkerArray", t + 3,
                    marker_array(i, t)))
        if i < 3:
            out.append(("/modes", "hawt_msgs/msg/Mode", t + 4, mode(i)))
    return out


def write_bag(path, messages, **kw):
    kw.setdefault("chunk_size", 4096)  # several chunks
    with BagWriter(path, turbine_yaml=TURBINE_YAML,
                   settings={"rotor_speed": 4.19, "elements": 8, "method": "radau"},
                   **kw) as w:
        for topic, _type, t, msg in messages:
            w.write(topic, msg, t)
    return path


def rosbags_read(path):
    """All messages through rosbags (independent reader), types registered from the
    definitions stored in the file itself."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    out = []
    with Reader(path) as reader:
        for conn in reader.connections:
            if conn.msgtype not in store.types:
                store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        for conn, t, raw in reader.messages():
            out.append((conn.topic, conn.msgtype, t, store.deserialize_cdr(raw, conn.msgtype)))
        connections = {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}
    return out, connections


def run_child(code, *args, env_extra=None):
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.update(env_extra or {})
    return subprocess.Popen([sys.executable, "-u", "-c", textwrap.dedent(code), *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            cwd=str(REPO))


def wait_for_line(proc, prefix, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            if proc.poll() is not None:
                raise AssertionError(f"child exited ({proc.returncode}): {proc.stderr.read()}")
            continue
        if line.startswith(prefix):
            return line.strip()
    raise AssertionError(f"no line {prefix!r} from the child within {timeout} s")


# ----------------------------------------------------------------------------------------
# interfaces
# ----------------------------------------------------------------------------------------

def test_interfaces_import_and_roundtrip():
    msgs = [
        blade_deflection(1, 1, T0),
        blade_deflection(3, 0, T0),  # empty arrays
        mode(1),
        AnalysisSettings(turbine="paper", rotor_speed=4.19, elements=8, steps=360,
                         method="radau"),
        ModalAnalysis.Request(rotor_speed=float("nan"), elements=0, steps=0, method=""),
        ModalAnalysis.Response(success=True, message="ok", modes=[mode(0), mode(1)],
                               settings=AnalysisSettings(turbine="paper"), compute_time=1.5),
        ModalAnalysisAction.Goal(rotor_speed=4.19, elements=6),
        ModalAnalysisAction.Result(success=False, message="cancelled"),
        ModalAnalysisAction.Feedback(progress=0.25, stage="monodromy"),
    ]
    for msg in msgs:
        back = deserialize_message(serialize_message(msg), type(msg))
        if isinstance(msg, ModalAnalysis.Request):
            assert math.isnan(back.rotor_speed)
            continue
        assert back == msg, type(msg)
    # defaults of the request mean "node default"
    req = ModalAnalysis.Request()
    assert (req.rotor_speed, req.elements, req.steps, req.method) == (0.0, 0, 0, "")
    # the action's generated service/message types exist (rclpy.action needs them)
    assert ModalAnalysisAction.Impl.SendGoalService and ModalAnalysisAction.Impl.FeedbackMessage
    assert bag.type_name_of(ModalAnalysisAction.Feedback()) == \
        "hawt_msgs/action/ModalAnalysis_Feedback"


def test_rclpy_action_module_imports():
    import rclpy.action  # noqa: F401 - needs action_msgs/unique_identifier_msgs at run time


def test_message_definition_text():
    text = bag.message_definition("hawt_msgs/msg/BladeDeflection")
    own = (REPO / "msg_defs/hawt_msgs/msg/BladeDeflection.msg").read_text()
    assert text.startswith(own.rstrip("\n"))
    sep = "=" * 80
    for dep in ("std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Vector3"):
        assert text.count(f"{sep}\nMSG: {dep}\n") == 1, dep
    # services' and actions' parts are messages too
    resp = bag.message_definition("hawt_msgs/srv/ModalAnalysis_Response")
    assert "MSG: hawt_msgs/Mode\n" in resp and "MSG: hawt_msgs/ModeShape\n" in resp
    assert bag.message_definition("hawt_msgs/action/ModalAnalysis_Feedback").startswith(
        "# Feedback")
    h = bag.type_hash("sensor_msgs/msg/JointState")
    assert h is not None and h.startswith("RIHS01_") and len(h) == 7 + 64
    assert bag.type_hash("hawt_msgs/msg/BladeDeflection").startswith("RIHS01_")


def test_serialize_is_readable_by_rosbags_where_rclpy_pads():
    """rclpy pads empty float64[]: rosbags rejects that; bag.serialize does not."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    cases = [joint_state(1, T0), blade_deflection(3, 0, T0), mode(0),
             JointState(name=["a"], position=[], velocity=[], effort=[])]
    for msg in cases:
        tn = bag.type_name_of(msg)
        if tn not in store.types:
            store.register(get_types_from_msg(bag.message_definition(tn), tn))
        data = bag.serialize(msg)
        assert deserialize_message(data, type(msg)) == msg
        decoded = store.deserialize_cdr(data, tn)  # raises on a size mismatch
        if isinstance(msg, JointState):
            assert list(decoded.name) == list(msg.name)
            assert list(decoded.position) == list(msg.position)
    # messages without empty 8-byte sequences keep rclpy's own bytes
    full = JointState(name=["a"], position=[1.0], velocity=[2.0], effort=[3.0])
    assert not bag_serialization._has_empty_8byte_sequence(full)
    assert bag_serialization._has_empty_8byte_sequence(joint_state(0, T0))  # effort=[]
    assert len(bag.serialize(full)) == len(serialize_message(full))


# ----------------------------------------------------------------------------------------
# bags
# ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def written_bag(tmp_path_factory):
    messages = expected_messages()
    path = write_bag(tmp_path_factory.mktemp("bag") / "run.mcap", messages)
    return path, messages


def _check_same(read, messages, compare):
    assert len(read) == len(messages)
    times = [t for _, _, t, _ in read]
    assert times == sorted(times), "log times must be monotonic"
    for (topic, tn, t, msg), (etopic, etn, et, emsg) in zip(read, messages, strict=True):
        assert (topic, tn, t) == (etopic, etn, et)
        compare(msg, emsg)


def test_bag_read_back_by_mcap_ros2(written_bag):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path, messages = written_bag
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        read = [(channel.topic, schema.name, message.log_time, decoded)
                for schema, channel, message, decoded in reader.iter_decoded_messages()]

    def compare(got, exp):
        if isinstance(exp, JointState):
            assert list(got.name) == list(exp.name)
            assert list(got.position) == list(exp.position)
            assert list(got.velocity) == list(exp.velocity)
        elif isinstance(exp, BladeDeflection):
            assert got.blade == exp.blade and got.header.frame_id == exp.header.frame_id
            assert list(got.span) == list(exp.span)
            assert [(v.x, v.y, v.z) for v in got.displacement] == \
                [(v.x, v.y, v.z) for v in exp.displacement]
            assert got.root_force.x == exp.root_force.x
        elif isinstance(exp, MarkerArray):
            assert [m.id for m in got.markers] == [m.id for m in exp.markers]
            assert [p.y for p in got.markers[2].points] == [p.y for p in exp.markers[2].points]
        else:
            assert got.index == exp.index and got.shape.teeter_real == exp.shape.teeter_real

    _check_same(read, messages, compare)


def test_bag_read_back_by_rosbags(written_bag):
    path, messages = written_bag
    read, connections = rosbags_read(path)
    counts = {}
    for topic, tn, _, _ in messages:
        counts[topic] = (tn, counts.get(topic, (tn, 0))[1] + 1)
    assert connections == counts

    def compare(got, exp):
        if isinstance(exp, JointState):
            assert list(got.position) == list(exp.position)
            assert list(got.velocity) == list(exp.velocity)
            assert (got.header.stamp.sec, got.header.stamp.nanosec) == \
                (exp.header.stamp.sec, exp.header.stamp.nanosec)
        elif isinstance(exp, BladeDeflection):
            assert list(got.span) == list(exp.span)
            assert [v.z for v in got.rotation] == [v.z for v in exp.rotation]
            assert got.root_moment.y == exp.root_moment.y
        elif isinstance(exp, MarkerArray):
            assert len(got.markers) == 3 and got.markers[1].points[3].x == 3.0
        else:
            assert got.frequency_per_rev == exp.frequency_per_rev
            assert list(got.shape.span) == list(exp.shape.span)

    _check_same(read, messages, compare)


def test_bag_read_back_by_bagreader(written_bag):
    path, messages = written_bag
    reader = BagReader(path)
    read = [tuple(m) for m in reader]
    def compare(got, exp):
        assert type(got) is type(exp) and got == exp

    _check_same(read, messages, compare)
    assert reader.finalized and not reader.truncated
    assert reader.attachments["turbine.yaml"].decode() == TURBINE_YAML
    assert reader.metadata["hawt"] == {"rotor_speed": "4.19", "elements": "8",
                                       "method": "radau"}
    # decoding without rclpy classes (schema-driven) gives the same values
    dyn = [m for m in BagReader(path, topics=["/joint_states"], decode="dynamic")]
    assert [list(m.message.position) for m in dyn] == \
        [list(m.position) for _, _, _, m in messages if isinstance(m, JointState)]


def test_rosbag2_records(written_bag):
    """Profile, schemas, channel metadata and the 'rosbag2' metadata record as rosbag2's
    MCAP storage plugin writes them."""
    from mcap.reader import make_reader

    path, messages = written_bag
    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        for ch in summary.channels.values():
            schema = summary.schemas[ch.schema_id]
            assert ch.message_encoding == "cdr"
            assert schema.encoding == "ros2msg"
            assert schema.name.count("/") == 2
            assert schema.data.decode() == bag.message_definition(schema.name)
            qos = yaml.safe_load(ch.metadata["offered_qos_profiles"])
            assert qos[0]["reliability"] == "reliable" and qos[0]["depth"] == 10
            assert ch.metadata["topic_type_hash"] == bag.type_hash(schema.name)
        assert {c.compression for c in summary.chunk_indexes} == {"zstd"}
        assert len(summary.chunk_indexes) > 3
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    info = yaml.safe_load(metadata["rosbag2"]["serialized_metadata"])
    info = info["rosbag2_bagfile_information"]
    assert info["storage_identifier"] == "mcap" and info["version"] == 9
    assert info["message_count"] == len(messages)
    assert info["starting_time"]["nanoseconds_since_epoch"] == T0
    counts = {t["topic_metadata"]["name"]: t["message_count"]
              for t in info["topics_with_message_count"]}
    assert counts["/blade_1/deflection"] == N_STEPS and counts["/modes"] == 3


def test_bag_info(written_bag):
    path, messages = written_bag
    info = bag_info(path)
    assert info["finalized"] and not info["truncated"]
    assert info["message_count"] == len(messages)
    assert info["topics"]["/markers"] == {
        "type": "visualization_msgs/msg/MarkerArray", "count": N_STEPS,
        "type_hash": bag.type_hash("visualization_msgs/msg/MarkerArray"),
        "message_encoding": "cdr"}
    assert info["start_time"] == T0
    assert info["end_time"] == T0 + (N_STEPS - 1) * DT + 3
    assert info["duration"] == pytest.approx(((N_STEPS - 1) * DT + 3) / 1e9)
    assert info["attachments"] == ["turbine.yaml"]
    text = format_bag_info(info)
    assert "/blade_0/deflection" in text and "hawt_msgs/msg/BladeDeflection" in text


def test_bag_folder_layout(tmp_path):
    """A path without .mcap is a rosbag2 folder (<name>_0.mcap + metadata.yaml)."""
    messages = expected_messages()[:20]
    folder = tmp_path / "bag_folder"
    write_bag(folder, messages, compression="lz4")
    assert (folder / "bag_folder_0.mcap").is_file()
    meta = yaml.safe_load((folder / "metadata.yaml").read_text())
    assert meta["rosbag2_bagfile_information"]["relative_file_paths"] == ["bag_folder_0.mcap"]
    read, _ = rosbags_read(folder)
    assert [(t, tn, lt) for t, tn, lt, _ in read] == [(t, tn, lt) for t, tn, lt, _ in messages]
    assert bag_info(folder)["compression"] == ["lz4"]
    assert len(list(BagReader(folder))) == len(messages)


def test_truncated_file_recovers_complete_chunks(written_bag, tmp_path):
    """Cutting a file anywhere loses at most the chunk being cut (and what follows)."""
    path, _ = written_bag
    data = path.read_bytes()
    full = [(m.topic, m.log_time) for m in BagReader(path, decode="raw")]
    previous = 0
    for cut in (len(data) // 7, len(data) // 3, len(data) // 2, len(data) - 100, len(data) - 1):
        cut_path = tmp_path / f"cut_{cut}.mcap"
        cut_path.write_bytes(data[:cut])
        reader = BagReader(cut_path, decode="raw")
        got = [(m.topic, m.log_time) for m in reader]
        assert got == full[: len(got)]
        assert reader.truncated
        if cut < len(data) - 40:  # the footer (and magic) are the last 37 bytes
            assert not reader.finalized
        assert len(got) >= previous
        previous = len(got)
        info = bag_info(cut_path)
        assert info["message_count"] == len(got) and info["truncated"]
    assert previous == len(full)  # cut in the summary: all messages are there


WRITER_CHILD = """
import sys, time
from hawt_ros.bag import BagWriter
from sensor_msgs.msg import JointState
path, mode = sys.argv[1], sys.argv[2]
w = BagWriter(path, chunk_size=2048, chunk_interval=0.3, turbine_yaml="name: t\\n")
if mode == "sigterm":
    import signal
    def handler(signum, frame):
        w.close()
        sys.exit(0)
    signal.signal(signal.SIGTERM, handler)
def js(i):
    return JointState(name=["yaw"], position=[float(i)], velocity=[1.0], effort=[2.0])
T0 = 1_700_000_000_000_000_000
for i in range(200):                       # many chunks closed by size
    w.write("/joint_states", js(i), T0 + i)
time.sleep(1.0)                            # the open chunk is closed by age
print("SAFE 200", flush=True)
i = 200
while True:                                # keep writing until killed
    w.write("/joint_states", js(i), T0 + i)
    i += 1
    if i == 205:
        print("WRITING", flush=True)
    if mode == "exit" and i == 300:
        sys.exit(0)                        # no close(): the atexit hook finalizes
    time.sleep(0.001)
"""


def killed_writer(path):
    """Run WRITER_CHILD into ``path`` and SIGKILL it while it writes."""
    proc = run_child(WRITER_CHILD, path, "kill")
    try:
        wait_for_line(proc, "WRITING")
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    return path


def test_sigkill_keeps_all_but_the_last_chunk(tmp_path):
    path = killed_writer(tmp_path / "killed.mcap")
    reader = BagReader(path)
    got = [(m.log_time, list(m.message.position)) for m in reader]
    assert not reader.finalized
    assert len(got) >= 200
    assert got == [(T0 + i, [float(i)]) for i in range(len(got))]
    info = bag_info(path)
    assert not info["finalized"]
    assert info["topics"]["/joint_states"]["count"] == len(got)
    assert info["start_time"] == T0 and info["end_time"] == T0 + len(got) - 1
    assert info["attachments"] == ["turbine.yaml"]


def test_close_from_signal_handler_finalizes(tmp_path):
    path = tmp_path / "sigterm.mcap"
    proc = run_child(WRITER_CHILD, path, "sigterm")
    try:
        wait_for_line(proc, "WRITING")
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) == 0, proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
    info = bag_info(path)
    assert info["finalized"] and info["message_count"] >= 205
    read, _ = rosbags_read(path)
    assert [t for _, _, t, _ in read] == [T0 + i for i in range(len(read))]
    assert len(read) == info["message_count"]


def test_atexit_finalizes(tmp_path):
    path = tmp_path / "atexit.mcap"
    proc = run_child(WRITER_CHILD, path, "exit")
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    info = bag_info(path)
    assert info["finalized"] and info["message_count"] == 300
    assert "rosbag2" in info["metadata"]


def test_writer_api_edges(tmp_path):
    path = tmp_path / "edges.mcap"
    w = BagWriter(path, chunk_interval=None)
    w.add_topic("/deflection", "hawt_msgs/BladeDeflection")  # short type names are accepted
    with pytest.raises(ValueError):
        w.write("/deflection", JointState())  # a topic keeps its type
    w.write_serialized("/deflection", "hawt_msgs/msg/BladeDeflection",
                       bag.serialize(blade_deflection(1, 0, T0)), T0)
    w.write("/settings", AnalysisSettings(turbine="x"))  # default log time: wall clock
    w.close()
    w.close()  # idempotent
    assert w.closed
    with pytest.raises(ValueError):
        w.write("/settings", AnalysisSettings())
    info = bag_info(path)
    assert info["topics"]["/deflection"]["count"] == 1
    assert info["topics"]["/settings"]["count"] == 1
    with pytest.raises(FileExistsError):
        BagWriter(tmp_path)  # a non-empty folder is never overwritten


def test_crcs_and_indexes_valid(written_bag):
    """Chunk CRCs, summary CRC and the message indexes agree with the data."""
    from mcap.reader import make_reader
    from mcap.stream_reader import StreamReader

    path, messages = written_bag
    with open(path, "rb") as f:
        records = list(StreamReader(f, validate_crcs=True).records)
    assert sum(type(r).__name__ == "Message" for r in records) == len(messages)
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        # indexed reading by topic and time range uses chunk and message indexes
        got = [m.log_time for _, _, m in reader.iter_messages(topics=["/markers"],
                                                                starting_at=T0 + 10 * DT,
                                                                ending_before=T0 + 20 * DT)]
    assert got == [T0 + i * DT + 3 for i in range(10, 20)]


def test_exception_during_chunk_write_leaves_consistent_file(tmp_path, monkeypatch):
    """A KeyboardInterrupt raised while a chunk is written (e.g. by a signal handler) must
    neither lose nor duplicate messages once the writer is closed."""
    path = tmp_path / "interrupted.mcap"
    w = BagWriter(path, chunk_size=1 << 30, chunk_interval=None)
    for i in range(10):
        w.write("/joint_states", joint_state(i, T0 + i), T0 + i)
    real_write = bag_writer._DirectFile.write
    calls = {"n": 0}

    def failing_write(self, data):
        calls["n"] += 1
        if calls["n"] == 1:
            raise KeyboardInterrupt
        return real_write(self, data)

    monkeypatch.setattr(bag_writer._DirectFile, "write", failing_write)
    with pytest.raises(KeyboardInterrupt):
        w.flush()
    monkeypatch.setattr(bag_writer._DirectFile, "write", real_write)
    w.write("/joint_states", joint_state(10, T0 + 10), T0 + 10)
    w.close()
    read, _ = rosbags_read(path)
    assert [t for _, _, t, _ in read] == [T0 + i for i in range(11)]
    assert bag_info(path)["message_count"] == 11


def test_short_writes_of_the_operating_system_are_completed(tmp_path, monkeypatch):
    """Reference: the MCAP CRCs (mcap's validating reader) and rosbags. os.write may write
    fewer bytes than given; with at most 7 bytes per call the file is still byte-complete:
    every message once, in order, all CRCs valid."""
    from mcap.reader import make_reader

    real_write = bag_writer._DirectFile.write
    monkeypatch.setattr(bag_writer._DirectFile, "write",
                        lambda self, data: real_write(self, bytes(data[:7])))
    path = tmp_path / "short.mcap"
    with BagWriter(path, chunk_size=512, chunk_interval=None, turbine_yaml="name: t\n") as w:
        for i in range(40):
            w.write("/joint_states", joint_state(i, T0 + i), T0 + i)
    with open(path, "rb") as f:
        got = [m.log_time for _, _, m in make_reader(f, validate_crcs=True).iter_messages()]
    assert got == [T0 + i for i in range(40)]
    read, _ = rosbags_read(path)
    assert len(read) == 40 and bag_info(path)["chunks"] > 1
