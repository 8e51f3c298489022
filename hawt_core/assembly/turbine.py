"""The coupled turbine: one residual ``R(ydot, y, t) = 0`` for rigid bodies and flexible blades.

Coupling (paper, "Coupling of Subsystems"): the blades are clamped to the hub, so their root
frames move with the velocity ``v`` and angular velocity ``omega`` that the rigid-body
kinematics give; the root section loads ``F0, M0`` of each blade (unknowns of the beam
equations, the loads the blade exerts on the hub) enter Kane's dynamical equations of the
rigid bodies.

Unknowns: ``[q (rigid coordinates), u (rigid generalized speeds), blade 0, ..., blade Nb-1
(, tower)]`` where each blade (and the tower) block is BeamElements' layout (see
fem/beam.py). Rows: ``[rigid kinematics, rigid dynamics, blade 0 rows, ... (, tower rows)]``.
``StateLayout`` gives names to all of it.

Flexible tower: a beam clamped at the ground (inertial root frame, t1 up); its tip node's
theta, V, Omega are the tower-top coordinates and speeds of the rigid system (they move the
yaw bearing, hence the blade roots), and the rigid system's Kane rows for those speeds (the
loads it exerts on the tower top) are the tower's tip loads (docs/rigid-bodies.md).
"""
from __future__ import annotations

import functools
from typing import Optional

import numpy as np
import scipy.sparse as sp

from ..aero.wind import Wind
from ..fem.discretization import beam_elements, pointwise_jacobian
from ..model import Turbine
from ..numerics.jacobian import (STEP, ColouredJacobian, beam_station_pattern,
                                 block_tridiagonal_pattern)
from ..numerics.rotations import cross, rot_T_apply
from ..rigid import RigidSystem
from .layout import StateLayout
from .rotor_aero import RotorAerodynamics, description
from .tower_aero import TowerDrag

__all__ = ["TurbineModel"]


#: Trailing dimensions of each entry of the blades' root data (RotorAerodynamics.root_data).
_AIR_TAIL = {"vectors": 2, "B": 2, "P": 1, "time": 0, "spin": 0, "skew": 1}

#: Residual between the collocation times of a periodic steady state, relative to the load
#: scale, that its harmonics must reach (solvers/periodic.py): in a vacuum, and in wind (the
#: airfoil tables are C1 in the angle of attack, so the orbit's Fourier series decays
#: algebraically: NREL 5-MW at 8 m/s, 16 elements: 4e-7, 2e-6, 2e-8 with 4, 8, 16 harmonics,
#: 1e-8 still at 32).
INTERPOLATION_TOL = 1e-8
AERO_INTERPOLATION_TOL = 1e-6

#: Rigid coordinates of the drivetrain (hawt_core.rigid.kane): labelled "drivetrain".
DRIVETRAIN_COORDINATES = ("shaft_twist", "generator_azimuth")

