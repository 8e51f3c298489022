"""Aerodynamic drag on the flexible tower, inside the turbine's one residual.

Per unit length at each Gauss point of the tower beam (fem/beam.py's ``section_loads``):

    f = 1/2 rho C_d D |W_perp| W_perp,    W = U_wind - V,

W the air's velocity relative to the section (the free wind at the deformed reference line's
point and time, aero/wind.py, minus the section's inertial velocity V), W_perp its part
across the deformed tower axis (AeroDyn's TwrAero drag: the axial part and the tower's own
shadow do not load it), D the outer diameter and C_d the drag coefficient of the turbine's
tower table (model.TowerAerodynamics, interpolated linearly in height).  Linearized about a
steady wind U, an along-wind section velocity v feels the damping rho C_d D U per unit length
and an across-wind one half of it (|W_perp| does not change to first order).  Smooth in the
state while |W_perp| > 0 (always in wind): complex-step safe.

Frames: the tower's root frame is the inertial N (n1 = t1 up, the tower's base at the
ground, N's origin at the undeformed tower top: a Gauss point at height x above the base sits
at n1 = x - L); V and the loads are in the section frame (b turned by the section's rotation).
Not modelled: the tower's lift, its unsteady (vortex-shedding) loads, the nacelle's and hub's
drag.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..aero.wind import Wind
from ..model import Turbine
from ..numerics.rotations import rot_apply

__all__ = ["TowerDrag"]


class TowerDrag:
    """The drag loads of ``turbine``'s tower (``beam``: its BeamElements) in ``wind``, air
    density ``rho`` [kg/m^3]: ``section_loads(t)`` is the beam's callback at times ``t``
    (K,) of a batch of K towers."""

    def __init__(self, turbine: Turbine, beam, wind: Wind, rho: float):
        table = turbine.tower_aerodynamics
        if table is None or turbine.tower is None:
            raise ValueError("tower drag needs a flexible tower with a tower_aerodynamics "
                             "table")
        self.length = float(turbine.tower.length)
        s = beam.xg / self.length
        D = np.interp(s, table.stations, table.diameter)
        Cd = np.interp(s, table.stations, table.drag)
        #: 1/2 rho C_d D per Gauss point [kg/m^2], (N, G, 1)
        self.coefficient = (0.5 * float(rho) * Cd * D)[:, :, None]
        self.set_wind(wind)

    def set_wind(self, wind: Wind) -> None:
        """Blow ``wind`` from now on (the tower's own shadow is not a load on it)."""
        self.wind = replace(wind, tower_radius=0.0)

    def section_loads(self, t):
        """fem/beam.py's ``section_loads`` for a batch of towers at times ``t`` (K,) [s]."""
        def loads(sec):
            X = sec["position"]                             # (N, G, K, 3), from the base
            P = X - np.array([self.length, 0.0, 0.0])       # in N, from the tower top
            time = np.broadcast_to(np.asarray(t, float), X.shape[:-1])
            U = self.wind.velocity(time, P)                 # N = the tower's root frame
            W = rot_apply(sec["theta"], U) - sec["V"]       # section frame
            speed = np.sqrt(W[..., 1] * W[..., 1] + W[..., 2] * W[..., 2])
            force = np.zeros(W.shape, dtype=W.dtype)
            force[..., 1:] = (self.coefficient * speed)[..., None] * W[..., 1:]
            return force, np.zeros_like(force)
        return loads
