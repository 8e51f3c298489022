"""Recording ROS 2 messages into MCAP in the layout rosbag2 writes, on ``mcap.writer.Writer``.

:class:`BagWriter` writes rclpy message objects (or already serialized CDR bytes) the way
rosbag2's MCAP storage plugin does: profile ``ros2``; one schema per type, named
``pkg/msg/Type``, encoding ``ros2msg``, whose text is the type's ``.msg`` definition followed
by every nested type's; message encoding ``cdr``; per-channel metadata
``offered_qos_profiles`` (YAML) and ``topic_type_hash`` (``RIHS01_...``); at close a
Metadata record ``rosbag2`` whose ``serialized_metadata`` is the bag's ``metadata.yaml``
text.  Chunks are compressed (zstd by default, lz4 or none on request).

The records, chunks, indexes, statistics, summary and footer are written by the ``mcap``
package's :class:`mcap.writer.Writer`. This module adds what a recorder running beside a
live node needs:

* a chunk is also closed when its oldest message is ``chunk_interval`` seconds old (a
  background thread calls the Writer's public ``flush()``), so a quiet recorder loses at
  most that much;
* crash safety: the Writer writes into :class:`_StagedStream`, which keeps the bytes of one
  Writer call in memory and hands them to the operating system (unbuffered) only when the
  call has returned.  So the file always ends at a record boundary of a completed call: a
  writer killed with SIGKILL loses at most its open chunk (everything before stays readable
  by :class:`~hawt_ros.bag.reader.BagReader` and :func:`~hawt_ros.bag.info.bag_info`, which
  recover unfinalized files), and a write interrupted by an exception from a signal
  handler (KeyboardInterrupt, SystemExit) keeps its unwritten bytes staged for the next
  one: nothing is lost or written twice;
* ``close()`` is idempotent, runs at interpreter exit for every open writer (``atexit``)
  and is safe from a signal handler: when the signal interrupts an operation of the same
  writer, the close is deferred to the end of that operation.

A path ending in ``.mcap`` is written as a bare MCAP file. Any other path is a rosbag2
*bag folder*: ``<path>/<name>_0.mcap`` plus ``<path>/metadata.yaml`` written at close,
which ``ros2 bag info/play`` on a ROS installation and ``rosbags`` read.
"""

from __future__ import annotations

import atexit
import json
import os
import threading
import time
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence

from .definitions import message_definition, normalize_type, type_hash, type_name_of
from .serialization import qos_dict, serialize, yaml_text

__all__ = ["BagWriter", "close_all_writers", "PROFILE", "SCHEMA_ENCODING", "MESSAGE_ENCODING",
           "ROSBAG2_METADATA_VERSION"]

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
ROSBAG2_METADATA_VERSION = 9  # Jazzy


class _DirectFile:
    """Write-only file without user-space buffering: what :meth:`write` returned as written
    is with the operating system and survives a SIGKILL of the process."""

    def __init__(self, path: Path):
        self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)

    def write(self, data) -> int:
        """One ``os.write``: the number of bytes written (possibly fewer than given)."""
        return os.write(self._fd, data)

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


class _StagedStream:
    """The stream ``mcap.writer.Writer`` writes into: bytes are staged in memory, and
    :meth:`commit` (called once the Writer's call has returned) writes them to the file.
    ``tell()`` counts every byte handed over, staged or written (the offsets in the indexes
    are file offsets). An interrupted commit leaves the unwritten rest staged."""

    def __init__(self, file: _DirectFile):
        self.file = file
        self._staged = bytearray()
        self._position = 0

    def write(self, data) -> int:
        self._staged += data
        self._position += len(data)
        return len(data)

    def tell(self) -> int:
        return self._position

    def flush(self) -> None:
        """Nothing: bytes reach the file only through :meth:`commit`."""

    def commit(self) -> None:
        while self._staged:
            written = self.file.write(self._staged)
            del self._staged[:written]


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


