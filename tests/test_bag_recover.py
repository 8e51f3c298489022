"""``hawt recover`` (hawt_ros/bag/recover.py): a recording killed with SIGKILL, cut at any byte
or with a damaged chunk becomes a finalized file that the independent readers open: rosbags
(AnyReader and its rosbag2 Reader), mcap's seeking reader (summary, statistics, indexes) and
mcap-ros2-support's decoder.

References: the messages a writer wrote (known in the test: log time i and position i for the
i-th message), and hawt's own recovering reader of the crashed file; the recovered file must
hold exactly those, byte for byte, and every reader must count the same number.
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from test_msgs_mcap import T0, killed_writer, rosbags_read

from hawt_ros.bag import BagReader, BagWriter, bag_info, recover, unfinalized_recordings
from hawt_ros.bag.reader import Scan, scan_records
from hawt_ros.bag.recover import is_finalized, recovered_path

pytestmark = pytest.mark.ros
HAWT_EXE = Path(sys.executable).parent / "hawt"


@pytest.fixture(scope="module")
def crashed(tmp_path_factory):
    """An MCAP file whose writer was killed with SIGKILL while writing."""
    path = killed_writer(tmp_path_factory.mktemp("crash") / "killed.mcap")
    assert not is_finalized(path)
    return path


def _independent_counts(path: Path) -> dict:
    """Messages per reader, each independent of hawt's code."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader

    counts = {}
    with AnyReader([path]) as reader:
        counts["rosbags"] = sum(1 for _ in reader.messages())
    counts["rosbags.rosbag2"] = len(rosbags_read(path)[0])
    with open(path, "rb") as f:
        decoded = make_reader(f, decoder_factories=[DecoderFactory()])
        counts["mcap_ros2"] = sum(1 for _ in decoded.iter_decoded_messages())
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        counts["mcap summary"] = summary.statistics.message_count
        counts["mcap seeking"] = sum(1 for _ in reader.iter_messages())
    return counts


def test_crashed_file_is_recovered_for_every_reader(crashed, tmp_path):
    expected = [(m.log_time, list(m.message.position)) for m in BagReader(crashed)]
    assert len(expected) >= 200                 # the 200 written before the pause survive
    out = tmp_path / "fixed.mcap"
    report = recover(crashed, out)
    assert not report.was_finalized and report.messages == len(expected)
    assert report.topics == {"/joint_states": len(expected)}
    assert is_finalized(out) and bag_info(out)["finalized"]
    counts = _independent_counts(out)
    assert set(counts.values()) == {len(expected)}, counts
    # content: the rosbags decoding of each message is the message written
    read, connections = rosbags_read(out)
    assert [(t, list(m.position)) for _, _, t, m in read] == expected
    assert expected == [(T0 + i, [float(i)]) for i in range(len(expected))]
    assert connections == {"/joint_states": ("sensor_msgs/msg/JointState", len(expected))}
    # what else the crashed file held: the attachment and the rosbag2 metadata record
    info = bag_info(out)
    assert info["attachments"] == ["turbine.yaml"]
    meta = info["metadata"]["rosbag2"]["serialized_metadata"]
    assert f"message_count: {len(expected)}" in meta
    # the channel's QoS and type hash are the recorded ones
    from mcap.reader import make_reader
    scan = Scan()
    for _ in scan_records(crashed, scan):
        pass
    old = {c.topic: c.metadata for c in scan.channels.values()}
    with open(out, "rb") as f:
        new = {c.topic: c.metadata for c in make_reader(f).get_summary().channels.values()}
    assert new == old and "topic_type_hash" in new["/joint_states"]


def test_cut_anywhere_and_damaged_chunk(tmp_path):
    """A file cut at many byte offsets, and one with a flipped byte inside a chunk: recovery
    keeps a prefix of the messages (every complete chunk before the damage) and the result is
    readable by every reader."""
    from sensor_msgs.msg import JointState
    full = tmp_path / "full.mcap"
    with BagWriter(full, chunk_size=1024, chunk_interval=None) as w:
        for i in range(300):
            w.write("/joint_states", JointState(name=["yaw"], position=[float(i)]), T0 + i)
    data = full.read_bytes()
    for k, cut in enumerate((200, len(data) // 3, len(data) // 2, len(data) - 100)):
        part = tmp_path / f"cut{k}.mcap"
        part.write_bytes(data[:cut])
        n_hawt = sum(1 for _ in BagReader(part))
        report = recover(part, tmp_path / f"cut{k}-fixed.mcap")
        assert report.messages == n_hawt
        got = [list(m.message.position) for m in BagReader(report.output)]
        assert got == [[float(i)] for i in range(n_hawt)]
        if n_hawt:
            counts = _independent_counts(Path(report.output))
            assert set(counts.values()) == {n_hawt}, counts
    from mcap.reader import make_reader
    with open(full, "rb") as f:
        chunks = make_reader(f).get_summary().chunk_indexes
    middle = chunks[len(chunks) // 2]           # a byte in the middle of the middle chunk
    damaged = bytearray(data)
    damaged[middle.chunk_start_offset + middle.chunk_length // 2] ^= 0xFF
    bad = tmp_path / "damaged.mcap"
    bad.write_bytes(bytes(damaged))
    report = recover(bad)
    assert report.output == str(recovered_path(bad))
    assert 0 < report.messages < 300 and report.stopped_at
    assert set(_independent_counts(Path(report.output)).values()) == {report.messages}


def test_recover_refuses_what_it_should(crashed, tmp_path):
    with pytest.raises(FileExistsError, match="being recovered"):
        recover(crashed, crashed)
    out = tmp_path / "once.mcap"
    recover(crashed, out)
    with pytest.raises(FileExistsError, match="exists"):
        recover(crashed, out)
    assert recover(crashed, out, overwrite=True).messages > 0
    text = tmp_path / "notes.mcap"
    text.write_text("not an mcap file")
    with pytest.raises(ValueError, match="not an MCAP file"):
        recover(text, tmp_path / "x.mcap")
    with pytest.raises(ValueError, match="ending in .mcap"):
        recover(crashed, tmp_path / "x.bag")
    with pytest.raises(FileNotFoundError):
        recover(tmp_path / "missing.mcap")


def test_recover_command_line_and_the_runs_folder(crashed, tmp_path):
    """`hawt recover` prints what it did (JSON with --json), exits 2 with one line on bad
    input; unfinalized_recordings (what the node names at start) lists the crashed file
    until it has been recovered."""
    folder = tmp_path / "runs"
    folder.mkdir()
    copy = folder / "hawt-crashed.mcap"
    copy.write_bytes(crashed.read_bytes())
    good = folder / "hawt-good.mcap"
    with BagWriter(good, chunk_interval=None):
        pass
    assert unfinalized_recordings(folder) == [copy]
    done = subprocess.run([str(HAWT_EXE), "recover", str(copy), "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["output"] == str(recovered_path(copy)) and report["messages"] >= 200
    assert unfinalized_recordings(folder) == []
    again = subprocess.run([str(HAWT_EXE), "recover", str(copy)], capture_output=True,
                           text=True, timeout=120)
    assert again.returncode == 2 and "exists" in again.stderr
    assert len(again.stderr.strip().splitlines()) == 1
