"""Rigid-body subsystem of the turbine (nacelle yaw, shaft, teetering hub) by Kane's method.

Reproduces Patil, Lee & Hodges (AIAA 2001-0064), "Treatment of Rigid-Body Subsystem",
Eqs. 7-11, as a general vector implementation of Kane's method in plain NumPy: any number of
blades, undersling, precone, shaft tilt, yaw and teeter springs/dampers, gravity on the hub
mass, either DOF removable.  See ``docs/rigid-bodies.md``.

Frames (every basis right-handed; "x turned by a about z" is a right-handed rotation)
-------------------------------------------------------------------------------------
* tower T = inertial N: ``n1`` (= ``t1``) points up along the yaw axis; gravity is ``-g n1``.
  Origin: the point TY on the yaw axis at the tower top (fixed for a rigid tower).
  Flexible tower (``turbine.tower`` given): TY moves with the tower's tip node and the yaw
  bearing sits on the tip section frame (basis ``T = C(theta_tip)^T``), ``Y = T rot1(qy)``;
  the tower-top velocity and angular velocity (tip-node V, Omega, B components) are six more
  generalized speeds whose Kane rows are the loads the rigid system exerts on the tower top
  (see ``generalized_forces`` and docs/rigid-bodies.md, "Flexible tower").
* nacelle Y: N turned by the yaw angle ``qy`` about ``y1 = n1``
  (``y2 = cos qy n2 + sin qy n3``, ``y3 = -sin qy n2 + cos qy n3``).
* tilted nacelle frame Y': Y turned by ``+tilt`` about ``y2``
  (``y'3 = cos(tilt) y3 + sin(tilt) y1``: positive tilt raises the shaft axis towards ``+y1``;
  the hub sits at ``+d s3``, so positive tilt raises the rotor). Zero tilt: Y' = Y.
* shaft S: Y' turned by the azimuth ``psi = Omega0 t`` about ``s3 = y'3``
  (``s1 = cos psi y'1 + sin psi y'2``, ``s2 = -sin psi y'1 + cos psi y'2``); at t = 0 blade 0
  points (nearly) up, ``s1 = y'1``.  Omega0 is prescribed (the drive torque is a workless
  constraint torque about s3 for every generalized speed).
* hub H: S turned by ``-qh`` about ``s2 = h2``, i.e. the paper's sign
  ``h1 = cos qh s1 + sin qh s3``, ``h3 = -sin qh s1 + cos qh s3``
  (positive qh tilts blade 0's root axis h1 towards +s3, downwind/flapwise).
* blade k root frame b (k = 0..Nb-1, ``phi_k = 2 pi k / Nb``): H turned by ``phi_k`` about
  ``h3``, then by ``-precone`` about its own ``b2`` so that a positive precone tilts ``b1``
  towards ``+h3`` (``b1 = cos(beta) a1 + sin(beta) h3`` with ``a1`` the unconed direction).
  Two blades: blade 1 ("D") has ``d1 = -h1, d2 = -h2, d3 = h3`` (no precone).
* blade k root point: ``P_k = TY + h y1 + d s3 + e (cos phi_k h1 + sin phi_k h2) - lhd1 h3``
  (h = ``nacelle.shaft_height`` along the yaw axis, d = ``nacelle.yaw_to_teeter`` along the
  (tilted) shaft, negative upwind, e = ``hub.radius``, lhd1 = ``hub.undersling``).  The
  teeter-axis point is ``SH = TY + h y1 + d s3``; with a rigid tower ``h`` changes nothing
  (TY is fixed and the yaw axis passes through it).

Generalized coordinates and speeds (paper's Eq. 7)
--------------------------------------------------
``q = (qy, qh)``, ``u = (U1, U2)`` with ``U1 = qy'`` and ``U2 = omega^H . h2``; hence
``qh' = U1 (y1 . s2) - U2`` (= ``-U2 - sin(psi) U1`` without tilt; ``y1 . s2 =
-sin(psi) cos(tilt)``).  ``nacelle.yaw_free = False`` drops qy/U1 (yaw locked at 0);
``hub.teeter = False`` drops qh/U2 (hub fixed to the shaft).

Bodies
------
* nacelle Y: yaw inertia ``Iy_n = Iy - (hub yaw inertia at qh = 0)
  = Iy - Ihlat cos^2(tilt) - Ihlong sin^2(tilt) - m_hub d^2 cos^2(tilt)`` about y1 (model.py:
  Iy includes the hub; for the paper, ``Iy - Ihlat``); its mass centre is on the yaw axis at TY
  (so its mass and other inertias play no role with the rigid tower).
* hub H: principal inertia ``Ihlat`` about h1, h2 and ``Ihlong`` about h3, mass ``m_hub`` at SH.
* shaft S massless; the tower rigid and fixed, or a flexible beam (then the nacelle's mass at
  ``TY + Y cg_offset`` and its inertia ``diag(Iy_n - m |offset_perp|^2, I_pitch, I_roll)``
  about its mass centre matter, and the yaw bearing's point mass at TY).

Loads
-----
``root_force[k]`` / ``root_moment[k]`` are the force and moment that blade k exerts ON THE HUB,
applied at the root point P_k, with components in blade k's root frame b (the beam's root
reactions ``F0, M0``, not the reaction on the blade).  Yaw spring/damper: torque
``-(K_y qy + C_y U1) y1`` on Y (reaction on T).  Teeter spring/damper: torque
``(K_h qh + C_h qh') h2`` on H (reaction on S), i.e. it resists qh and the relative teeter rate
qh' (physically dissipative; see the note on Eq. 9 in docs/rigid-bodies.md).

Residuals and signs
-------------------
``dynamics`` returns Kane's ``F_r + F_r*`` (generalized active plus inertia forces), r over the
active speeds.  For the paper's configuration the teeter row equals the paper's Eq. 9
(theory.md) with the same sign, except that Eq. 9's damper term ``+ch U2`` is
``-ch (U2 + sin(psi) U1)`` here (= ``ch qh'``; equal when ch = 0).  The yaw row is the moment
balance about the yaw axis plus ``-(y1 . s2) = sin(psi) cos(tilt)`` times the teeter row.

Everything is complex-safe: no abs, real parts, comparisons or branches on q, u, udot or loads
(branches are only on the configuration), so Jacobians may be taken by complex step.
"""
from __future__ import annotations

