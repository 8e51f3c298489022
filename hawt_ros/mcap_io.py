"""MCAP recording and reading in the layout rosbag2 writes (pure Python).

Writing
    :class:`BagWriter` writes ROS 2 messages (rclpy message objects, or already
    serialized CDR bytes) into an MCAP file the way rosbag2's MCAP storage plugin does:
    profile ``ros2``; one schema per type, named ``pkg/msg/Type``, encoding ``ros2msg``,
    whose text is the type's ``.msg`` definition followed by every nested type's
    definition (rosbag2's "=====" / ``MSG: pkg/Type`` format); message encoding ``cdr``;
    per-channel metadata ``offered_qos_profiles`` (YAML) and ``topic_type_hash``
    (``RIHS01_...``); at close a Metadata record ``rosbag2`` whose ``serialized_metadata``
    is the bag's ``metadata.yaml`` text. Messages are chunked and compressed (zstd by
    default, lz4 or none on request); a chunk is closed when it holds ``chunk_size``
    bytes or is ``chunk_interval`` seconds old. The records are built with the ``mcap``
    package's record classes, but the file is written here: every write is one complete
    blob (a whole chunk with its message indexes, a schema, an attachment, the summary)
    straight to the operating system (no user-space buffering), and the writer's state
    changes only after it. So a writer killed with SIGKILL loses at most its open chunk
    (everything before stays readable by :class:`BagReader` and :func:`bag_info`, which
    recover unfinalized files), and an exception raised mid-write by a signal handler
    (KeyboardInterrupt, SystemExit) neither loses nor duplicates messages at close.

    A path ending in ``.mcap`` is written as a bare MCAP file. Any other path is a
    rosbag2 *bag folder*: ``<path>/<name>_0.mcap`` plus ``<path>/metadata.yaml`` written
    at close, which ``ros2 bag info/play`` on a ROS installation and ``rosbags`` read.

    ``close()`` finalizes the file (summary, indexes, footer). It is idempotent, safe
    at interpreter exit (open writers are closed by an ``atexit`` hook) and safe from a
    signal handler: when the signal interrupts a ``write`` of the same writer, the
    close is deferred to the end of that write.

Reading
    :class:`BagReader` iterates ``(topic, type_name, log_time_ns, message)`` in file
    order; :func:`bag_info` summarizes a bag (topics, types, counts, start/end,
    duration), from the summary section when the file was finalized and by scanning
    (and recovering) otherwise.

Message definitions come from the ``.msg``/``.srv``/``.action`` files that ROS packages
install under ``<prefix>/share/<pkg>/`` (prefixes: ``AMENT_PREFIX_PATH``, then this
Python's ``sys.prefix``, where the ROS wheels from PyPI put them), then from this
repository's ``msg_defs/`` (so hawt_msgs definitions are found even when not installed).

Serialization uses ``rclpy.serialization`` (fast, exact), except for one known defect:
it pads an *empty* sequence of 8-byte primitives (``float64[]``, ``int64[]``,
``uint64[]``) with 4 alignment bytes that the CDR standard (and the ``rosbags`` reader)
does not expect. Such messages are encoded instead with mcap-ros2-support's pure-Python
CDR encoder from the schema, so every file written here is readable by rclpy,
mcap-ros2-support and rosbags alike.

rclpy is imported lazily: reading with ``decode="dynamic"`` or ``decode="raw"`` and
:func:`bag_info` work without ROS installed (only ``mcap``/``mcap-ros2-support``).
"""

from __future__ import annotations

import array as _array
import atexit
import importlib
import json
import os
import re
import sys
import threading
import time
import struct
import weakref
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Mapping, Optional, Sequence, Tuple

import yaml

__all__ = [
    "BagWriter",
    "BagReader",
    "BagMessage",
    "bag_info",
    "format_bag_info",
    "message_definition",
    "type_hash",
    "type_name_of",
    "serialize",
    "close_all_writers",
    "DefinitionNotFound",
]

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
SEPARATOR = "=" * 80
ROSBAG2_METADATA_VERSION = 9  # Jazzy

_PRIMITIVES = {
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring",
}
_REPO_MSG_DEFS = Path(__file__).resolve().parents[1] / "msg_defs"


class DefinitionNotFound(LookupError):
    """No interface definition file was found for a type."""


# --------------------------------------------------------------------------------------
# Type names and interface definitions
# --------------------------------------------------------------------------------------

def _split_type(type_name: str) -> Tuple[str, str, str]:
    """'pkg/msg/Type' or 'pkg/Type' -> (pkg, kind, Type)."""
    parts = type_name.strip().split("/")
    if len(parts) == 2:
        return parts[0], "msg", parts[1]
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        return parts[0], parts[1], parts[2]
    raise ValueError(f"not a ROS 2 type name: {type_name!r} (expected 'pkg/msg/Type')")


def normalize_type(type_name: str) -> str:
    pkg, kind, name = _split_type(type_name)
    return f"{pkg}/{kind}/{name}"


