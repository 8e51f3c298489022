"""Recovering a crashed recording: ``hawt recover FILE.mcap`` (what ``mcap recover`` and
``ros2 bag reindex`` do).

A recorder killed with SIGKILL (or a machine losing power) leaves an MCAP file without its
summary, footer and closing magic.  hawt's own reader (:class:`~hawt_ros.bag.reader.BagReader`)
reads such a file up to its last complete chunk, but the other readers do not: rosbags stops
at "File end magic is invalid", mcap's seeking reader and mcap-ros2-support at the missing
footer.  :func:`recover` writes a new, finalized file from every complete chunk of the crashed
one: the same schemas (text as recorded), channels (topic, QoS, type hash), messages (log and
publish times, data byte for byte), attachments and metadata records, with the summary, the
indexes and rosbag2's ``metadata.yaml`` record rebuilt.  The crashed file is left as it is.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Optional

import yaml

from .reader import Scan, mcap_path, scan_records
from .writer import BagWriter

__all__ = ["recover", "RecoveryReport", "recovered_path", "unfinalized_recordings"]

#: MCAP's magic (the first and the last 8 bytes of a finalized file).
MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass
class RecoveryReport:
    """What :func:`recover` found and wrote."""

    source: str
    output: str
    messages: int = 0
    topics: Dict[str, int] = field(default_factory=dict)
    chunks: int = 0
    was_finalized: bool = False
    stopped_at: Optional[str] = None    # why reading the source stopped (its damaged tail)
    skipped: int = 0                    # messages of a channel whose schema is lost

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def recovered_path(path: os.PathLike | str) -> Path:
    """The default output of recovering ``path``: ``<stem>-recovered.mcap`` beside it."""
    p = mcap_path(path)
    return p.with_name(p.stem + "-recovered.mcap")


def is_finalized(path: os.PathLike | str) -> bool:
    """True when the file ends with MCAP's closing magic (a cheap test: 8 bytes)."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            f.seek(0, os.SEEK_END)
            if f.tell() < 2 * len(MCAP_MAGIC):
                return False
            f.seek(-len(MCAP_MAGIC), os.SEEK_END)
            return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except OSError:
        return False


def unfinalized_recordings(folder: os.PathLike | str) -> list:
    """The ``.mcap`` files in ``folder`` (not in its subfolders) that are not finalized,
    oldest first, leaving out those that already have a ``-recovered.mcap`` beside them."""
    d = Path(folder)
    if not d.is_dir():
        return []
    out = []
    for p in sorted(d.glob("*.mcap"), key=lambda q: q.stat().st_mtime):
        if p.stem.endswith("-recovered") or recovered_path(p).exists():
            continue
        if not is_finalized(p):
            out.append(p)
    return out


def _qos(metadata) -> Optional[list]:
    text = metadata.get("offered_qos_profiles")
    if not text:
        return None
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return None
    return value if isinstance(value, list) and all(isinstance(q, dict) for q in value) \
        else None


def recover(path: os.PathLike | str, output: Optional[os.PathLike | str] = None,
            *, overwrite: bool = False, progress=None) -> RecoveryReport:
    """Write a finalized copy of the MCAP file ``path`` (crashed or not) to ``output``
    (default :func:`recovered_path`) holding every complete chunk; returns what was found.

    ``progress(messages)`` is called every 10000 messages.  Raises FileExistsError when
    ``output`` exists (unless ``overwrite``) or is ``path`` itself, FileNotFoundError when
    ``path`` does not, ValueError when it is not an MCAP file at all.
    """
    src = mcap_path(path)
    if not src.is_file():
        raise FileNotFoundError(f"{src}: no such file")
    dst = Path(output) if output is not None else recovered_path(src)
    if dst.suffix != ".mcap":
        raise ValueError(f"output: {str(dst)!r} is not allowed; need a file name ending in "
                         ".mcap")
    if dst.exists() and dst.resolve() == src.resolve():
        raise FileExistsError(f"output {dst} is the file being recovered; give another name")
    if dst.exists() and not overwrite:
        raise FileExistsError(f"output {dst} exists; give another name (or --force)")
    with open(src, "rb") as f:
        if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise ValueError(f"{src} is not an MCAP file (it does not start with MCAP's "
                             "magic bytes)")

    scan = Scan()
    report = RecoveryReport(source=str(src), output=str(dst))
    tmp = dst.with_name(dst.name + ".partial.mcap")
    writer = BagWriter(tmp, chunk_interval=None, close_at_exit=False)
    try:
        registered: Dict[int, str] = {}
        for rec in scan_records(src, scan):
            ch = scan.channels.get(rec.channel_id)
            schema = scan.schemas.get(ch.schema_id) if ch is not None else None
            if schema is None:
                report.skipped += 1
                continue
            if rec.channel_id not in registered:
                writer.add_topic(ch.topic, schema.name, qos=_qos(ch.metadata),
                                 definition=schema.data.decode("utf-8", "replace"),
                                 type_hash=ch.metadata.get("topic_type_hash", ""))
                registered[rec.channel_id] = schema.name
            writer.write_serialized(ch.topic, schema.name, rec.data, log_time=rec.log_time,
                                    publish_time=rec.publish_time)
            report.topics[ch.topic] = report.topics.get(ch.topic, 0) + 1
            report.messages += 1
            if progress is not None and report.messages % 10000 == 0:
                progress(report.messages)
        for a in scan.attachments:
            writer.add_attachment(a.name, a.data, media_type=a.media_type,
                                  log_time=a.log_time)
        for name, data in scan.metadata.items():
            if name == "rosbag2":           # rebuilt from what was recovered, at close
                continue
            if name == "hawt":
                writer.custom_data.update(data)
            writer.add_metadata(name, data)
        writer.close()
        os.replace(tmp, dst)
    except BaseException:
        writer.close()
        tmp.unlink(missing_ok=True)
        raise
    report.chunks = scan.chunks
    report.was_finalized = scan.finalized
    report.stopped_at = scan.error
    return report


def format_report(r: RecoveryReport) -> str:
    """The lines ``hawt recover`` prints."""
    state = ("the file was finalized (copied)" if r.was_finalized else
             "the file was not finalized" + (f"; its tail is damaged ({r.stopped_at})"
                                             if r.stopped_at else ""))
    lines = [f"recovered {r.messages} messages from {r.chunks} chunks of {r.source} into "
             f"{r.output}", state]
    if r.skipped:
        lines.append(f"{r.skipped} messages left out: their channel's schema was lost")
    for topic in sorted(r.topics):
        lines.append(f"  {topic}: {r.topics[topic]}")
    return "\n".join(lines)