import numpy as np

from ..numerics.rotations import cross as _cross, dot as _dot, matvec as _mv, rot1, rot2, rot3
from ..numerics.rotations import tip_basis
from .actuators import ControlInputs

__all__ = ["RigidSystem"]


class RigidSystem:
    """Nacelle (yaw) + prescribed-speed shaft + teetering hub, Kane's method, any blade count.

    Parameters are read from a :class:`hawt_core.model.Turbine`.  All array arguments may be
    real or complex; see the module docstring for frames, signs and the meaning of the loads.
    With a rigid tower every method also accepts a batch: leading dimensions on ``q``, ``u``,
    their rates, ``t`` and the root loads (e.g. ``q`` (K, n_q), ``t`` (K,), root loads
    (K, Nb, 3)) give results with the same leading dimensions, one per batch entry (the
    time-parallel simulation evaluates a window of steps in one call this way).
    """

    def __init__(self, turbine):
        rotor, hub, nac = turbine.rotor, turbine.hub, turbine.nacelle
        self.turbine = turbine
        self.n_blades = int(rotor.blades)
        self.omega0 = float(rotor.speed)
        self.precone = float(rotor.precone)
        self.e = float(hub.radius)
        self.lhd1 = float(hub.undersling)
        self.d = float(nac.yaw_to_teeter)
        #: height of the shaft/yaw-axis intersection above the tower-top point [m]
        self.shaft_height = float(getattr(nac, "shaft_height", 0.0))
        #: point mass at the tower-top point that does not yaw [kg]
        self.yaw_bearing_mass = float(getattr(nac, "yaw_bearing_mass", 0.0))
        self.tilt = float(nac.shaft_tilt)
        self.yaw_free = bool(nac.yaw_free)
        self.teeter = bool(hub.teeter)
        self.k_yaw = float(nac.yaw_stiffness)
        self.c_yaw = float(nac.yaw_damping)
        self.k_teeter = float(hub.teeter_stiffness)
        self.c_teeter = float(hub.teeter_damping)
        self.hub_mass = float(hub.mass)
        #: counterweight point mass [kg] and its position relative to the teeter-axis point
        #: SH in the hub basis h (opposite blade 0)
        self.counterweight_mass = float(getattr(hub, "counterweight_mass", 0.0))
        self.counterweight_offset = np.array(
            [-float(getattr(hub, "counterweight_radius", 0.0)), 0.0, 0.0])
        self.hub_inertia = np.diag([hub.inertia_lateral, hub.inertia_lateral,
                                    hub.inertia_longitudinal]).astype(float)
        self.g = float(turbine.gravity.g) if turbine.gravity.enabled else 0.0
        ct, st = np.cos(self.tilt), np.sin(self.tilt)
        hub_yaw_inertia = (hub.inertia_lateral * ct ** 2 + hub.inertia_longitudinal * st ** 2
                           + self.hub_mass * (self.d * ct) ** 2)
        #: yaw inertia of the nacelle body alone (Iy minus the hub's share at qh = 0)
        self.nacelle_yaw_inertia = float(nac.yaw_inertia) - hub_yaw_inertia
        #: True when the tower is a flexible beam: the tower-top motion (6 more generalized
        #: speeds, values taken from the tower's tip node) enters everything
        self.flexible_tower = turbine.tower is not None
        self.nacelle_mass = float(nac.mass)
        #: nacelle mass centre relative to the tower-top point TY, in Y (y1 up, y2, y3 shaft)
        self.nacelle_cg = np.array(nac.cg_offset, float).reshape(3)
        i_yaw_cg = self.nacelle_yaw_inertia - self.nacelle_mass * (self.nacelle_cg[1] ** 2
                                                                     + self.nacelle_cg[2] ** 2)
        #: nacelle body inertia about its mass centre, Y basis (yaw, pitch about y2, roll about y3)
        self.nacelle_inertia = np.diag([i_yaw_cg, float(nac.inertia_pitch),
                                        float(nac.inertia_roll)])
        if self.flexible_tower and i_yaw_cg < 0:
            raise ValueError(
                "nacelle.yaw_inertia: %g kg m^2 is not allowed with this hub and nacelle mass "
                "centre; need at least %g (hub share + nacelle mass x offset^2)"
                % (nac.yaw_inertia, nac.yaw_inertia - i_yaw_cg))

        dt = getattr(turbine, "drivetrain", None)
        #: flexible shaft: twist DOF (rotor azimuth - gearbox-input azimuth) with its spring
        self.shaft_flexible = dt is not None and dt.stiffness is not None
        #: free generator: the gearbox-input azimuth is a DOF (else it turns at Omega0 t)
        self.generator_free = dt is not None and dt.generator == "free"
        self.k_shaft = float(dt.stiffness) if self.shaft_flexible else 0.0
        self.c_shaft = float(dt.damping) if dt is not None else 0.0
        #: generator rotor inertia about its axis (high-speed shaft) [kg m^2] and gear ratio
        self.generator_inertia = float(dt.generator_inertia) if dt is not None else 0.0
        self.gearbox_ratio = float(dt.gearbox_ratio) if dt is not None else 1.0
        #: the generator torque law's slope dT/d(omega_g) [N m s/rad, HSS] (free generator)
        self.generator_slope = (float(getattr(dt, "generator_torque_slope", 0.0))
                                if self.generator_free else 0.0)
        self.active = (self.yaw_free, self.teeter, self.shaft_flexible, self.generator_free)
        names = (("yaw", "yaw_rate"), ("teeter", "teeter_speed"),
                 ("shaft_twist", "shaft_twist_rate"), ("generator_azimuth", "generator_rate"))
        coords = [c for (c, _), on in zip(names, self.active) if on]
        speeds = [v for (_, v), on in zip(names, self.active) if on]
        self.coordinates = tuple(coords)
        self.speeds = tuple(speeds)
        self.n_q = len(coords)
        self.n_u = len(speeds)

        nb = self.n_blades
        self._tilt_rotation = rot2(self.tilt)
        self.blade_azimuth = 2.0 * np.pi * np.arange(nb) / nb
        #: (Nb, 3, 3): columns = blade k's root basis b in the hub basis h
        self.root_in_hub = np.array([rot3(p) @ rot2(-self.precone)
                                     for p in self.blade_azimuth])
        #: (Nb, 3): root point relative to the teeter-axis point SH, hub basis h
        self.root_offset_hub = np.array([[self.e * np.cos(p), self.e * np.sin(p), -self.lhd1]
                                         for p in self.blade_azimuth])
        #: the blades' pitch already built into their meshes (structural sign, model.Rotor)
        self.mesh_pitch = float(rotor.pitch)
        #: pitch bearings and generator torque as functions of time (set_controls), or None:
        #: the blades held at the mesh's pitch, no generator torque
        self.controls = None

    def set_controls(self, controls) -> None:
        """Drive the pitch bearings and the generator by ``controls`` (rigid.actuators.
        ControlInputs, or None to remove them).  Blade k's root frame turns about its root
        axis b1 by ``-beta_k(t) - Rotor.pitch`` (beta towards feather; the mesh already holds
        Rotor.pitch), at the rate ``-beta_k'`` (the bearing's motion is prescribed: its torque is
        a constraint torque, reacted by the hub).  The generator torque ``T(t)`` [N m] acts
        on the generator rotor against its spin, reacted by the nacelle: ``-N T`` on the
        generator-speed row (N the gearbox ratio); it needs the free generator."""
        if controls is None:
            self.controls = None
            return
        if not isinstance(controls, ControlInputs):
            raise ValueError(f"controls: {type(controls).__name__} is not allowed; need a "
                             "hawt_core.rigid.actuators.ControlInputs")
        if controls.n_blades != self.n_blades:
            raise ValueError(f"controls: {controls.n_blades} blades is not allowed; this "
                             f"turbine has {self.n_blades}")
        if not self.generator_free and np.any(controls.generator_torque(0.0) != 0):
            raise ValueError("controls: a generator torque needs drivetrain.generator: free "
                             "(this turbine's generator turns at the prescribed speed)")
        controls.torque_allowed = self.generator_free
        self.controls = controls

    def pitch_turn(self, t):
        """(delta, delta_dot) (t.shape + (Nb,)): the turn of each root frame about b1 beyond
        the mesh's pitch [rad] and its rate [rad/s]; None without controls."""
        if self.controls is None:
            return None
        beta, rate = self.controls.pitch(t)
        return -beta - self.mesh_pitch, -rate

    def _generator_torque_row(self, t, U4=0.0):
        """The generator torque's generalized force on the generator-speed row, (t.shape):
        minus the gear ratio N times the torque, which is the controls' (trimmed or
        commanded) torque plus the torque law's slope times the generator's speed change
        N U4 (U4: the gearbox-input speed beyond Omega0)."""
        if not self.generator_free:
            return 0.0
        N = self.gearbox_ratio
        row = -N * N * self.generator_slope * U4 if self.generator_slope else 0.0
        if self.controls is not None:
            row = row - N * self.controls.generator_torque(t)
        return row

    # ------------------------------------------------------------------ helpers
    def _split(self, x, n):
        """Active entries (..., n) -> (yaw, teeter, shaft twist, generator) parts (...),
        zeros for the DOFs this turbine does not have."""
        x = np.asarray(x)
        if x.ndim == 0 or x.shape[-1] != n:
            raise ValueError(f"expected shape (..., {n}), got {x.shape}")
        out, i = [], 0
        for on in self.active:
            if on:
                out.append(x[..., i])
                i += 1
            else:
                out.append(np.zeros(x.shape[:-1]))
        return tuple(out)

    def _join(self, *parts):
        """(yaw, teeter, shaft twist, generator) parts -> active entries on a last axis."""
        out = [p for p, on in zip(parts, self.active) if on]
        if not out:
            return np.zeros(np.shape(parts[0]) + (0,))
        return np.stack(np.broadcast_arrays(*out), -1)

    def azimuth(self, t, q=None):
        """Rotor (shaft) azimuth [rad]: ``Omega0 t`` plus the generator's azimuth deviation
        and the shaft twist when the drivetrain has them (blade 0 up at 0)."""
        psi = self.omega0 * np.asarray(t)
        if q is not None and (self.shaft_flexible or self.generator_free):
            _, _, qd, qg = self._split(q, self.n_q)
            psi = psi + qd + qg
        return psi

    def frames(self, q, t, tower=None):
        """Basis matrices in N (columns = unit vectors): dict Y, S, H and B (Nb, 3, 3); with a
        flexible tower also T (the tower-top section frame; Y = T rot1(qy))."""
        qy, qh, _, _ = self._split(q, self.n_q)
        if self.flexible_tower:
            Tt = tip_basis(self._tower_state(tower)[..., 0, :])
            Y = Tt @ rot1(qy)
        else:
            Tt = None
            Y = rot1(qy)
        S = (Y @ self._tilt_rotation if self.tilt else Y) @ rot3(self.azimuth(t, q))
        H = S @ rot2(-qh)
        B = H[..., None, :, :] @ self.root_in_hub                       # (..., Nb, 3, 3)
        turn = self.pitch_turn(t)
        if turn is not None:
            B = B @ rot1(turn[0])                                      # the pitch bearings
        out = {"Y": Y, "S": S, "H": H, "B": B}
        if Tt is not None:
            out["T"] = Tt
        return out

    def teeter_point(self, frames) -> np.ndarray:
        """Position [m] of the teeter-axis point SH (rotor apex) relative to the tower-top
        point TY, inertial components: ``h y1 + d s3`` (``frames`` from :meth:`frames`)."""
        return self.shaft_height * frames["Y"][..., :, 0] + self.d * frames["S"][..., :, 2]

    def _kin(self, q, u, t):
        """Velocities, partial velocities and their ingredients, all in N (the last result is
        cached: one residual evaluation asks for it twice, root motion and dynamics; callers
        treat the returned dict as read-only)."""
        q, u, t = np.asarray(q), np.asarray(u), np.asarray(t)
        return self._cached("_kin_cache", (q, u, t), lambda: self._kin_uncached(q, u, t))

    def _cached(self, slot, arrays, compute):
        """The last result of ``compute()`` kept in attribute ``slot``, keyed by the bytes,
        dtypes and shapes of ``arrays`` (and the controls' version)."""
        key = tuple((a.dtype.str, a.shape, a.tobytes()) for a in arrays) + (
            None if self.controls is None else (id(self.controls), self.controls.version),)
        cached = getattr(self, slot, None)
        if cached is not None and cached[0] == key:
            return cached[1]
        out = compute()
        setattr(self, slot, (key, out))
        return out

    def _kin_uncached(self, q, u, t):
        qy, qh, qd, qg = self._split(q, self.n_q)
        U1, U2, U3, U4 = self._split(u, self.n_u)
        fr = self.frames(q, t)
        Y, S, H = fr["Y"], fr["S"], fr["H"]
        y1, s3, h2 = Y[..., :, 0], S[..., :, 2], H[..., :, 1]
        # batch shapes: scalars (...), vectors (..., 3); Uc (..., 4, 1) against row vectors
        Uc = np.stack(np.broadcast_arrays(U1, U2, U3, U4), -1)[..., None]
        z = 0.0 * h2
        w_Y = Uc[..., 0, :] * y1
        y1h2 = _dot(y1, h2)               # = y1 . s2
        # partial angular velocities (rows: U1 yaw, U2 teeter, U3 shaft twist, U4 generator),
        # (..., 4, 3): the shaft S spins with both drivetrain speeds, the gearbox input E
        # with the generator's, the generator rotor G at N times it
        N = self.gearbox_ratio
        if self.teeter:
            wr_H = np.stack([y1 - y1h2[..., None] * h2, h2, s3, s3], -2)
        else:
            wr_H = np.stack([y1, z, s3, s3], -2)
        wr_S = np.stack([y1, z, s3, s3], -2)
        wr_E = np.stack([y1, z, z, s3], -2)
        wr_G = np.stack([y1, z, z, N * s3], -2)
        w_H = (wr_H * Uc).sum(-2) + self.omega0 * s3
        w_G = (wr_G * Uc).sum(-2) + N * self.omega0 * s3
        # partial velocities of SH (teeter-axis point) and of the root points
        vr_SH = np.stack([self.d * _cross(y1, s3), z, z, z], -2)
        v_SH = vr_SH[..., 0, :] * Uc[..., 0, :]
        rho = np.swapaxes(H @ self.root_offset_hub.T, -1, -2)          # (..., Nb, 3) in N
        vr_P = vr_SH[..., :, None, :] + _cross(wr_H[..., :, None, :],
                                               rho[..., None, :, :])     # (..., 2, Nb, 3)
        v_P = v_SH[..., None, :] + _cross(w_H[..., None, :], rho)
        return dict(qy=qy, qh=qh, qd=qd, U1=U1, U2=U2, U3=U3, U4=U4, fr=fr, y1=y1,
                    s3=s3, h2=h2, y1h2=y1h2, w_Y=w_Y, w_H=w_H, w_G=w_G, wr_H=wr_H,
                    wr_S=wr_S, wr_E=wr_E, wr_G=wr_G,
                    vr_SH=vr_SH, v_SH=v_SH, vr_P=vr_P, v_P=v_P, rho=rho)

    # ------------------------------------------------------------------ flexible tower
    def _tower_state(self, tower):
        """(..., 5, 3) tower-top state [theta, V, Omega, Vdot, Omegadot] (zeros when None)."""
        if tower is None:
            return np.zeros((5, 3))
        tw = np.asarray(tower)
        if tw.ndim < 2 or tw.shape[-1] != 3 or tw.shape[-2] not in (3, 5):
            raise ValueError(f"tower: expected shape (..., 5, 3) (theta, V, Omega, Vdot, "
                             f"Omegadot of the tower tip), got {tw.shape}")
        if tw.shape[-2] == 3:
            tw = np.concatenate([tw, np.zeros(tw.shape[:-2] + (2, 3), dtype=tw.dtype)], -2)
        return tw

    def _check_tower(self, tower):
        if tower is not None and not self.flexible_tower:
            raise ValueError("tower: this rigid system has a rigid tower; pass tower=None")

    def _kin_tower(self, q, u, t, tower):
        """Flexible-tower kinematics in N: velocities and partial velocities for the speeds
        z = (U1, U2, U3, U4, V_1..3, Omega_1..3) (yaw, teeter, shaft twist, generator, the
        tower top; removed DOFs included, with zero partials).  Batched: q (..., n_q),
        u (..., n_u), t (...), tower (..., 5, 3); vectors (..., 3), partials (..., 10, 3).
        The last result is cached (as _kin: root motion, rotor spin and Kane's equations
        of one residual evaluation ask for the same); callers treat it as read-only."""
        q, u, t = np.asarray(q), np.asarray(u), np.asarray(t)
        tw = self._tower_state(tower)
        return self._cached("_kin_tower_cache", (q, u, t, tw),
                            lambda: self._kin_tower_uncached(q, u, t, tw))

    def _kin_tower_uncached(self, q, u, t, tw):
        """_kin_tower without the cache; ``tw`` already checked (_tower_state, (..., 5, 3))."""
        qy, qh, qd, qg = self._split(q, self.n_q)
        U1, U2, U3, U4 = (np.asarray(x) for x in self._split(u, self.n_u))
        fr = self.frames(q, t, tw)
        Tt, Y, S, H = fr["T"], fr["Y"], fr["S"], fr["H"]
        y1, s3, h2 = Y[..., :, 0], S[..., :, 2], H[..., :, 1]
        w_T = _mv(Tt, tw[..., 2, :])
        v_T = _mv(Tt, tw[..., 1, :])
        w_Y = w_T + U1[..., None] * y1
        y1h2 = _dot(y1, h2)
        z = 0.0 * h2
        if self.teeter:
            wr1, wr2 = y1 - y1h2[..., None] * h2, h2
        else:
            wr1, wr2 = y1, z
        N = self.gearbox_ratio
        w_H = (w_T + wr1 * U1[..., None] + wr2 * U2[..., None]
               + (self.omega0 + U3 + U4)[..., None] * s3)
        w_G = w_Y + N * (self.omega0 + U4)[..., None] * s3
        r_SH = self.shaft_height * y1 + self.d * s3
        r_c = _mv(Y, self.nacelle_cg)
        v_SH = v_T + _cross(w_Y, r_SH)
        rho = np.swapaxes(H @ self.root_offset_hub.T, -1, -2)       # (..., Nb, 3) in N
        v_P = v_SH[..., None, :] + _cross(w_H[..., None, :], rho)
        b = [Tt[..., :, j] for j in range(3)]                       # tower-top basis in N
        zt = [z, z, z]                                              # no tower-top translation
        rows = lambda vs: np.stack(vs, -2)                          # (..., 10, 3)
        wr_Y = rows([y1, z, z, z] + zt + b)
        wr_H = rows([wr1, wr2, s3, s3] + zt + b)
        wr_S = rows([y1, z, s3, s3] + zt + b)
        wr_E = rows([y1, z, z, s3] + zt + b)                        # gearbox input
        wr_G = rows([y1, z, z, N * s3] + zt + b)                    # generator rotor
        vr_SH = rows([_cross(y1, r_SH), z, z, z] + b + [_cross(bj, r_SH) for bj in b])
        vr_c = rows([_cross(y1, r_c), z, z, z] + b + [_cross(bj, r_c) for bj in b])
        vr_P = vr_SH[..., :, None, :] + _cross(wr_H[..., :, None, :],
                                               rho[..., None, :, :])  # (..., 10, Nb, 3)
        vr_T = rows([z, z, z, z] + b + zt)                          # the tower-top point TY
        return dict(vr_T=vr_T, qy=qy, qh=qh, qd=qd, U1=U1, U2=U2, U3=U3, U4=U4, fr=fr, tw=tw,
                    Tt=Tt, y1=y1, s3=s3, h2=h2, w_G=w_G, wr_S=wr_S, wr_E=wr_E, wr_G=wr_G,
                    y1h2=y1h2, w_T=w_T, v_T=v_T, w_Y=w_Y, w_H=w_H, wr1=wr1, wr2=wr2,
                    r_SH=r_SH, r_c=r_c, v_SH=v_SH, v_P=v_P, rho=rho, wr_Y=wr_Y, wr_H=wr_H,
                    vr_SH=vr_SH, vr_c=vr_c, vr_P=vr_P)

    def _kane_tower(self, q, u, udot, t, Fb, Mb, tower):
        """Kane's F_r + F_r* for z = (U1, U2, U3, U4, V_1..3, Omega_1..3), flexible tower;
        batched as _kin_tower (Fb, Mb (..., Nb, 3)), result (..., n_u + 6)."""
        k = self._kin_tower(q, u, t, tower)
        Ud1, Ud2, Ud3, Ud4 = (np.asarray(x)[..., None] for x in self._split(udot, self.n_u))
        U1, U2, qy, qh = k["U1"], k["U2"], k["qy"], k["qh"]
        U3, U4 = k["U3"], k["U4"]
        tw, Tt = k["tw"], k["Tt"]
        y1, s3, h2 = k["y1"], k["s3"], k["h2"]
        w_T, v_T, w_Y, w_H = k["w_T"], k["v_T"], k["w_Y"], k["w_H"]
        Y, H, B = k["fr"]["Y"], k["fr"]["H"], k["fr"]["B"]
        gen = lambda P, v: np.einsum("...ri,...i->...r", P, v)     # partials . vector
        # --- accelerations (tower top: a_T = T (Vdot + Omega x V), alpha_T = T Omegadot)
        alpha_T = _mv(Tt, tw[..., 4, :])
        a_T = _mv(Tt, tw[..., 3, :]) + _cross(w_T, v_T)
        y1dot = _cross(w_T, y1)
        alpha_Y = alpha_T + Ud1 * y1 + U1[..., None] * y1dot
        s3dot = _cross(w_Y, s3)
        h2dot = _cross(w_H, h2)
        if self.teeter:
            wr1dot = y1dot - ((_dot(y1dot, h2) + _dot(y1, h2dot))[..., None] * h2
                              + k["y1h2"][..., None] * h2dot)
            wr2dot = h2dot
        else:
            wr1dot = y1dot
            wr2dot = 0.0 * h2
        alpha_H = (alpha_T + k["wr1"] * Ud1 + k["wr2"] * Ud2 + (Ud3 + Ud4) * s3
                   + wr1dot * U1[..., None] + wr2dot * U2[..., None]
                   + (self.omega0 + U3 + U4)[..., None] * s3dot)
        r_SH, r_c = k["r_SH"], k["r_c"]
        a_SH = a_T + _cross(alpha_Y, r_SH) + _cross(w_Y, _cross(w_Y, r_SH))
        a_c = a_T + _cross(alpha_Y, r_c) + _cross(w_Y, _cross(w_Y, r_c))
        # --- generalized inertia forces (hub at SH, nacelle at its mass centre)
        I_H = H @ self.hub_inertia @ np.swapaxes(H, -1, -2)
        I_Y = Y @ self.nacelle_inertia @ np.swapaxes(Y, -1, -2)
        T_H = -(_mv(I_H, alpha_H) + _cross(w_H, _mv(I_H, w_H)))
        T_Y = -(_mv(I_Y, alpha_Y) + _cross(w_Y, _mv(I_Y, w_Y)))
        Fstar = (gen(k["wr_H"], T_H) + gen(k["vr_SH"], -self.hub_mass * a_SH)
                 + gen(k["wr_Y"], T_Y) + gen(k["vr_c"], -self.nacelle_mass * a_c)
                 + gen(k["vr_T"], -self.yaw_bearing_mass * a_T))
        if self.generator_inertia:
            N = self.gearbox_ratio
            alpha_G = alpha_Y + N * Ud4 * s3 + N * (self.omega0 + U4)[..., None] * s3dot
            Fstar = Fstar + gen(k["wr_G"], self._generator_inertia_torque(alpha_G, k["w_G"],
                                                                           s3))
        gN = np.array([-self.g, 0.0, 0.0])
        if self.counterweight_mass:
            # the counterweight at SH + rho_c (hub-fixed), with its weight
            rho_c = _mv(H, self.counterweight_offset)
            vr_cw = k["vr_SH"] + _cross(k["wr_H"], rho_c[..., None, :])
            a_cw = a_SH + _cross(alpha_H, rho_c) + _cross(w_H, _cross(w_H, rho_c))
            Fstar = Fstar + gen(vr_cw, self.counterweight_mass * (gN - a_cw))
        # --- generalized active forces
        F_N = _mv(B, Fb)
        M_N = _mv(B, Mb)
        F = (np.einsum("...rki,...ki->...r", k["vr_P"], F_N) + gen(k["wr_H"], M_N.sum(axis=-2))
             + gen(k["vr_SH"], self.hub_mass * gN) + gen(k["vr_c"], self.nacelle_mass * gN)
             + gen(k["vr_T"], self.yaw_bearing_mass * gN))
        # yaw spring/damper between Y and the tower top: works only through U1; the
        # generator torque on the generator row
        drive = self._rows(yaw=-self.k_yaw * qy - self.c_yaw * U1,
                           generator=self._generator_torque_row(t, U4))
        F = F + np.concatenate([drive, np.zeros(drive.shape[:-1] + (6,))], -1)
        if self.teeter:
            qhdot = U1 * k["y1h2"] - U2
            tau = (self.k_teeter * qh + self.c_teeter * qhdot)[..., None] * h2   # on H
            F = F + gen(k["wr_H"] - k["wr_S"], tau)                             # reaction on S
        if self.shaft_flexible:
            # shaft spring and damper on S about s3, reaction on the gearbox input E
            tau = -(self.k_shaft * k["qd"] + self.c_shaft * U3)[..., None] * s3
            F = F + gen(k["wr_S"] - k["wr_E"], tau)
        res = F + Fstar
        return np.concatenate([self._join(*(res[..., r] for r in range(4))), res[..., 4:]],
                              -1)

    def generalized_forces(self, q, u, udot, t, root_force, root_moment, tower=None):
        """Kane's ``F_r + F_r*`` for every generalized speed: (n_u,) without a flexible tower
        (= :meth:`dynamics`), (n_u + 6,) with one: the rows of the active speeds, then those of
        the tower-top speeds V_tip, Omega_tip, which are the force and the moment (about the
        tower-top point) that the rigid system exerts ON the tower top, in the tower-top
        section frame B.  ``tower``: (5, 3) [theta, V, Omega, Vdot, Omegadot] of the tower's
        tip node (B components; None = at rest, undeformed)."""
        if not self.flexible_tower:
            self._check_tower(tower)
            return self.dynamics(q, u, udot, t, root_force, root_moment)
        Fb = np.asarray(root_force)
        Mb = np.asarray(root_moment)
        nb = self.n_blades
        if Fb.shape[-2:] != (nb, 3) or Mb.shape[-2:] != (nb, 3):
            raise ValueError(f"root loads must have shape (..., {nb}, 3)")
        return self._kane_tower(q, u, udot, t, Fb, Mb, tower)

    def tower_top_loads(self, q, u, udot, t, root_force, root_moment, tower=None):
        """(force (3,), moment (3,)) exerted by the rigid system (with the blade root loads)
        on the tower top, tower-top section frame B; the moment is about the tower-top point."""
        if not self.flexible_tower:
            raise ValueError("tower: this turbine has a rigid tower")
        r = self.generalized_forces(q, u, udot, t, root_force, root_moment, tower)
        return r[self.n_u:self.n_u + 3], r[self.n_u + 3:]

    # ------------------------------------------------------------------ public API
    def root_motion(self, q, u, t, tower=None):
        """(v, w), arrays (Nb, 3): inertial velocity of each blade-root point and inertial
        angular velocity of the hub (= root frame), each in that blade's root basis b.
        ``tower``: the tower-top state (flexible tower only, see generalized_forces)."""
        if self.flexible_tower:
            k = self._kin_tower(q, u, t, tower)
            B = k["fr"]["B"]
            v = np.einsum("...kji,...kj->...ki", B, k["v_P"])
            w = np.einsum("...kji,...j->...ki", B, k["w_H"])
            return v, self._with_pitch_rate(w, t)
        self._check_tower(tower)
        k = self._kin(q, u, t)
        B = k["fr"]["B"]
        Bt = np.swapaxes(B, -1, -2)
        v = _mv(Bt, k["v_P"])                                    # B^T v_P per blade
        w = _mv(Bt, k["w_H"][..., None, :])
        return v, self._with_pitch_rate(w, t)

    def _with_pitch_rate(self, w, t):
        """The root frames' angular velocities (..., Nb, 3) plus the pitch rate about b1."""
        turn = self.pitch_turn(t)
        if turn is None:
            return w
        w = w + 0 * turn[1][..., None]          # the pitch rate's batch shape, complex-safe
        w[..., 0] = w[..., 0] + turn[1]
        return w

    def rotor_spin(self, q, u, t, tower=None):
        """(...): the hub's angular velocity about the shaft axis s3 [rad/s], w_H . s3 (the
        nominal speed plus the drivetrain's speeds, and what yaw and tower motion add about
        s3): the speed whose tangential velocity the rotor's swirl scales with."""
        k = self._kin_tower(q, u, t, tower) if self.flexible_tower else self._kin(q, u, t)
        return _dot(k["w_H"], k["s3"])

    def root_points(self, q, t, tower=None):
        """(..., Nb, 3): the blade-root points P_k relative to the tower-top point TY [m],
        inertial components (a flexible tower's tip displacement not included: the caller
        adds it where it matters)."""
        fr = self.frames(q, t, tower)
        rho = np.swapaxes(fr["H"] @ self.root_offset_hub.T, -1, -2)             # (..., Nb, 3)
        return self.teeter_point(fr)[..., None, :] + rho

    def gravity_in_root(self, q, t, tower=None):
        """(Nb, 3): the gravity vector ``-g n1`` [m/s^2] in each blade's root basis b."""
        self._check_tower(tower)
        B = self.frames(q, t, tower)["B"]
        return -self.g * B[..., 0, :]           # rows of B^T n1

    def qdot(self, q, u, t):
        """Coordinate rates from the speeds: qy' = U1, qh' = U1 (y1 . s2) - U2, and the
        drivetrain's shaft twist and generator azimuth rates U3, U4."""
        U1, U2, U3, U4 = self._split(u, self.n_u)
        return self._join(U1, U1 * self._y1s2(t, q) - U2, U3, U4)

    def _y1s2(self, t, q=None):
        return -np.sin(self.azimuth(t, q)) * np.cos(self.tilt)

    def kinematics(self, q, qdot, u, t):
        """Residual of the kinematic ODEs, (n_q,): ``qy' - U1`` and
        ``qh' + U2 - (y1 . s2) U1`` (= ``qh' + U2 + sin(psi) U1`` without tilt)."""
        qd = np.asarray(qdot)
        if qd.ndim == 0 or qd.shape[-1] != self.n_q:
            raise ValueError(f"expected qdot shape (..., {self.n_q}), got {qd.shape}")
        return qd - self.qdot(q, u, t)

    def dynamics(self, q, u, udot, t, root_force, root_moment, tower=None):
        """Kane's dynamical equations ``F_r + F_r* = 0``, residual (n_u,).

        ``root_force``, ``root_moment``: (Nb, 3) loads exerted BY the blades ON the hub at
        the root points, each in that blade's root basis b.  ``tower``: tower-top state
        (flexible tower only; see generalized_forces, which also gives the tower-top loads).
        """
        if self.flexible_tower:
            return self.generalized_forces(q, u, udot, t, root_force, root_moment,
                                           tower)[:self.n_u]
        self._check_tower(tower)
        k = self._kin(q, u, t)
        Ud1, Ud2, Ud3, Ud4 = self._split(udot, self.n_u)
        U1, U2, U3, U4 = k["U1"], k["U2"], k["U3"], k["U4"]
        qy, qh, qd = k["qy"], k["qh"], k["qd"]
        y1, s3, h2, wr_H, w_H, w_Y = k["y1"], k["s3"], k["h2"], k["wr_H"], k["w_H"], k["w_Y"]
        H, B = k["fr"]["H"], k["fr"]["B"]
        Fb = np.asarray(root_force)
        Mb = np.asarray(root_moment)
        nb = self.n_blades
        if Fb.shape[-2:] != (nb, 3) or Mb.shape[-2:] != (nb, 3):
            raise ValueError(f"root loads must have shape (..., {nb}, 3)")
        # scalars broadcast against vectors (batch entries on leading axes)
        U1c, U2c = np.asarray(U1)[..., None], np.asarray(U2)[..., None]
        Udc = np.stack(np.broadcast_arrays(Ud1, Ud2, Ud3, Ud4), -1)[..., None]
        spin = (np.asarray(U3) + np.asarray(U4))[..., None]        # drivetrain speeds

        # --- accelerations
        h2dot = _cross(w_H, h2)
        s3dot = _cross(w_Y, s3)
        if self.teeter:
            wr1dot = -(_dot(y1, h2dot)[..., None] * h2 + k["y1h2"][..., None] * h2dot)
            wr2dot = h2dot
        else:
            wr1dot = 0.0 * h2
            wr2dot = 0.0 * h2
        alpha_H = ((wr_H * Udc).sum(-2) + wr1dot * U1c + wr2dot * U2c
                   + (self.omega0 + spin) * s3dot)
        a_SH = self.d * (_cross(y1, s3) * Udc[..., 0, :] + _cross(y1, s3dot) * U1c)

        # --- generalized inertia forces
        I_H = H @ self.hub_inertia @ np.swapaxes(H, -1, -2)
        T_star = -(_mv(I_H, alpha_H) + _cross(w_H, _mv(I_H, w_H)))
        R_star = -self.hub_mass * a_SH
        Fstar = _mv(wr_H, T_star) + _mv(k["vr_SH"], R_star)
        Fstar = Fstar + self._rows(yaw=-self.nacelle_yaw_inertia * Ud1)
        if self.generator_inertia:
            N = self.gearbox_ratio
            alpha_G = ((k["wr_G"] * Udc).sum(-2)
                       + N * (self.omega0 + np.asarray(U4))[..., None] * s3dot)
            Fstar = Fstar + _mv(k["wr_G"], self._generator_inertia_torque(alpha_G, k["w_G"],
                                                                          s3))
        if self.counterweight_mass:
            # the counterweight at SH + rho_c (hub-fixed): v = v_SH + w_H x rho_c
            rho_c = _mv(H, self.counterweight_offset)
            vr_cw = k["vr_SH"] + _cross(wr_H, rho_c[..., None, :])
            a_cw = (a_SH + _cross(alpha_H, rho_c) + _cross(w_H, _cross(w_H, rho_c)))
            gN = np.zeros(3)
            gN[0] = -self.g
            Fstar = Fstar + _mv(vr_cw, self.counterweight_mass * (gN - a_cw))

        # --- generalized active forces
        F_N = _mv(B, Fb)
        M_N = _mv(B, Mb)
        F = (k["vr_P"] * F_N[..., None, :, :]).sum((-1, -2)) + _mv(wr_H, M_N.sum(axis=-2))
        F = F + k["vr_SH"][..., 0] * (-self.hub_mass * self.g)
        F = F + self._rows(yaw=-self.k_yaw * qy - self.c_yaw * U1)
        if self.teeter:
            qhdot = U1 * k["y1h2"] - U2
            tau = (self.k_teeter * qh + self.c_teeter * qhdot)[..., None] * h2  # on H
            F = F + _mv(wr_H - k["wr_S"], tau)                                # reaction on S
        if self.shaft_flexible:
            # shaft spring and damper on S about s3, reaction on the gearbox input E
            tau = -(self.k_shaft * qd + self.c_shaft * U3)[..., None] * s3
            F = F + _mv(k["wr_S"] - k["wr_E"], tau)
        if self.controls is not None or self.generator_slope:
            F = F + self._rows(generator=self._generator_torque_row(t, U4))
        res = F + Fstar
        return self._join(*(res[..., r] for r in range(4)))

    @staticmethod
    def _rows(yaw=0.0, teeter=0.0, twist=0.0, generator=0.0):
        """Values of the (yaw, teeter, shaft twist, generator) rows -> array (..., 4)."""
        return np.stack(np.broadcast_arrays(yaw, teeter, twist, generator), -1)

    def _generator_inertia_torque(self, alpha, w_G, s3):
        """Inertia torque ``-(I alpha + omega x I omega)`` of the generator rotor: a body of
        inertia ``generator_inertia`` about its axis (parallel to s3, the high-speed shaft,
        spinning at N times the gearbox-input speed) and none across it; ``alpha``, ``w_G``
        its angular acceleration and velocity, inertial components."""
        J = self.generator_inertia
        return -(J * _dot(s3, alpha)[..., None] * s3
                 + J * _dot(s3, w_G)[..., None] * _cross(w_G, s3))


    def relabelling_signs(self):
        """Signs (n_q + n_u,) mapping the rigid unknowns under the blade relabelling symmetry
        of Fast Floquet: the state ``(S q, S u)`` at ``t + T/Nb`` puts blade k where blade
        k+1 was at ``t`` (root motion, gravity and loads follow the blades; the yaw row is
        unchanged and the teeter row changes sign with S).  Yaw: +1.  Teeter (two blades
        only): -1, since turning the hub by 180 deg about h3 flips qh and U2.  A teetering hub
        with three or more blades has no such symmetry: ValueError.  The drivetrain (shaft
        twist, generator azimuth) turns with the whole rotor: +1."""
        if self.teeter and self.n_blades != 2:
            raise ValueError("a teetering hub with %d blades has no blade-relabelling symmetry"
                             % self.n_blades)
        if self.counterweight_mass:
            raise ValueError("a hub with a counterweight has no blade-relabelling symmetry")
        signs = [1.0] * int(self.yaw_free) + [-1.0] * int(self.teeter) + [1.0] * (
            int(self.shaft_flexible) + int(self.generator_free))
        return np.array(signs * 2)

    def hub_kinetic_energy(self, q, u, t, tower=None):
        """Kinetic energy of the rigid bodies (nacelle + hub, blades excluded) [J]; with a
        flexible tower including the tower-top motion (``tower``: see generalized_forces)."""
        if self.flexible_tower:
            k = self._kin_tower(q, u, t, tower)
            H, Y = k["fr"]["H"], k["fr"]["Y"]
            wH, wY = k["w_H"], k["w_Y"]
            v_c = k["v_T"] + _cross(wY, k["r_c"])
            I_H = H @ self.hub_inertia @ H.T
            I_Y = Y @ self.nacelle_inertia @ Y.T
            v_cw = k["v_SH"] + _cross(wH, H @ self.counterweight_offset)
            return (0.5 * (wH @ (I_H @ wH)) + 0.5 * self.hub_mass * (k["v_SH"] @ k["v_SH"])
                    + 0.5 * (wY @ (I_Y @ wY)) + 0.5 * self.nacelle_mass * (v_c @ v_c)
                    + 0.5 * self.yaw_bearing_mass * (k["v_T"] @ k["v_T"])
                    + 0.5 * self.counterweight_mass * (v_cw @ v_cw)
                    + 0.5 * self.generator_inertia * (k["s3"] @ k["w_G"]) ** 2)
        self._check_tower(tower)
        k = self._kin(q, u, t)
        H = k["fr"]["H"]
        w = k["w_H"]
        I_H = H @ self.hub_inertia @ np.swapaxes(H, -1, -2)
        v_cw = k["v_SH"] + _cross(w, _mv(H, self.counterweight_offset))
        return (0.5 * _dot(w, _mv(I_H, w)) + 0.5 * self.hub_mass * _dot(k["v_SH"], k["v_SH"])
                + 0.5 * self.counterweight_mass * _dot(v_cw, v_cw)
                + 0.5 * self.nacelle_yaw_inertia * k["U1"] ** 2
                + 0.5 * self.generator_inertia * _dot(k["s3"], k["w_G"]) ** 2)
