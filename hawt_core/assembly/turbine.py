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
from ..fem.beam import BeamElements
from ..fem.beam_jacobian import PointwiseBeamJacobian
from ..fem.sections import mesh_beam
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
        self.beam = BeamElements(mesh_beam(turbine.blade, pitch=turbine.rotor.pitch))
        self.n_blades = int(turbine.rotor.blades)
        self.nq, self.nu = self.rigid.n_q, self.rigid.n_u
        #: the flexible tower's beam (None: rigid tower)
        self.tower = BeamElements(mesh_beam(turbine.tower)) if turbine.tower is not None else None
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
        self._beam_pointwise = PointwiseBeamJacobian(
            self.beam, len(self.aero.state_names) if self.n_aero else 0)
        self._tower_pointwise = (PointwiseBeamJacobian(self.tower)
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
        arrays with leading dimensions (..., Nb); with dynamic inflow also ``spin``, the
        rotor's actual speed, rigid.rotor_spin); None in a vacuum."""
        if self.aero is None:
            return None
        fr = self.rigid.frames(q, t, tower)
        P = self.rigid.root_points(q, t, tower) if self.aero.field else None
        air = self.aero.root_data(fr["B"], fr["S"], P, t)
        if self.aero.inflow == "oye":
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
        return beam_station_pattern(self.beam.pattern_blocks(), self.beam.xg.shape[1], k)

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

        Structured by subsystem so that the work is a handful of vectorized calls:
        blade rows w.r.t. their own unknowns (all colours of all blades in ONE batched beam
        call), blade rows w.r.t. the rigid unknowns (through the root motion, one batched call),
        rigid rows w.r.t. rigid unknowns and root loads (a few small calls).
        """
        y = np.asarray(y, float)
        ydot = np.asarray(ydot, float)
        if self.tower is not None:
            return self._jacobians_tower(ydot, y, t)
        nq, nu, nr, nb, nbl = self.nq, self.nu, self.nq + self.nu, self.n_blades, self.blade_size
        q, u, qd, ud = y[:nq], y[nq:nr], ydot[:nq], ydot[nq:nr]
        yb = y[nr:].reshape(nb, nbl)
        ydb = ydot[nr:].reshape(nb, nbl)
        v, w = self.rigid.root_motion(q, u, t)
        g = self.rigid.gravity_in_root(q, t) if self.gravity else None
        rows_y, cols_y, vals_y = [], [], []
        rows_d, cols_d, vals_d = [], [], []
        self._blade_block_jacobians(v, w, g, self._air(q, u, t), yb, ydb,
                                    (rows_y, cols_y, vals_y), (rows_d, cols_d, vals_d))
        if nr:          # the rigid columns and the rigid rows (they vary with the azimuth)
            c = self.coupling_jacobians(ydot, y, t)
            rc, kc = c["rigid"], c["root_loads"]
            for J, rows, cols, vals in ((c["y_cols"], rows_y, cols_y, vals_y),
                                        (c["ydot_cols"], rows_d, cols_d, vals_d)):
                rr, cc = np.nonzero(J)
                rows.append(rr), cols.append(rc[cc]), vals.append(J[rr, cc])
            rr, cc = np.nonzero(c["y_rows"])
            rows_y.append(rc[rr]), cols_y.append(kc[cc]), vals_y.append(c["y_rows"][rr, cc])
        shape = (self.n, self.n)
        Jy = sp.csc_matrix((np.concatenate(vals_y), (np.concatenate(rows_y), np.concatenate(cols_y))), shape=shape)
        Jd = sp.csc_matrix((np.concatenate(vals_d), (np.concatenate(rows_d), np.concatenate(cols_d))), shape=shape)
        return Jy, Jd

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

    def _jacobians_tower(self, ydot, y, t):
        """Structured Jacobians with a flexible tower: blade rows w.r.t. blade unknowns (one
        batched call), blade rows w.r.t. the rigid unknowns and the tower-top theta, V, Omega
        (one batched call through the root motion and gravity), tower rows w.r.t. tower
        unknowns at fixed tip loads (one batched call), and the rigid rows plus the tower-top
        loads (which enter the tower's tip equilibrium rows additively) w.r.t. the rigid
        unknowns and rates, the blade root loads and the tower-top state and rates."""
        h = STEP
        nq, nu, nr, nb, nbl = self.nq, self.nu, self.nq + self.nu, self.n_blades, self.blade_size
        to = self.layout.tower_offset
        q, u, ud = y[:nq], y[nq:nr], ydot[nq:nr]
        yb = y[nr:to].reshape(nb, nbl)
        ydb = ydot[nr:to].reshape(nb, nbl)
        yt, ydt = y[to:], ydot[to:]
        tw = self.tower_top(ydot, y)
        v, w = self.rigid.root_motion(q, u, t, tw)
        g = self.rigid.gravity_in_root(q, t, tw) if self.gravity else None
        rows_y, cols_y, vals_y = [], [], []
        rows_d, cols_d, vals_d = [], [], []
        Jy_parts, Jd_parts = (rows_y, cols_y, vals_y), (rows_d, cols_d, vals_d)
        self._blade_block_jacobians(v, w, g, self._air(q, u, t, tw), yb, ydb, Jy_parts,
                                    Jd_parts)
        gf = self.rigid.generalized_forces(q, u, ud, t, yb[:, 0:3], yb[:, 3:6], tw)
        tip = gf[nu:]
        self._block_jacobians(lambda: self._tower_jac,
                              lambda Yd, Y, C, cap: self._tower_residual(Yd, Y, tip, C, t,
                                                                         capture=cap),
                              yt[None], ydt[None], [to], Jy_parts, Jd_parts,
                              constant_rates="tower", pointwise=self._tower_pointwise)

        # blade rows w.r.t. rigid q, u and the tower-top theta, V, Omega (root motion,
        # gravity), all perturbations in one batched call
        tip_cols = np.concatenate([self._tip_theta, self._tip_V, self._tip_Om])
        xcols = np.concatenate([np.arange(nr), tip_cols])
        nx = len(xcols)
        x = np.concatenate([q, u, tw[0], tw[1], tw[2]]) + 1j * h * np.eye(nx)   # (nx, nx)
        twx = np.concatenate([x[:, nr:].reshape(nx, 3, 3),
                              np.broadcast_to(tw[3:], (nx, 2, 3))], axis=1)
        tt = np.full(nx, float(t))
        vx, wx = self.rigid.root_motion(x[:, :nq], x[:, nq:nr], tt, twx)   # (nx, nb, 3)
        gx = self.rigid.gravity_in_root(x[:, :nq], tt, twx).reshape(nx * nb, 3) \
            if self.gravity else None
        r = self._blade_residual(np.tile(ydb, (nx, 1)), np.tile(yb, (nx, 1)).astype(complex),
                                 vx.reshape(nx * nb, 3), wx.reshape(nx * nb, 3), gx,
                                 self._air_flat(self._air(x[:, :nq], x[:, nq:nr], tt, twx),
                                                nx * nb)).imag / h
        r = r.reshape(nx, nb * nbl)
        rr, cc = np.nonzero(r.T)
        rows_y.append(nr + rr), cols_y.append(xcols[cc]), vals_y.append(r.T[rr, cc])

        # rigid rows and tower-top loads w.r.t. rigid unknowns/rates, root loads, tower top:
        # every perturbation of y, then of ydot, in one batched call
        out_rows = np.concatenate([np.arange(nr), self._tip_rows])
        cols_wrt_y = np.concatenate([np.arange(nr), self._root_cols, tip_cols])
        cols_wrt_d = np.concatenate([np.arange(nr), self._tip_V, self._tip_Om])
        ny, M = len(cols_wrt_y), len(cols_wrt_y) + len(cols_wrt_d)
        yy = np.tile(y.astype(complex), (M, 1))
        yyd = np.tile(ydot.astype(complex), (M, 1))
        yy[np.arange(ny), cols_wrt_y] += 1j * h
        yyd[ny + np.arange(M - ny), cols_wrt_d] += 1j * h
        Fb = yy[:, nr:to].reshape(M, nb, nbl)
        tm = np.full(M, float(t))
        rk = self.rigid.kinematics(yy[:, :nq], yyd[:, :nq], yy[:, nq:nr], tm).reshape(M, nq)
        d = np.concatenate([rk, self.rigid.generalized_forces(
            yy[:, :nq], yy[:, nq:nr], yyd[:, nq:nr], tm, Fb[:, :, 0:3], Fb[:, :, 3:6],
            self.tower_top(yyd, yy))], axis=1).imag / h                     # (M, nr + 6)
        for part, cols, rr_, cc_, vv_ in ((d[:ny], cols_wrt_y, rows_y, cols_y, vals_y),
                                          (d[ny:], cols_wrt_d, rows_d, cols_d, vals_d)):
            pr, pc = np.nonzero(part)
            rr_.append(out_rows[pc]), cc_.append(cols[pr]), vv_.append(part[pr, pc])
        shape = (self.n, self.n)
        Jy = sp.csc_matrix((np.concatenate(vals_y), (np.concatenate(rows_y),
                                                     np.concatenate(cols_y))), shape=shape)
        Jd = sp.csc_matrix((np.concatenate(vals_d), (np.concatenate(rows_d),
                                                     np.concatenate(cols_d))), shape=shape)
        return Jy, Jd

    def coupling_jacobians(self, ydot, y, t):
        """Exact (complex-step) partial derivatives of the rigid-body coupling, the entries of
        dR/dy and dR/dydot that vary with the azimuth when the yaw is free (rigid tower):

        * ``y_cols``, ``ydot_cols`` (n, nq + nu): every row w.r.t. the rigid unknowns
          ``rigid`` (the rigid rows, and the blade rows through the root motion and gravity;
          the blade rows do not depend on the rigid rates);
        * ``y_rows`` (nq + nu, len(root_loads)): the rigid rows w.r.t. the blades' root
          loads ``root_loads`` (the only other unknowns they depend on; no rate enters).

        ``t`` may be an array of M times: the arrays then have a leading dimension M (same
        state, several azimuths, in the same two batched calls: blade rows for all rigid
        perturbations, rigid rows for all perturbations of y and ydot)."""
        if self.tower is not None:
            raise ValueError("coupling_jacobians: not available with a flexible tower")
        y = np.asarray(y, float)
        ydot = np.asarray(ydot, float)
        ts = np.atleast_1d(np.asarray(t, float))
        M = len(ts)
        h = STEP
        nq, nu, nr, nb, nbl = self.nq, self.nu, self.nq + self.nu, self.n_blades, self.blade_size
        rc = np.arange(nr)
        kc = self._root_cols
        yb, ydb = y[nr:].reshape(nb, nbl), ydot[nr:].reshape(nb, nbl)
        # blade rows: perturb the rigid unknowns through the root motion and gravity
        x = np.tile(y[:nr].astype(complex), (M * nr, 1)) + 1j * h * np.tile(np.eye(nr), (M, 1))
        tt = np.repeat(ts, nr)
        v, w = self.rigid.root_motion(x[:, :nq], x[:, nq:], tt)
        g = self.rigid.gravity_in_root(x[:, :nq], tt).reshape(M * nr * nb, 3) \
            if self.gravity else None
        air = self._air(x[:, :nq], x[:, nq:], tt)
        rb = self._blade_residual(np.tile(ydb, (M * nr, 1)),
                                  np.tile(yb, (M * nr, 1)).astype(complex),
                                  v.reshape(M * nr * nb, 3), w.reshape(M * nr * nb, 3), g,
                                  self._air_flat(air, M * nr * nb)).imag / h
        y_cols = np.zeros((M, self.n, nr))
        y_cols[:, nr:] = rb.reshape(M, nr, nb * nbl).transpose(0, 2, 1)
        ydot_cols = np.zeros((M, self.n, nr))
        # rigid rows, one call: perturbations of y at the rigid and root-load columns, then
        # of ydot at the rigid columns, at every time
        cols = np.concatenate([rc, kc])
        P = len(cols) + nr
        Y = np.tile(y.astype(complex), (P, 1))
        Yd = np.tile(ydot.astype(complex), (P, 1))
        Y[np.arange(len(cols)), cols] += 1j * h
        Yd[len(cols) + rc, rc] += 1j * h
        Y, Yd, T = np.tile(Y, (M, 1)), np.tile(Yd, (M, 1)), np.repeat(ts, P)
        F = Y[:, nr:].reshape(M * P, nb, nbl)
        d = np.concatenate([self.rigid.kinematics(Y[:, :nq], Yd[:, :nq], Y[:, nq:nr], T),
                            self.rigid.dynamics(Y[:, :nq], Y[:, nq:nr], Yd[:, nq:nr], T,
                                                F[:, :, 0:3], F[:, :, 3:6])], axis=1)
        d = (d.imag / h).reshape(M, P, nr).transpose(0, 2, 1)               # (M, nr, P)
        y_cols[:, :nr] = d[:, :, :nr]
        y_rows = d[:, :, nr:len(cols)]
        ydot_cols[:, :nr] = d[:, :, len(cols):]
        if np.ndim(t) == 0:
            y_cols, ydot_cols, y_rows = y_cols[0], ydot_cols[0], y_rows[0]
        return {"rigid": rc, "root_loads": kc, "y_cols": y_cols, "ydot_cols": ydot_cols,
                "y_rows": y_rows}

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
