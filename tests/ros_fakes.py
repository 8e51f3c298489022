"""Stand-ins for hawt_core.simulate (Simulator) and hawt_core.modal (modal_analysis) with the
APIs of docs/ARCHITECTURE.md, for the ROS node tests only.

The node loads them when the environment variable HAWT_ROS_FAKE names this file
(HAWT_ROS_FAKE_PARTS selects 'simulate' and/or 'modal'; see hawt_ros/backend.py). Knobs, also
from the environment (so they reach the node's process and its analysis workers):

* HAWT_FAKE_STEP_COST   seconds of CPU burnt per Simulator.step() (default 0)
* HAWT_FAKE_FAIL_AT     simulation time [s] at which step() raises SimulationError
* HAWT_FAKE_NAN_AT      simulation time [s] from which the teeter angle is NaN (a bad simulator)
* HAWT_FAKE_MODAL_SECONDS  CPU seconds a fake modal analysis burns (default 0.3), in 20 slices
                           with progress and cancel checks between them
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

import numpy as np


class SimulationError(RuntimeError):
    pass


class Cancelled(RuntimeError):
    pass


def _burn(seconds: float) -> None:
    end = time.perf_counter() + seconds
    x = 0.0
    while time.perf_counter() < end:
        x += math.sin(x + 1.0)


def _env_float(name, default=None):
    v = os.environ.get(name, "")
    return float(v) if v.strip() else default


class Simulator:
    """Analytic motion with the Simulator API: teeter and yaw oscillate, blades flap."""

    def __init__(self, model, step_deg=1.0, perturb=None, record=True):
        self.model = model
        self.record = bool(record)       # no histories kept either way
        self.omega = float(model.rotor_speed)
        self.dt = math.radians(step_deg) / self.omega
        self.perturb = dict(perturb or {})
        self.t = 0.0
        self.y = np.zeros(model.n)
        self.n_blades = model.n_blades
        self.stations = np.asarray(model.beam.props.nodes, float)
        self._cost = _env_float("HAWT_FAKE_STEP_COST", 0.0)
        self._fail_at = _env_float("HAWT_FAKE_FAIL_AT")
        self._nan_at = _env_float("HAWT_FAKE_NAN_AT")
        self.steps = 0
        self._sync_y()

    def step(self):
        if self._fail_at is not None and self.t + self.dt >= self._fail_at:
            raise SimulationError(f"fake: Newton did not converge at t = {self.t + self.dt:.4f} s")
        if self._cost:
            _burn(self._cost)
        self.t += self.dt
        self.steps += 1
        self._sync_y()

    def _motion(self):
        """The analytic rigid motion at self.t: yaw, yaw_rate, teeter, teeter_rate."""
        t, w = self.t, self.omega
        a = self.perturb.get("teeter", 0.01)
        yr = self.perturb.get("yaw_rate", 0.0)
        out = {"yaw": self.perturb.get("yaw", 0.0) + yr * t + 0.001 * math.sin(2 * w * t),
               "yaw_rate": yr + 0.002 * w * math.cos(2 * w * t),
               "teeter": a * math.cos(w * t), "teeter_rate": -a * w * math.sin(w * t)}
        if self._nan_at is not None and t >= self._nan_at:
            out["teeter"] = float("nan")
        return out

    def _sync_y(self):
        """Write the rigid coordinates/speeds into y at the model's layout indices."""
        lay, rig = self.model.layout, self.model.rigid
        n = self._motion()
        psi = self.omega * self.t
        vals = {"yaw": n["yaw"], "yaw_rate": n["yaw_rate"], "teeter": n["teeter"],
                "teeter_speed": -n["teeter_rate"] - math.sin(psi) * n["yaw_rate"]}
        for name in tuple(rig.coordinates) + tuple(rig.speeds):
            self.y[lay[name]] = vals[name]

    def named(self):
        """As hawt_core.simulate.Simulator.named(): time, azimuth in [0, 2 pi), yaw and teeter
        from y, their rates from the model's rigid.qdot; locked DOFs report 0."""
        m, lay = self.model, self.model.layout
        nq, nr = m.nq, m.nq + m.nu
        qd = np.real(m.rigid.qdot(self.y[:nq], self.y[nq:nr], self.t)) if nq else np.zeros(0)
        out = {"time": self.t, "azimuth": (self.omega * self.t) % (2 * math.pi), "yaw": 0.0,
               "yaw_rate": 0.0, "teeter": 0.0, "teeter_rate": 0.0}
        for name in ("yaw", "teeter"):
            if name in lay:
                out[name] = float(self.y[lay[name]])
                out[name + "_rate"] = float(qd[lay[name]])
        return out

    def blade_deflections(self):
        out = []
        L = self.stations[-1]
        x = self.stations / L
        for k in range(self.n_blades):
            ph = self.omega * self.t + math.pi * k
            u = np.zeros((len(x), 3))
            u[:, 2] = 0.05 * x ** 2 * (1 + 0.2 * math.sin(ph))
            u[:, 1] = -0.01 * x ** 2 * (1 + 0.1 * math.cos(ph))
            th = np.zeros((len(x), 3))
            th[:, 1] = -0.1 * x * (1 + 0.2 * math.sin(ph))
            line = np.zeros((len(x), 3))
            line[:, 0] = self.stations
            out.append({"stations": self.stations.copy(), "positions": line, "u": u,
                        "theta": th, "root_force": np.array([1.2e5, 100.0 * math.sin(ph), 500.0]),
                        "root_moment": np.array([10.0, -2000.0 * math.cos(ph), 300.0])})
        return out


