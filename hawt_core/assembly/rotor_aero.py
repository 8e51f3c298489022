"""Blade-element loads on every blade of the whole turbine, with the wake frozen.

The turbine's residual (assembly/turbine.py) gives each blade's beam, at every Gauss point, the
air velocity relative to the deformed section:

    W = U_wind - a U0 s3 - a' Omega0 r t - V

with ``U_wind`` the free wind (aero/wind.py; its direction relative to the rotor follows the
yaw, tilt, azimuth, teeter and tower-top rotation of the rigid system, through the blade's
root frame; with shear, tower shadow, a history or a gust it is evaluated at each Gauss
point's position P_k + B_k (X0 + u) and time: the root point from the rigid system, the
deflected line from the beam, the tower top's own displacement neglected), ``s3`` the shaft
axis and ``t`` the direction of the blade's rotation (``s3 x b1``,
normalized), both in the root frame, ``V`` the section's inertial velocity (rigid motion and
deformation) and the airfoil loads of aero/strip.py.

Frozen wake: the axial and tangential inductions ``a``, ``a'`` at each Gauss point are held at
the axisymmetric blade-element-momentum steady state of the rotor at the same rotor speed,
pitch and rotor-normal wind ``U0`` (assembly/aero_blade.py: Ning's BEM with Prandtl's tip and
hub losses and Buhl's high-induction thrust, solved with the flexible blade), as OpenFAST's
linearization does with ``FrozenWake = True`` (AeroDyn v15 user guide, "Linearization"): the
induced velocity moves with the rotor (along its perturbed shaft axis) but does not respond
to the perturbations.  Perturbation loads therefore come from the sections' motion (the
aerodynamic damping and stiffness of quasi-steady strip theory); no extra unknowns.

The inductions stay frozen whatever the wind does (a gust changes the loads through the
relative velocity only).  Not modelled here: skewed-wake correction of the inductions in
yawed or tilted flow, loads on the tower and nacelle, dynamic inflow and
unsteady-airfoil states (the blade model has Oye's inflow; the turbine's linearization is
quasi-steady), the aerodynamic centre's offset from the reference line.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..aero.strip import BladeStrips
from ..aero.wind import Wind
from ..model import Turbine
from ..numerics.rotations import rot_apply
from .aero_blade import AeroelasticBlade, distance_from_shaft

__all__ = ["FrozenWakeRotor"]


#: What the model is, in a result's settings.
DESCRIPTION = ("blade-element momentum (Prandtl tip/hub loss, Buhl), frozen wake, "
               "quasi-steady airfoils")


class FrozenWakeRotor:
    """The aerodynamic loads of the blades of ``turbine`` (with ``elements`` per blade, at
    ``rotor_speed`` [rad/s]) in ``wind`` (aero.wind.Wind: the inductions from its speed and
    direction at the reference height; shear, shadow, history and gust act on the relative
    velocity), air density ``rho`` [kg/m^3].

    ``inductions``: (a, a') (N, G) at the beam's Gauss points, default the axisymmetric BEM
    steady state; ``blade_state`` is then that solution's beam state (a starting guess for the
    turbine's steady state)."""

    def __init__(self, turbine: Turbine, wind: Wind, rotor_speed: float, beam,
                 rho: float = 1.225, inductions: Optional[tuple] = None):
        aero = turbine.aerodynamics
        if aero is None:
            raise ValueError(f"wind: turbine {turbine.name!r} has no aerodynamics section, so "
                             "it cannot be analysed in wind")
        #: the wind varies over the rotor or in time: evaluated at each Gauss point
        self.field = bool(wind.shear_exponent or wind.tower_radius or wind.history
                          or wind.gust is not None)
        if not wind.speed > 0:
            raise ValueError(f"wind.speed: {wind.speed!r} is not allowed; need a number > 0 "
                             "[m/s]")
        self.wind = wind
        self.omega = float(rotor_speed)
        self.rho = float(rho)
        self.velocity = np.asarray(wind.velocity(0.0, np.zeros(3)), float)       # in N
        tilt = float(turbine.nacelle.shaft_tilt)
        # rotor-normal speed of the reference (unyawed) rotor: s3 = cos(tilt) n3 + sin n1
        self.normal_speed = float(self.velocity @ np.array([np.sin(tilt), 0.0, np.cos(tilt)]))
        if not self.normal_speed > 0:
            raise ValueError(f"wind.direction: {wind.direction!r} is not allowed; the wind must "
                             "blow through the rotor from upwind (|direction| < 90 deg)")
        L = turbine.blade.length
        xg = beam.xg
        self.r = distance_from_shaft(turbine, xg)[:, :, None]
        self.strips = BladeStrips(aero, xg / L, beam.props.element_frames(), rho)
        self.blade_state = None
        if inductions is None:
            blade = AeroelasticBlade(turbine, self.normal_speed, elements=beam.N,
                                     rotor_speed=self.omega, rho=rho)
            y = blade.steady_state()
            inductions = blade.inductions(y)
            self.blade_state = y[:blade.n_beam]
        a, ap = (np.asarray(x, float) for x in inductions)
        if a.shape != xg.shape or ap.shape != xg.shape:
            raise ValueError(f"inductions: need two arrays of shape {xg.shape} (elements, "
                             "Gauss points)")
        # the frozen induced velocity's magnitudes along s3 and along t [m/s], (N, G, 1, 1)
        self._axial = (a * self.normal_speed)[:, :, None, None]
        self._swirl = (ap[:, :, None] * self.omega * self.r)[..., None]
        self.inductions = (a, ap)

    def root_data(self, B, S, P, t):
        """What the blades' loads need from the rigid system, a dict of arrays with leading
        dimensions (..., Nb): ``vectors`` (..., Nb, m, 3), the shaft axis s3, the direction
        of rotation t (and the uniform free wind first, unless the wind is a field) in each
        root frame; for a field also ``B`` (the root bases, ..., Nb, 3, 3), ``P`` (the root
        points relative to the tower top, ..., Nb, 3) and ``time`` (..., Nb).  From the root
        bases ``B``, the shaft basis ``S`` (..., 3, 3) (RigidSystem.frames: columns are unit
        vectors in N), the root points ``P`` and the times ``t`` (...)."""
        s3 = np.einsum("...ji,...j->...i", B, S[..., None, :, 2])
        # t = s3 x b1 / |s3 x b1| in root components (b1 = e1)
        tt = np.zeros(s3.shape, dtype=s3.dtype)
        norm = np.sqrt(s3[..., 1] ** 2 + s3[..., 2] ** 2)
        tt[..., 1], tt[..., 2] = s3[..., 2] / norm, -s3[..., 1] / norm
        if not self.field:
            wind = np.einsum("...ji,j->...i", B, self.velocity)
            return {"vectors": np.stack([wind, s3, tt], axis=-2)}
        time = np.broadcast_to(np.asarray(t, float)[..., None], s3.shape[:-1])
        return {"vectors": np.stack([s3, tt], axis=-2), "B": B, "P": P, "time": time}

    def loads(self, air):
        """The beam's ``section_loads`` callback (fem/beam.py) for blades with root data
        ``air`` (root_data, leading dimension the beam batch): force and moment per length
        in turned-b components from the Gauss-point velocities and the free wind."""
        st = self.strips

        def section_loads(sec):
            vec = sec["wind"]
            if self.field:
                s3, t = (st.to_section(vec[..., j, :]) for j in range(2))
                # the Gauss points in N, the wind there, in root then turned-b components
                X = air["P"] + np.einsum("bij,ngbj->ngbi", air["B"], sec["position"])
                U = self.wind.velocity(air["time"], X)
                Ub = np.einsum("bji,ngbj->ngbi", air["B"], U)
                wind = st.to_section(rot_apply(sec["theta"], Ub))
            else:
                wind, s3, t = (st.to_section(vec[..., j, :]) for j in range(3))
            W = wind - self._axial * s3 - self._swirl * t - st.to_section(sec["V"])
            force, moment, _ = st.loads(W)
            return st.from_section(force), st.from_section(moment)
        return section_loads