def type_name_of(msg_or_class: Any) -> str:
    """'pkg/msg/Type' of an rclpy message instance or class."""
    cls = msg_or_class if isinstance(msg_or_class, type) else type(msg_or_class)
    parts = cls.__module__.split(".")
    if len(parts) < 2 or parts[1] not in ("msg", "srv", "action"):
        raise TypeError(f"{cls!r} is not a generated ROS 2 interface class")
    return f"{parts[0]}/{parts[1]}/{cls.__name__}"


def message_class(type_name: str) -> type:
    """The rclpy class of 'pkg/msg/Type' (imports the generated Python module)."""
    pkg, kind, name = _split_type(type_name)
    module = importlib.import_module(f"{pkg}.{kind}")
    cls = getattr(module, name, None)
    if cls is None and "_" in name:  # e.g. action/Fibonacci_Feedback -> Fibonacci.Feedback
        base, _, part = name.rpartition("_")
        cls = getattr(getattr(module, base, None), part, None)
    if cls is None:
        raise DefinitionNotFound(f"{pkg}.{kind} has no {name}")
    return cls


def _search_roots(extra: Sequence[os.PathLike | str] = ()) -> List[Path]:
    roots: List[Path] = []
    for p in extra:
        roots.append(Path(p))
    for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if p:
            roots.append(Path(p) / "share")
    roots.append(Path(sys.prefix) / "share")
    roots.append(_REPO_MSG_DEFS)
    seen, out = set(), []
    for r in roots:
        if r not in seen:
            seen.add(r)
            out.append(r)
    return out


_SECTION_SUFFIXES = {
    "srv": {"_Request": 0, "_Response": 1},
    "action": {"_Goal": 0, "_Result": 1, "_Feedback": 2},
}


def _find_file(pkg: str, kind: str, base: str, ext: str, extra=()) -> Optional[Path]:
    for root in _search_roots(extra):
        f = root / pkg / kind / f"{base}.{ext}"
        if f.is_file():
            return f
    return None


_definition_cache: Dict[Tuple[str, Tuple[str, ...]], str] = {}


def _own_definition(type_name: str, extra=()) -> str:
    """The .msg text of one type (no nested definitions)."""
    pkg, kind, name = _split_type(type_name)
    if kind == "msg":
        f = _find_file(pkg, "msg", name, "msg", extra)
        if f is None:
            raise DefinitionNotFound(
                f"no definition of {type_name}: looked for {pkg}/msg/{name}.msg under "
                + ", ".join(str(r) for r in _search_roots(extra)))
        return f.read_text()
    for suffix, section in _SECTION_SUFFIXES[kind].items():
        if name.endswith(suffix):
            base = name[: -len(suffix)]
            f = _find_file(pkg, kind, base, kind, extra)
            if f is None:
                break
            sections = re.split(r"^---[ \t]*$", f.read_text(), flags=re.M)
            return sections[section].strip("\n") + "\n"
    raise DefinitionNotFound(f"no .msg definition for {type_name} "
                             "(services and actions: use their _Request/_Response, "
                             "_Goal/_Result/_Feedback messages)")