class TurbineModel:
    """Rigid nacelle/hub (Kane) + flexible blades (mixed beam elements), one residual.

    ``elements`` overrides the blade's element count; ``rotor_speed`` the rotor speed.
    ``wind`` (aero.wind.Wind): blade-element loads on the blades in that wind, frozen wake
    (assembly/rotor_aero.py; the turbine needs its ``aerodynamics``), air density ``rho``
    [kg/m^3], ``inductions`` (a, a') to freeze (default: the rotor's axisymmetric BEM
    steady state); None: in a vacuum (the paper's model).  ``inflow`` ("frozen" or "oye":
    dynamic inflow) and ``airfoil`` ("quasi-steady" or "jones": unsteady airfoil) add
    aerodynamic unknowns after each blade's beam unknowns (assembly/rotor_aero.py); a blade's
    block is then ``blade_size`` long.
    """

    def __init__(self, turbine: Turbine, elements: Optional[int] = None,
                 rotor_speed: Optional[float] = None, wind: Optional[Wind] = None,
                 rho: float = 1.225, inductions: Optional[tuple] = None,
                 inflow: str = "frozen", airfoil: str = "quasi-steady"):
        if rotor_speed is not None:
            turbine = turbine.with_rotor_speed(rotor_speed)
        if elements is not None:
            turbine = turbine.with_elements(elements)
        self.turbine = turbine
        self.rotor_speed = float(turbine.rotor.speed)
        self.period = 2 * np.pi / self.rotor_speed if self.rotor_speed > 0 else np.inf
        self.rigid = RigidSystem(turbine)
        self.beam = beam_elements(turbine.blade, pitch=turbine.rotor.pitch)
        self.n_blades = int(turbine.rotor.blades)
        self.nq, self.nu = self.rigid.n_q, self.rigid.n_u
        #: the flexible tower's beam (None: rigid tower)
        self.tower = beam_elements(turbine.tower) if turbine.tower is not None else None
        #: the blades' aerodynamics (None: in a vacuum)
        self.wind, self.rho = wind, float(rho)
        self.aero = (RotorAerodynamics(turbine, wind, self.rotor_speed, self.beam, rho,
                                       inductions, inflow, airfoil)
                     if wind is not None else None)
        #: the flexible tower's drag in wind (None: none, or no tower table, or rigid tower)
        self.tower_drag = (TowerDrag(turbine, self.tower, wind, rho)
                           if wind is not None and self.tower is not None
                           and turbine.tower_aerodynamics is not None else None)
        #: what a periodic steady state's harmonics must reach (solvers/periodic.py)
        self.interpolation_tol = AERO_INTERPOLATION_TOL if wind is not None \
            else INTERPOLATION_TOL
        #: unknowns per blade: its beam's, then its aerodynamic states
        self.n_aero = self.aero.n if self.aero is not None else 0
        self.blade_size = self.beam.n + self.n_aero
        self._capture = None      # a dict the aerodynamics fill during one residual (aero_loads)
        #: a free generator's torque, trimmed by the steady state (solvers/trim.py
        #: GeneratorTrim: its ``torque`` [N m, HSS]) once a steady-state solver set it up
        self.generator_trim = None
        self.layout = StateLayout(self.rigid, self.n_blades, self.beam, self.tower,
                                  aero_states=self.aero.state_names if self.n_aero else ())
        self.n = self.layout.n
        blade_diff = np.concatenate([self.beam.differential, np.ones(self.n_aero, bool)])
        self.differential = np.concatenate(
            [np.ones(self.nq + self.nu, bool), np.tile(blade_diff, self.n_blades)]
            + ([self.tower.differential] if self.tower is not None else []))
        self.gravity = bool(turbine.gravity.enabled)
        #: columns of the blades' root loads (F0, M0 of blade 0, then blade 1, ...): the only
        #: blade unknowns the rigid rows depend on
        self._root_cols = np.concatenate([self.layout.blade_offset(k) + np.arange(6)
                                          for k in range(self.n_blades)])
        self._root_cols.setflags(write=False)
        if self.tower is not None:
            tl = self.layout.tower()
            #: tower tip unknowns: theta, V, Omega (each 3), and the tip equilibrium rows (in
            #: BeamElements' block order they sit where the tip's u, theta unknowns are)
            self._tip_theta, self._tip_V, self._tip_Om = tl.theta[-1], tl.V[-1], tl.Omega[-1]
            self._tip_rows = np.concatenate([tl.u[-1], tl.theta[-1]])
            self._tower_g = np.array([[-float(turbine.gravity.g), 0.0, 0.0]]) \
                if self.gravity else None
        self._reference_jac = None  # built on first use by jacobians_reference (tests only)
        self._load_scale = None     # computed on first use by load_scale
        #: the beam blocks' Jacobians from steps of the Gauss-point integrands
        #: (fem/beam_jacobian.py); False: by the colours of their patterns (tests and bench
        #: compare the two)
        self.pointwise_jacobians = True
        self._beam_pointwise = pointwise_jacobian(
            self.beam, len(self.aero.state_names) if self.n_aero else 0)
        self._tower_pointwise = (pointwise_jacobian(self.tower)
                                 if self.tower is not None else None)
        #: dR/dydot (rows, cols, values) of the blocks whose rows are affine in the rates
        #: with constant coefficients (_block_jacobians), computed on first use:
        #: (key, pointwise) -> entries
        self._rate_jacobians = {}

    @functools.cached_property
    def _beam_jac(self) -> ColouredJacobian:
        """The colours of a blade block's pattern (built when first used: pointwise_jacobians
        False)."""
        return ColouredJacobian(self._blade_pattern())

    @functools.cached_property
    def _tower_jac(self) -> ColouredJacobian:
        """The colours of the tower block's pattern (as _beam_jac)."""
        return ColouredJacobian(block_tridiagonal_pattern(self.tower.pattern_blocks()))

    def with_turbine(self, turbine: Turbine) -> "TurbineModel":
        """The model of ``turbine`` (the same mesh and rotor speed are the caller's to keep)
        in this model's wind, with this model's frozen inductions."""
        if self.aero is None:
            return TurbineModel(turbine)
        return TurbineModel(turbine, wind=self.wind, rho=self.rho,
                            inductions=self.aero.inductions, inflow=self.aero.inflow,
                            airfoil=self.aero.airfoil)

    def set_controls(self, controls) -> None:
        """Drive the pitch bearings and the generator torque by ``controls``
        (hawt_core.rigid.ControlInputs; None: the blades at the mesh's pitch, no generator
        torque); see RigidSystem.set_controls for the frames and signs."""
        self.rigid.set_controls(controls)

    @property
    def aero_description(self) -> Optional[str]:
        """What the aerodynamic model is (rotor_aero.description), None in a vacuum."""
        if self.aero is None:
            return None
        return description(self.aero.inflow, self.aero.airfoil, self.aero.skew_factor,
                           self.tower_drag is not None)

    def set_wind(self, wind: Wind) -> None:
        """Blow ``wind`` from now on (RotorAerodynamics.set_wind); ValueError in a vacuum."""
        if self.aero is None:
            raise ValueError("wind: this model is in a vacuum (built without wind)")
        self.aero.set_wind(wind)
        if self.tower_drag is not None:
            self.tower_drag.set_wind(wind)
        self.wind = wind

    @property
    def controls(self):
        """The ControlInputs driving the actuators, or None."""
        return self.rigid.controls

    def dynamic_dimension(self) -> int:
        """Number of dynamic states (finite eigenvalues of the linearized descriptor system):
        two per rigid coordinate and per flexible section direction of every beam element;
        equal to the exact deflation count (tests/test_assembly.py), without its O(n^3)."""
        d = 2 * self.nq + self.n_blades * (self.beam.dynamic_dimension() + self.n_aero)
        return d + (self.tower.dynamic_dimension() if self.tower is not None else 0)

    def tower_top(self, ydot, y) -> Optional[np.ndarray]:
        """(..., 5, 3) tower-top state [theta, V, Omega, Vdot, Omegadot] of the tower's tip
        node (tip section frame) for states (..., n), or None for a rigid tower."""
        if self.tower is None:
            return None
        return np.stack([y[..., self._tip_theta], y[..., self._tip_V], y[..., self._tip_Om],
                         ydot[..., self._tip_V], ydot[..., self._tip_Om]], -2)

    def _air(self, q, u, t, tower=None):
        """What the blades' aerodynamic loads need from the rigid coordinates q (..., nq) and
        speeds u (..., nu) at times t (...) and the tower-top state (RotorAerodynamics.root_data:
        arrays with leading dimensions (..., Nb); with dynamic inflow or an unsteady airfoil
        also ``spin``, the rotor's actual speed, rigid.rotor_spin); None in a vacuum."""
        if self.aero is None:
            return None
        fr = self.rigid.frames(q, t, tower)
        P = self.rigid.root_points(q, t, tower) if self.aero.field else None
        air = self.aero.root_data(fr["B"], fr["S"], P, t)
        if self.aero.inflow == "oye" or self.aero.lag is not None:
            spin = self.rigid.rotor_spin(q, u, t, tower)
            air["spin"] = np.broadcast_to(np.asarray(spin)[..., None],
                                          fr["B"].shape[:-2]).copy()
        return air

    @staticmethod
    def _air_flat(air, rows):
        """Root data (or None) with its leading dimensions (..., Nb) merged into ``rows``."""
        if air is None:
            return None
        return {k: a.reshape((rows,) + a.shape[a.ndim - _AIR_TAIL[k]:]) for k, a in air.items()}

    @staticmethod
    def _air_tile(air, C):
        """Flat root data (or None) repeated C times along the batch (colours)."""
        if air is None:
            return None
        return {k: np.tile(a, (C,) + (1,) * (a.ndim - 1)) for k, a in air.items()}

    def _blade_pattern(self):
        """Sparsity of one blade block's rows w.r.t. its unknowns: the beam's blocks and the
        aerodynamic states of each Gauss point."""
        k = len(self.aero.state_names) if self.n_aero else 0
        return beam_station_pattern(self.beam.pattern_blocks(), self.beam.station_points(), k)

    def _blade_residual(self, ydb, yb, v, w, g, air, out=None, capture=None):
        """Blade rows (K, blade_size) of K blades at root motions v, w (K, 3), gravity g
        (K, 3) or None and root data ``air`` (leading dimension K) or None (in a vacuum);
        ``out``: a dict the aerodynamics fill (RotorAerodynamics.loads); ``capture``: the
        beam's (BeamElements.residual)."""
        if air is None:
            return self.beam.residual(ydb, yb, v, w, g, capture=capture)
        nb = self.beam.n
        if out is None:
            out = self._capture if self._capture is not None else {}
        rb = self.beam.residual(ydb[:, :nb], yb[:, :nb], v, w, g, wind=air["vectors"],
                                section_loads=self.aero.loads(air, yb[:, nb:], ydb[:, nb:],
                                                              out), capture=capture)
        return np.concatenate([rb, out["rows"]], axis=1) if self.n_aero else rb

    def _tower_residual(self, ydt, yt, tip_loads, batch=1, t=0.0, capture=None):
        """Tower beam rows (batch, n_t) at times ``t`` (scalar or (batch,)): clamped at the
        ground (root frame inertial, at rest), gravity along -t1, tip loads = the rigid
        system's loads on the tower top, the tower's drag in wind (tower_aero.py)."""
        tip_loads = np.atleast_2d(tip_loads)
        z = np.zeros((batch, 3), dtype=tip_loads.dtype)
        g = None if self._tower_g is None else np.repeat(self._tower_g, batch, axis=0)
        tl = np.broadcast_to(tip_loads, (batch, 6))
        drag = None if self.tower_drag is None else self.tower_drag.section_loads(
            np.broadcast_to(np.asarray(t, float), (batch,)))
        return self.tower.residual(ydt, yt, z, z, g, tl[:, :3], tl[:, 3:],
                                   section_loads=drag, capture=capture)

    def aero_loads(self, y, t):
        """Aerodynamic loads on each blade at the state ``y`` and time ``t`` [s], integrated
        along the span: (force, moment), (Nb, 3), in each blade's root frame b [N], the
        moment about its root point [N m]: the residual's section loads turned from the
        section frames into b and integrated with the beam's Gauss rule.  They depend on the
        state only (no added mass), so no rates are needed.  Zeros in a vacuum."""
        nb = self.n_blades
        if self.aero is None:
            return np.zeros((nb, 3)), np.zeros((nb, 3))
        y = np.asarray(y, float)
        self._capture = captured = {}
        try:
            self.residual(np.zeros_like(y), y, t)
        finally:
            self._capture = None
        f, m, theta, position = captured["loads"]                        # (N, G, Nb, 3)
        fb, mb = rot_T_apply(theta, f), rot_T_apply(theta, m)
        weights = self.beam.h[:, None] * self.beam.w[None, :]              # (N, G)
        F = np.einsum("ng,ngbi->bi", weights, fb)
        M = np.einsum("ng,ngbi->bi", weights, cross(position, fb) + mb)
        return np.real(F), np.real(M)

    # ------------------------------------------------------------------ residual
    def residual(self, ydot, y, t):
        """R(ydot, y, t): rigid kinematics, rigid dynamics, blades[, tower]. Complex-safe.

        ``ydot``, ``y`` (n,) and a time ``t`` [s] give (n,); a batch ``ydot``, ``y`` (K, n)
        with times ``t`` (K,) gives (K, n), the residual at K instants in one vectorized call
        (the time-parallel simulation evaluates a window of steps this way)."""
        y, ydot = np.asarray(y), np.asarray(ydot)
        if y.ndim == 2:
            return self._residual_batch(ydot, y, np.broadcast_to(t, y.shape[:1]))
        return self._residual_batch(ydot[None], y[None], np.reshape(t, 1))[0]

    def _residual_batch(self, ydot, y, t):
        """(K, n) residual rows at K instants t (K,)."""
        if self.tower is not None:
            return self._residual_tower(ydot, y, t)
        K, nb, nbl = y.shape[0], self.n_blades, self.blade_size
        nq, nu, nr = self.nq, self.nu, self.nq + self.nu
        q, u = y[:, :nq], y[:, nq:nr]
        qd, ud = ydot[:, :nq], ydot[:, nq:nr]
        yb = y[:, nr:].reshape(K, nb, nbl)
        v, w = self.rigid.root_motion(q, u, t)                            # (K, nb, 3)
        g = self.rigid.gravity_in_root(q, t).reshape(K * nb, 3) if self.gravity else None
        air = self._air(q, u, t)
        rb = self._blade_residual(ydot[:, nr:].reshape(K * nb, nbl), yb.reshape(K * nb, nbl),
                                  v.reshape(K * nb, 3), w.reshape(K * nb, 3), g,
                                  self._air_flat(air, K * nb))
        out = np.empty((K, self.n), dtype=rb.dtype)
        out[:, :nq] = self.rigid.kinematics(q, qd, u, t)
        out[:, nq:nr] = self.rigid.dynamics(q, u, ud, t, yb[:, :, 0:3], yb[:, :, 3:6])
        out[:, nr:] = rb.reshape(K, nb * nbl)
        return out

    def _residual_tower(self, ydot, y, t):
        """(K, n) residual rows at K instants t (K,) with the flexible tower: the rigid
        system on the tower top (its loads on the tower are the tower's tip loads)."""
        K = y.shape[0]
        nq, nu, nr = self.nq, self.nu, self.nq + self.nu
        nb, nbl, to = self.n_blades, self.blade_size, self.layout.tower_offset
        q, u = y[:, :nq], y[:, nq:nr]
        qd, ud = ydot[:, :nq], ydot[:, nq:nr]
        yb = y[:, nr:to].reshape(K, nb, nbl)
        ydb = ydot[:, nr:to].reshape(K, nb, nbl)
        tw = self.tower_top(ydot, y)                                      # (K, 5, 3)
        v, w = self.rigid.root_motion(q, u, t, tw)                        # (K, nb, 3)
        g = self.rigid.gravity_in_root(q, t, tw).reshape(K * nb, 3) if self.gravity else None
        rb = self._blade_residual(ydb.reshape(K * nb, nbl), yb.reshape(K * nb, nbl),
                                  v.reshape(K * nb, 3), w.reshape(K * nb, 3), g,
                                  self._air_flat(self._air(q, u, t, tw), K * nb))
        rk = self.rigid.kinematics(q, qd, u, t)
        gf = self.rigid.generalized_forces(q, u, ud, t, yb[:, :, 0:3], yb[:, :, 3:6], tw)
        rt = self._tower_residual(ydot[:, to:], y[:, to:], gf[:, nu:], K, t)
        return np.concatenate([rk.reshape(K, nq), gf[:, :nu], rb.reshape(K, nb * nbl),
                               rt.reshape(K, -1)], axis=1)

    def sparsity(self) -> sp.csr_matrix:
        """Structural pattern of dR/dy and dR/dydot (an over-estimate at block level)."""
        nr = self.nq + self.nu
        blade = self._blade_pattern()
        P = sp.lil_matrix((self.n, self.n), dtype=bool)
        P[:, :nr] = True                    # rigid unknowns enter every row (root motion)
        P[:nr, :nr] = True
        P[:nr, self._root_cols] = True      # root loads enter the rigid dynamics
        blocks = [sp.csr_matrix((nr, nr), dtype=bool)] + [blade] * self.n_blades
        if self.tower is not None:
            tip = np.concatenate([self._tip_theta, self._tip_V, self._tip_Om])
            to = self.layout.tower_offset
            P[:to, tip] = True                # tower-top motion: rigid rows and blade rows
            # blade root loads -> tower-top loads
            P[self._tip_rows[:, None], self._root_cols[None, :]] = True
            blocks.append(block_tridiagonal_pattern(self.tower.pattern_blocks()))
        P = sp.csr_matrix(P)
        P = P + sp.block_diag(blocks, format="csr")
        return P.astype(bool)

    def jacobians(self, ydot, y, t):
        """Exact (complex-step) sparse Jacobians (dR/dy, dR/dydot), csc.

        Structured by subsystem so that the work is a handful of vectorized calls: blade rows
        w.r.t. their own unknowns (the Gauss-point steps of all blades in ONE batched beam
        call), the flexible tower's rows w.r.t. its unknowns at fixed tip loads (one call),
        and the rigid-body coupling (coupling_jacobians, two calls): every row w.r.t. the
        rigid unknowns and the tower top's theta, V, Omega (through the root motion, gravity,
        the air), the rigid rows and the tower-top loads (which enter the tower's tip rows
        additively) w.r.t. those, the root loads and the rates.
        """
        y = np.asarray(y, float)
        ydot = np.asarray(ydot, float)
        nq, nu, nr, nb, nbl = self.nq, self.nu, self.nq + self.nu, self.n_blades, self.blade_size
        to = self.layout.tower_offset if self.tower is not None else self.n
        q, u, ud = y[:nq], y[nq:nr], ydot[nq:nr]
        yb = y[nr:to].reshape(nb, nbl)
        ydb = ydot[nr:to].reshape(nb, nbl)
        tw = self.tower_top(ydot, y)
        v, w = self.rigid.root_motion(q, u, t, tw)
        g = self.rigid.gravity_in_root(q, t, tw) if self.gravity else None
        Jy_parts, Jd_parts = ([], [], []), ([], [], [])
        self._blade_block_jacobians(v, w, g, self._air(q, u, t, tw), yb, ydb, Jy_parts,
                                    Jd_parts)
        if self.tower is not None:
            tip = self.rigid.generalized_forces(q, u, ud, t, yb[:, 0:3], yb[:, 3:6], tw)[nu:]
            self._block_jacobians(lambda: self._tower_jac,
                                  lambda Yd, Y, C, cap: self._tower_residual(
                                      Yd, Y, tip, C, t, capture=cap),
                                  y[None, to:], ydot[None, to:], [to], Jy_parts, Jd_parts,
                                  constant_rates="tower", pointwise=self._tower_pointwise)
        if nr or self.tower is not None:
            self._append_coupling(self.coupling_jacobians(ydot, y, t), Jy_parts, Jd_parts)
        shape = (self.n, self.n)
        return tuple(sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                           np.concatenate(cols))), shape=shape)
                     for rows, cols, vals in (Jy_parts, Jd_parts))

    def _block_jacobians(self, jac, fun, yy, yyd, offsets, Jy_parts, Jd_parts,
                         constant_rates=None, pointwise=None):
        """Block-diagonal Jacobian entries of ``len(offsets)`` identical beams (the beam k's
        unknowns and rows start at ``offsets[k]``; ``yy``, ``yyd`` (nblk, n)) by complex
        steps, all steps of all beams in one call of ``fun(Yd, Y, C, capture) -> (C*nblk,
        n)``; appends (rows, cols, values) of dR/dy to ``Jy_parts``, of dR/dydot to
        ``Jd_parts``.

        ``pointwise``: a PointwiseBeamJacobian of the block (fem/beam_jacobian.py): the
        18 + k steps of the Gauss-point integrands (``capture``); None or
        ``self.pointwise_jacobians`` False: the colours of ``jac()`` (a ColouredJacobian,
        54 or more steps): the same values to round-off, two to three times the work.

        ``constant_rates``: a key, for blocks whose rows are affine in the rates with
        constant coefficients (a beam: the rates enter through the hat-weighted udot,
        thetadot, the constant mass matrices' [Pdot, Hdot] and the tip body's; the section
        loads read no rate; RotorAerodynamics.constant_rate_coefficients for the blades'
        aerodynamic states): dR/dydot is then computed once per model, the same for every
        beam (identical meshes), and only dR/dy is stepped: half the cost."""
        h = STEP
        nblk, n = yy.shape
        cached = self._rate_jacobians.get((constant_rates, self.pointwise_jacobians))
        if pointwise is not None and self.pointwise_jacobians:
            D = pointwise.directions

            def step(rates):
                return pointwise.entries(lambda Yd, Y, cap: fun(Yd, Y, D, cap), yyd, yy,
                                         rates)
        else:
            jac = jac()
            C = jac.n_colours
            seeds = np.repeat(jac.seeds, nblk, axis=0) * (1j * h)          # (C*nblk, n)
            Y, Yd = np.tile(yy, (C, 1)), np.tile(yyd, (C, 1))

            def step(rates):
                r = fun(Yd + seeds, Y, C, None) if rates else fun(Yd, Y + seeds, C, None)
                comp = r.imag.reshape(C, nblk, n) / h
                return jac._rows, jac._cols, comp[jac._col_colour, :, jac._rows].T
        for parts, (rows, cols, vals) in ((Jy_parts, step(False)),
                                          (Jd_parts, cached or step(True))):
            if parts is Jd_parts and cached is None and constant_rates is not None:
                self._rate_jacobians[(constant_rates, self.pointwise_jacobians)] = \
                    (rows, cols, vals[:1])
            for k in range(nblk):
                parts[0].append(rows + offsets[k]), parts[1].append(cols + offsets[k])
                parts[2].append(vals[min(k, len(vals) - 1)])

    def _blade_block_jacobians(self, v, w, g, air, yb, ydb, Jy_parts, Jd_parts):
        """Blade rows w.r.t. their own unknowns at the root motion (v, w), gravity g (Nb, 3)
        and the blades' root data ``air`` (_air; None in a vacuum) (see _block_jacobians)."""
        rep = lambda a, C: None if a is None else np.tile(a, (C, 1))    # (C*nb, 3)
        air = self._air_flat(air, self.n_blades)
        self._block_jacobians(
            lambda: self._beam_jac, lambda Yd, Y, C, cap: self._blade_residual(
                Yd, Y, rep(v, C), rep(w, C), rep(g, C), self._air_tile(air, C), capture=cap),
            yb, ydb, [self.layout.blade_offset(k) for k in range(self.n_blades)],
            Jy_parts, Jd_parts, constant_rates="blade" if (
                self.aero is None or self.aero.constant_rate_coefficients) else None,
            pointwise=self._beam_pointwise)

    @staticmethod
    def _append_coupling(c, Jy_parts, Jd_parts):
        """Append the nonzero entries of coupling_jacobians' blocks ``c`` (one time) to the
        (rows, cols, values) lists of dR/dy and dR/dydot."""
        for J, rows, cols, (rr_, cc_, vv_) in (
                (c["y_cols"], None, c["cols"], Jy_parts),
                (c["ydot_cols"], None, c["cols"], Jd_parts),
                (c["y_rows"], c["rows"], c["row_cols"], Jy_parts)):
            r, k = np.nonzero(J)
            rr_.append(r if rows is None else rows[r]), cc_.append(cols[k])
            vv_.append(J[r, k])

    def coupling_jacobians(self, ydot, y, t):
        """Exact (complex-step) partial derivatives of the rigid-body coupling: the entries of
        dR/dy and dR/dydot that turn with the azimuth (the blades turn, the yaw axis and the
        tower do not), which the window solver replaces every window (solvers/march/window.py):

        * ``cols``: the rigid unknowns, and with a flexible tower the tower top's theta, V,
          Omega (the tip node's; they move the rigid system);
        * ``y_cols``, ``ydot_cols`` (n, len(cols)): the coupling's part of those columns:
          the blade rows (through the root motion, gravity and the air the blades see), the
          rigid rows and, with a tower, the tower's tip equilibrium rows through the loads
          the rigid system exerts on the tower top. The tower's own beam terms are NOT
          included (they do not depend on the rigid system; the tip rows add the two), so
          these are the whole columns only on a rigid tower. The blade rows read no rate of
          these unknowns;
        * ``rows``: the rigid rows (and the tower's tip rows); ``row_cols``: the blades' root
          loads, the only other unknowns the coupling reads; ``y_rows`` (len(rows),
          len(row_cols)): the coupling's part there (no rate enters).

        ``t`` may be an array of M times: the arrays then have a leading dimension M (same
        state, several azimuths, in the same two batched calls: blade rows for all
        perturbations of ``cols``, coupling rows for all perturbations of y and ydot)."""
        y = np.asarray(y, float)
        ydot = np.asarray(ydot, float)
        ts = np.atleast_1d(np.asarray(t, float))
        M = len(ts)
        h = STEP
        nq, nu, nr, nb, nbl = self.nq, self.nu, self.nq + self.nu, self.n_blades, self.blade_size
        tower = self.tower is not None
        to = self.layout.tower_offset if tower else self.n
        yb, ydb = y[nr:to].reshape(nb, nbl), ydot[nr:to].reshape(nb, nbl)
        tw = self.tower_top(ydot, y)
        if tower:
            tip_cols = np.concatenate([self._tip_theta, self._tip_V, self._tip_Om])
            rate_cols = np.concatenate([np.arange(nr), self._tip_V, self._tip_Om])
            out_rows = np.concatenate([np.arange(nr), self._tip_rows])
            x0 = np.concatenate([y[:nr], tw[0], tw[1], tw[2]])
        else:
            tip_cols = np.zeros(0, int)
            rate_cols = out_rows = np.arange(nr)
            x0 = y[:nr]
        xcols = np.concatenate([np.arange(nr), tip_cols])
        kc = self._root_cols
        nx = len(xcols)
        # blade rows: perturb the rigid unknowns (and the tower top) through the root motion,
        # gravity and the air
        x = np.tile(x0.astype(complex), (M * nx, 1)) + 1j * h * np.tile(np.eye(nx), (M, 1))
        tt = np.repeat(ts, nx)
        twx = (np.concatenate([x[:, nr:].reshape(M * nx, 3, 3),
                               np.broadcast_to(tw[3:], (M * nx, 2, 3))], axis=1)
               if tower else None)
        q, u = x[:, :nq], x[:, nq:nr]
        v, w = self.rigid.root_motion(q, u, tt, twx)
        g = self.rigid.gravity_in_root(q, tt, twx).reshape(M * nx * nb, 3) \
            if self.gravity else None
        rb = self._blade_residual(np.tile(ydb, (M * nx, 1)),
                                  np.tile(yb, (M * nx, 1)).astype(complex),
                                  v.reshape(M * nx * nb, 3), w.reshape(M * nx * nb, 3), g,
                                  self._air_flat(self._air(q, u, tt, twx), M * nx * nb)
                                  ).imag / h
        y_cols = np.zeros((M, self.n, nx))
        y_cols[:, nr:to] = rb.reshape(M, nx, nb * nbl).transpose(0, 2, 1)
        ydot_cols = np.zeros((M, self.n, nx))
        # coupling rows, one call: perturbations of y at xcols and the root loads, then of
        # ydot at the rate columns, at every time
        cols_y = np.concatenate([xcols, kc])
        ny = len(cols_y)
        P = ny + len(rate_cols)
        Y = np.tile(y.astype(complex), (P, 1))
        Yd = np.tile(ydot.astype(complex), (P, 1))
        Y[np.arange(ny), cols_y] += 1j * h
        Yd[ny + np.arange(len(rate_cols)), rate_cols] += 1j * h
        Y, Yd, T = np.tile(Y, (M, 1)), np.tile(Yd, (M, 1)), np.repeat(ts, P)
        F = Y[:, nr:to].reshape(M * P, nb, nbl)
        d = np.concatenate([
            self.rigid.kinematics(Y[:, :nq], Yd[:, :nq], Y[:, nq:nr], T).reshape(M * P, nq),
            self.rigid.generalized_forces(Y[:, :nq], Y[:, nq:nr], Yd[:, nq:nr], T,
                                          F[:, :, 0:3], F[:, :, 3:6],
                                          self.tower_top(Yd, Y))], axis=1)
        d = (d.imag / h).reshape(M, P, len(out_rows)).transpose(0, 2, 1)   # (M, rows, P)
        y_cols[:, out_rows] = d[:, :, :nx]
        y_rows = d[:, :, nx:ny]
        ydot_cols[:, out_rows[:, None], np.searchsorted(xcols, rate_cols)[None, :]] = d[:, :, ny:]
        if np.ndim(t) == 0:
            y_cols, ydot_cols, y_rows = y_cols[0], ydot_cols[0], y_rows[0]
        return {"cols": xcols, "rows": out_rows, "row_cols": kc, "y_cols": y_cols,
                "ydot_cols": ydot_cols, "y_rows": y_rows}

    def jacobians_reference(self, ydot, y, t):
        """The same Jacobians by plain coloured complex steps on the whole residual (slow;
        the reference for tests of :meth:`jacobians`)."""
        if self._reference_jac is None:  # colouring the whole pattern is not cheap: lazily
            self._reference_jac = ColouredJacobian(self.sparsity())
        Jy = self._reference_jac(lambda yy: self.residual(ydot, yy, t), y)
        Jd = self._reference_jac(lambda yd: self.residual(yd, y, t), ydot)
        return Jy, Jd

    def linearize(self, y, ydot=None, t=0.0):
        """``(E, A)`` with ``E x' = A x`` for perturbations about (ydot, y) at time t."""
        ydot = np.zeros(self.n) if ydot is None else ydot
        Jy, Jd = self.jacobians(ydot, y, t)
        return Jd, -Jy

    # ------------------------------------------------------------------ steady state
    def _rigid_rotation_state(self, settle: bool = True) -> np.ndarray:
        """Rigid coordinates and speeds zero; blades undeformed in rigid rotation with the
        hub (their aerodynamic states settled, _settle_aero_states, unless ``settle`` is
        False: zero); a flexible tower at rest, undeformed (zeros)."""
        y = np.zeros(self.n)
        v, w = self.rigid.root_motion(np.zeros(self.nq), np.zeros(self.nu), 0.0)
        for k in range(self.n_blades):
            off = self.layout.blade_offset(k)
            y[off:off + self.beam.n] = self.beam.rigid_body_state(np.real(v[k]), np.real(w[k]))
        return self._settle_aero_states(y) if settle else y

    def _settle_aero_states(self, y) -> np.ndarray:
        """``y`` with every blade's aerodynamic states at their steady values for its beam
        state at t = 0 (RotorAerodynamics.initial_states: the frozen inductions, the lag
        states at the angle of attack of the blades' own motion)."""
        if not self.n_aero:
            return y
        y = y.copy()
        offs = [self.layout.blade_offset(k) for k in range(self.n_blades)]
        alpha = None
        if self.aero.lag is not None:       # the angles of attack, with the lag states zero
            for off in offs:
                y[off + self.beam.n:off + self.blade_size] = self.aero.initial_states()
            nq, nr = self.nq, self.nq + self.nu
            q, u = y[:nq], y[nq:nr]
            tw = self.tower_top(np.zeros(self.n), y)
            v, w = self.rigid.root_motion(q, u, 0.0, tw)
            g = self.rigid.gravity_in_root(q, 0.0, tw) if self.gravity else None
            yb = np.stack([y[off:off + self.blade_size] for off in offs])
            out = {}
            self._blade_residual(np.zeros_like(yb), yb, v, w, g,
                                 self._air_flat(self._air(q, u, 0.0, tw), self.n_blades), out)
            alpha = out["alpha"]                                        # (N, G, Nb)
        for k, off in enumerate(offs):
            y[off + self.beam.n:off + self.blade_size] = self.aero.initial_states(
                None if alpha is None else alpha[..., k])
        return y

    def initial_guess(self) -> np.ndarray:
        """The rigid rotation (_rigid_rotation_state); in wind every blade in the blade's
        own aeroelastic steady state on the spinning hub (aerodynamic states settled)."""
        y = self._rigid_rotation_state(settle=False)
        if self.aero is not None and self.aero.blade_state is not None:
            for k in range(self.n_blades):
                off = self.layout.blade_offset(k)
                y[off:off + self.beam.n] = self.aero.blade_state
        return self._settle_aero_states(y)       # once, at the blades' final beam state

    def load_scale(self) -> float:
        """The scale [N] of the loads a steady state balances: the largest residual (at
        least 1) of the blades turning undeformed with the hub, rigid coordinates zero, at
        t = 0 (centrifugal, gravity and aerodynamic loads against unloaded sections); the
        steady-state solvers' tolerances are relative to it."""
        if self._load_scale is None:
            r = self.residual(np.zeros(self.n), self._rigid_rotation_state(), 0.0)
            self._load_scale = max(1.0, float(np.abs(r).max()))
        return self._load_scale

    def display_rows(self):
        """Indices and weights of displacement-like unknowns (units: metres of motion): rigid
        rotations (yaw, teeter, shaft twist, generator azimuth) times the rotor radius; blade displacements; blade bending slopes (theta2,
        theta3) times the blade length (the tip metres they cause); the twist theta1 times the
        sections' torsional radius of gyration sqrt(i1 / m) (the metres its mass moves: a twist
        times the blade length would outweigh a flap deflection by the span-to-chord ratio, and
        a torsion sideband would then name a flap mode's frequency); the tower's displacements
        and its rotations times the rotor radius."""
        lay = self.layout
        R = self.turbine.hub.radius + self.turbine.blade.length
        L = self.turbine.blade.length
        sec = self.turbine.blade.sections
        r_g = float(np.sqrt(np.mean(sec.i1) / np.mean(sec.mass)))
        idx, wts = [], []
        for name in ("yaw", "teeter") + DRIVETRAIN_COORDINATES:
            if name in lay:
                idx.append(lay[name]), wts.append(R)
        for k in range(self.n_blades):
            b = lay.blade(k)
            u, th = b.u[1:].ravel(), b.theta[1:].ravel()
            idx += u.tolist() + th.tolist()
            wts += [1.0] * len(u) + [r_g, L, L] * (len(th) // 3)
        if lay.has_tower:   # tower displacements [m] and rotations (rotor radius: tip metres)
            tl = lay.tower()
            u, th = tl.u[1:].ravel(), tl.theta[1:].ravel()
            idx += u.tolist() + th.tolist()
            wts += [1.0] * len(u) + [R] * len(th)
        return np.array(idx), np.array(wts)

    # ------------------------------------------------------------------ symmetry
    def blade_relabelling(self) -> sp.csr_matrix:
        """Matrix S of the blade-relabelling symmetry ``R(S ydot, S y, t + T/Nb) =
        S R(ydot, y, t)``: after 1/Nb revolution blade k stands where blade k+1 stood, so
        the state S y has blade k+1's unknowns in blade k's slot (S[k, k+1] = I); the rigid
        unknowns map as the rigid system says (the teeter angle of a two-bladed hub changes
        sign); the tower maps to itself. Used by Peters' Fast Floquet and the multi-blade
        transform. (With two blades S is its own inverse, so the direction only shows from
        three blades on.)"""
        rigid_sign = self.rigid.relabelling_signs()
        nr = self.nq + self.nu
        rows, cols, vals = list(range(nr)), list(range(nr)), list(rigid_sign)
        if self.tower is not None:      # the tower (inertial frame) maps to itself
            tw = self.layout.tower_offset + np.arange(self.tower.n)
            rows += tw.tolist()
            cols += tw.tolist()
            vals += [1.0] * self.tower.n
        nb = self.blade_size
        for k in range(self.n_blades):
            src = self.layout.blade_offset((k + 1) % self.n_blades) + np.arange(nb)
            dst = self.layout.blade_offset(k) + np.arange(nb)
            rows += dst.tolist()
            cols += src.tolist()
            vals += [1.0] * nb
        return sp.csr_matrix((vals, (rows, cols)), shape=(self.n, self.n))