# ------------------------------------------------------------------------------ modal
#: The paper's Table 2, 4 elements per blade (per-rev; docs/theory.md).
TABLE2_N4 = [
    ("yaw", None, 0.0, 0.0),
    ("teeter", None, 1.0, 0.045299),
    ("flap", "symmetric", 2.4347, 0.0), ("flap", "antisymmetric", 7.3210, 0.0),
    ("flap", "symmetric", 15.5465, 0.0), ("flap", "antisymmetric", 28.3486, 0.0),
    ("torsion", "symmetric", 2.2896, 0.0), ("torsion", "antisymmetric", 2.2915, 0.0),
    ("torsion", "symmetric", 6.5738, 0.0), ("torsion", "antisymmetric", 6.5742, 0.0),
    ("lag", "symmetric", 4.7523, 0.0), ("lag", "antisymmetric", 4.9927, 0.0),
    ("lag", "symmetric", 33.5731, 0.0), ("lag", "antisymmetric", 34.1087, 0.0),
]


@dataclass
class Mode:
    family: str
    symmetry: object
    index: int
    frequency_per_rev: float
    real_per_rev: float
    frequency_hz: float
    damping_ratio: float

    def to_dict(self):
        return {k: getattr(self, k) for k in ("family", "symmetry", "index", "frequency_per_rev",
                                              "real_per_rev", "frequency_hz", "damping_ratio")}


@dataclass
class ModalResult:
    modes: list
    settings: dict
    unresolved: int = 0
    compute_time: float = 0.0

    def to_dict(self):
        return {"settings": self.settings, "modes": [m.to_dict() for m in self.modes],
                "unresolved_modes": self.unresolved, "compute_time": self.compute_time}


def modal_analysis(turbine, elements=None, rotor_speed=None, steps=None, method="auto",
                   progress=None, cancel=None):
    method = method or "auto"
    if method not in ("auto", "radau", "paper", "hill"):
        raise ValueError(f"method: {method!r} is not allowed; choose one of auto, radau, "
                         "paper, hill")
    method = "radau" if method == "auto" else method     # the paper's two-bladed rotor
    t0 = time.perf_counter()
    seconds = _env_float("HAWT_FAKE_MODAL_SECONDS", 0.3)
    n = 20
    for i in range(n):
        if cancel is not None and cancel():
            raise Cancelled(f"fake analysis cancelled at {i}/{n}")
        if progress is not None:
            progress(i / n, f"fake stage {i + 1}/{n}")
        _burn(seconds / n)
    omega = float(rotor_speed or turbine.rotor.speed)
    counts = {}
    modes = []
    for fam, sym, f, r in TABLE2_N4:
        counts[(fam, sym)] = counts.get((fam, sym), 0) + 1
        s = complex(r, f) * omega
        damping = -s.real / abs(s) if abs(s) > 0 else float("nan")
        modes.append(Mode(fam, sym, counts[(fam, sym)], f, r, f * omega / (2 * math.pi), damping))
    modes.sort(key=lambda m: (m.frequency_per_rev, m.real_per_rev))
    settings = {"turbine": turbine.name,
                "elements": int(elements or turbine.blade.elements),
                "rotor_speed": omega, "method": method,
                "steps": int(steps or (400 if method == "radau" else 1000)), "fast": True}
    if progress is not None:
        progress(1.0, "done")
    return ModalResult(modes, settings, 0, time.perf_counter() - t0)