def _dependencies(text: str, pkg: str) -> List[str]:
    """Non-primitive field types of a .msg text, as 'pkg/msg/Type', in order."""
    deps: List[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        tok = line.split()[0]
        tok = re.sub(r"\[.*\]$", "", tok)          # arrays
        tok = re.sub(r"<=\d+$", "", tok)           # bounded strings
        if tok in _PRIMITIVES:
            continue
        if "/" in tok:
            dpkg, _, dname = tok.partition("/")
            if "/" in dname:  # pkg/msg/Type
                dname = dname.split("/")[-1]
        else:
            if tok == "Header":  # ROS 1 style; ROS 2 requires std_msgs/Header
                dpkg, dname = "std_msgs", "Header"
            else:
                dpkg, dname = pkg, tok
        full = f"{dpkg}/msg/{dname}"
        if full not in deps:
            deps.append(full)
    return deps


def message_definition(type_name: str, extra_paths: Sequence[os.PathLike | str] = ()) -> str:
    """Full rosbag2-style definition text of a type, nested definitions included.

    Format (as rosbag2 and mcap-ros2-support write it): the type's own .msg text, then for
    every nested non-primitive type (depth first, each once) a line of 80 '=', a line
    ``MSG: pkg/Type`` and that type's .msg text.
    """
    type_name = normalize_type(type_name)
    key = (type_name, tuple(str(p) for p in extra_paths))
    if key in _definition_cache:
        return _definition_cache[key]
    own = _own_definition(type_name, extra_paths)
    pkg = type_name.split("/")[0]
    order: List[str] = []
    texts: Dict[str, str] = {}

    def visit(tn: str, text: str, tpkg: str) -> None:
        for dep in _dependencies(text, tpkg):
            if dep in texts or dep == type_name:
                continue
            dtext = _own_definition(dep, extra_paths)
            texts[dep] = dtext
            order.append(dep)
            visit(dep, dtext, dep.split("/")[0])

    visit(type_name, own, pkg)
    parts = [own.rstrip("\n")]
    for dep in order:
        dpkg, _, dname = _split_type(dep)
        parts.append(f"{SEPARATOR}\nMSG: {dpkg}/{dname}\n{texts[dep].rstrip(chr(10))}")
    full = "\n".join(parts) + "\n"
    _definition_cache[key] = full
    return full


def type_hash(type_name: str, extra_paths: Sequence[os.PathLike | str] = ()) -> Optional[str]:
    """The RIHS01 type hash of a type from the ``.json`` type description that rosidl
    installs beside the definition, or None if there is none."""
    pkg, kind, name = _split_type(type_name)
    full = f"{pkg}/{kind}/{name}"
    base = name
    if kind in _SECTION_SUFFIXES:
        for suffix in _SECTION_SUFFIXES[kind]:
            if name.endswith(suffix):
                base = name[: -len(suffix)]
    f = _find_file(pkg, kind, base, "json", extra_paths)
    if f is None:
        return None
    try:
        for h in json.loads(f.read_text()).get("type_hashes", []):
            if h.get("type_name") == full:
                return h.get("hash_string")
    except (OSError, ValueError):
        return None
    return None


# --------------------------------------------------------------------------------------
# Serialization
# --------------------------------------------------------------------------------------

_EIGHT_BYTE_SEQ = re.compile(r"^sequence<(double|int64|uint64|long double)(,\s*\d+)?>$")
_NESTED = re.compile(r"^(sequence<)?([A-Za-z_]\w*/[A-Za-z_]\w*)(,\s*\d+)?(>)?(\[\d+\])?$")
_risky_cache: Dict[type, Tuple[Tuple[str, str, Optional[type]], ...]] = {}


def _risky_fields(cls: type) -> Tuple[Tuple[str, str, Optional[type]], ...]:
    """Fields of an rclpy class through which an empty 8-byte primitive sequence can occur:
    (field, 'seq' | 'nested' | 'nested_seq', nested class)."""
    if cls in _risky_cache:
        return _risky_cache[cls]
    _risky_cache[cls] = ()  # recursion guard
    out = []
    for fname, ftype in cls.get_fields_and_field_types().items():
        if _EIGHT_BYTE_SEQ.match(ftype):
            out.append((fname, "seq", None))
            continue
        m = _NESTED.match(ftype)
        if m:
            pkg, name = m.group(2).split("/")
            try:
                sub = message_class(f"{pkg}/msg/{name}")
            except Exception:  # noqa: BLE001 - unknown nested class: be conservative
                out.append((fname, "unknown", None))
                continue
            if _risky_fields(sub):
                kind = "nested_seq" if (m.group(1) or m.group(5)) else "nested"
                out.append((fname, kind, sub))
    _risky_cache[cls] = tuple(out)
    return _risky_cache[cls]


def _has_empty_8byte_sequence(msg: Any) -> bool:
    for fname, kind, _sub in _risky_fields(type(msg)):
        value = getattr(msg, fname)
        if kind == "unknown":
            return True
        if kind == "seq":
            if len(value) == 0:
                return True
        elif kind == "nested":
            if _has_empty_8byte_sequence(value):
                return True
        else:
            for item in value:
                if _has_empty_8byte_sequence(item):
                    return True
    return False


def _to_plain(value: Any) -> Any:
    """rclpy message -> nested dicts/lists that mcap-ros2-support's encoder accepts."""
    if hasattr(value, "get_fields_and_field_types"):
        return {f: _to_plain(getattr(value, f)) for f in value.get_fields_and_field_types()}
    if isinstance(value, (list, tuple)):
        return [_to_plain(v) for v in value]
    if isinstance(value, _array.array):
        return value.tolist()
    if type(value).__module__ == "numpy":
        return value.tolist()
    if isinstance(value, bytearray):
        return bytes(value)
    return value


_encoder_cache: Dict[str, Any] = {}


def _dynamic_encoder(type_name: str, definition: str):
    enc = _encoder_cache.get(type_name)
    if enc is None:
        from mcap_ros2._dynamic import serialize_dynamic

        encoders = serialize_dynamic(type_name, definition)
        enc = encoders[type_name]
        _encoder_cache[type_name] = enc
    return enc


def serialize(msg: Any, type_name: Optional[str] = None, definition: Optional[str] = None) -> bytes:
    """CDR bytes of an rclpy message that rclpy, mcap-ros2-support and rosbags all read."""
    from rclpy.serialization import serialize_message

    if not _has_empty_8byte_sequence(msg):
        return serialize_message(msg)
    type_name = type_name or type_name_of(msg)
    definition = definition or message_definition(type_name)
    return bytes(_dynamic_encoder(type_name, definition)(_to_plain(msg)))


# --------------------------------------------------------------------------------------
# QoS
# --------------------------------------------------------------------------------------

_INFINITE = {"sec": 9223372036, "nsec": 854775807}


def _duration_dict(d: Any) -> Dict[str, int]:
    ns = getattr(d, "nanoseconds", None)
    if ns is None:
        return dict(_INFINITE)
    if ns == 0:  # rmw "default" = unset = infinite, as rosbag2 writes it
        return dict(_INFINITE)
    return {"sec": int(ns // 1_000_000_000), "nsec": int(ns % 1_000_000_000)}


def _policy(p: Any, default: str) -> str:
    name = getattr(p, "name", None)
    if name is None:
        return str(p).lower() if p is not None else default
    return name.lower()


def qos_dict(qos: Any = None) -> Dict[str, Any]:
    """An offered QoS profile in rosbag2's metadata-v9 form (rclpy QoSProfile, a dict in
    that form, or None for reliable/volatile/keep_last 10)."""
    if qos is None:
        return {
            "history": "keep_last", "depth": 10, "reliability": "reliable",
            "durability": "volatile", "deadline": dict(_INFINITE), "lifespan": dict(_INFINITE),
            "liveliness": "automatic", "liveliness_lease_duration": dict(_INFINITE),
            "avoid_ros_namespace_conventions": False,
        }
    if isinstance(qos, Mapping):
        out = qos_dict(None)
        out.update(qos)
        return out
    return {
        "history": _policy(qos.history, "keep_last"),
        "depth": int(qos.depth),
        "reliability": _policy(qos.reliability, "reliable"),
        "durability": _policy(qos.durability, "volatile"),
        "deadline": _duration_dict(qos.deadline),
        "lifespan": _duration_dict(qos.lifespan),
        "liveliness": _policy(qos.liveliness, "automatic"),
        "liveliness_lease_duration": _duration_dict(qos.liveliness_lease_duration),
        "avoid_ros_namespace_conventions": bool(qos.avoid_ros_namespace_conventions),
    }


def _yaml(data: Any) -> str:
    return yaml.safe_dump(data, default_flow_style=False, sort_keys=False)


# --------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------

class _DirectFile:
    """Write-only file without user-space buffering: every write goes to the OS at once,
    so what was written survives a SIGKILL of the process."""

    def __init__(self, path: Path):
        self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self._pos = 0

    def write(self, data) -> int:
        view = memoryview(data).cast("B")
        total = len(view)
        while view:
            n = os.write(self._fd, view)
            view = view[n:]
        self._pos += total
        return total

    def tell(self) -> int:
        return self._pos

    def flush(self) -> None:
        pass

    def fsync(self) -> None:
        if self._fd >= 0:
            os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    @property
    def closed(self) -> bool:
        return self._fd < 0


MCAP_MAGIC = b"\x89MCAP0\r\n"


def _record_bytes(record: Any) -> bytes:
    from mcap.data_stream import RecordBuilder

    builder = RecordBuilder()
    record.write(builder)
    return bytes(builder.end())


class _McapFile:
    """Minimal chunked MCAP writer (records and summary as the mcap package writes them)
    whose every file write is ONE complete blob (a whole chunk with its message indexes, an
    attachment, a metadata record, the whole summary), and whose in-memory state changes
    only after the write. So an exception raised anywhere by a signal handler
    (KeyboardInterrupt, SystemExit) leaves file and state consistent, and a SIGKILL leaves
    a file whose every complete chunk is readable. Schemas and channels are written to the
    data section (outside chunks) as they are registered, and repeated in the summary."""

    def __init__(self, f: "_DirectFile", profile: str, library: str, compression: str):
        from mcap.records import Header

        self.f = f
        self.compression = compression
        if compression == "zstd":
            import zstandard

            self._compress = zstandard.compress
        elif compression == "lz4":
            import lz4.frame

            self._compress = lz4.frame.compress
        else:
            self._compress = None
        self.schemas: Dict[int, Any] = {}
        self.channels: Dict[int, Any] = {}
        self.chunk_indexes: List[Any] = []
        self.attachment_indexes: List[Any] = []
        self.metadata_indexes: List[Any] = []
        self.channel_counts: Dict[int, int] = {}
        self.message_count = 0
        self.start_time = 0
        self.end_time = 0
        self._reset_chunk()
        self.f.write(MCAP_MAGIC + _record_bytes(Header(profile=profile, library=library)))

    def _reset_chunk(self) -> None:
        self.chunk_parts: List[bytes] = []
        self.chunk_size = 0
        self.chunk_index: Dict[int, List[Tuple[int, int]]] = {}
        self.chunk_start = 0
        self.chunk_end = 0
        self.chunk_messages = 0

    def add_schema(self, name: str, encoding: str, data: bytes) -> int:
        from mcap.records import Schema

        schema = Schema(id=len(self.schemas) + 1, name=name, encoding=encoding, data=data)
        self.f.write(_record_bytes(schema))
        self.schemas[schema.id] = schema
        return schema.id

    def add_channel(self, topic: str, message_encoding: str, schema_id: int,
                    metadata: Dict[str, str]) -> int:
        from mcap.records import Channel

        channel = Channel(id=len(self.channels) + 1, topic=topic,
                          message_encoding=message_encoding, schema_id=schema_id,
                          metadata=dict(metadata))
        self.f.write(_record_bytes(channel))
        self.channels[channel.id] = channel
        self.channel_counts[channel.id] = 0
        return channel.id

    def add_message(self, channel_id: int, log_time: int, publish_time: int, sequence: int,
                    data: bytes) -> None:
        from mcap.records import Message

        blob = _record_bytes(Message(channel_id=channel_id, log_time=log_time, data=data,
                                     publish_time=publish_time, sequence=sequence))
        offset = self.chunk_size
        self.chunk_parts.append(blob)
        self.chunk_size += len(blob)
        self.chunk_index.setdefault(channel_id, []).append((log_time, offset))
        if self.chunk_messages == 0:
            self.chunk_start = self.chunk_end = log_time
        else:
            self.chunk_start = min(self.chunk_start, log_time)
            self.chunk_end = max(self.chunk_end, log_time)
        self.chunk_messages += 1

    def flush_chunk(self) -> None:
        from mcap.records import Chunk, ChunkIndex, MessageIndex

        if self.chunk_messages == 0:
            return
        data = b"".join(self.chunk_parts)
        compressed = self._compress(data) if self._compress else data
        chunk_bytes = _record_bytes(Chunk(
            compression=self.compression, data=compressed,
            message_start_time=self.chunk_start, message_end_time=self.chunk_end,
            uncompressed_crc=zlib.crc32(data), uncompressed_size=len(data)))
        start = self.f.tell()
        index_parts, offsets, pos = [], {}, start + len(chunk_bytes)
        for cid, recs in self.chunk_index.items():
            b = _record_bytes(MessageIndex(channel_id=cid, records=list(recs)))
            offsets[cid] = pos
            pos += len(b)
            index_parts.append(b)
        index_bytes = b"".join(index_parts)
        chunk_index = ChunkIndex(
            message_start_time=self.chunk_start, message_end_time=self.chunk_end,
            chunk_start_offset=start, chunk_length=len(chunk_bytes),
            message_index_offsets=offsets, message_index_length=len(index_bytes),
            compression=self.compression, compressed_size=len(compressed),
            uncompressed_size=len(data))
        counts = {cid: len(recs) for cid, recs in self.chunk_index.items()}
        first = self.message_count == 0
        self.f.write(chunk_bytes + index_bytes)          # one write: chunk + its indexes
        # --- commit (the chunk is in the file) ---
        self.chunk_indexes.append(chunk_index)
        for cid, n in counts.items():
            self.channel_counts[cid] = self.channel_counts.get(cid, 0) + n
        self.message_count += sum(counts.values())
        self.start_time = self.chunk_start if first else min(self.start_time, self.chunk_start)
        self.end_time = self.chunk_end if first else max(self.end_time, self.chunk_end)
        self._reset_chunk()

    def add_attachment(self, name: str, media_type: str, data: bytes, log_time: int,
                       create_time: int) -> None:
        from mcap.records import Attachment, AttachmentIndex

        blob = _record_bytes(Attachment(create_time=create_time, log_time=log_time, name=name,
                                        media_type=media_type, data=data))
        offset = self.f.tell()
        self.f.write(blob)
        self.attachment_indexes.append(AttachmentIndex(
            offset=offset, length=len(blob), log_time=log_time, create_time=create_time,
            data_size=len(data), name=name, media_type=media_type))

    def add_metadata(self, name: str, data: Dict[str, str]) -> None:
        from mcap.records import Metadata, MetadataIndex

        blob = _record_bytes(Metadata(name=name, metadata=dict(data)))
        offset = self.f.tell()
        self.f.write(blob)
        self.metadata_indexes.append(MetadataIndex(offset=offset, length=len(blob), name=name))

    def finish(self) -> None:
        """Flush the open chunk, then write DataEnd, summary, footer and magic (one write)."""
        from mcap.opcode import Opcode
        from mcap.records import DataEnd, Footer, Statistics, SummaryOffset

        self.flush_chunk()
        data_end = _record_bytes(DataEnd(data_section_crc=0))
        summary_start = self.f.tell() + len(data_end)
        groups = [
            (Opcode.SCHEMA, list(self.schemas.values())),
            (Opcode.CHANNEL, list(self.channels.values())),
            (Opcode.STATISTICS, [Statistics(
                attachment_count=len(self.attachment_indexes),
                channel_count=len(self.channels),
                channel_message_counts=dict(self.channel_counts),
                chunk_count=len(self.chunk_indexes),
                message_count=self.message_count,
                message_end_time=self.end_time,
                message_start_time=self.start_time,
                metadata_count=len(self.metadata_indexes),
                schema_count=len(self.schemas))]),
            (Opcode.CHUNK_INDEX, self.chunk_indexes),
            (Opcode.ATTACHMENT_INDEX, self.attachment_indexes),
            (Opcode.METADATA_INDEX, self.metadata_indexes),
        ]
        parts, offsets, pos = [], [], summary_start
        for opcode, records in groups:
            if not records:
                continue
            blob = b"".join(_record_bytes(r) for r in records)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=pos,
                                         group_length=len(blob)))
            parts.append(blob)
            pos += len(blob)
        summary_offset_start = pos
        parts.extend(_record_bytes(o) for o in offsets)
        summary = b"".join(parts)
        crc = zlib.crc32(summary)
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, summary_start,
                                     summary_offset_start), crc)
        footer = _record_bytes(Footer(summary_start=summary_start,
                                      summary_offset_start=summary_offset_start,
                                      summary_crc=crc))
        self.f.write(data_end + summary + footer + MCAP_MAGIC)


