"""Every help screen opens: ``hawt --help``, each subcommand's (and any nested
subcommand's), the ROS subcommands hawt_ros adds through the entry
point, and ``hawt-node --help``.

Reference: argparse's contract (``--help`` prints a usage line and exits 0).  A help string
with a bare ``%`` (argparse %-formats help) made ``hawt simulate --help`` and
``hawt operating-points --help`` exit 2 with "unsupported format character"; this test
walks the registered parsers rather than a list, so a new command is covered the day it
is added."""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hawt_core.cli import build_parser, main, plugin_commands


def _subcommand_paths(parser: argparse.ArgumentParser, prefix=()):
    """Every command path under ``parser``: ("modes",), ("import", "openfast"), ..."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield prefix + (name,)
                yield from _subcommand_paths(sub, prefix + (name,))


def _help_of(argv, capsys):
    """(exit status, stdout, stderr) of ``hawt ARGV --help`` run in this process (a parse
    error returns status 2 instead of raising SystemExit)."""
    try:
        code = main(list(argv) + ["--help"])
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


CORE_PATHS = list(_subcommand_paths(build_parser()))


def test_the_walk_sees_every_command():
    """The walk is not vacuous: the core commands and the ROS plugin's are all there."""
    names = {p[0] for p in CORE_PATHS}
    assert {"blade-modes", "modes", "campbell", "simulate", "operating-points", "import",
            "aero-table", "flutter", "turbines"} <= names
    assert {"record", "play", "info", "recover", "call", "echo"} <= set(plugin_commands())


@pytest.mark.parametrize("path", [()] + CORE_PATHS, ids=lambda p: " ".join(p) or "hawt")
def test_help_opens(path, capsys):
    code, out, err = _help_of(path, capsys)
    assert code == 0, err
    assert out.startswith("usage: hawt"), out[:200]
    assert "error" not in err


def _plugin_paths():
    try:
        from hawt_ros.cli import build_parser as ros_parser
    except ImportError:          # hawt_ros not installed: the plugin list is empty too
        return []
    return list(_subcommand_paths(ros_parser()))


@pytest.mark.parametrize("path", _plugin_paths(), ids=lambda p: " ".join(p))
def test_ros_subcommand_help_opens(path, capsys):
    code, out, err = _help_of(path, capsys)
    assert code == 0, err
    assert out.startswith(f"usage: hawt {path[0]}"), out[:200]


def test_node_help_opens(tmp_path):
    exe = Path(sys.executable).with_name("hawt-node")
    if not exe.exists():
        pytest.skip("hawt-node is not installed in this venv")
    env = dict(os.environ, ROS_LOG_DIR=str(tmp_path))
    out = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=60,
                         env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("usage: hawt-node"), out.stdout[:200]
