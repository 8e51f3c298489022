"""Helpers shared by the ROS test files (imported as a plain module: pytest puts tests/ on
sys.path)."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import pytest


def require_ros(import_error: Optional[str], exe: Path) -> None:
    """Skip when rclpy/hawt_msgs could not be imported (``import_error``), unless
    HAWT_REQUIRE_ROS=1 (scripts/test.sh, CI): then fail. Fail when the console script ``exe``
    is missing from the venv."""
    if import_error is not None:
        msg = f"rclpy/hawt_msgs cannot be imported ({import_error})"
        if os.environ.get("HAWT_REQUIRE_ROS") == "1":
            pytest.fail(msg + " but HAWT_REQUIRE_ROS=1")
        pytest.skip(msg)
    if not exe.exists():
        pytest.fail(f"{exe} missing: install hawt into this venv (pip install -e .)")
