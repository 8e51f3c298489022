"""Summary of a bag (``hawt info``, like ``ros2 bag info``): from the summary section of a
finalized file, else by scanning (and recovering) the records."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any, Dict, Mapping, Optional

from .reader import Scan, mcap_path, scan_records

__all__ = ["bag_info", "format_bag_info"]

def _topics_info(channels: Mapping[int, Any], schemas: Mapping[int, Any],
                 counts: Mapping[int, int]) -> Dict[str, Dict[str, Any]]:
    """bag_info's ``topics``: {topic: {type, count, type_hash, message_encoding}}."""
    topics = {}
    for cid, ch in channels.items():
        schema = schemas.get(ch.schema_id)
        topics[ch.topic] = {
            "type": schema.name if schema else "",
            "count": int(counts.get(cid, 0)),
            "type_hash": ch.metadata.get("topic_type_hash"),
            "message_encoding": ch.message_encoding,
        }
    return topics


def _from_summary(path: Path) -> Optional[Dict[str, Any]]:
    """bag_info from the summary section of a finalized file (None if unusable)."""
    from mcap.reader import make_reader

    try:
        with open(path, "rb") as f:
            reader = make_reader(f)
            header = reader.get_header()
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:
                return None
            stats = summary.statistics
            topics = _topics_info(summary.channels, summary.schemas,
                                  stats.channel_message_counts)
            metadata = {}
            for m in reader.iter_metadata():
                metadata[m.name] = dict(m.metadata)
            attachments = [a.name for a in summary.attachment_indexes]
            compression = sorted({c.compression or "none" for c in summary.chunk_indexes})
            start = int(stats.message_start_time) if stats.message_count else None
            end = int(stats.message_end_time) if stats.message_count else None
            return {
                "path": str(path), "profile": header.profile, "library": header.library,
                "finalized": True, "truncated": False, "error": None,
                "topics": topics, "message_count": int(stats.message_count),
                "start_time": start, "end_time": end,
                "duration": (end - start) / 1e9 if start is not None else 0.0,
                "chunks": int(stats.chunk_count), "compression": compression,
                "attachments": attachments, "metadata": metadata,
            }
    except Exception:  # noqa: BLE001 - fall back to scanning
        return None


def bag_info(path: os.PathLike | str) -> Dict[str, Any]:
    """Summary of a bag: ``topics`` ({topic: {type, count, type_hash, ...}}),
    ``message_count``, ``start_time``/``end_time`` (ns, None when empty), ``duration`` (s),
    ``finalized``, ``truncated``, ``chunks``, ``compression``, ``attachments`` (names),
    ``metadata`` (records by name), ``profile``, ``library``. Uses the summary section of a
    finalized file; scans (recovering) an unfinalized or damaged one."""
    p = mcap_path(path)
    info = _from_summary(p)
    if info is not None:
        return info
    scan = Scan()
    counts: Dict[int, int] = {}
    start = end = None
    n = 0
    for rec in scan_records(p, scan):
        counts[rec.channel_id] = counts.get(rec.channel_id, 0) + 1
        n += 1
        start = rec.log_time if start is None else min(start, rec.log_time)
        end = rec.log_time if end is None else max(end, rec.log_time)
    topics = _topics_info(scan.channels, scan.schemas, counts)
    return {
        "path": str(p),
        "profile": scan.header.profile if scan.header else "",
        "library": scan.header.library if scan.header else "",
        "finalized": scan.finalized, "truncated": scan.truncated, "error": scan.error,
        "topics": topics, "message_count": n, "start_time": start, "end_time": end,
        "duration": (end - start) / 1e9 if start is not None else 0.0,
        "chunks": scan.chunks, "compression": sorted(scan.compression),
        "attachments": [a.name for a in scan.attachments], "metadata": scan.metadata,
    }


def format_bag_info(info: Mapping[str, Any]) -> str:
    """Human-readable text of :func:`bag_info` (like ``ros2 bag info``)."""
    def stamp(ns):
        if ns is None:
            return "-"
        sec, frac = divmod(int(ns), 1_000_000_000)
        return (time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(sec))
                + f".{frac:09d} UTC ({sec}.{frac:09d})")

    state = "finalized" if info["finalized"] else (
        "NOT finalized (recovered" + (f"; stopped at: {info['error']}" if info.get("error") else "")
        + ")")
    lines = [
        f"Files:             {info['path']}",
        f"Bag state:         {state}",
        f"Duration:          {info['duration']:.9f} s",
        f"Start:             {stamp(info['start_time'])}",
        f"End:               {stamp(info['end_time'])}",
        f"Messages:          {info['message_count']}",
        f"Chunks:            {info['chunks']} ({', '.join(info['compression']) or '-'})",
        f"Attachments:       {', '.join(info['attachments']) or '-'}",
    ]
    topics = info["topics"]
    if topics:
        width = max(len(t) for t in topics)
        first = True
        for name in sorted(topics):
            t = topics[name]
            prefix = "Topic information: " if first else " " * 19
            lines.append(f"{prefix}Topic: {name:<{width}} | Type: {t['type']} | "
                         f"Count: {t['count']} | Serialization Format: "
                         f"{t.get('message_encoding', 'cdr')}")
            first = False
    else:
        lines.append("Topic information: -")
    return "\n".join(lines)
