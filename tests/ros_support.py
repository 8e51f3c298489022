"""Helpers shared by the ROS test files (imported as a plain module: pytest puts tests/ on
sys.path)."""
from __future__ import annotations

import itertools
import os
from pathlib import Path
from typing import Optional

import pytest

_domains = itertools.count()


def require_ros(import_error: Optional[str], exe: Optional[Path] = None) -> None:
    """Skip when rclpy/hawt_msgs could not be imported (``import_error``), unless
    HAWT_REQUIRE_ROS=1 (scripts/test.sh, CI): then fail. Fail when the console script ``exe``
    (if given) is missing from the venv. Usable in a test and at module level (the skip then
    skips the whole module; a failure is a collection error)."""
    if import_error is not None:
        msg = f"rclpy/hawt_msgs cannot be imported ({import_error})"
        if os.environ.get("HAWT_REQUIRE_ROS") == "1":
            pytest.fail(msg + " but HAWT_REQUIRE_ROS=1")
        pytest.skip(msg, allow_module_level=True)
    if exe is not None and not exe.exists():
        pytest.fail(f"{exe} missing: install hawt into this venv (pip install -e .)")


def domain_id() -> int:
    """A ROS domain of this test alone, in 1..101: from the pid and a counter shared by every
    ROS test file of this pytest process; under pytest-xdist each worker draws from its own
    share of the range (gw0 from the first 101 / workers, ...), so two workers never share
    a domain."""
    workers = max(1, int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
    worker = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0")[2:] or 0) % workers
    share = 101 // workers
    return worker * share + (os.getpid() * 7 + next(_domains) * 13) % share + 1


def child_env(domain: int, tmp_path: Path, **extra: str) -> dict:
    """The environment of a child process (node, CLI, script) on ``domain``: this process's
    environment, discovery on localhost, rcl logs in ``tmp_path``/roslog, plus ``extra``."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               ROS_LOG_DIR=str(tmp_path / "roslog"))
    env.update(extra)
    return env
