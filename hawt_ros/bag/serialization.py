"""CDR serialization of rclpy messages that every reader accepts, and offered QoS profiles
in rosbag2's metadata form.

Serialization uses ``rclpy.serialization`` (fast, exact), except for one known defect:
it pads an *empty* sequence of 8-byte primitives (``float64[]``, ``int64[]``,
``uint64[]``) with 4 alignment bytes that the CDR standard (and the ``rosbags`` reader)
does not expect. Such messages are encoded instead with mcap-ros2-support's CDR encoder
built from the schema text (the encoder its ``Writer.write_message`` uses, which has no
public entry point of its own), so every file written here is readable by rclpy,
mcap-ros2-support and rosbags alike.
"""

from __future__ import annotations

import array as _array
import re
from typing import Any, Dict, Mapping, Optional, Tuple

import yaml

from .definitions import message_class, message_definition, type_name_of

__all__ = ["serialize", "qos_dict", "yaml_text"]

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


def yaml_text(data: Any) -> str:
    """YAML as rosbag2 writes its metadata (block style, keys in order)."""
    return yaml.safe_dump(data, default_flow_style=False, sort_keys=False)

