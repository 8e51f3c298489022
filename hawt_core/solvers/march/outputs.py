"""What a simulation reports: named rigid states, blade deflections, recorded time histories
(``history()``, ``save()`` to CSV/NPZ) and the run summary (a mixin of the Simulator).
"""

from __future__ import annotations

import math

import numpy as np

from ...io.tables import write_table
from .initial import NAMED, BladeIndex

__all__ = ['SimulationOutputs']


class SimulationOutputs:
    """Outputs of :class:`~hawt_core.solvers.march.Simulator` (mixin)."""

    # ------------------------------------------------------------------ outputs
    def _init_outputs(self):
        m = self.model
        lay = m.layout
        self._iy = lay["yaw"] if "yaw" in lay else None
        self._it = lay["teeter"] if "teeter" in lay else None
        self._blades = [BladeIndex(lay, k) for k in range(m.n_blades)]
        self._stations = np.array(m.beam.props.nodes, float)
        self._stations.setflags(write=False)
        self._positions = np.array(m.beam.props.node_positions(), float)
        self._positions.setflags(write=False)
        self._N = m.beam.N

    def _rates(self):
        m = self.model
        nq, nr = m.nq, m.nq + m.nu
        return np.real(m.rigid.qdot(self.y[:nq], self.y[nq:nr], self.t)) if nq else np.zeros(0)

    def named(self) -> dict:
        """time [s], azimuth [rad, in [0, 2 pi)], yaw [rad], yaw_rate [rad/s], teeter [rad],
        teeter_rate (= d teeter/dt) [rad/s]; locked DOFs report 0."""
        qd = self._rates()
        y = self.y
        m = self.model
        # the rotor's azimuth: Omega0 t, plus the drivetrain's twist and generator angle
        psi = m.rigid.azimuth(self.t, y[:m.nq]) if m.nq else self.omega * self.t
        az = float(np.real(psi)) % (2 * math.pi)
        out = {"time": self.t, "azimuth": az, "yaw": 0.0, "yaw_rate": 0.0,
               "teeter": 0.0, "teeter_rate": 0.0}
        if self._iy is not None:
            out["yaw"] = float(y[self._iy])
            out["yaw_rate"] = float(qd[self._iy])
        if self._it is not None:
            out["teeter"] = float(y[self._it])
            out["teeter_rate"] = float(qd[self._it])
        return out

    def blade_deflections(self) -> list:
        """Per blade: dict(stations (N+1,) [m] (span along b1), positions (N+1, 3) [m] (the
        undeformed reference line in the root frame b: (stations, 0, 0) unless the blade
        has prebend or sweep), u (N+1,3) [m], theta (N+1,3) (Rodrigues, root frame b),
        root_force (3,) [N], root_moment (3,) [N m] (loads on the hub, frame b))."""
        y = self.y
        out = []
        N = self._N
        for b in self._blades:
            u = np.zeros((N + 1, 3))
            th = np.zeros((N + 1, 3))
            u[1:] = y[b.u].reshape(N, 3)
            th[1:] = y[b.theta].reshape(N, 3)
            out.append({"stations": self._stations, "positions": self._positions,
                        "u": u, "theta": th,
                        "root_force": y[b.root_force].copy(),
                        "root_moment": y[b.root_moment].copy()})
        return out

    def _record(self):
        nm = self.named()
        y = self.y
        row = [nm[k] for k in NAMED]
        parts = [np.array(row)]
        for b in self._blades:
            parts += [y[b.u], y[b.theta], y[b.root_force], y[b.root_moment]]
        self._hist.append(np.concatenate(parts))

    def columns(self) -> list:
        """Names of the history columns (CSV header)."""
        cols = list(NAMED)
        for k in range(len(self._blades)):
            # stored as all u then all theta
            us = [f"blade{k}_node{i}_u{c}" for i in range(1, self._N + 1) for c in (1, 2, 3)]
            ths = [f"blade{k}_node{i}_theta{c}" for i in range(1, self._N + 1) for c in (1, 2, 3)]
            cols += us + ths
            cols += [f"blade{k}_root_force{c}" for c in (1, 2, 3)]
            cols += [f"blade{k}_root_moment{c}" for c in (1, 2, 3)]
        return cols

    def history(self) -> dict:
        """Time histories: dict of arrays: the NAMED scalars, and per blade ``u`` (steps,
        N+1, 3), ``theta`` (steps, N+1, 3), ``root_force``, ``root_moment`` (steps, 3) under
        keys ``blade{k}_u`` etc. (root node rows are zero: clamped)."""
        if not self.record:
            raise ValueError("history: this Simulator was created with record=False")
        H = np.array(self._hist)
        out = {k: H[:, i] for i, k in enumerate(NAMED)}
        c = len(NAMED)
        N = self._N
        for k in range(len(self._blades)):
            for name in ("u", "theta"):
                a = np.zeros((len(H), N + 1, 3))
                a[:, 1:] = H[:, c:c + 3 * N].reshape(-1, N, 3)
                out[f"blade{k}_{name}"] = a
                c += 3 * N
            for name in ("root_force", "root_moment"):
                out[f"blade{k}_{name}"] = H[:, c:c + 3]
                c += 3
        return out

    def save(self, path) -> None:
        """Write the time histories to ``path``: CSV (header row, columns ``columns()``:
        time, azimuth, yaw, yaw_rate, teeter, teeter_rate [s, rad, rad/s], then per blade and
        node u1..u3 [m] and theta1..theta3 (Rodrigues), then the root loads [N, N m]) or NPZ
        (the same columns as arrays, plus ``stations``)."""
        if not self.record:
            raise ValueError("save: this Simulator was created with record=False")
        write_table(path, self.columns(), np.array(self._hist),
                    extra={"stations": self._stations})


    def summary(self) -> dict:
        sim = self.t - self.t0
        wall = self.wall_seconds
        return {"simulated_seconds": sim, "wall_seconds": wall,
                "real_time_factor": (sim / wall) if wall > 0 else float("inf"),
                "steps": self.steps, "newton_iterations": self.newton_iterations,
                "residual_evaluations": self.residual_evaluations,
                "jacobian_evaluations": self.jacobian_evaluations,
                "factorizations": self.factorizations, "rejected_steps": self.rejected_steps,
                "low_rank_updates": self.low_rank_updates, "method": self.method,
                **({"windows": self._win.windows, "window_steps": self.window_steps,
                    "window_iterations": self._win.iterations,
                    "window_rigid_updates": self._win.updates,
                    "window_failures": self._win.failures,
                    "residual_instants": self._win.residual_instants}
                   if self._win is not None else {}),
                "step_seconds": self.h, "step_deg": math.degrees(self.h * self.omega),
                "unknowns": self.n}