_open_writers: "weakref.WeakSet[BagWriter]" = weakref.WeakSet()


def close_all_writers() -> None:
    """Close every BagWriter still open (atexit hook; also callable from a signal handler)."""
    for w in list(_open_writers):
        try:
            w.close()
        except Exception:  # noqa: BLE001 - at exit: close what can be closed
            pass


atexit.register(close_all_writers)


def _time_ns(t: Any) -> int:
    if t is None:
        return time.time_ns()
    if isinstance(t, int):
        return t
    ns = getattr(t, "nanoseconds", None)          # rclpy.time.Time
    if ns is not None:
        return int(ns)
    if hasattr(t, "sec") and hasattr(t, "nanosec"):  # builtin_interfaces/Time
        return int(t.sec) * 1_000_000_000 + int(t.nanosec)
    if isinstance(t, float):
        raise TypeError("log times are integer nanoseconds (got a float)")
    raise TypeError(f"cannot use {t!r} as a time")


@dataclass
class _Topic:
    name: str
    type_name: str
    channel_id: int
    definition: str
    qos: List[Dict[str, Any]]
    type_hash: Optional[str]
    count: int = 0


class BagWriter:
    """Write ROS 2 messages into a rosbag2-layout MCAP file (see the module docstring).

    Parameters
    ----------
    path:
        ``something.mcap`` for a bare MCAP file; any other path is a rosbag2 bag folder
        (created; must not exist or be empty) holding ``<name>_0.mcap`` and, after
        ``close()``, ``metadata.yaml``.
    chunk_size:
        Close the open chunk once its messages reach this many (uncompressed) bytes.
    chunk_interval:
        ... or once its oldest message is this many seconds old (checked at each write and
        by a background thread, so a quiet writer loses at most this much on SIGKILL).
        ``None`` or 0 disables the time limit and the thread.
    compression:
        ``"zstd"`` (default), ``"lz4"`` or ``"none"``; both compressors come with the
        ``mcap`` package's own dependencies (zstandard, lz4).
    turbine_yaml:
        Text of the turbine description; stored as attachment ``turbine.yaml``.
    settings:
        Run settings; stored as Metadata record ``hawt`` (values as text: strings as
        they are, everything else as JSON) and as rosbag2 ``custom_data``.
    """

    def __init__(
        self,
        path: os.PathLike | str,
        *,
        chunk_size: int = 256 * 1024,
        chunk_interval: Optional[float] = 1.0,
        compression: str = "zstd",
        turbine_yaml: Optional[str] = None,
        settings: Optional[Mapping[str, Any]] = None,
        extra_msg_paths: Sequence[os.PathLike | str] = (),
        ros_distro: Optional[str] = None,
        close_at_exit: bool = True,
    ):
        path = Path(path)
        if path.suffix == ".mcap":
            self.bag_dir: Optional[Path] = None
            self.path = path
            path.parent.mkdir(parents=True, exist_ok=True)
        else:
            if path.exists() and (not path.is_dir() or any(path.iterdir())):
                raise FileExistsError(f"bag folder {path} exists and is not empty")
            path.mkdir(parents=True, exist_ok=True)
            self.bag_dir = path
            self.path = path / f"{path.name}_0.mcap"
        if compression not in ("zstd", "lz4", "none", ""):
            raise ValueError(f"compression must be 'zstd', 'lz4' or 'none', not {compression!r}")
        self.compression = "" if compression in ("none", "") else compression
        self.chunk_size = int(chunk_size)
        self.chunk_interval = float(chunk_interval) if chunk_interval else 0.0
        self.extra_msg_paths = tuple(extra_msg_paths)
        self.ros_distro = ros_distro or os.environ.get("ROS_DISTRO") or "jazzy"
        self.custom_data: Dict[str, str] = {}

        self._lock = threading.RLock()
        self._owner: Optional[int] = None
        self._close_pending = False
        self._closed = False
        self._file = _DirectFile(self.path)
        self._mcap = _McapFile(self._file, PROFILE, self._library(), self.compression)
        self._topics: Dict[str, _Topic] = {}
        self._schemas: Dict[str, int] = {}
        self._pending_since: Optional[float] = None
        self._last_default_time = 0
        self.message_count = 0
        self.start_time: Optional[int] = None
        self.end_time: Optional[int] = None

        if turbine_yaml is not None:
            self.add_attachment("turbine.yaml", turbine_yaml, media_type="application/yaml")
        if settings:
            self.add_settings(settings)

        if close_at_exit:
            _open_writers.add(self)
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        if self.chunk_interval > 0:
            self._thread = threading.Thread(target=self._flush_loop, name="BagWriter-flush",
                                            daemon=True)
            self._thread.start()

    # ---- helpers -----------------------------------------------------------------------
    @staticmethod
    def _library() -> str:
        try:
            from importlib.metadata import version

            mcap_version = version("mcap")
        except Exception:  # noqa: BLE001
            mcap_version = "?"
        return f"hawt mcap_io (mcap-python/{mcap_version})"

    def _acquire(self) -> bool:
        """Take the lock for an operation. False if closed."""
        self._lock.acquire()
        self._owner = threading.get_ident()
        if self._closed:
            self._release()
            return False
        return True

    def _release(self) -> None:
        self._owner = None
        self._lock.release()
        if self._close_pending and not self._closed:
            self.close()

    def _flush_loop(self) -> None:
        interval = self.chunk_interval
        while not self._stop.wait(min(interval / 2.0, 0.5)):
            since = self._pending_since
            if since is not None and time.monotonic() - since >= interval:
                if not self._lock.acquire(timeout=1.0):
                    continue
                try:
                    self._owner = threading.get_ident()
                    if not self._closed:
                        self._flush_chunk()
                finally:
                    self._owner = None
                    self._lock.release()
                if self._close_pending and not self._closed:
                    self.close()

    def _flush_chunk(self) -> None:
        self._mcap.flush_chunk()
        self._pending_since = None

    # ---- public API --------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def topics(self) -> Dict[str, str]:
        return {t.name: t.type_name for t in self._topics.values()}

    def add_topic(self, topic: str, type_name: str, qos: Any = None,
                  definition: Optional[str] = None) -> None:
        """Register a topic (done implicitly by the first write). ``qos``: the offered QoS
        (rclpy QoSProfile, a rosbag2-style dict, a list of those, or None)."""
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            self._add_topic(topic, type_name, qos, definition)
        finally:
            self._release()

    def _add_topic(self, topic: str, type_name: str, qos: Any = None,
                   definition: Optional[str] = None) -> _Topic:
        existing = self._topics.get(topic)
        type_name = normalize_type(type_name)
        if existing is not None:
            if existing.type_name != type_name:
                raise ValueError(f"topic {topic} already has type {existing.type_name}, "
                                 f"not {type_name}")
            return existing
        if definition is None:
            definition = message_definition(type_name, self.extra_msg_paths)
        schema_id = self._schemas.get(type_name)
        if schema_id is None:
            schema_id = self._mcap.add_schema(type_name, SCHEMA_ENCODING, definition.encode())
            self._schemas[type_name] = schema_id
        qos_list = [qos_dict(q) for q in qos] if isinstance(qos, (list, tuple)) else [qos_dict(qos)]
        thash = type_hash(type_name, self.extra_msg_paths)
        metadata = {"offered_qos_profiles": _yaml(qos_list).strip()}
        if thash:
            metadata["topic_type_hash"] = thash
        channel_id = self._mcap.add_channel(topic, MESSAGE_ENCODING, schema_id, metadata)
        t = _Topic(topic, type_name, channel_id, definition, qos_list, thash)
        self._topics[topic] = t
        return t

    def write(self, topic: str, msg: Any, log_time: Any = None, publish_time: Any = None,
              *, qos: Any = None) -> None:
        """Write an rclpy message. ``log_time``: int nanoseconds, rclpy Time or
        builtin_interfaces/Time; default the wall clock (made non-decreasing)."""
        if self._closed:
            raise ValueError("BagWriter is closed")
        type_name = type_name_of(msg)
        t = self._topics.get(topic)
        definition = t.definition if t is not None else None
        if definition is None:
            definition = message_definition(type_name, self.extra_msg_paths)
        data = serialize(msg, type_name, definition)
        self.write_serialized(topic, type_name, data, log_time, publish_time, qos=qos)

    def write_serialized(self, topic: str, type_name: str, data: bytes, log_time: Any = None,
                         publish_time: Any = None, *, qos: Any = None) -> None:
        """Write CDR bytes (e.g. from a raw subscription or :func:`serialize`)."""
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            t = self._add_topic(topic, type_name, qos)
            if log_time is None:
                lt = max(time.time_ns(), self._last_default_time)
                self._last_default_time = lt
            else:
                lt = _time_ns(log_time)
            pt = lt if publish_time is None else _time_ns(publish_time)
            t.count += 1
            self._mcap.add_message(t.channel_id, log_time=lt, publish_time=pt,
                                   sequence=t.count, data=bytes(data))
            self.message_count += 1
            self.start_time = lt if self.start_time is None else min(self.start_time, lt)
            self.end_time = lt if self.end_time is None else max(self.end_time, lt)
            now = time.monotonic()
            if self._pending_since is None:
                self._pending_since = now
            if self._mcap.chunk_size >= self.chunk_size or (
                    self.chunk_interval and now - self._pending_since >= self.chunk_interval):
                self._flush_chunk()
        finally:
            self._release()

    def add_attachment(self, name: str, data: bytes | str, *,
                       media_type: str = "application/octet-stream",
                       log_time: Optional[int] = None) -> None:
        """Store a file in the bag (written at once, outside the chunks)."""
        if isinstance(data, str):
            data = data.encode()
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            now = time.time_ns()
            self._mcap.add_attachment(name, media_type, data, log_time=log_time or now,
                                      create_time=now)
        finally:
            self._release()

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Store a Metadata record (string -> string map)."""
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            self._mcap.add_metadata(name, {str(k): str(v) for k, v in data.items()})
        finally:
            self._release()

    def add_settings(self, settings: Mapping[str, Any], name: str = "hawt") -> None:
        """Run settings as Metadata record ``name`` and rosbag2 custom_data."""
        text = {str(k): v if isinstance(v, str) else json.dumps(v) for k, v in settings.items()}
        self.custom_data.update(text)
        self.add_metadata(name, text)

    def flush(self) -> None:
        """Close the open chunk now (it then survives a SIGKILL)."""
        if not self._acquire():
            return
        try:
            self._flush_chunk()
        finally:
            self._release()

    def close(self) -> None:
        """Finalize the file (idempotent; safe at exit and from signal handlers)."""
        if self._closed:
            return
        me = threading.get_ident()
        if not self._lock.acquire(blocking=False):
            if self._owner == me:
                # A signal handler interrupted an operation of this writer in this thread:
                # finish it first; _release() then closes.
                self._close_pending = True
                return
            if not self._lock.acquire(timeout=5.0):
                self._close_pending = True
                return
        try:
            if self._closed:
                return
            self._owner = me
            self._stop.set()
            try:
                self._flush_chunk()
                metadata_yaml = self._metadata_yaml()
                self._mcap.add_metadata("rosbag2", {"serialized_metadata": metadata_yaml})
                self._mcap.finish()
            finally:
                self._closed = True
                self._file.close()
                _open_writers.discard(self)
            if self.bag_dir is not None:
                tmp = self.bag_dir / "metadata.yaml.tmp"
                tmp.write_text(metadata_yaml)
                os.replace(tmp, self.bag_dir / "metadata.yaml")
        finally:
            self._owner = None
            self._lock.release()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)

    def _metadata_yaml(self) -> str:
        start = self.start_time or 0
        duration = (self.end_time - self.start_time) if self.start_time is not None else 0
        topics = [{
            "topic_metadata": {
                "name": t.name,
                "type": t.type_name,
                "serialization_format": MESSAGE_ENCODING,
                "offered_qos_profiles": t.qos,
                "type_description_hash": t.type_hash or "",
            },
            "message_count": t.count,
        } for t in self._topics.values()]
        info = {
            "rosbag2_bagfile_information": {
                "version": ROSBAG2_METADATA_VERSION,
                "storage_identifier": "mcap",
                "duration": {"nanoseconds": duration},
                "starting_time": {"nanoseconds_since_epoch": start},
                "message_count": self.message_count,
                "topics_with_message_count": topics,
                "compression_format": "",
                "compression_mode": "",
                "relative_file_paths": [self.path.name],
                "files": [{
                    "path": self.path.name,
                    "starting_time": {"nanoseconds_since_epoch": start},
                    "duration": {"nanoseconds": duration},
                    "message_count": self.message_count,
                }],
                "custom_data": dict(self.custom_data) or None,
                "ros_distro": self.ros_distro,
            }
        }
        return _yaml(info)

    def __enter__(self) -> "BagWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):  # pragma: no cover - best effort
        try:
            if not self._closed:
                self.close()
        except Exception:  # noqa: BLE001
            pass


# --------------------------------------------------------------------------------------
# Reading (recovering)
# --------------------------------------------------------------------------------------

def _mcap_path(path: os.PathLike | str) -> Path:
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
class _Scan:
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


def _iter_records(path: Path, scan: _Scan) -> Iterator[Any]:
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
        self.path = _mcap_path(path)
        self.topic_filter = set(topics) if topics is not None else None
        self.decode = decode
        self._scan = _Scan()
        self._decoders: Dict[int, Any] = {}

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
                from mcap_ros2._dynamic import generate_dynamic

                if schema is None:
                    raise ValueError(f"channel {channel.topic} has no schema")
                dec = generate_dynamic(schema.name, schema.data.decode())[schema.name]
        self._decoders[channel.id] = dec
        return dec

    def __iter__(self) -> Iterator[BagMessage]:
        self._scan = _Scan()
        self._decoders = {}
        for rec in _iter_records(self.path, self._scan):
            ch = self._scan.channels.get(rec.channel_id)
            if ch is None:
                continue
            if self.topic_filter is not None and ch.topic not in self.topic_filter:
                continue
            schema = self._scan.schemas.get(ch.schema_id)
            msg = self._decoder(ch)(rec.data)
            yield BagMessage(ch.topic, schema.name if schema else "", rec.log_time, msg,
                             rec.publish_time, ch.metadata)


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
    p = _mcap_path(path)
    info = _from_summary(p)
    if info is not None:
        return info
    scan = _Scan()
    counts: Dict[int, int] = {}
    start = end = None
    n = 0
    for rec in _iter_records(p, scan):
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
