"""Reading MCAP bags, recovering unfinalized or truncated files.

:class:`BagReader` iterates ``(topic, type_name, log_time_ns, message)`` in file order;
a file cut anywhere (a writer killed with SIGKILL) is read up to its last complete chunk.
Decoding: rclpy classes where importable, else mcap-ros2-support's decoder from the
schema (``mcap_ros2.decoder.DecoderFactory``), or the raw CDR bytes.  rclpy is imported
lazily: ``decode="dynamic"`` or ``"raw"`` work without ROS installed.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Mapping, Optional

from .definitions import message_class

__all__ = ["BagReader", "BagMessage", "mcap_path", "scan_records", "Scan"]

def mcap_path(path: os.PathLike | str) -> Path:
    p = Path(path)
    if p.is_dir():
        files = sorted(p.glob("*.mcap"))
        if not files:
            raise FileNotFoundError(f"no .mcap file in bag folder {p}")
        if len(files) > 1:
            raise ValueError(f"bag folder {p} has several .mcap files; give one of them")
        return files[0]
    return p


@dataclass
class Scan:
    header: Any = None
    schemas: Dict[int, Any] = field(default_factory=dict)
    channels: Dict[int, Any] = field(default_factory=dict)
    metadata: Dict[str, Dict[str, str]] = field(default_factory=dict)
    attachments: List[Any] = field(default_factory=list)
    finalized: bool = False
    truncated: bool = False
    error: Optional[str] = None
    chunks: int = 0
    compression: set = field(default_factory=set)


def scan_records(path: Path, scan: Scan) -> Iterator[Any]:
    """Every schema/channel/message record of the file in file order, recovering from a
    truncated or damaged tail (stops there and records why in ``scan``)."""
    from mcap.exceptions import McapError
    from mcap.records import (Attachment, Channel, Chunk, DataEnd, Footer, Header, Message,
                              Metadata, Schema)
    from mcap.stream_reader import StreamReader, breakup_chunk

    with open(path, "rb") as f:
        reader = StreamReader(f, emit_chunks=True, validate_crcs=False,
                              record_size_limit=1 << 32)
        records = reader.records
        while True:
            try:
                rec = next(records)
            except StopIteration:
                break
            except (McapError, EOFError, ValueError, struct.error, OSError, MemoryError) as exc:
                scan.truncated = True
                scan.error = f"{type(exc).__name__}: {exc}"
                break
            if isinstance(rec, Chunk):
                try:
                    inner = breakup_chunk(rec, validate_crc=True)
                except Exception as exc:  # noqa: BLE001 - damaged chunk: stop here
                    scan.truncated = True
                    scan.error = f"damaged chunk: {type(exc).__name__}: {exc}"
                    break
                scan.chunks += 1
                scan.compression.add(rec.compression or "none")
                for r in inner:
                    if isinstance(r, Schema):
                        scan.schemas[r.id] = r
                    elif isinstance(r, Channel):
                        scan.channels[r.id] = r
                    elif isinstance(r, Message):
                        yield r
                continue
            if isinstance(rec, Header):
                scan.header = rec
            elif isinstance(rec, Schema):
                scan.schemas.setdefault(rec.id, rec)
            elif isinstance(rec, Channel):
                scan.channels.setdefault(rec.id, rec)
            elif isinstance(rec, Message):
                yield rec
            elif isinstance(rec, Metadata):
                scan.metadata[rec.name] = dict(rec.metadata)
            elif isinstance(rec, Attachment):
                scan.attachments.append(rec)
            elif isinstance(rec, DataEnd):
                pass
            elif isinstance(rec, Footer):
                scan.finalized = True



@dataclass
class BagMessage:
    topic: str
    type_name: str
    log_time: int
    message: Any
    publish_time: int = 0
    channel_metadata: Mapping[str, str] = field(default_factory=dict)

    def __iter__(self):  # (topic, type, log_time, msg) unpacking
        return iter((self.topic, self.type_name, self.log_time, self.message))


class BagReader:
    """Iterate the messages of a bag (bare .mcap file or rosbag2 folder) in file order.

    Each item is a :class:`BagMessage`, which unpacks as ``(topic, type_name, log_time_ns,
    message)``. ``decode``: ``"rclpy"`` (rclpy message objects; types must be importable),
    ``"dynamic"`` (mcap-ros2-support objects built from the schema; no ROS needed),
    ``"auto"`` (rclpy where the type is importable, else dynamic) or ``"raw"`` (CDR bytes).
    Unfinalized or truncated files are read up to the last complete chunk; afterwards
    ``truncated``/``finalized``/``error`` tell what was found.
    """

    def __init__(self, path: os.PathLike | str, topics: Optional[Iterable[str]] = None,
                 decode: str = "auto"):
        if decode not in ("auto", "rclpy", "dynamic", "raw"):
            raise ValueError(f"decode must be auto, rclpy, dynamic or raw, not {decode!r}")
        self.path = mcap_path(path)
        self.topic_filter = set(topics) if topics is not None else None
        self.decode = decode
        self._scan = Scan()
        self._decoders: Dict[int, Any] = {}
        self._dynamic = None            # mcap_ros2 DecoderFactory, made on first need

    @property
    def truncated(self) -> bool:
        return self._scan.truncated

    @property
    def finalized(self) -> bool:
        return self._scan.finalized

    @property
    def error(self) -> Optional[str]:
        return self._scan.error

    @property
    def metadata(self) -> Dict[str, Dict[str, str]]:
        return self._scan.metadata

    @property
    def attachments(self) -> Dict[str, bytes]:
        return {a.name: a.data for a in self._scan.attachments}

    def _decoder(self, channel) -> Any:
        dec = self._decoders.get(channel.id)
        if dec is not None:
            return dec
        schema = self._scan.schemas.get(channel.schema_id)
        type_name = schema.name if schema is not None else ""
        mode = self.decode
        if mode == "raw":
            dec = bytes
        else:
            cls = None
            if mode in ("auto", "rclpy"):
                try:
                    from rclpy.serialization import deserialize_message

                    cls = message_class(type_name)
                except Exception:  # noqa: BLE001
                    if mode == "rclpy":
                        raise
            if cls is not None:
                dec = (lambda data, _c=cls: deserialize_message(data, _c))
            else:
                if schema is None:
                    raise ValueError(f"channel {channel.topic} has no schema")
                if self._dynamic is None:
                    from mcap_ros2.decoder import DecoderFactory

                    self._dynamic = DecoderFactory()
                dec = self._dynamic.decoder_for(channel.message_encoding, schema)
                if dec is None:
                    raise ValueError(f"channel {channel.topic}: cannot decode "
                                     f"{channel.message_encoding!r} with a "
                                     f"{schema.encoding!r} schema")
        self._decoders[channel.id] = dec
        return dec

    def __iter__(self) -> Iterator[BagMessage]:
        self._scan = Scan()
        self._decoders = {}
        for rec in scan_records(self.path, self._scan):
            ch = self._scan.channels.get(rec.channel_id)
            if ch is None:
                continue
            if self.topic_filter is not None and ch.topic not in self.topic_filter:
                continue
            schema = self._scan.schemas.get(ch.schema_id)
            msg = self._decoder(ch)(rec.data)
            yield BagMessage(ch.topic, schema.name if schema else "", rec.log_time, msg,
                             rec.publish_time, ch.metadata)


