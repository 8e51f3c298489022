"""The closed loop: the turbine simulated in wind (solvers/march) with a controller commanding its
pitch bearings and generator torque (rigid/actuators.py) once per controller step.

Each controller step of ``dt`` (a whole number of simulation steps, so that the simulation
lands on every call): the measurements at the step's start go to the controller, its demands
are clipped to the actuator limits (counted and reported, never applied raw) and ramped in
over the step (the actuators' first-order hold: one step of delay, ServoDyn's behaviour with
no pitch-actuator model), then the turbine is simulated to the step's end.

The rotor speed is free: the generator is the drivetrain's free generator (its torque from the
controller), started from the operating point at the initial wind (rotor speed and pitch of
the schedule, generator torque balancing the rotor's aerodynamic torque there).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Callable, Optional

import numpy as np

from ..assembly import TurbineModel
from ..assembly.aero_blade import AeroelasticBlade
from ..io.tables import write_table
from ..numerics.rotations import rot1
from ..rigid import ControlInputs
from ..solvers.march import SimulationError, Simulator
from ..solvers.periodic import periodic_steady_state
from ..solvers.equilibrium import NoEquilibrium
from ..solvers.steady import constant_steady_state
from .discon import Measurements

__all__ = ["ActuatorLimits", "ClosedLoop", "free_generator"]


@dataclass(frozen=True)
class ActuatorLimits:
    """Pitch range [rad, towards feather] and rate [rad/s], generator torque range [N m,
    HSS] and rate [N m/s]; None: unlimited."""

    pitch_min: float = -math.pi / 2
    pitch_max: float = math.pi / 2
    pitch_rate: Optional[float] = None
    torque_max: Optional[float] = None
    torque_rate: Optional[float] = None

    @classmethod
    def from_discon(cls, values: dict) -> "ActuatorLimits":
        """From a DISCON.IN read by io.discon.read_discon (PC_MinPit, PC_MaxPit, PC_MaxRat,
        VS_MaxTq, VS_MaxRat where present)."""
        def num(k, default=None):
            v = values.get(k)
            return float(v) if isinstance(v, float) else default
        return cls(pitch_min=num("PC_MinPit", -math.pi / 2),
                   pitch_max=num("PC_MaxPit", math.pi / 2), pitch_rate=num("PC_MaxRat"),
                   torque_max=num("VS_MaxTq"), torque_rate=num("VS_MaxRat"))

    def clip(self, pitch, torque, last_pitch, last_torque, dt):
        """(pitch, torque, what was clipped: list of field names)."""
        clipped = []
        p = np.asarray(pitch, float)
        q = np.clip(p, self.pitch_min, self.pitch_max)
        if self.pitch_rate is not None:
            d = self.pitch_rate * dt
            q = np.clip(q, last_pitch - d, last_pitch + d)
        if np.any(q != p):
            clipped.append("pitch")
        tq = float(torque)
        t2 = max(0.0, tq) if self.torque_max is None else min(max(0.0, tq), self.torque_max)
        if self.torque_rate is not None:
            d = self.torque_rate * dt
            t2 = min(max(t2, last_torque - d), last_torque + d)
        if t2 != tq:
            clipped.append("torque")
        return q, t2, clipped


def free_generator(turbine):
    """The turbine with its drivetrain's generator free (the rotor speed a DOF), the shaft
    as the file has it, and no torque-law slope of its own (the controller's torque is the
    generator's whole torque); ValueError without a drivetrain."""
    dt = turbine.drivetrain
    if dt is None:
        raise ValueError(f"turbine {turbine.name!r}: no drivetrain section, so no generator "
                         "for a controller to drive")
    return replace(turbine, drivetrain=replace(dt, generator="free", generator_torque_slope=0.0))


#: Harmonics of the periodic state the closed loop starts from, and the interpolation error
#: accepted (relative to the load scale): a start, not a result; the controller's transient
#: follows anyway (4 harmonics: ~5 s for the NREL 5-MW at 4 elements, 48: ~50 s)
INITIAL_HARMONICS, INITIAL_TOL = 4, 2e-2


def initial_state(model) -> np.ndarray:
    """The model's constant steady state, or (gravity, tilt, shear) its periodic state at
    t = 0 with INITIAL_HARMONICS harmonics."""
    try:
        return constant_steady_state(model)
    except NoEquilibrium:
        raise
    except ValueError:
        ps = periodic_steady_state(model, harmonics=INITIAL_HARMONICS,
                                   max_harmonics=INITIAL_HARMONICS,
                                   interpolation_tol=INITIAL_TOL)
        return ps.at(0.0)


#: the columns of a closed-loop history, per blade k the pitch{k}_deg and tip deflections
BASE_COLUMNS = ("time", "wind_speed", "rotor_speed_rpm", "generator_speed_rpm",
                "generator_power_kw", "generator_torque_knm", "shaft_power_kw")


class ClosedLoop:
    """A turbine in wind under a controller.

    ``turbine`` (at its initial operating point: ``rotor.speed``, ``rotor.pitch``); ``wind``
    (aero.wind.Wind); ``controller``: an object with ``step(Measurements) -> Demands`` and
    ``close()`` (control.discon.DisconController, control.builtin.BuiltinController) or None
    (actuators held: constant pitch and generator torque); ``dt`` [s]: requested controller
    step (rounded to whole simulation steps); ``efficiency`` [-] of the generator
    (electrical / mechanical power); ``limits``: ActuatorLimits.  ``elements``, ``inflow``,
    ``airfoil``, ``step_deg``, ``method``: as for TurbineModel and Simulator.  ``record``
    False keeps only the last history row (a node running for hours).

    It offers what a Simulator offers a caller that steps and reads it (the ROS node):
    ``step()`` (one controller step of ``dt``), ``t``, ``named()``, ``blade_deflections()``.
    """

    def __init__(self, turbine, wind, controller=None, dt: float = 0.05,
                 efficiency: float = 1.0, limits: Optional[ActuatorLimits] = None,
                 elements: Optional[int] = None, inflow: str = "oye",
                 airfoil: str = "quasi-steady", step_deg: float = 1.0, method: str = "auto",
                 rho: float = 1.225, record: bool = True):
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt: {dt!r} is not allowed; need a controller step > 0 [s]")
        if not 0 < efficiency <= 1:
            raise ValueError(f"efficiency: {efficiency!r} is not allowed; need 0 < e <= 1")
        turbine = free_generator(turbine)
        if elements is not None:
            turbine = turbine.with_elements(elements)
        self.turbine = turbine
        self.wind = wind
        self.controller = controller
        self.efficiency = float(efficiency)
        self.limits = limits or ActuatorLimits()
        nb = int(turbine.rotor.blades)
        self.gearbox = float(turbine.drivetrain.gearbox_ratio)
        pitch0 = -float(turbine.rotor.pitch)
        # the initial state: the steady (or periodic) state with the generator held at the
        # rotor speed, its torque the shaft's there, moved into the free generator's layout
        # (in the steady wind of t = 0: a history or a gust would make it aperiodic)
        steady = replace(wind, speed=float(wind.hub_speed(0.0)), history=(), gust=None)
        held = TurbineModel(replace(turbine, drivetrain=replace(turbine.drivetrain,
                                                                generator="prescribed")),
                            wind=steady, rho=rho, inflow=inflow, airfoil=airfoil)
        y_held = initial_state(held)
        torque0 = self._holding_torque(held, y_held, rho)
        self.inputs = ControlInputs(nb, pitch=pitch0, torque=torque0)
        self.model = TurbineModel(turbine, wind=wind, rho=rho, inflow=inflow, airfoil=airfoil,
                                  inductions=held.aero.inductions)
        self.model.set_controls(self.inputs)
        index = {name: i for i, name in enumerate(held.layout.names())}
        y0 = np.array([y_held[index[name]] if name in index else 0.0
                       for name in self.model.layout.names()])
        self.sim = Simulator(self.model, step_deg=step_deg, method=method, record=False,
                             y0=y0)
        #: simulation steps per controller step, and the controller step [s]
        self.substeps = max(1, int(round(dt / self.sim.h)))
        self.dt = self.substeps * self.sim.h
        self.omega0 = self.model.rotor_speed
        lay = self.model.layout
        self._i_gen = lay["generator_rate"]
        self._i_twist = lay["shaft_twist_rate"] if "shaft_twist_rate" in lay else None
        self._tips = [lay.blade(j).u[-1] for j in range(nb)]
        self._roots = [lay.blade(j).root_moment for j in range(nb)]
        self._tower = lay.tower() if lay.has_tower else None
        #: (time, the tower top's inertial velocity) at the last measurement (for the
        #: fore-aft and side-side accelerations ROSCO reads)
        self._top_velocity = None
        #: the measurements of the last history row (the next controller call's, taken
        #: once per instant)
        self._measured = None
        self.clipped = {"pitch": 0, "torque": 0}
        #: what the last controller step clipped (field names)
        self.last_clipped = []
        #: demands that replace the controller's (set_override): pitch (Nb,) [rad], torque
        #: [N m]; None: the controller's
        self.override = {"pitch": None, "torque": None}
        self.record = bool(record)
        self.rows = []
        self.wall_seconds = 0.0
        self._last = (self.inputs.pitch(0.0)[0].copy(), torque0)
        self._record()

    def _holding_torque(self, held, y, rho) -> float:
        """Generator torque [N m, HSS] that holds the rotor at its speed: the shaft's spring
        torque in the held model's state, or (a rigid shaft) the rotor's aerodynamic torque
        from the axisymmetric BEM steady state (assembly/aero_blade.py)."""
        t = self.turbine
        if t.drivetrain.stiffness is not None:
            return max(0.0, float(t.drivetrain.stiffness) * float(y[held.layout["shaft_twist"]])
                       / self.gearbox)
        blade = AeroelasticBlade(t, float(np.real(self.wind.velocity(0.0, np.zeros(3))[2])),
                                 elements=t.blade.elements, rho=rho)
        q_blade, _ = blade.root_loads(blade.steady_state())
        return max(0.0, t.rotor.blades * float(q_blade) / self.gearbox)

    # ------------------------------------------------------------------ signals
    def speeds(self):
        """(rotor speed, generator speed) [rad/s] (generator on the high-speed shaft)."""
        y = self.sim.y
        u_gen = float(y[self._i_gen])
        u_twist = float(y[self._i_twist]) if self._i_twist is not None else 0.0
        return self.omega0 + u_gen + u_twist, self.gearbox * (self.omega0 + u_gen)

    def hub_wind(self, t) -> float:
        """Horizontal wind speed at the hub [m/s]."""
        U = np.real(self.wind.velocity(t, np.zeros(3)))
        return float(math.hypot(U[1], U[2]))

    def measurements(self) -> Measurements:
        t = self.sim.t
        rotor, gen = self.speeds()
        pitch = self.inputs.pitch(t)[0]
        torque = float(self.inputs.generator_torque(t))
        shaft = torque * gen
        y = self.sim.y
        # out-of-plane root bending: the root moment turned back from the pitched root frame
        # into the hub's (coned) one, its component about b2
        delta = self.model.rigid.pitch_turn(t)[0]
        oop = np.array([float((rot1(d) @ y[r])[1]) for d, r in zip(delta, self._roots)])
        az = float(np.real(self.model.rigid.azimuth(t, y[:self.model.nq]))) % (2 * math.pi)
        return Measurements(time=t, pitch=pitch, generator_speed=gen, rotor_speed=rotor,
                            generator_torque=torque, electrical_power=shaft * self.efficiency,
                            shaft_power=shaft, hub_wind=self.hub_wind(t), azimuth=az,
                            root_out_of_plane=oop,
                            tower_top_acceleration=self._top_acceleration(t))

    def _top_acceleration(self, t) -> tuple:
        """(fore-aft, side-side) [m/s^2] of the tower top: the change of its inertial
        velocity over the last controller step, along the nacelle's y3 (downwind) and y2;
        (0, 0) with a rigid tower or at the first call."""
        if self._tower is None:
            return (0.0, 0.0)
        y = self.sim.y
        m = self.model
        top = np.stack([y[self._tower.theta[-1]], y[self._tower.V[-1]], y[self._tower.Omega[-1]]])
        fr = m.rigid.frames(y[:m.nq], t, top)
        v = fr["T"] @ top[1]                                   # inertial components
        last, self._top_velocity = self._top_velocity, (t, v)
        if last is None or not t > last[0]:
            return (0.0, 0.0)
        a = (v - last[1]) / (t - last[0])
        return (float(a @ fr["Y"][:, 2]), float(a @ fr["Y"][:, 1]))

    def _record(self):
        """One history row at the current instant (what the actuators do, not what was
        demanded: the demands are ramped in over the step); its measurements are kept for
        the next controller call."""
        m = self._measured = self.measurements()
        y = self.sim.y
        row = [m.time, m.hub_wind, m.rotor_speed * 30 / math.pi,
               m.generator_speed * 30 / math.pi, m.electrical_power / 1e3,
               m.generator_torque / 1e3, m.shaft_power / 1e3]
        row += list(np.degrees(m.pitch))
        for tip in self._tips:
            row += [float(y[tip][2]), float(y[tip][1])]     # flap (b3), edge (b2) [m]
        row += list(m.root_out_of_plane / 1e3)
        if self._tower is not None:
            # the tower's loads on the ground, root frame t (t1 up, t2 lateral, t3 downwind):
            # fore-aft bending about t2, side-side about t3
            M = y[self._tower.root_moment]
            row += [float(M[1]) / 1e3, float(M[2]) / 1e3]
        if not np.all(np.isfinite(row)):
            raise SimulationError(f"closed loop: non-finite signals at t = {m.time:.6g} s")
        if not self.record:
            self.rows.clear()
        self.rows.append(row)

    # ------------------------------------------------------------------ as a Simulator
    @property
    def t(self) -> float:
        """Simulation time [s]."""
        return self.sim.t

    def named(self) -> dict:
        """The simulator's named scalars (time, azimuth, yaw, teeter and rates), plus every
        rigid coordinate by name (the drivetrain's ``shaft_twist``, ``generator_azimuth``) and
        the ``rotor_speed`` [rad/s]."""
        out = self.sim.named()
        out["rotor_speed"] = self.speeds()[0]
        y = self.sim.y
        for i, c in enumerate(self.model.rigid.coordinates):
            out.setdefault(c, float(y[i]))
        return out

    def blade_deflections(self) -> list:
        """The simulator's blade deflections and root loads (Simulator.blade_deflections)."""
        return self.sim.blade_deflections()

    def rotor_state(self) -> dict:
        """The signals of the current instant a controller reads, as SI values (what the ROS
        node publishes on ``rotor_state``): ``time`` [s], ``wind_speed`` [m/s] and
        ``wind_direction`` [rad] at the hub, ``rotor_speed`` and ``generator_speed``
        [rad/s], ``generator_torque`` [N m, HSS], ``mechanical_power`` and
        ``electrical_power`` [W], ``pitch`` [rad, towards feather] and
        ``root_out_of_plane_moment`` [N m] per blade, ``pitch_override`` and
        ``torque_override`` (an external command holds), ``tower_top_displacement`` (3,) [m]
        in the tower root frame t (t1 up, t2 lateral, t3 downwind; zeros on a rigid tower)
        and ``tower_top_acceleration`` (fore-aft, side-side) [m/s^2] over the last controller
        step; ``aerodynamic_force``, ``aerodynamic_moment``, ``aerodynamic_thrust``,
        ``aerodynamic_torque``: :meth:`aero_loads`.  From the last record (the controller's
        measurements) and the state: nothing changes."""
        m = self._measured
        if m is None:
            raise ValueError("rotor_state: nothing recorded yet")
        y = self.sim.y
        top = np.zeros(3) if self._tower is None else np.array(y[self._tower.u[-1]], float)
        F, M, thrust, torque = self.aero_loads()
        return {"time": m.time, "wind_speed": m.hub_wind,
                "wind_direction": float(self.wind.direction),
                "rotor_speed": m.rotor_speed, "generator_speed": m.generator_speed,
                "generator_torque": m.generator_torque, "mechanical_power": m.shaft_power,
                "electrical_power": m.electrical_power,
                "pitch": np.asarray(m.pitch, float).copy(),
                "root_out_of_plane_moment": np.asarray(m.root_out_of_plane, float).copy(),
                "pitch_override": self.override["pitch"] is not None,
                "torque_override": self.override["torque"] is not None,
                "tower_top_displacement": top,
                "tower_top_acceleration": tuple(m.tower_top_acceleration),
                "aerodynamic_force": F, "aerodynamic_moment": M,
                "aerodynamic_thrust": thrust, "aerodynamic_torque": torque}

    def aero_loads(self):
        """The aerodynamic loads now: per blade (force, moment) (Nb, 3) integrated along the
        span in its root frame b [N, N m about the root point] (TurbineModel.aero_loads),
        and the rotor's thrust along the shaft axis s3 [N] and torque about it through the
        hub centre [N m]."""
        m, y, t = self.model, self.sim.y, self.sim.t
        F, M = m.aero_loads(y, t)
        q = y[:m.nq]
        tower = m.tower_top(np.zeros_like(y), y)
        fr = m.rigid.frames(q, t, tower)
        B, s3 = fr["B"], fr["S"][:, 2]
        P = m.rigid.root_points(q, t, tower) - m.rigid.teeter_point(fr)[None, :]
        FN, MN = np.einsum("kij,kj->ki", B, F), np.einsum("kij,kj->ki", B, M)
        torque = float(np.sum((np.cross(P, FN) + MN) @ s3))
        return F, M, float(np.sum(FN @ s3)), torque

    def last(self) -> dict:
        """The last history row by column name."""
        return dict(zip(self.columns(), self.rows[-1]))

    def columns(self) -> list:
        nb = len(self._tips)
        return (list(BASE_COLUMNS) + [f"pitch{k + 1}_deg" for k in range(nb)]
                + [f"tip{k + 1}_{d}_m" for k in range(nb) for d in ("flap", "edge")]
                + [f"root{k + 1}_out_of_plane_knm" for k in range(nb)]
                + (["tower_base_fore_aft_knm", "tower_base_side_side_knm"]
                   if self._tower is not None else []))

    # ------------------------------------------------------------------ running
    def set_override(self, pitch=None, torque=None) -> None:
        """Replace the controller's pitch (one angle or one per blade [rad, towards
        feather]) and/or generator torque [N m, HSS] from the next step on (None: leave that
        one as it is; clear_override gives it back); clipped to the limits like the
        controller's demands, never applied raw."""
        if pitch is not None:
            p = np.asarray(pitch, float)
            p = np.full(self.inputs.n_blades, float(p)) if p.ndim == 0 else p
            if p.shape != (self.inputs.n_blades,) or not np.all(np.isfinite(p)):
                raise ValueError(f"pitch: {np.asarray(pitch).tolist()!r} is not allowed; need "
                                 f"one finite angle [rad] or {self.inputs.n_blades}")
            self.override["pitch"] = p
        if torque is not None:
            if not np.isfinite(torque):
                raise ValueError(f"torque: {torque!r} is not allowed; need a finite number "
                                 "[N m]")
            self.override["torque"] = float(torque)

    def set_wind(self, speed: float, direction: float = 0.0) -> None:
        """A new steady wind from the next step on: ``speed`` [m/s] at hub height (0.1 to
        100) and ``direction`` [rad] about the yaw axis (|direction| < pi/2; aero.wind.Wind);
        the shear and tower shadow stay, a history or gust ends.  A step in the wind the
        rotor sees (its dynamic inflow lags it; Oye's time constants stay those of the
        start)."""
        if not (np.isfinite(speed) and 0.1 <= speed <= 100.0):
            raise ValueError(f"wind speed: {speed!r} is not allowed; need 0.1 to 100 [m/s]")
        if not (np.isfinite(direction) and abs(direction) < math.pi / 2):
            raise ValueError(f"wind direction: {direction!r} is not allowed; need |direction| "
                             "< pi/2 [rad] (the rotor faces the wind)")
        w = replace(self.wind, speed=float(speed), direction=float(direction), history=(),
                    gust=None)
        self.model.set_wind(w)
        self.wind = w

    def clear_override(self, which=("pitch", "torque")) -> None:
        """Give ``which`` ("pitch", "torque") back to the controller."""
        for k in ([which] if isinstance(which, str) else which):
            self.override[k] = None

    def step(self) -> None:
        """One controller step: measure, ask (the controller is called even while
        overridden: its filters and integrators follow), override, clip, ramp in,
        simulate."""
        t0 = self.sim.t
        self.last_clipped = []
        if self.controller is not None or any(v is not None for v in self.override.values()):
            if self.controller is not None:
                # the record's measurements of this instant, with the wind now blowing
                # (set_wind may have changed it since)
                m = replace(self._measured, hub_wind=self.hub_wind(t0))
                demands = self.controller.step(m)
                pitch, torque = demands.pitch, demands.torque
            else:
                pitch, torque = self._last
            if self.override["pitch"] is not None:
                pitch = self.override["pitch"]
            if self.override["torque"] is not None:
                torque = self.override["torque"]
            pitch, torque, clipped = self.limits.clip(pitch, torque, self._last[0],
                                                      self._last[1], self.dt)
            for k in clipped:
                self.clipped[k] += 1
            self.last_clipped = clipped
            self.inputs.command(t0, t0 + self.dt, pitch=pitch, torque=torque)
            self._last = (pitch, torque)
        self.sim.advance(self.substeps)
        self._record()

    def run(self, duration: float, progress: Optional[Callable] = None) -> dict:
        """Simulate ``duration`` [s] (whole controller steps; on an error the history so far
        is kept: save() it, then close()). Returns summary()."""
        n = int(math.ceil(duration / self.dt - 1e-9))
        w0 = time.perf_counter()
        last = w0
        try:
            for i in range(n):
                self.step()
                if progress is not None and time.perf_counter() - last > 0.25:
                    last = time.perf_counter()
                    r = self.rows[-1]
                    progress((i + 1) / n, f"t = {r[0]:.2f} s, {r[2]:.2f} rpm, "
                                          f"{r[4]:.0f} kW, pitch {r[7]:.2f} deg")
        finally:
            self.wall_seconds += time.perf_counter() - w0
        return self.summary()

    def close(self) -> None:
        if self.controller is not None:
            self.controller.close()

    def history(self) -> dict:
        H = np.array(self.rows)
        return {c: H[:, i] for i, c in enumerate(self.columns())}

    def save(self, path) -> None:
        """CSV (header row) or NPZ of the history (columns())."""
        write_table(path, self.columns(), np.array(self.rows))

    def summary(self) -> dict:
        H = self.history()
        sim = float(H["time"][-1] - H["time"][0])
        last = {c: float(v[-1]) for c, v in H.items()}
        return {"simulated_seconds": sim, "wall_seconds": self.wall_seconds,
                "real_time_factor": sim / self.wall_seconds if self.wall_seconds else None,
                "controller_step": self.dt, "controller_calls": len(self.rows) - 1,
                "clipped": dict(self.clipped), "final": last}

