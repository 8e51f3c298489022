"""ROS 2 type names and interface definitions as rosbag2 stores them in an MCAP schema.

Definitions come from the ``.msg``/``.srv``/``.action`` files that ROS packages install
under ``<prefix>/share/<pkg>/`` (prefixes: ``AMENT_PREFIX_PATH``, then this Python's
``sys.prefix``, where the ROS wheels from PyPI put them), then from this repository's
``msg_defs/`` (so hawt_msgs definitions are found even when not installed).  The text of a
type is its own ``.msg`` followed by every nested type's (rosbag2's "=====" / ``MSG:
pkg/Type`` format); the type hash is the ``RIHS01_...`` string of rosidl's ``.json``
type description.
"""

from __future__ import annotations

import importlib
import json
import os
import re
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

__all__ = ["DefinitionNotFound", "normalize_type", "type_name_of", "message_class",
           "message_definition", "type_hash", "SEPARATOR"]

SEPARATOR = "=" * 80

_PRIMITIVES = {
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring",
}
_REPO_MSG_DEFS = Path(__file__).resolve().parents[2] / "msg_defs"


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


