"""Frames, blade geometry and rotor loads for the node's messages (NumPy only, no rclpy).

Frames published by the node (see docs/ros.md; model frames as in hawt_core/rigid/kane.py):

* ``nacelle``: origin TY on the yaw axis at the tower top; axes (y1 up along the yaw axis,
  y2, y3 along the untilted shaft). Yaws with the nacelle (joint ``yaw``), does not spin.
* ``hub``: origin SH on the teeter axis (d along the shaft from TY); axes (h1, h2, h3) spin
  with the rotor azimuth (joint ``rotor_azimuth``) and teeter about h2 (joint ``teeter``).
* ``blade_<k>_root``: blade k's undeformed root frame b (b1 span, b2 lead-lag, b3 flap), at
  the root point; the frame of hawt_msgs/BladeDeflection.

Loads (efforts of sensor_msgs/JointState), all from the root loads the blades exert on the
hub (``root_force``/``root_moment`` of Simulator.blade_deflections()):

* ``yaw``: moment about the yaw axis y1 through TY [N m];
* ``teeter``: moment about the teeter axis h2 through SH [N m];
* ``rotor_azimuth``: moment about the shaft axis s3 through SH [N m] (the torque the blades
  exert on the hub about the shaft; the prescribed-speed drive supplies its negative, up to
  the hub's own inertia torque).
"""
from __future__ import annotations

import numpy as np

__all__ = ["RotorGeometry"]


class RotorGeometry:
    """Geometry helpers bound to a turbine model's rigid system (``model.rigid``)."""

    def __init__(self, rigid):
        self.rigid = rigid
        self.n_blades = int(rigid.n_blades)

    def q(self, named: dict) -> np.ndarray:
        """Rigid coordinates vector from Simulator.named()."""
        # every coordinate the rigid system has, in its order (a drivetrain's shaft twist and
        # generator azimuth when ``named`` carries them, e.g. ClosedLoop.named(); else 0)
        return np.array([float(named.get(c, 0.0)) for c in self.rigid.coordinates], dtype=float)

    def frames(self, named: dict, t: float) -> dict:
        return self.rigid.frames(self.q(named), float(t))

    def loads(self, named: dict, t: float, root_force, root_moment, frames=None) -> tuple:
        """(yaw moment, teeter moment, shaft torque) [N m] from the blade root loads
        ``root_force``/``root_moment`` (Nb, 3) in each blade's root frame. ``frames``:
        ``self.frames(named, t)`` when the caller has it already."""
        fr = self.frames(named, t) if frames is None else frames
        Y, S, H, B = fr["Y"], fr["S"], fr["H"], fr["B"]
        Fb = np.asarray(root_force, float).reshape(self.n_blades, 3)
        Mb = np.asarray(root_moment, float).reshape(self.n_blades, 3)
        F = np.einsum("kij,kj->ki", B, Fb)                 # inertial components
        M = np.einsum("kij,kj->ki", B, Mb)
        rho = self.rigid.root_offset_hub @ H.T             # root points from SH, inertial
        s3, h2, y1 = S[:, 2], H[:, 1], Y[:, 0]
        m_sh = (np.cross(rho, F) + M).sum(axis=0)          # moment about SH
        r_ty = rho + self.rigid.teeter_point(fr)          # root points from TY
        m_ty = (np.cross(r_ty, F) + M).sum(axis=0)         # moment about TY
        return float(m_ty @ y1), float(m_sh @ h2), float(m_sh @ s3)

    def blade_points(self, named: dict, t: float, line, u, frame: str = "nacelle",
                     frames=None) -> np.ndarray:
        """Deformed reference-line points of every blade, (Nb, S, 3), in ``frame``
        ('nacelle' or 'hub'). ``line`` (Nb, S, 3): the undeformed reference-line points in
        the root frames [m] (the simulation's ``positions``: ``(span, 0, 0)`` unless the
        blade has prebend or sweep); ``u`` (Nb, S, 3) displacements in the root frames.
        ``frames``: as for :meth:`loads`."""
        local = np.asarray(line, float) + np.asarray(u, float)   # in b
        rih = self.rigid.root_in_hub                      # (Nb, 3, 3) b in h
        p_h = np.einsum("kij,ksj->ksi", rih, local) + self.rigid.root_offset_hub[:, None, :]
        if frame == "hub":
            return p_h
        if frame != "nacelle":
            raise ValueError(f"frame: {frame!r} is not allowed; choose nacelle or hub")
        fr = self.frames(named, t) if frames is None else frames
        Y, H = fr["Y"], fr["H"]
        p_n = np.einsum("ij,ksj->ksi", H, p_h) + self.rigid.teeter_point(fr)  # from TY
        return np.einsum("ji,ksj->ksi", Y, p_n)            # components in the nacelle basis