_COMPRESSIONS = ("zstd", "lz4", "none", "")


class BagWriter:
    """Write ROS 2 messages into a rosbag2-layout MCAP file (see the module docstring).

    Parameters
    ----------
    path:
        ``something.mcap`` for a bare MCAP file; any other path is a rosbag2 bag folder
        (created; must not exist or be empty) holding ``<name>_0.mcap`` and, after
        ``close()``, ``metadata.yaml``.
    chunk_size:
        Close the open chunk once its records exceed this many (uncompressed) bytes.
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
        from mcap.writer import CompressionType, Writer

        if compression not in _COMPRESSIONS:
            raise ValueError(f"compression: {compression!r} is not allowed; choose 'zstd', "
                             "'lz4' or 'none'")
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
        self._stream = _StagedStream(self._file)
        kind = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "": CompressionType.NONE}[self.compression]
        self._mcap = Writer(self._stream, chunk_size=self.chunk_size, compression=kind)
        self._mcap.start(profile=PROFILE, library=self._library())
        self._stream.commit()
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
        return f"hawt_ros.bag (mcap-python/{mcap_version})"

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
        """Close the open chunk (mcap's public ``Writer.flush``) and write it out."""
        self._mcap.flush()
        self._stream.commit()
        self._pending_since = None

    # ---- public API --------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def topics(self) -> Dict[str, str]:
        return {t.name: t.type_name for t in self._topics.values()}

    def add_topic(self, topic: str, type_name: str, qos: Any = None,
                  definition: Optional[str] = None, type_hash: Optional[str] = None) -> None:
        """Register a topic (done implicitly by the first write). ``qos``: the offered QoS
        (rclpy QoSProfile, a rosbag2-style dict, a list of those, or None); ``definition``
        and ``type_hash``: the schema text and RIHS01 hash when known (a recovered file's),
        else found from the type's ``.msg`` files."""
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            self._add_topic(topic, type_name, qos, definition, type_hash)
            self._stream.commit()
        finally:
            self._release()

    def _add_topic(self, topic: str, type_name: str, qos: Any = None,
                   definition: Optional[str] = None,
                   thash: Optional[str] = None) -> _Topic:
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
            schema_id = self._mcap.register_schema(type_name, SCHEMA_ENCODING,
                                                   definition.encode())
            self._schemas[type_name] = schema_id
        qos_list = [qos_dict(q) for q in qos] if isinstance(qos, (list, tuple)) else [qos_dict(qos)]
        if thash is None:
            thash = type_hash(type_name, self.extra_msg_paths)
        metadata = {"offered_qos_profiles": yaml_text(qos_list).strip()}
        if thash:
            metadata["topic_type_hash"] = thash
        channel_id = self._mcap.register_channel(topic, MESSAGE_ENCODING, schema_id, metadata)
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
            before = self._stream.tell()
            self._mcap.add_message(t.channel_id, log_time=lt, data=bytes(data),
                                   publish_time=pt, sequence=t.count)
            self.message_count += 1
            self.start_time = lt if self.start_time is None else min(self.start_time, lt)
            self.end_time = lt if self.end_time is None else max(self.end_time, lt)
            now = time.monotonic()
            if self._stream.tell() != before:        # the Writer closed the chunk (size)
                self._pending_since = None
            elif self._pending_since is None:
                self._pending_since = now
            elif self.chunk_interval and now - self._pending_since >= self.chunk_interval:
                self._mcap.flush()
                self._pending_since = None
            self._stream.commit()
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
            self._mcap.add_attachment(create_time=now, log_time=log_time or now, name=name,
                                      media_type=media_type, data=data)
            self._stream.commit()
        finally:
            self._release()

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Store a Metadata record (string -> string map)."""
        if not self._acquire():
            raise ValueError("BagWriter is closed")
        try:
            self._mcap.add_metadata(name, {str(k): str(v) for k, v in data.items()})
            self._stream.commit()
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
                self._stream.commit()
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
        return yaml_text(info)

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
