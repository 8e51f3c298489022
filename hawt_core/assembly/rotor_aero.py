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
relative velocity only).

Dynamic inflow (``inflow="oye"``): the inductions become four differential unknowns per Gauss
point of every blade, (a, a', z_a, z_t): each blade element's quasi-steady inductions from its
own loads (the annulus momentum balance of aero/bem.py's ``quasi_steady_inductions`` with
Prandtl's factor of the local inflow angle, Buhl's high-induction thrust; the free wind's
component along the shaft at the element, U_n, as the momentum balance's speed, and the axial
induced velocity a U_n along the shaft) filtered by Oye's two time constants
(aero/inflow.py; tau1 from the rotor's mean induction, held constant as AeroDyn's DBEMT_Mod =
1; tau2 per station): the induction lags the loads, as in AeroDyn's DBEMT, and in a steady
uniform axial wind it settles on the axisymmetric BEM inductions of the frozen wake.  With
shear, yaw, a tower shadow or a wind history each element's induction follows its own loads
and its own wind (a per-element BEM; no skewed-wake correction).

Unsteady airfoil (``airfoil="jones"``): Theodorsen's thin-airfoil theory in attached flow on
each section, the circulatory lift lagged by Wagner's function in Jones's approximation
(aero/unsteady.py), as HAWCStab2's and OpenFAST's attached-flow models:

* the circulatory input is the angle of attack at the three-quarter chord, alpha_34, of the
  air velocity relative to that point (W + b (1/2 - a) alpha' n: the section's pitch rate
  alpha' relative to the rotor's rigid spin, b the semi-chord, a Theodorsen's axis position
  of the reference line, n the chord's normal; strip.BladeStrips.three_quarter_chord);
* the polars are read at an effective angle that lags it, per Gauss point
  ``s_i' = (b_i w / b) (alpha_34 - s_i)``, ``alpha_eff = (1 - A1 - A2) alpha_34 + A1 s1 +
  A2 s2`` (w the chord-plane speed; s_i = alpha_34 in steady flow): a harmonic alpha_34 gives
  Jones's C(k) on the circulatory lift; lift stays normal to the relative velocity, at the
  aerodynamic centre;
* the non-circulatory (added-mass) lift and moment of Theodorsen (aero/unsteady.py's
  added_mass_loads: the air's inertia, the pitch damping -pi rho U b^3 (1/2 - a) alpha') from
  the section's pitch rate and acceleration and the rate of the air's normal velocity as the
  section frame sees it (RotorAerodynamics._section_motion); they shed no vorticity, so Oye's
  inductions respond to the circulatory loads alone.

In steady operation the pitch rate and the normal velocity's rate vanish (to the
discretization: the Gauss points' angular velocity), so the steady state is the quasi-steady
airfoil's.  Dynamic stall (the separated-flow states) is not modelled: attached flow only.

Skewed wake (``Aerodynamics.skew_factor`` K > 0, AeroDyn's default): in yawed or tilted flow
the axial induced velocity (frozen or Oye's) is redistributed over the disk by Pitt and Peters'
factor 1 + K (r / R) tan(chi / 2) cos(psi) (aero/inflow.py), larger on the downwind half, as
AeroDyn applies it after its (D)BEMT inductions: the skew angle chi0 and the azimuth psi from
the reference wind (its speed and direction at the hub, whatever the shear or shadow) and each
blade's actual root frame, so a yaw or teeter motion changes them in the residual.  In axial
flow the factor is 1.

Not modelled here: the skewed-wake momentum correction (AeroDyn's SkewMomCorr), loads on
the tower and nacelle, the aerodynamic centre's offset from the reference line.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..aero.bem import prandtl_loss, quasi_steady_inductions
from ..aero.inflow import (oye_residuals, oye_steady, oye_time_constants, skew_angles,
                           skewed_wake_factor)
from ..aero.strip import BladeStrips, inflow_sine
from ..aero.unsteady import JONES
from ..aero.wind import Wind
from ..model import Turbine
from ..numerics.rotations import cross, dot, rot_apply
from .aero_blade import AeroelasticBlade, annulus_mean, distance_from_shaft

__all__ = ["RotorAerodynamics", "INFLOW_MODELS", "AIRFOIL_MODELS", "description"]


#: Induction models: held at the axisymmetric BEM steady state, or Oye's dynamic inflow.
INFLOW_MODELS = ("frozen", "oye")
#: Airfoil models: the polars at the quasi-steady angle of attack, or Jones's lag.
AIRFOIL_MODELS = ("quasi-steady", "jones")


def description(inflow: str = "frozen", airfoil: str = "quasi-steady",
                skew_factor: float = 0.0, tower_drag: bool = False) -> str:
    """What the turbine's aerodynamic model is, in a result's settings (``tower_drag``: the
    flexible tower's drag is on, assembly/tower_aero.py)."""
    wake = ("frozen wake" if inflow == "frozen"
            else "Oye dynamic inflow per blade element")
    foil = ("quasi-steady airfoils" if airfoil == "quasi-steady"
            else "Jones two-state unsteady airfoils (attached flow)")
    skew = (f", Pitt-Peters skewed wake (K = {skew_factor:.4g})" if skew_factor > 0
            else "")
    tower = ", tower drag" if tower_drag else ""
    return f"blade-element momentum (Prandtl tip/hub loss, Buhl), {wake}{skew}, {foil}{tower}"



class RotorAerodynamics:
    """The aerodynamic loads of the blades of ``turbine`` (with ``elements`` per blade, at
    ``rotor_speed`` [rad/s]) in ``wind`` (aero.wind.Wind: the inductions from its speed and
    direction at the reference height; shear, shadow, history and gust act on the relative
    velocity), air density ``rho`` [kg/m^3].

    ``inductions``: (a, a') (N, G) at the beam's Gauss points, default the axisymmetric BEM
    steady state; ``blade_state`` is then that solution's beam state (a starting guess for the
    turbine's steady state).  ``inflow`` (INFLOW_MODELS) and ``airfoil`` (AIRFOIL_MODELS):
    the module's models; the dynamic ones add ``n`` differential unknowns per blade (after
    its beam's), ``state_names`` per Gauss point, state-major (state j of Gauss point g of
    element e at ``(j N + e) G + g``)."""

    #: the rows are affine in the rates with constant coefficients: the added-mass loads
    #: read V', Omega' through constant section constants (pi rho b^2 and the chord's
    #: normal), Oye's rows weigh the rates by tau1, tau2 fixed at construction
    #: (DBEMT_Mod = 1) and see circulatory loads only, Jones's by one (TurbineModel reuses
    #: dR/dydot; a model whose time constants follow the state must say False)
    constant_rate_coefficients = True

    def __init__(self, turbine: Turbine, wind: Wind, rotor_speed: float, beam,
                 rho: float = 1.225, inductions: Optional[tuple] = None,
                 inflow: str = "frozen", airfoil: str = "quasi-steady"):
        if inflow not in INFLOW_MODELS:
            raise ValueError(f"inflow: {inflow!r} is not allowed; choose one of "
                             f"{', '.join(INFLOW_MODELS)}")
        if airfoil not in AIRFOIL_MODELS:
            raise ValueError(f"airfoil: {airfoil!r} is not allowed; choose one of "
                             f"{', '.join(AIRFOIL_MODELS)}")
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
            blade = AeroelasticBlade(turbine, self.normal_speed, elements=beam.elements,
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
        self.inflow, self.airfoil = inflow, airfoil
        #: Pitt and Peters' skewed-wake constant K (0: no correction) and r / R per Gauss point
        self.skew_factor = float(aero.skew_factor)
        self.radius_ratio = self.r / float(distance_from_shaft(turbine, L))
        self.description = description(inflow, airfoil, self.skew_factor)
        self.lag = JONES if airfoil == "jones" else None
        names = ["a", "a_tangential", "a_filter", "a_tangential_filter"] \
            if inflow == "oye" else []
        if self.lag is not None:
            names += [f"alpha_lag{i + 1}" for i in range(self.lag.states)]
        #: the aerodynamic unknowns per Gauss point, and their count per blade
        self.state_names = tuple(names)
        N, G = xg.shape
        self.n = len(names) * N * G
        self.blades = int(turbine.rotor.blades)
        self.cos_cone = float(np.cos(turbine.rotor.precone))
        self.hub_r = float(distance_from_shaft(turbine, 0.0))
        self.tip_r = float(distance_from_shaft(turbine, L))
        if inflow == "oye":
            # tau1 from the frozen inductions' area-weighted mean (Oye; held constant)
            tau1, tau2 = oye_time_constants(turbine.hub.radius + L, self.normal_speed,
                                            annulus_mean(beam, self.r, a),
                                            self.r / self.cos_cone)
            self.tau1, self.tau2 = float(tau1), tau2                 # [s], (N, G, 1)

    def set_wind(self, wind: Wind) -> None:
        """Blow ``wind`` from now on (a controller's live wind input): the free wind the
        loads see; the frozen inductions and Oye's time constants stay those of the wind
        the model was built in."""
        if wind.shear_exponent != self.wind.shear_exponent or \
                wind.tower_radius != self.wind.tower_radius:
            raise ValueError("wind: a new wind must keep the shear exponent and tower shadow "
                             "the aerodynamics were built with")
        self.wind = wind
        self.velocity = np.asarray(wind.velocity(0.0, np.zeros(3)), float)   # in N

    def initial_states(self, alpha=None) -> np.ndarray:
        """The aerodynamic unknowns (n,) of one blade in steady flow: the frozen inductions
        (and Oye's first stages at (1 - k) of them), the lag states at the quasi-steady angle
        of attack ``alpha`` (N, G) [rad] (zero without it)."""
        out = []
        if self.inflow == "oye":
            (za, a), (zt, ap) = (oye_steady(x) for x in self.inductions)
            out += [a, ap, za, zt]
        if self.lag is not None:
            al = np.zeros(self.r.shape[:2]) if alpha is None else np.real(alpha)
            out += [al] * self.lag.states
        return np.concatenate([np.ravel(x) for x in out]) if out else np.zeros(0)

    def root_data(self, B, S, P, t):
        """What the blades' loads need from the rigid system, a dict of arrays with leading
        dimensions (..., Nb): ``vectors`` (..., Nb, m, 3), the shaft axis s3, the direction
        of rotation t (and the uniform free wind first, unless the wind is a field) in each
        root frame; for a field also ``B`` (the root bases, ..., Nb, 3, 3), ``P`` (the root
        points relative to the tower top, ..., Nb, 3) and ``time`` (..., Nb); with a skewed-wake
        correction ``skew`` (..., Nb, 2): skew_angles of the reference wind.  From the root
        bases ``B``, the shaft basis ``S`` (..., 3, 3) (RigidSystem.frames: columns are unit
        vectors in N), the root points ``P`` and the times ``t`` (...)."""
        s3 = np.einsum("...ji,...j->...i", B, S[..., None, :, 2])
        # t = s3 x b1 / |s3 x b1| in root components (b1 = e1)
        tt = np.zeros(s3.shape, dtype=s3.dtype)
        norm = np.sqrt(s3[..., 1] ** 2 + s3[..., 2] ** 2)
        tt[..., 1], tt[..., 2] = s3[..., 2] / norm, -s3[..., 1] / norm
        wind = np.einsum("...ji,j->...i", B, self.velocity)
        skew = {"skew": np.stack(skew_angles(wind, s3), axis=-1)} if self.skew_factor else {}
        if not self.field:
            return {"vectors": np.stack([wind, s3, tt], axis=-2), **skew}
        time = np.broadcast_to(np.asarray(t, float)[..., None], s3.shape[:-1])
        return {"vectors": np.stack([s3, tt], axis=-2), "B": B, "P": P, "time": time, **skew}

    def _section_motion(self, sec, spin, s3, wind, induced):
        """The section's motion relative to the air that Theodorsen's pitch-rate and
        added-mass terms read, (N, G, K) arrays: the pitch rate [rad/s] and acceleration
        [rad/s^2] about B1 relative to the rotor's rigid spin (``spin`` [rad/s] (K,) about the
        shaft axis ``s3``: a coned blade's spin has a part about B1 that pitches no section
        relative to the air; in steady operation both are zero, so the steady state stays
        the quasi-steady one, as OpenFAST's), and the rate [m/s^2] of the air's velocity
        normal to the chord as the section frame sees it (Theodorsen's h'' + U alpha'):

            d(W_B)/dt = -Omega x wind_B + Omega_rel x induced_B - Vdot_B

        the free wind fixed in space (its changes along the section's path in a shear or a
        gust carry no added-mass load here), the induced velocity fixed in the rotor
        (``induced`` (N, G, K, 3) in B; its own rate, Oye's, left out: slow), V's component
        rates those of the beam's unknowns; all in section-frame components."""
        st = self.strips
        omega = st.to_section(sec["Omega"])
        spin = np.asarray(spin)[..., None]
        rel = omega - spin * s3
        pitch_rate = rel[..., 0]
        # d(Omega_1 - spin s3_1)/dt with s3 fixed in the rotor: d(s3_B)/dt = s3_B x Omega_rel
        pitch_acc = (st.to_section(sec["Omegadot"])[..., 0]
                     - spin[..., 0] * (s3[..., 1] * rel[..., 2] - s3[..., 2] * rel[..., 1]))
        rate = cross(rel, induced) - cross(omega, wind) - st.to_section(sec["Vdot"])
        return pitch_rate, pitch_acc, dot(rate, st.normal)

    def loads(self, air, x=None, xd=None, out=None):
        """The beam's ``section_loads`` callback (fem/beam.py) for blades with root data
        ``air`` (root_data, leading dimension the beam batch K): force and moment per length
        in turned-b components from the Gauss-point velocities and the free wind.  ``x``,
        ``xd`` (K, n): the blades' aerodynamic unknowns and their rates (n > 0); their rows
        (K, n) are put in ``out["rows"]``, the quasi-steady angle of attack (N, G, K) in
        ``out["alpha"]``."""
        st = self.strips
        out = {} if out is None else out
        N, G = self.r.shape[:2]
        k = len(self.state_names)

        def states(v):      # (K, n) -> (k, N, G, K)
            return v.reshape(v.shape[0], k, N, G).transpose(1, 2, 3, 0)

        X = states(x) if self.n else None
        Xd = states(xd) if self.n else None

        def section_loads(sec):
            vec = sec["wind"]
            if self.field:
                s3, t = (st.to_section(vec[..., j, :]) for j in range(2))
                # the Gauss points in N, the wind there, in root then turned-b components
                Xp = air["P"] + np.einsum("bij,ngbj->ngbi", air["B"], sec["position"])
                U = self.wind.velocity(air["time"], Xp)
                Ub = np.einsum("bji,ngbj->ngbi", air["B"], U)
                wind = st.to_section(rot_apply(sec["theta"], Ub))
            else:
                wind, s3, t = (st.to_section(vec[..., j, :]) for j in range(3))
            if self.inflow == "oye":
                a, ap = X[0], X[1]
                # the rotor's actual speed (the root data's, per blade), else the nominal one
                spin = air.get("spin")
                omega = self.omega if spin is None else spin
                # the free wind along the shaft at the element (AeroDyn's disk-normal speed):
                # the axial induced velocity's and the momentum balance's speed
                normal = np.sum(wind * s3, axis=-1)
                axial = (a * normal)[..., None]
                swirl = (ap * omega * self.r)[..., None]
            else:
                axial, swirl = self._axial, self._swirl
            if self.skew_factor:
                # Pitt-Peters: more axial induction on the disk's downwind half
                a_now = X[0] if self.inflow == "oye" else self.inductions[0][..., None]
                skew = air["skew"]
                axial = axial * skewed_wake_factor(skew[..., 0], skew[..., 1], a_now,
                                                   self.radius_ratio,
                                                   self.skew_factor)[..., None]
            induced = axial * s3 + swirl * t
            W = wind - induced - st.to_section(sec["V"])
            alpha, w = st.angle_of_attack(W)
            rows = []
            alpha_eff = None
            if self.lag is not None:
                pitch_rate, pitch_acc, normal_rate = self._section_motion(
                    sec, air["spin"], s3, wind, induced)
                # the circulatory lift's input: the angle at the three-quarter chord
                alpha, _ = st.angle_of_attack(st.three_quarter_chord(W, pitch_rate))
                j0 = 4 if self.inflow == "oye" else 0
                lag = X[j0:j0 + self.lag.states]
                alpha_eff = (1.0 - sum(self.lag.A)) * alpha
                lag_rows = []
                for i, (Ai, bi) in enumerate(zip(self.lag.A, self.lag.b)):
                    alpha_eff = alpha_eff + Ai * lag[i]
                    lag_rows.append(Xd[j0 + i] - bi * w / st.semichord * (alpha - lag[i]))
            out["alpha"] = alpha
            force, moment, _ = st.loads(W, alpha_eff)
            if self.inflow == "oye":
                # each element's quasi-steady inductions from its own (circulatory: the
                # added-mass loads shed no vorticity) loads, filtered (Oye)
                thrust = np.sum(force * s3, axis=-1)
                drive = np.sum(force * t, axis=-1)
                sphi = inflow_sine(W, s3, t)
                F = prandtl_loss(self.blades, self.r, self.tip_r, self.hub_r, sphi)
                qs = quasi_steady_inductions(self.blades, thrust, drive, a, F, self.r,
                                             self.rho, normal, omega, self.cos_cone)
                (za, Wa), (zt, Wt) = (oye_residuals(X[2 + j], X[j], Xd[2 + j], Xd[j], qs[j],
                                                    self.tau1, self.tau2) for j in range(2))
                rows += [Wa, Wt, za, zt]            # the unknowns' order: a, a', z_a, z_t
            if self.lag is not None:
                rows += lag_rows
                f_nc, m_nc = st.added_mass_loads(normal_rate, pitch_rate, pitch_acc, w)
                force, moment = force + f_nc, moment + m_nc
            if rows:
                out["rows"] = np.stack(rows).transpose(3, 0, 1, 2).reshape(
                    rows[0].shape[-1], -1)
            f_sec, m_sec = st.from_section(force), st.from_section(moment)
            # what TurbineModel.aero_loads integrates
            out["loads"] = (f_sec, m_sec, sec["theta"], sec["position"])
            return f_sec, m_sec
        return section_loads
