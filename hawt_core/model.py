"""Typed, immutable description of a turbine (the in-memory form of a turbine YAML file).

Units are SI throughout: metres, kilograms, seconds, radians, newtons.

Frames (Patil, Lee & Hodges 2001, and docs/theory.md):
- tower T: fixed; ``t1 = y1`` points up along the yaw axis (gravity acts along ``-t1``).
- nacelle Y: yaws about ``y1`` by ``qy``; ``y3`` is the (untilted) shaft direction.
- shaft S: spins about ``s3`` at the prescribed rotor speed; azimuth ``psi = Omega0 t``,
  at ``t = 0`` blade 1 points up (``s1 = y1``).
- hub H: teeters about ``h2 = s2`` (``h1 = cos qh s1 + sin qh s3``).
- blade k (k = 0..Nb-1) root frame b: ``b1`` spanwise outward, ``b2`` in the plane of rotation
  towards the direction of motion, ``b3`` along the shaft (flap).  Blade k's root frame is blade
  0's turned by ``2 pi k / Nb`` about ``h3``, then by the precone about its own ``b2``.

Cross-sectional properties are given at spanwise stations and interpolated linearly.
Section matrices use the ordering ``[F1, F2, F3, M1, M2, M3]`` (stiffness) and
``[V1, V2, V3, Omega1, Omega2, Omega3]`` (mass), expressed in the reference cross-section
frame b (reference line = the elastic/reference axis).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np

#: Names of the optional flexible directions (None = rigid in that direction).
FLEXIBLE_DIRECTIONS = ("ea", "ga2", "ga3")


def _frozen_array(a, ndim=None) -> np.ndarray:
    arr = np.array(a, dtype=float)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"expected a {ndim}-d array, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class SectionTable:
    """Spanwise cross-sectional properties of a beam (blade or tower).

    ``stations`` are fractions of the beam length, strictly increasing from 0 to 1.
    Every property array has one value per station.

    Attributes (per station):
        mass: mass per unit length m [kg/m].
        i1, i2, i3: mass moments of inertia per unit length about b1 (torsion, ``I1 = I2 + I3``
            for a thin section), b2 (flap axis) and b3 (lead-lag axis) [kg m].
        gj: torsional rigidity [N m^2]; ei2: flap bending rigidity (about b2) [N m^2];
            ei3: lead-lag bending rigidity (about b3) [N m^2].
        ea, ga2, ga3: axial and shear rigidities [N]; ``None`` means rigid (zero compliance,
            the paper's inextensible, shear-rigid blade).
        twist: structural twist [rad]: the principal axes of the section properties are
            turned by this angle about b1 (positive from b2 towards b3); the reference frame
            itself stays untwisted.
        cg_offset: (x2, x3) of the mass centre from the reference line [m], shape (ns, 2).
        tension_offset: (x2, x3) of the tension centre (where EA acts, and the bending
            moments are taken about) [m], shape (ns, 2).
        shear_offset: (x2, x3) of the shear centre (the torsional moment is taken about
            it: a transverse force through the reference line twists the section) [m],
            shape (ns, 2); None: at the tension centre.
        stiffness_6x6 / mass_6x6: optional full matrices, shape (ns, 6, 6), in frame b; when
            given they replace the matrices built from the scalar properties above.
        prebend, sweep: offsets of the reference line from the straight b1 axis along b3
            (prebend, out of the plane of rotation, downwind positive) and b2 (sweep, in
            the plane of rotation, towards the direction of motion) [m]; None = straight.
            The stations are then fractions of the span along b1, the section properties
            are per unit length of the curved line and act in its local section frame
            (b turned to the line's tangent, fem/sections.py: mesh_beam).
    """

    stations: np.ndarray
    mass: np.ndarray
    i1: np.ndarray
    i2: np.ndarray
    i3: np.ndarray
    gj: np.ndarray
    ei2: np.ndarray
    ei3: np.ndarray
    ea: Optional[np.ndarray] = None
    ga2: Optional[np.ndarray] = None
    ga3: Optional[np.ndarray] = None
    twist: Optional[np.ndarray] = None
    cg_offset: Optional[np.ndarray] = None
    tension_offset: Optional[np.ndarray] = None
    shear_offset: Optional[np.ndarray] = None
    stiffness_6x6: Optional[np.ndarray] = None
    mass_6x6: Optional[np.ndarray] = None
    prebend: Optional[np.ndarray] = None
    sweep: Optional[np.ndarray] = None

    def __post_init__(self):
        for name in ("stations", "mass", "i1", "i2", "i3", "gj", "ei2", "ei3"):
            object.__setattr__(self, name, _frozen_array(getattr(self, name), 1))
        for name in ("ea", "ga2", "ga3", "twist", "prebend", "sweep"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _frozen_array(getattr(self, name), 1))
        for name in ("cg_offset", "tension_offset", "shear_offset"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _frozen_array(getattr(self, name), 2))
        for name in ("stiffness_6x6", "mass_6x6"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _frozen_array(getattr(self, name), 3))

    @property
    def n_stations(self) -> int:
        return len(self.stations)

    def rigid_directions(self) -> tuple:
        """Names among ('ea', 'ga2', 'ga3') that are rigid (not given)."""
        if self.stiffness_6x6 is not None:
            return tuple(n for k, n in enumerate(FLEXIBLE_DIRECTIONS)
                         if not np.all(np.isfinite(self.stiffness_6x6[:, k, k])))
        return tuple(n for n in FLEXIBLE_DIRECTIONS if getattr(self, n) is None)

    @classmethod
    def uniform(cls, **props) -> "SectionTable":
        """A uniform table (two stations, 0 and 1) from scalar properties."""
        out = {"stations": [0.0, 1.0]}
        for k, v in props.items():
            out[k] = None if v is None else [v, v]
        return cls(**out)


def order_text(order) -> str:
    """" of order p" for elements of the p-version (order > 1; None or 0: 1), "" for the
    paper's element: what messages and tables append to an element count."""
    p = int(order or 1)
    return f" of order {p}" if p > 1 else ""


#: Mode families a beam's modal damping ratios name, per bending plane: the bending
#: strain they damp (index into [gamma1, gamma2, gamma3, kappa1, kappa2, kappa3]).
MODAL_FAMILIES = {"flap": 4, "edge": 5, "fore_aft": 4, "side_side": 5}


@dataclass(frozen=True)
class BeamDamping:
    """Structural damping of a beam (a property of the material, so of the model).

    Two viscous forms, summed (Rayleigh damping of a beam, in the section frame of the
    file's matrices; docs/structural_damping.md):

    - ``stiffness`` (6,) [s]: mu per section strain [gamma1, gamma2, gamma3, kappa1,
      kappa2, kappa3], the section loads' viscous part ``[F, M]_d = diag(mu) S
      d[gamma, kappa]/dt`` (Kelvin-Voigt; BeamDyn's ``mu``, HAWC2's ``damping_posdef``
      k-terms).  In a clamped beam whose mu is the same for every strain this gives every
      mode ``zeta = mu omega / 2``.
    - ``mass`` (6,) [1/s]: alpha per section velocity component [v1, v2, v3, omega1,
      omega2, omega3], a distributed load ``-diag(alpha) mu_s (the section's velocity
      relative to the beam's root frame)`` (HAWC2's m-terms): ``zeta = alpha / (2 omega)``.
    - ``modal``: damping ratios [-] (fractions, not %) of the clamped, non-rotating beam's
      modes by family, e.g. ``{"flap": (0.0048, 0.0048), "edge": (0.0048,)}`` (ElastoDyn's
      BldFlDmp, BldEdDmp; a tower's ``fore_aft``, ``side_side``: TwrFADmp, TwrSSDmp).  The
      discretization turns them into the two forms above (fem/damping.py): with one ratio a
      family gets ``mu`` on its bending strain (ElastoDyn's own rule, 2 zeta / omega), with
      two also ``alpha`` on its bending plane's velocities, so that the bare beam's (no tip
      mass) first modes of the family have exactly these ratios.
    """

    stiffness: tuple = (0.0,) * 6
    mass: tuple = (0.0,) * 6
    modal: Optional[dict] = None

    @property
    def enabled(self) -> bool:
        """Whether any damping is given."""
        return bool(any(self.stiffness) or any(self.mass) or self.modal)

    def text(self) -> str:
        """One line for tables and logs: what the damping is."""
        if self.modal:
            return "modal " + ", ".join(
                f"{k} " + "/".join(f"{100 * z:.4g}" for z in v) + " %"
                for k, v in self.modal.items())
        parts = []
        if any(self.stiffness):
            parts.append("mu " + " ".join(f"{v:.3g}" for v in self.stiffness) + " s")
        if any(self.mass):
            parts.append("alpha " + " ".join(f"{v:.3g}" for v in self.mass) + " 1/s")
        return "; ".join(parts) or "none"


@dataclass(frozen=True, eq=False)
class Beam:
    """A flexible beam: length [m], section table and number of finite elements.

    ``tip_mass`` [kg]: a rigid body at the tip point of the reference line (ElastoDyn's
    TipMass: a tip brake, a tip weight); ``tip_inertia`` (J1, J2, J3) [kg m^2]: its
    principal inertias about the tip section's axes (b1 spanwise, b2, b3), about its
    centre of mass at the tip point.

    ``order``: the polynomial degree of the elements' fields.  1 is the paper's mixed
    element (fem/beam.py: linear u, theta, V, Omega, constant F, M, element-averaged
    properties; second order in the element count); 2 and more the p-version of the same
    formulation (fem/spectral.py: degree-p fields, the properties integrated exactly
    between the file's stations; its error falls like h^(2p) on smooth modes).

    ``damping``: the beam's structural damping (BeamDamping) or None (undamped).
    """

    length: float
    sections: SectionTable
    elements: int = 4
    tip_mass: float = 0.0
    tip_inertia: tuple = (0.0, 0.0, 0.0)
    order: int = 1
    damping: Optional[BeamDamping] = None

    def mesh_text(self, elements=None) -> str:
        """"3 elements of order 6" or "4 elements" (the paper's element): the mesh of
        ``elements`` (default this beam's) elements of this beam's order, for messages."""
        n = int(elements or self.elements)
        return f"{n} element{'s' if n != 1 else ''}{order_text(self.order)}"


@dataclass(frozen=True)
class Hub:
    """Hub: blade roots at ``radius`` (e) from the shaft axis along h1.

    ``undersling`` (lhd1) [m] moves the blade roots from the teeter axis along -h3 (the sign
    of the paper's Eq. 11). ``teeter`` False makes the hub rigid on the shaft.
    ``inertia_lateral`` (Ihlat, about h1 and h2) and ``inertia_longitudinal`` (Ihlong, about h3)
    [kg m^2]; teeter spring [N m/rad] and damper [N m s/rad]; hub ``mass`` [kg] (only matters
    with gravity).  ``counterweight_mass`` [kg]: a point mass on the hub at
    ``counterweight_radius`` [m] from the teeter-axis point along -h1 (opposite blade 0), the
    balance of a one-bladed rotor; it is not included in the nacelle's yaw inertia (like the
    blades) and breaks the blade relabelling symmetry of a rotor with two or more blades.
    """

    radius: float = 1.8
    undersling: float = 0.0
    teeter: bool = True
    inertia_lateral: float = 50.0
    inertia_longitudinal: float = 5.0
    teeter_stiffness: float = 0.0
    teeter_damping: float = 0.0
    mass: float = 0.0
    counterweight_mass: float = 0.0
    counterweight_radius: float = 0.0


@dataclass(frozen=True)
class Nacelle:
    """Nacelle: yaw bearing on the tower top.

    ``yaw_inertia`` (Iy) [kg m^2] is the inertia about the yaw axis of everything but the
    blades, hub included (so the nacelle body alone carries Iy - Ihlat);
    ``yaw_to_teeter`` (d) [m] is the distance from the yaw axis to the teeter axis (the rotor
    apex of a rigid hub) along the shaft, positive downwind (+y3): negative for an upwind
    rotor (ElastoDyn's OverHang); ``shaft_tilt`` [rad]; ``yaw_free`` False locks the yaw
    bearing; ``mass`` [kg].

    Only with a flexible tower (or gravity on a moving tower top) do these matter:
    ``cg_offset`` (x1, x2, x3) [m] of the nacelle mass centre from the tower-top point TY in
    the nacelle frame Y (y1 up, y2 lateral, y3 along the untilted shaft, downwind);
    ``inertia_pitch`` (about y2, nodding) and ``inertia_roll`` (about y3) [kg m^2] of the
    nacelle body about its mass centre (its yaw inertia follows from ``yaw_inertia``);
    ``shaft_height`` [m]: height of the point where the shaft axis meets the yaw axis above
    the tower-top point TY, along y1 (ElastoDyn's Twr2Shft); ``yaw_bearing_mass`` [kg]: a
    point mass at TY that does not yaw (ElastoDyn's YawBrMass).
    """

    yaw_inertia: float = 16599.0
    yaw_stiffness: float = 0.0
    yaw_damping: float = 0.0
    yaw_to_teeter: float = 2.388
    shaft_tilt: float = 0.0
    yaw_free: bool = True
    mass: float = 0.0
    cg_offset: tuple = (0.0, 0.0, 0.0)
    inertia_pitch: float = 0.0
    inertia_roll: float = 0.0
    shaft_height: float = 0.0
    yaw_bearing_mass: float = 0.0


@dataclass(frozen=True)
class Rotor:
    """Rotor speed Omega0 [rad/s], blade count, precone [rad] and the blades' collective
    ``pitch`` [rad]: every blade turned as a rigid body about its root axis b1, positive
    from b2 towards b3 (the sign of the structural twist; ElastoDyn's BlPitch, positive
    towards feather, is minus it)."""

    speed: float = 6.02
    blades: int = 2
    precone: float = 0.0
    pitch: float = 0.0


#: What a drivetrain's generator does: "prescribed" (it turns at the rotor speed times the
#: gear ratio, held by its torque: the paper's constant-speed rotor, here behind a flexible
#: shaft) or "free" (no torque: the whole drivetrain may turn, a zero-frequency mode).
GENERATOR_MODES = ("prescribed", "free")


@dataclass(frozen=True)
class Drivetrain:
    """Low-speed shaft between the hub and the gearbox, and the generator behind it.

    ``stiffness`` [N m/rad] and ``damping`` [N m s/rad] of the shaft's torsion (ElastoDyn
    DTTorSpr, DTTorDmp; ``stiffness`` None: a rigid shaft); ``generator_inertia`` [kg m^2]
    of the generator rotor about the high-speed shaft (GenIner), which turns at
    ``gearbox_ratio`` times the low-speed shaft (GBRatio); ``generator``: one of
    GENERATOR_MODES.  New DOFs (hawt_core.rigid.kane): the shaft twist (rotor azimuth minus
    the gearbox-input azimuth) and, with a free generator, the gearbox-input azimuth.
    ``generator_torque_slope`` [N m s/rad, high-speed shaft]: with a free generator, the
    slope dT/d(omega) of its torque law at the operating point (the torque is then the
    trimmed or commanded torque plus the slope times the generator's speed change: an
    electrical damping; ServoDyn's simple variable-speed law in region 2, T = K omega^2, has
    2 K omega); 0: a torque that does not depend on the speed.
    """

    stiffness: Optional[float] = None
    damping: float = 0.0
    generator_inertia: float = 0.0
    gearbox_ratio: float = 1.0
    generator: str = "prescribed"
    generator_torque_slope: float = 0.0


@dataclass(frozen=True, eq=False)
class Polar:
    """An airfoil's lift, drag and pitching-moment coefficients against the angle of attack
    (one table: one Reynolds number).

    ``alpha`` [rad] strictly increasing; ``cl``, ``cd``, ``cm`` [-] one per angle (``cm``
    about the quarter chord, nose up positive, as AeroDyn's); ``reynolds`` [-] and
    ``thickness`` (t/c) [-] of the table when known (None otherwise).
    """

    name: str
    alpha: np.ndarray
    cl: np.ndarray
    cd: np.ndarray
    cm: np.ndarray
    reynolds: Optional[float] = None
    thickness: Optional[float] = None

    def __post_init__(self):
        for k in ("alpha", "cl", "cd", "cm"):
            object.__setattr__(self, k, _frozen_array(getattr(self, k), 1))


#: AeroDyn's default constant of the Pitt/Peters skewed-wake correction (SkewRedistrFactor).
PITT_PETERS_SKEW = 15.0 * np.pi / 32.0


@dataclass(frozen=True, eq=False)
class Aerodynamics:
    """The blade's aerodynamic description (AeroDyn's blade file and airfoil polars), held
    for the aeroelastic analyses; the structural analyses run in a vacuum and do not use it.

    Per aerodynamic station (``stations``: fractions of the blade's span ``blade.length``
    along b1, 0 to 1): ``chord`` [m]; ``twist`` [rad], hawt's sign (positive from b2 towards
    b3, i.e. AeroDyn's BlTwist, positive towards feather, is minus it); ``airfoil``: the
    index into ``polars`` of the station's airfoil; ``ac_prebend``, ``ac_sweep`` [m]: the
    aerodynamic centre's offsets along b3 and b2 (AeroDyn's BlCrvAC and -BlSwpAC; None =
    on the straight b1 axis; hawt's aerodynamics do not use them: the loads act on the
    beam's own line); ``ac_chordwise`` [m]: the aerodynamic centre's distance from the
    beam's reference line along the chord, towards the leading edge, where the loads act
    (their moment about the reference line; a HAWC2 blade: a quarter chord, its c2 line
    being the half chord; None = at the reference line, as AeroDyn's loads act at the blade
    nodes); ``cant`` [rad]: the airfoil plane's tilt about the chord (AeroDyn's BlCrvAng;
    None = 0).  ``skew_factor`` [-]: the constant K of Pitt and Peters'
    skewed-wake correction of the axial induction in yawed or tilted flow (aero/inflow.py;
    AeroDyn's SkewRedistrFactor, default 15 pi / 32); 0 = no correction.
    """

    stations: np.ndarray
    chord: np.ndarray
    twist: np.ndarray
    airfoil: np.ndarray
    polars: tuple
    ac_prebend: Optional[np.ndarray] = None
    ac_sweep: Optional[np.ndarray] = None
    cant: Optional[np.ndarray] = None
    skew_factor: float = PITT_PETERS_SKEW
    ac_chordwise: Optional[np.ndarray] = None

    def __post_init__(self):
        object.__setattr__(self, "skew_factor", float(self.skew_factor))
        for k in ("stations", "chord", "twist"):
            object.__setattr__(self, k, _frozen_array(getattr(self, k), 1))
        for k in ("ac_prebend", "ac_sweep", "cant", "ac_chordwise"):
            if getattr(self, k) is not None:
                object.__setattr__(self, k, _frozen_array(getattr(self, k), 1))
        idx = np.array(self.airfoil, dtype=int)
        idx.setflags(write=False)
        object.__setattr__(self, "airfoil", idx)
        object.__setattr__(self, "polars", tuple(self.polars))


@dataclass(frozen=True, eq=False)
class TowerAerodynamics:
    """The tower's aerodynamic drag (AeroDyn's tower table with TwrAero = True): per station
    (``stations``: fractions of the tower's length from its base, 0 to 1) the outer
    ``diameter`` [m] and the ``drag`` coefficient [-] of the flow across the tower axis.
    Used in wind on a flexible tower (assembly/tower_aero.py)."""

    stations: np.ndarray
    diameter: np.ndarray
    drag: np.ndarray

    def __post_init__(self):
        for k in ("stations", "diameter", "drag"):
            object.__setattr__(self, k, _frozen_array(getattr(self, k), 1))


@dataclass(frozen=True)
class Gravity:
    enabled: bool = False
    g: float = 9.81


@dataclass(frozen=True, eq=False)
class Turbine:
    """A whole turbine. ``tower`` None means a rigid tower (the paper's example);
    ``drivetrain`` None a rigid shaft turning at the prescribed rotor speed (the paper's);
    ``aerodynamics`` None: no aerodynamic description (the paper's turbine in a vacuum);
    ``tower_aerodynamics`` None: no drag on the tower."""

    name: str
    rotor: Rotor
    hub: Hub
    nacelle: Nacelle
    blade: Beam
    tower: Optional[Beam] = None
    gravity: Gravity = field(default_factory=Gravity)
    drivetrain: Optional[Drivetrain] = None
    aerodynamics: Optional[Aerodynamics] = None
    tower_aerodynamics: Optional[TowerAerodynamics] = None

    def with_rotor_speed(self, speed: float) -> "Turbine":
        return replace(self, rotor=replace(self.rotor, speed=float(speed)))

    def with_elements(self, n: int) -> "Turbine":
        return replace(self, blade=replace(self.blade, elements=int(n)))

    def structural_damping_text(self) -> str:
        """What structural damping the beams carry, for tables' headers and logs:
        "structural damping: blade modal flap 0.4775/0.4775 %, edge 0.4775 %; tower ...",
        or "" for an undamped structure (the paper's turbine: its tables unchanged)."""
        parts = [f"{name} {beam.damping.text()}"
                 for name, beam in (("blade", self.blade), ("tower", self.tower))
                 if beam is not None and beam.damping is not None and beam.damping.enabled]
        return ("structural damping: " + "; ".join(parts)) if parts else ""

    def without_structural_damping(self) -> "Turbine":
        """This turbine with undamped blades and tower (a conservative structure)."""
        return replace(self, blade=replace(self.blade, damping=None),
                       tower=None if self.tower is None else replace(self.tower, damping=None))

    def distance_from_shaft(self, x) -> np.ndarray:
        """Distance [m] from the shaft axis of the points at span ``x`` [m] of the undeformed
        blade: the root point is at the hub radius e in the hub plane (rigid/kane.py) and the
        coned blade axis b1 leaves it, so e + x cos(precone)."""
        return self.hub.radius + np.asarray(x) * np.cos(self.rotor.precone)


@dataclass(frozen=True, eq=False)
class Wing:
    """A cantilever wing in a uniform stream (the classic aeroelastic benchmark cases, run with
    the turbine's beam and airfoil models; assembly/wing.py).

    ``beam``: the wing as a Beam (b1 along the span, b2 chordwise towards the leading edge,
    b3 normal to the chord; the reference line is the elastic axis); ``chord`` [m];
    ``elastic_axis``: the reference line's position as a fraction of the chord from the
    leading edge; ``density`` [kg/m^3] of the air; ``lift_slope`` [1/rad]."""

    name: str
    beam: Beam
    chord: float
    elastic_axis: float
    density: float = 1.225
    lift_slope: float = 2.0 * np.pi

    @property
    def axis_semichords(self) -> float:
        """The elastic axis aft of mid-chord in semi-chords (Theodorsen's a)."""
        return 2.0 * self.elastic_axis - 1.0
