"""Where the node gets its simulation and modal analysis from (no rclpy import).

Normally ``hawt_core.solvers.march`` (Simulator, SimulationError) and ``hawt_core.analyses.modal``
(modal_analysis, Cancelled). For tests only, the environment variable ``HAWT_ROS_FAKE`` may
name a Python file (or module) providing stand-ins with the same API; ``HAWT_ROS_FAKE_PARTS``
(comma separated, default ``simulate,modal``) says which parts it replaces. The analysis
worker processes inherit the environment, so they use the same backend as the node.
"""
from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from types import SimpleNamespace

__all__ = ["load_backend"]

_cache = {}


def _fake_module():
    spec = os.environ.get("HAWT_ROS_FAKE", "").strip()
    if not spec:
        return None
    if spec in _cache:
        return _cache[spec]
    if spec.endswith(".py") or os.sep in spec:
        name = "_hawt_ros_fake_" + str(abs(hash(spec)))
        s = importlib.util.spec_from_file_location(name, spec)
        if s is None or s.loader is None:
            raise ImportError(f"HAWT_ROS_FAKE: cannot load {spec!r}")
        mod = importlib.util.module_from_spec(s)
        sys.modules[name] = mod
        s.loader.exec_module(mod)
    else:
        mod = importlib.import_module(spec)
    _cache[spec] = mod
    return mod


def _fake_parts() -> set:
    return {p.strip() for p in os.environ.get("HAWT_ROS_FAKE_PARTS", "simulate,modal").split(",")
            if p.strip()}


#: part -> (module, (entry point, exception class))
_PARTS = {"simulate": ("hawt_core.solvers.march", ("Simulator", "SimulationError")),
          "modal": ("hawt_core.analyses.modal", ("modal_analysis", "Cancelled"))}


def load_backend(part: str) -> SimpleNamespace:
    """``part`` 'simulate' -> namespace(Simulator, SimulationError, source);
    'modal' -> namespace(modal_analysis, Cancelled, source). Raises ImportError with a clear
    text when the part is not available."""
    if part not in _PARTS:
        raise ValueError(f"part: {part!r} is not allowed; choose simulate or modal")
    module, names = _PARTS[part]
    fake = _fake_module()
    if fake is not None and part in _fake_parts():
        return SimpleNamespace(**{n: getattr(fake, n) for n in names},
                               source=f"fake ({os.environ['HAWT_ROS_FAKE']})")
    mod = importlib.import_module(module)
    # the entry point itself must exist; the exception class falls back to RuntimeError
    return SimpleNamespace(**{names[0]: getattr(mod, names[0])},
                           **{n: getattr(mod, n, RuntimeError) for n in names[1:]},
                           source=module)
