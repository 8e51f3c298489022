"""Floquet modal analysis of the coupled turbine (the paper's Table 2), with automatic labels.

Pipeline: steady state (constant, or periodic by harmonic balance) -> exact periodic
linearization ``E(t) x' = A(t) x`` -> monodromy by time marching (hawt_core.floquet: Radau IIA
by default, the paper's central differencing with ``method="paper"``), Peters' Fast Floquet
over ``T/Nb`` when the blades are identical and equally spaced -> characteristic exponents with
the integer-per-rev ambiguity resolved by the dominant harmonic of the periodic eigenvector ->
labels.

Which multipliers are reported: the descriptor system has one multiplier per dynamic state
(12N + 4 for the paper's rotor), but a marching scheme resolves only the modes whose frequency
is well below its step rate; the highest mesh modes (hundreds per-rev) come back damped out
(Radau) or aliased (central differencing). Each Floquet mode is matched (by the modal assurance
criterion of its eigenvector at t = 0) to a mode of the time-averaged pencil; modes matched to an
averaged mode above the method's resolution limit (``steps / 8`` per-rev for Radau IIA,
``steps / 12`` for central differencing) are left out and counted in ``unresolved``.

Labels: ``family`` is yaw or teeter when the rigid-body rotation moves the blade tips more
than the elastic deflection does, otherwise the strain-energy-dominant direction (flap, lag,
torsion, axial, shear); ``symmetry`` compares the blades in their own frames (symmetric /
antisymmetric for two blades; collective / cyclic / differential for more); ``index``
counts within (family, symmetry) by frequency.  With a flexible tower, ``family`` is tower
when the tower's elastic motion dominates, and ``symmetry`` is then its direction
(fore-aft, side-side, torsion, axial).
"""
from __future__ import annotations

import json
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np
import scipy.linalg as sl
from scipy.optimize import linear_sum_assignment

from .assembly import TurbineModel
from .blade_modes import FAMILIES, check_elements, classify_energy, deflate_infinite, equilibrate
from .floquet import LinearPeriodicDAE, _dominant_harmonic, floquet_analysis, periodic_modes
from .hill import hill_modes
from .model import Turbine
from .multiblade import MultiBladeTransform, fixed_frame_modes
from .periodic import periodic_steady_state
from .threads import blas_threads

#: "auto": multi-blade coordinates (Hill's method with constant coefficients, one
#: eigenproblem) where they make the system time-invariant (3+ identical blades on a rigid
#: hub, constant steady state), otherwise Radau IIA monodromy; "radau", "paper": monodromy
#: by time marching; "hill": Hill's method (in multi-blade coordinates where the rotor's
#: symmetry allows it, in the rotating frame otherwise)
METHODS = ("auto", "radau", "paper", "hill")
DEFAULT_STEPS = {"radau": 400, "paper": 1000}
#: Largest frequency [per-rev] reported by Hill's method and multi-blade coordinates (the
#: resolution of the default 400 Radau IIA steps, steps / 8).
DEFAULT_MAX_PER_REV = 50.0
#: Relative residual above which the blade-relabelling symmetry is taken not to hold.
SYMMETRY_TOL = 1e-8
#: Resolution limit: reported frequencies below steps / this (per-rev over a full period).
STEPS_PER_CYCLE = {"radau": 8.0, "paper": 12.0}
MAX_STEPS = 1_000_000
#: Most samples of the periodic eigenvectors per period (memory: samples x rows x modes).
MAX_SAMPLES = 512
#: Most finite elements per blade accepted by :func:`validate_request`.
MAX_ELEMENTS = 512


class Cancelled(RuntimeError):
    """The analysis was cancelled through the ``cancel`` callback."""


@dataclass
class Mode:
    """One Floquet mode.  ``frequency_per_rev`` (and the other unprefixed fields) are the
    dominant frequency of the motion that names the mode, the paper's convention: the
    blades' deflection in the rotating frame for blade modes, the tower top or the yaw angle
    (fixed frame) for tower and yaw modes.  With three or more blades the fixed-frame view
    (multi-blade coordinates, as OpenFAST's MBC3 or HAWCStab2 report): ``fixed_frame_per_rev``
    / ``fixed_frame_hz`` / ``fixed_frame_damping_ratio`` of the dominant fixed-frame harmonic,
    ``whirl`` (collective, forward, backward, differential) and ``cyclic_order`` (k of the
    dominant cyclic pair cos k psi, sin k psi; 0 collective, Nb/2 differential); None for
    one- and two-bladed rotors."""

    family: str
    symmetry: Optional[str]
    index: int
    frequency_per_rev: float
    real_per_rev: float
    frequency_hz: float
    damping_ratio: float
    blade_phase_deg: Optional[float] = None
    fixed_frame_per_rev: Optional[float] = None
    fixed_frame_hz: Optional[float] = None
    fixed_frame_damping_ratio: Optional[float] = None
    whirl: Optional[str] = None
    cyclic_order: Optional[int] = None
    participation: dict = field(default_factory=dict, repr=False)
    column: int = field(default=-1, repr=False)

    @property
    def label(self) -> str:
        """e.g. 'flap 1 antisymmetric', 'teeter 1'."""
        return f"{self.family} {self.index} {self.symmetry or ''}".strip()

    def to_dict(self) -> dict:
        return {"family": self.family, "symmetry": self.symmetry, "index": self.index,
                "frequency_per_rev": self.frequency_per_rev, "real_per_rev": self.real_per_rev,
                "frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio,
                "blade_phase_deg": self.blade_phase_deg,
                "fixed_frame_per_rev": self.fixed_frame_per_rev,
                "fixed_frame_hz": self.fixed_frame_hz,
                "fixed_frame_damping_ratio": self.fixed_frame_damping_ratio,
                "whirl": self.whirl, "cyclic_order": self.cyclic_order}


@dataclass
class ModalResult:
    """Result of :func:`modal_analysis`; ``modes`` sorted by frequency then real part."""

    modes: list
    settings: dict
    floquet: object = field(repr=False)
    model: TurbineModel = field(repr=False)
    steady: object = field(repr=False)
    unresolved: int = 0
    compute_time: float = 0.0
    timings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"settings": self.settings, "modes": [m.to_dict() for m in self.modes],
                "unresolved_modes": self.unresolved, "compute_time": self.compute_time}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), **kw)

    def find(self, family: str, symmetry: Optional[str] = None, index: int = 1) -> Mode:
        for m in self.modes:
            if m.family == family and m.index == index and (symmetry is None or m.symmetry == symmetry):
                return m
        raise KeyError(f"mode: no {family} {symmetry or ''} {index} in this result")

    def table(self) -> str:
        s = self.settings
        if s["method"] in ("radau", "paper"):
            how = f"{s['method']}, {s['steps']} steps/period{', fast Floquet' if s['fast'] else ''}"
        elif s.get("frame") == "multi-blade" and not s.get("hill_harmonics"):
            how = "multi-blade coordinates, time-invariant: one eigenproblem"
        else:
            how = (f"Hill's method, {s.get('frame', 'rotating')} frame, "
                   f"{s.get('hill_harmonics', 0)} harmonics")
        header = (f"Dominant frequencies of the turbine '{s['turbine']}' (Floquet, {how}), "
                  f"{s['elements']} elements per blade, rotor speed {s['rotor_speed']:.4g} rad/s")
        footer = []
        if self.unresolved:
            if s["method"] in ("radau", "paper"):
                footer.append(f"({self.unresolved} mesh modes above the temporal resolution "
                              f"{s['resolution_per_rev']:.0f} per-rev not shown: raise --steps)")
            else:
                footer.append(f"({self.unresolved} modes above {s['resolution_per_rev']:.0f} "
                              "per-rev not shown: raise --max-per-rev)")
        footer.append(f"computed in {self.compute_time:.2f} s")
        return format_table(header, self.modes, footer)

    def shape_samples(self, mode: Mode):
        """Periodic eigenvector of ``mode`` over one revolution: (times (M,), states (M, n)).

        Marching the real Floquet solution from x(0) would grow with exp(eta t); these are the
        periodic parts p(t) on every state row (complex), from the Floquet result samples.
        """
        fl = self.floquet
        rows = fl.sample_rows
        P = np.zeros((len(fl.sample_times), self.model.n), complex)
        P[:, rows] = fl.periodic_sample(mode.column)
        return fl.sample_times, P

    def plot(self, path, modes=None):
        """Mode-shape pictures (like the paper's Figs. 1-12) to a PNG file."""
        from .plotting import plot_turbine_modes
        return plot_turbine_modes(self, path, modes=modes)


def _ordinal(k: int) -> str:
    return {1: "1st", 2: "2nd", 3: "3rd"}.get(k, f"{k}th")


def mode_name(m) -> str:
    """'1st antisymmetric flap', '1st backward-whirl lag', 'teeter', '1st side-side tower'."""
    if m.family in ("yaw", "teeter"):
        return m.family
    return f"{_ordinal(m.index)} {(m.symmetry or '')} {m.family}".replace("  ", " ")


def _eigenvalue_text(freq: float, real: float) -> str:
    if abs(freq) < 5e-7 and abs(real) < 5e-7:
        return "0"
    if abs(freq) < 5e-7:
        return f"{real:+.6f}"
    return f"{real:+.6f} ± {freq:.6f} i"


def _fixed(m):
    """The fixed-frame frequency of a mode (Mode or the hawt_msgs/Mode message, whose whirl
    is empty for one and two blades), or None."""
    f = getattr(m, "fixed_frame_per_rev", None)
    return None if not getattr(m, "whirl", None) or f is None or not np.isfinite(f) else f


def format_table(header: str, modes, footer=()) -> str:
    """The modes as a table like the paper's Table 2. ``modes``: objects with the attributes
    family, symmetry, index, frequency_per_rev, real_per_rev, frequency_hz, damping_ratio
    (Mode, or the hawt_msgs/Mode message of the ROS service).  Three or more blades (modes
    with fixed-frame fields): the fixed-frame eigenvalue, Hz and damping ratio, and the
    rotating-frame dominant frequency beside them."""
    fixed = bool(modes) and all(_fixed(m) is not None for m in modes)
    if fixed:
        lines = [header, f"{'mode':<30}{'fixed-frame eigenvalue (per-rev)':>34}{'Hz':>11}"
                         f"{'damping':>11}{'rotating':>11}"]
    else:
        lines = [header, f"{'mode':<30}{'eigenvalue (per-rev)':>28}{'Hz':>11}{'damping':>11}"]
    for m in modes:
        name = mode_name(m)
        if fixed:
            ev = _eigenvalue_text(m.fixed_frame_per_rev, m.real_per_rev)
            zeta = m.fixed_frame_damping_ratio
            damping = f"{zeta:>11.2e}" if np.isfinite(zeta) else f"{'-':>11}"
            lines.append(f"{name:<30}{ev:>34}{m.fixed_frame_hz:>11.5f}{damping}"
                         f"{m.frequency_per_rev:>11.5f}")
            continue
        ev = _eigenvalue_text(m.frequency_per_rev, m.real_per_rev)
        damping = f"{m.damping_ratio:>11.2e}" if np.isfinite(m.damping_ratio) else f"{'-':>11}"
        lines.append(f"{name:<30}{ev:>28}{m.frequency_hz:>11.5f}{damping}")
    return "\n".join(lines + list(footer))


# ---------------------------------------------------------------------------- validation
#: Largest accepted max_per_rev (Hill's method and multi-blade coordinates).
MAX_PER_REV = 1000.0


def validate_request(elements=None, rotor_speed=None, steps=None, method=None,
                     max_per_rev=None):
    """Check analysis overrides; raises ValueError naming the field, value and what's allowed."""
    if elements is not None:
        if isinstance(elements, bool):      # check_elements would take True for 1
            raise ValueError(f"elements: {elements!r} is not allowed; need an integer >= 1")
        if check_elements(elements) > MAX_ELEMENTS:
            raise ValueError(f"elements: {elements!r} is not allowed; need at most "
                             f"{MAX_ELEMENTS} per blade")
    if rotor_speed is not None:
        r = float(rotor_speed)
        if not np.isfinite(r) or r <= 0:
            raise ValueError(f"rotor_speed: {rotor_speed!r} is not allowed; need a finite "
                             "number > 0 [rad/s]")
    if steps is not None:
        if isinstance(steps, bool) or not float(steps).is_integer() or not 8 <= int(steps) <= MAX_STEPS:
            raise ValueError(f"steps: {steps!r} is not allowed; need an integer from 8 to {MAX_STEPS}")
    if method is not None and method not in METHODS:
        raise ValueError(f"method: {method!r} is not allowed; choose one of {', '.join(METHODS)}")
    if max_per_rev is not None:
        try:
            f = float(max_per_rev)
        except (TypeError, ValueError):
            f = float("nan")
        if isinstance(max_per_rev, bool) or not (0 < f <= MAX_PER_REV):
            raise ValueError(f"max_per_rev: {max_per_rev!r} is not allowed; need a number "
                             f"> 0 and <= {MAX_PER_REV:g} [per-rev]")


# ---------------------------------------------------------------------------- analysis
def periodic_dae(model: TurbineModel, steady, check_symmetry: bool = True) -> LinearPeriodicDAE:
    """The exact periodic linearization about ``steady`` as a LinearPeriodicDAE, with the
    blade relabelling S for Fast Floquet and multi-blade coordinates when the rotor has the
    symmetry (identical, equally spaced blades; a rigid hub or two blades on a teeter hinge).
    With ``check_symmetry`` the identity ``E(t + T/Nb) = S E(t) S^T`` (and A) is verified at
    two times; if it does not hold to SYMMETRY_TOL, S is dropped with a RuntimeWarning and
    the full period is used (a wrong symmetry would give wrong exponents)."""
    cache = {}

    def jac(t):
        t = float(t)
        if t not in cache:
            if len(cache) > 64:
                cache.clear()
            Jy, Jd = model.jacobians(steady.rate_at(t), steady.at(t), t)
            cache[t] = (Jd, -Jy)
        return cache[t]

    S, nb = None, None
    if model.n_blades >= 2:
        try:
            S, nb = model.blade_relabelling(), model.n_blades
        except ValueError:
            S, nb = None, None
    dae = LinearPeriodicDAE(lambda t: jac(t)[0], lambda t: jac(t)[1], model.period,
                            model.differential, S=S, blades=nb)
    if S is not None and check_symmetry:
        # times on the Fourier sampler's first grid (their linearizations are reused)
        err = dae.check_symmetry(model.period * np.array([0.0, 0.2]))
        dae.symmetry_error = err
        if not err <= SYMMETRY_TOL:
            warnings.warn(f"blade-relabelling symmetry: residual {err:.1e} > {SYMMETRY_TOL:.0e}"
                          "; using the full period (no Fast Floquet, no multi-blade "
                          "coordinates)", RuntimeWarning, stacklevel=2)
            dae = LinearPeriodicDAE(dae.E, dae.A, model.period, model.differential)
            dae.symmetry_error = err
    return dae


def dynamic_dimension(dae: LinearPeriodicDAE) -> int:
    """Number of dynamic states (finite eigenvalues of the pencil at t = 0), found by exact
    deflation of the infinite eigenvalues (blade_modes.deflate_infinite): the dimension of the
    consistent subspace.  O(n^3): the analyses use TurbineModel.dynamic_dimension (a count)
    instead, which tests/test_assembly.py checks against this."""
    Ar, _, _ = deflate_infinite(dae.A(0.0).toarray(), dae.E(0.0).toarray())
    return int(Ar.shape[0])


def _display_rows(model: TurbineModel):
    """Indices and weights of displacement-like unknowns (units: metres of motion): rigid
    rotations times the rotor radius; blade displacements; blade bending slopes (theta2,
    theta3) times the blade length (the tip metres they cause); the twist theta1 times the
    sections' torsional radius of gyration sqrt(i1 / m) (the metres its mass moves: a twist
    times the blade length would outweigh a flap deflection by the span-to-chord ratio, and
    a torsion sideband would then name a flap mode's frequency); the tower's displacements
    and its rotations times the rotor radius."""
    lay = model.layout
    R = model.turbine.hub.radius + model.turbine.blade.length
    L = model.turbine.blade.length
    sec = model.turbine.blade.sections
    r_g = float(np.sqrt(np.mean(sec.i1) / np.mean(sec.mass)))
    idx, wts = [], []
    for name in ("yaw", "teeter"):
        if name in lay:
            idx.append(lay[name]), wts.append(R)
    for k in range(model.n_blades):
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


#: ``symmetry`` of a tower mode: the dominant tower-top motion
TOWER_DIRECTIONS = ("axial", "side-side", "fore-aft", "torsion")


def _tower_motion(model: TurbineModel, x):
    """Elastic tower motion of eigenvector x as metres: (largest, direction).

    Largest nodal displacement components (t1 axial, t2 side-side, t3 fore-aft) [m] and the
    largest torsion (rotation about t1) times the rotor radius (the rotor-tip metres it
    causes); bending rotations are counted through the displacements they come with."""
    tl = model.layout.tower()
    R = model.turbine.hub.radius + model.turbine.blade.length
    u = np.abs(x[tl.u[1:]]).max(axis=0)
    parts = np.array([u[0], u[1], u[2], R * np.abs(x[tl.theta[1:, 0]]).max()])
    j = int(np.argmax(parts))
    return float(parts[j]), TOWER_DIRECTIONS[j]


def _averaged_modes(dae: LinearPeriodicDAE, rows, weights):
    """Finite eigenpairs of the time-averaged pencil (exact for harmonics up to 4; the
    5-point grid is the Fourier sampler's first grid, so these linearizations may still be in
    periodic_dae's cache of recent ones, which is cleared when it exceeds 64 entries)."""
    ts = dae.period * np.arange(5) / 5
    E0 = sum(dae.E(t).toarray() for t in ts) / len(ts)
    A0 = sum(dae.A(t).toarray() for t in ts) / len(ts)
    As, Es, c = equilibrate(A0, E0)
    (al, be), X = sl.eig(As, Es, homogeneous_eigvals=True)
    ok = np.abs(be) > 1e-8 * np.abs(al)
    lam = al[ok] / be[ok]
    X = X[:, ok] / c[:, None]
    return lam, X[rows] * weights[:, None]


def _mac(a, B):
    num = np.abs(np.conj(a) @ B) ** 2
    den = (np.abs(a) ** 2).sum() * (np.abs(B) ** 2).sum(0)
    return num / np.where(den > 0, den, 1.0)


def label_modes(model: TurbineModel, fl, columns) -> list:
    """Modes (unsorted indices) labelled from their Floquet eigenvectors x(0)."""
    lay = model.layout
    R = model.turbine.hub.radius + model.turbine.blade.length
    sec = model.turbine.blade.sections
    r_g = float(np.sqrt(np.mean(sec.i1) / np.mean(sec.mass)))  # torsion radius of gyration
    nb = model.n_blades
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    modes = []
    for i in columns:
        x = fl.eigenvectors[:, i]
        # rigid rotations: RMS over the revolution of the periodic eigenvector (a teeter
        # oscillating at 1/rev may pass through zero at t = 0), as blade-tip metres
        rigid = {nm: R * float(np.sqrt(np.mean(np.abs(fl.periodic_sample(i)[:, pos[lay[nm]]]) ** 2)))
                 if lay[nm] in pos else R * abs(x[lay[nm]])
                 for nm in ("yaw", "teeter") if nm in lay}
        elastic = 0.0
        energy = np.zeros(6)
        for k in range(nb):
            b = lay.blade(k)
            u = x[b.u[1:]]
            th = x[b.theta[1:]]
            elastic = max(elastic, np.abs(u).max(), r_g * np.abs(th[:, 0]).max())
            off = lay.blade_offset(k)
            energy += classify_energy(model.beam, x[off:off + model.beam.n])
        tower, tower_dir = _tower_motion(model, x) if lay.has_tower else (0.0, None)
        rig_name = None
        if tower > 0 and tower >= max([elastic] + [0.25 * r for r in rigid.values()]):
            # the tower's elastic motion dominates: a tower mode (symmetry = direction). A
            # tower torsion under a free yaw bearing turns the yaw angle (relative to the
            # tower top) as much as the tower twists, and tower bending swings a free yaw and
            # the teeter (gyroscopic coupling), all counted in blade-tip metres: hence the
            # factor 0.25 on the rigid rotations (a heuristic, like the 3.0 below)
            rig_name = "tower"
        elif rigid and max(rigid.values()) >= 3.0 * elastic:
            # the free yaw angle alone is the rigid-body yaw mode; any rigid mode in which the
            # hub teeters appreciably is a teeter mode (the paper's labels)
            rig_name = "teeter" if rigid.get("teeter", 0.0) >= 0.25 * rigid.get("yaw", 0.0) \
                else "yaw"
        if rig_name == "tower":
            family, symmetry, phase = "tower", tower_dir, None
        elif rig_name is not None:
            family, symmetry, phase = rig_name, None, None
        else:
            family = FAMILIES[int(np.argmax(energy))]
        eta = _family_exponent(model, fl, i, family)
        if rig_name is None:
            symmetry, phase = _blade_symmetry(model, fl, i, eta)
        modes.append(Mode(family=family, symmetry=symmetry, index=0,
                          **_exponent_fields(eta, fl.omega),
                          blade_phase_deg=phase,
                          participation={**{k: float(v) for k, v in rigid.items()},
                                         **({"tower": tower} if lay.has_tower else {}),
                                         "elastic": float(elastic),
                                         **{f: float(e) for f, e in zip(
                                             ("axial", "shear2", "shear3", "torsion", "flap", "lag"),
                                             energy)}},
                          column=int(i)))
    return modes


#: Exponents within this (relative) of each other form a degenerate cluster whose basis
#: is re-chosen along the blade symmetry classes.
CLUSTER_TOL = 1e-7


def _blade_vectors(model: TurbineModel):
    """Per blade, the rows of its nodal u and theta (same local order for every blade), and
    their weights (theta times the blade length: tip metres)."""
    lay = model.layout
    rows = [np.concatenate([lay.blade(k).u[1:].ravel(), lay.blade(k).theta[1:].ravel()])
            for k in range(model.n_blades)]
    b0 = lay.blade(0)
    w = np.concatenate([np.ones(b0.u[1:].size),
                        np.full(b0.theta[1:].size, model.turbine.blade.length)])
    return rows, w


def separate_degenerate_modes(model: TurbineModel, fl, columns) -> int:
    """Re-choose the basis of every cluster of equal exponents among ``columns`` so that each
    vector belongs to one blade symmetry class (returns how many clusters were changed).

    Equal exponents have an arbitrary basis: with four blades the collective and
    differential torsion of a blade-local mode are exactly degenerate, and an eigen-solver
    returns any mix of them, which the labels then misread (two "collective torsion" at one
    frequency, none at the other).  The classes are the discrete Fourier components over
    the blades (m = 0 collective, Nb/2 differential, the others cyclic): with the blade
    vectors' components F_m (display rows, x(0)), the pure combinations c solve
    ``W_m c = G c`` with eigenvalue 1 (``W_m = F_m^H F_m``, ``G = sum_m W_m``).  A cluster
    is changed only if it splits completely into pure vectors (eigenvalue > 0.999)."""
    nb = model.n_blades
    if nb < 2 or len(columns) < 2:
        return 0
    blade_rows, w = _blade_vectors(model)
    cols = sorted((int(c) for c in columns), key=lambda c: (fl.exponents[c].imag,
                                                              fl.exponents[c].real))
    omega = fl.omega
    clusters, cur = [], [cols[0]]
    for c in cols[1:]:
        a, b = fl.exponents[cur[-1]], fl.exponents[c]
        if abs(a - b) <= CLUSTER_TOL * max(abs(a), omega):
            cur.append(c)
        else:
            clusters.append(cur)
            cur = [c]
    clusters.append(cur)
    nu = fl._n_upper
    changed = 0
    phase = np.exp(-2j * np.pi * np.outer(np.arange(nb), np.arange(nb)) / nb)   # (m, b)
    for cl in clusters:
        if len(cl) < 2:
            continue
        kinds = {0 if c < nu else 1 if c < 2 * nu else 2 for c in cl}
        if len(kinds) != 1 or 2 in kinds:
            continue                                # real exponents: leave them
        X = fl.eigenvectors
        B = np.array([X[br][:, cl] * w[:, None] for br in blade_rows])     # (Nb, rows, c)
        F = np.einsum("mb,brc->mrc", phase, B) / nb                          # (m, rows, c)
        Wm = np.einsum("mrc,mrd->mcd", np.conj(F), F)
        G = Wm.sum(0)
        if np.linalg.cond(G) > 1e12:
            continue
        Q, found = [], 0
        for m in range(nb):
            ev, vec = sl.eigh(Wm[m], G)
            sel = ev > 0.999
            Q.append(vec[:, sel])
            found += int(sel.sum())
        if found != len(cl):
            continue
        Q = np.concatenate(Q, axis=1)
        fl.recombine(cl, Q)
        changed += 1
    return changed


def _exponent_fields(eta: complex, w0: float) -> dict:
    """Mode fields frequency_per_rev, real_per_rev, frequency_hz and damping_ratio of the
    characteristic exponent ``eta`` [rad/s] at the rotor speed ``w0``."""
    return {"frequency_per_rev": float(eta.imag / w0), "real_per_rev": float(eta.real / w0),
            "frequency_hz": float(eta.imag / (2 * np.pi)),
            # a zero exponent (free yaw angle) has no damping ratio: report 0
            "damping_ratio": float(-eta.real / abs(eta)) if abs(eta) > 1e-6 * w0 else 0.0}


#: Blade unknowns whose motion names an elastic family: (field, component, weight), the
#: weight "L" standing for the blade length (a slope's tip metres), "r_g" for the sections'
#: torsional radius of gyration (a twist's metres of mass motion).
FAMILY_ROWS = {"flap": (("u", 2, 1.0), ("theta", 1, "L")),
               "lag": (("u", 1, 1.0), ("theta", 2, "L")),
               "torsion": (("theta", 0, "r_g"),),
               "axial": (("u", 0, 1.0),),
               "shear": (("u", 1, 1.0), ("u", 2, 1.0))}


def _family_rows(model: TurbineModel, family: str, blade: Optional[int] = None):
    """(rows, weights) of the motion that names ``family``: the yaw or teeter angle, the
    tower top (displacements, rotations times the rotor radius), or the blades' FAMILY_ROWS
    (all blades, or one)."""
    lay = model.layout
    R = model.turbine.hub.radius + model.turbine.blade.length
    if family in ("yaw", "teeter"):
        return ([lay[family]], [1.0]) if family in lay else ([], [])
    if family == "tower":
        tl = lay.tower()
        return (list(tl.u[-1]) + list(tl.theta[-1]), [1.0] * 3 + [R] * 3)
    sec = model.turbine.blade.sections
    scale = {"L": model.turbine.blade.length,
             "r_g": float(np.sqrt(np.mean(sec.i1) / np.mean(sec.mass)))}
    rows, wts = [], []
    for k in (range(model.n_blades) if blade is None else [blade]):
        b = lay.blade(k)
        for field_name, comp, w in FAMILY_ROWS[family]:
            r = getattr(b, field_name)[1:, comp]
            rows += r.tolist()
            wts += [scale.get(w, w)] * len(r)
    return rows, wts


def _family_exponent(model: TurbineModel, fl, i: int, family: str) -> complex:
    """Characteristic exponent of mode ``i`` with the integer-per-rev ambiguity resolved by the
    dominant harmonic of the motion that names the mode (the paper's convention): the teeter
    angle for teeter modes, the yaw angle for yaw modes, the tower top for tower modes, the
    blades' flap (u3 and the slope theta2), lag (u2, theta3), twist (theta1), ... motion for
    blade modes (ties: the non-negative frequency closest to zero).  With periodic
    coefficients a mode's vector has several harmonics, and a sideband of another family's
    motion (a torsion sideband of a flap mode) must not name its frequency."""
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    rows, wts = _family_rows(model, family)
    sel = [(pos[int(r)], w) for r, w in zip(rows, wts) if int(r) in pos]
    if not sel:
        return _nonnegative(complex(fl.exponents[i]))
    P = fl.periodic_sample(i)[:, [j for j, _ in sel]] * np.array([w for _, w in sel])[None, :]
    M = P.shape[0]
    energy = (np.abs(np.fft.fft(P, axis=0) / M) ** 2).sum(1)
    k = np.fft.fftfreq(M, 1.0 / M).astype(int)
    eta = complex(fl.exponents[i])
    best = _dominant_harmonic(energy, k, eta.imag, fl.omega, tie=1e-9)
    return _nonnegative(eta + 1j * k[best] * fl.omega)


def _nonnegative(eta: complex) -> complex:
    """The member of a conjugate pair with a non-negative frequency (the system is real: the
    conjugate mode has the conjugate exponent and the opposite dominant harmonic)."""
    return eta.conjugate() if eta.imag < 0 else eta


def _blade_symmetry(model: TurbineModel, fl, i: int, eta: complex):
    """Symmetry of the blade motions of mode ``i`` reported with the exponent ``eta``;
    (label, blade-to-blade phase [deg]).

    Blade k reaches at t + T/Nb the azimuth where blade k+1 was at t; with the periodic part
    p of the reported exponent the blades relate by ``p_k(t + T/Nb) = e^{i phase}
    p_{k+1}(t)`` (exactly for a rotor with the relabelling symmetry, in the least-squares
    sense otherwise; shifts of p by Fourier interpolation).  Phase 0: symmetric (two blades)
    or collective; 180 deg: antisymmetric or differential; other multiples of 360/Nb:
    cyclic.  Reporting a frequency one whole per-rev off turns the phase by 360/Nb, which is
    why the symmetry follows the reported exponent (with periodic coefficients the dominant
    harmonic can differ from the marching's principal one)."""
    nb = model.n_blades
    if nb < 2:
        return None, None
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    rows, w = _blade_vectors(model)
    if any(int(x) not in pos for r in rows for x in r):
        return None, None
    blades = [[pos[int(x)] for x in r] for r in rows]
    P = fl.periodic_sample(i)
    eta0 = complex(fl.exponents[i])
    flip = eta.imag * eta0.imag < 0 or (eta.imag == 0 and eta0.imag != 0 and
                                       abs(eta - eta0.conjugate()) < abs(eta - eta0))
    if flip:                        # eta is the conjugate member's exponent
        P, eta0 = np.conj(P), eta0.conjugate()
    M = P.shape[0]
    t = fl.sample_times
    dk = int(round((eta.imag - eta0.imag) / fl.omega))
    C = np.fft.fft(P * np.exp(-1j * dk * fl.omega * t)[:, None], axis=0) / M   # harmonics of p
    kk = np.fft.fftfreq(M, 1.0 / M)
    shift = np.exp(1j * kk * 2 * np.pi / nb)[:, None]                       # t -> t + T/Nb
    z = 0j
    for k in range(nb):
        a = C[:, blades[k]] * w[None, :] * shift
        b_ = C[:, blades[(k + 1) % nb]] * w[None, :]
        z += np.vdot(b_, a)
    phase = float(np.degrees(np.angle(z))) if abs(z) > 0 else 0.0
    step = round(phase / (360.0 / nb)) % nb
    if nb == 2:
        return ("symmetric" if step == 0 else "antisymmetric"), phase
    if step == 0:
        return "collective", phase
    if nb % 2 == 0 and step == nb // 2:
        return "differential", phase
    return "cyclic", phase


def _index(modes):
    counts = {}
    for m in modes:
        key = (m.family, m.symmetry)
        counts[key] = counts.get(key, 0) + 1
        m.index = counts[key]
    return modes


def _monodromy_modes(model: TurbineModel, dae: LinearPeriodicDAE, method: str, steps: int,
                     use_fast: bool, rows, wts, d: int):
    """Floquet by time marching (Radau IIA or the paper's central differencing): the
    FloquetResult, the labelled resolved modes, the count of unresolved ones and the
    resolution limit [per-rev]."""
    # samples of the periodic eigenvectors per period: the dominant harmonic is resolved up
    # to samples / 2 per-rev, so the reported band is also capped at samples / 2.5
    samples = int(min(MAX_SAMPLES, max(128, 2 ** np.ceil(np.log2(2.5 * steps / STEPS_PER_CYCLE[method])))))
    fl = floquet_analysis(dae, method=method, steps=steps, fast=use_fast, samples=samples,
                          observed=rows, weights=wts ** 2, dynamic_dim=d)
    omega = model.rotor_speed
    limit = min(steps / STEPS_PER_CYCLE[method], samples / 2.5)
    lam0, X0 = _averaged_modes(dae, rows, wts)
    resolved = []
    unresolved = 0
    for i in fl.modes():
        # annihilated by the marching (|multiplier| < 1e-8: it would decay by e^-18 within a
        # revolution) or without a dominant harmonic: an unresolved mesh mode, not a result
        if abs(fl.multipliers[i]) < 1e-8 or fl.harmonic_share[i] < 0.05:
            unresolved += 1
            continue
        v = fl.eigenvectors[rows, i] * wts
        mac = _mac(v, X0)
        j = int(np.argmax(mac)) if len(mac) else -1
        f_avg = abs(lam0[j].imag) / omega if j >= 0 else 0.0
        if f_avg > limit:
            unresolved += 1
        else:
            resolved.append(i)
    resolved = np.array(resolved, int)
    if method == "paper":
        # Central differencing keeps |multiplier| = 1 for the unresolved mesh modes and aliases
        # them onto low frequencies, where they also mix with the free-yaw double multiplier
        # at 1: keep only the modes that an L-stable Radau IIA march (which annihilates
        # unresolved modes) confirms, within 1 % in frequency and 0.01 per-rev in real part.
        ref = floquet_analysis(dae, method="radau", steps=max(128, steps // 4), fast=use_fast,
                               observed=rows, weights=wts ** 2, dynamic_dim=d)
        keep = [j for j in ref.modes() if abs(ref.multipliers[j]) > 1e-12]
        fr, rr = ref.frequency_per_rev[keep], ref.real_per_rev[keep]
        fi = fl.frequency_per_rev[resolved][:, None]
        ri = fl.real_per_rev[resolved][:, None]
        ok = (np.abs(fi - fr[None]) <= 1e-2 * np.maximum(1, fr[None])) & (np.abs(ri - rr[None]) <= 1e-2)
        cost = np.where(ok, np.abs(fi - fr[None]) + np.abs(ri - rr[None]), 1e6)
        pi, pj = linear_sum_assignment(cost)  # one paper mode per confirming Radau mode
        pairs = [(resolved[a], keep[b]) for a, b in zip(pi, pj) if ok[a, b]]
        unresolved += len(resolved) - len(pairs)
        # labels from the Radau eigenvectors: with central differencing the unresolved mesh
        # modes alias onto the unit circle and mix into nearly equal multipliers' eigenvectors
        modes = label_modes(model, ref, [b for _, b in pairs])
        for m, (a, _) in zip(modes, pairs):
            for name, value in _exponent_fields(_family_exponent(model, fl, a, m.family),
                                                fl.omega).items():
                setattr(m, name, value)
            m.column = int(a)
    else:
        separate_degenerate_modes(model, fl, resolved)
        modes = label_modes(model, fl, resolved)
    return fl, modes, unresolved, limit


def _hill_floquet(model: TurbineModel, dae: LinearPeriodicDAE, transform, max_per_rev: float,
                  rows, wts, d: int):
    """Floquet modes by Hill's method (hawt_core.hill) on ``dae``: the rotating-frame system,
    or with ``transform`` (a MultiBladeTransform) the system in multi-blade coordinates
    (constant for an isotropic rotor without gravity: one eigenproblem).  Returns the
    rotating-frame FloquetResult (samples x(t) = T(t) q(t) e^{eta t} over a revolution, so that
    labels, shapes and Campbell tracking work as for the marching) and the HillModes."""
    omega = model.rotor_speed
    srows = np.unique(rows)
    pos = {int(r): i for i, r in enumerate(srows)}
    obs = np.array([pos[int(r)] for r in rows])
    frame_rows = rows
    hm = hill_modes(dae, max_per_rev * omega, observed=frame_rows, weights=wts ** 2)
    T = model.period
    M = int(min(MAX_SAMPLES, max(128, 2 ** np.ceil(np.log2(2.5 * max_per_rev)))))
    tm = np.arange(M) * T / M
    lam = hm.exponents
    tol = 1e-7 * omega
    upper = [i for i in range(lam.size) if lam[i].imag > tol]
    real = [i for i in range(lam.size) if abs(lam[i].imag) <= tol]
    order = upper + real
    groups = transform.blade_groups(srows) if transform is not None else None
    X = np.empty((M, srows.size, len(order)), complex)
    x0 = np.empty((model.n, len(order)), complex)
    eta0 = np.empty(len(order), complex)
    T0 = transform.matrix(0.0) if transform is not None else None
    for j, i in enumerate(order):
        q = hm.periodic(i, tm, srows)                              # (M, rows), dae frame
        q0 = hm.vectors[:, :, i].sum(axis=0)                       # (n,) at t = 0
        x = transform.to_rotating(q, tm, groups) if transform is not None else q
        xf = T0 @ q0 if transform is not None else q0
        eta = lam[i]
        if j >= len(upper):            # real exponent: a real solution (fix the phase)
            eta = complex(eta.real, 0.0)
            k = int(np.argmax(np.abs(xf)))
            ph = np.conj(xf[k]) / abs(xf[k]) if abs(xf[k]) > 0 else 1.0
            x, xf = np.real(x * ph), np.real(xf * ph)
        X[:, :, j] = x * np.exp(eta * tm)[:, None]
        x0[:, j] = xf
        eta0[j] = eta
    fl = periodic_modes(eta0, X, x0, len(upper), period=T, sample_rows=srows, observed=obs,
                        weights=wts ** 2, method="hill", steps=0, fast=False, blades=1,
                        n_dynamic=d, timings=dict(hm.timings))
    return fl, hm


_WHIRL_SYMMETRY = {"collective": "collective", "forward": "forward-whirl",
                   "backward": "backward-whirl", "differential": "differential"}


def _add_fixed_frame(model, transform, fl, modes, rows, wts):
    """Fixed-frame fields of every mode (three or more blades); the blade modes' symmetry
    becomes their whirl: collective, backward-whirl, forward-whirl (-k for the k-th cyclic
    pair, k >= 2), differential.  The frequency and the whirl of a blade mode come from the
    motion that names it (as its rotating-frame frequency does: hawt_core.modal
    FAMILY_ROWS), the whirl of a yaw, teeter or tower mode from all blade motion."""
    blade_rows = [(r, w) for r, w in zip(rows, wts) if r >= model.layout.blade_offset(0)
                  and r < model.layout.blade_offset(0) + model.n_blades * model.beam.n]
    br, bw = [r for r, _ in blade_rows], [w for _, w in blade_rows]
    specs = {}
    for m in modes:
        fr, fw = _family_rows(model, m.family)
        specs[m.column] = (fr, fw, fr, fw) if m.family in FAMILY_ROWS else (fr, fw, br, bw)
    ff = fixed_frame_modes(transform, fl, specs)
    for m in modes:
        f = ff[m.column]
        x = _exponent_fields(f.exponent, fl.omega)
        m.fixed_frame_per_rev = x["frequency_per_rev"]
        m.fixed_frame_hz = x["frequency_hz"]
        m.fixed_frame_damping_ratio = x["damping_ratio"]
        m.whirl = f.whirl
        m.cyclic_order = f.order
        if m.family not in ("yaw", "teeter", "tower"):
            sym = _WHIRL_SYMMETRY[f.whirl]
            if f.whirl in ("forward", "backward") and f.order > 1:
                sym = f"{sym}-{f.order}"
            m.symmetry = sym


def modal_analysis(turbine: Turbine, elements: Optional[int] = None,
                   rotor_speed: Optional[float] = None, steps: Optional[int] = None,
                   method: Optional[str] = None, fast: Optional[bool] = None,
                   harmonics: int = 8, max_per_rev: Optional[float] = None,
                   progress: Optional[Callable[[float, str], None]] = None,
                   cancel: Optional[Callable[[], bool]] = None) -> ModalResult:
    """Floquet modal analysis of ``turbine``; overrides for elements, rotor speed [rad/s],
    marching steps per period, method (METHODS; default "auto": multi-blade coordinates where
    they make the system time-invariant, otherwise Radau IIA) and ``max_per_rev`` (the band
    of Hill's method / multi-blade coordinates, default DEFAULT_MAX_PER_REV).  ``harmonics``:
    of the periodic steady state.  Three or more blades: every mode also carries its
    fixed-frame frequency and whirl.  ``progress(fraction, message)`` is called between
    stages; ``cancel()`` returning True raises Cancelled."""
    method = method or "auto"
    validate_request(elements, rotor_speed, steps, method, max_per_rev)
    with blas_threads():
        return _modal_analysis(turbine, elements, rotor_speed, steps, method, fast, harmonics,
                               max_per_rev, progress, cancel)


def _modal_analysis(turbine, elements, rotor_speed, steps, method, fast, harmonics,
                    max_per_rev, progress, cancel) -> ModalResult:
    t0 = time.perf_counter()
    timings = {}

    def stage(frac, msg):
        if cancel is not None and cancel():
            raise Cancelled(f"modal analysis cancelled during: {msg}")
        if progress is not None:
            progress(frac, msg)

    stage(0.0, "building the model")
    model = TurbineModel(turbine, elements=elements, rotor_speed=rotor_speed)
    stage(0.05, "steady state")
    steady = periodic_steady_state(model, harmonics=harmonics)
    timings["steady_state"] = time.perf_counter() - t0
    stage(0.2, "linearization")
    dae = periodic_dae(model, steady)
    transform = MultiBladeTransform(model) if model.n_blades >= 3 else None
    mbc = transform.dae(dae) if transform is not None and dae.S is not None else None
    if method == "auto":
        method = "hill" if mbc is not None and steady.constant else "radau"
    use_fast = dae.S is not None if fast is None else (bool(fast) and dae.S is not None)
    rows, wts = _display_rows(model)
    # the dominant harmonic is judged on displacement-like rows weighted to tip metres
    d = model.dynamic_dimension()
    t1 = time.perf_counter()
    omega = model.rotor_speed
    extra = {}
    if method in ("radau", "paper"):
        steps = int(steps) if steps is not None else DEFAULT_STEPS[method]
        stage(0.3, f"monodromy ({method}, {steps} steps)")
        fl, modes, unresolved, limit = _monodromy_modes(model, dae, method, steps, use_fast,
                                                        rows, wts, d)
    else:
        limit = float(max_per_rev) if max_per_rev is not None else DEFAULT_MAX_PER_REV
        frame = "multi-blade" if mbc is not None else "rotating"
        stage(0.3, f"Hill's method ({frame} frame, modes below {limit:g} per-rev)")
        fl, hm = _hill_floquet(model, mbc if mbc is not None else dae,
                               transform if mbc is not None else None, limit, rows, wts, d)
        use_fast, steps = False, None
        separate_degenerate_modes(model, fl, fl.modes())
        modes = label_modes(model, fl, fl.modes())
        unresolved = max(0, d - int(fl.exponents.size))     # above the band
        extra = {"frame": frame, "hill_harmonics": hm.harmonics,
                 "hill_size": hm.size, "coefficient_harmonics": hm.coefficient_harmonics}
    timings["floquet"] = time.perf_counter() - t1
    stage(0.85, "labelling modes")
    if transform is not None:
        _add_fixed_frame(model, transform, fl, modes, rows, wts)
        modes.sort(key=lambda m: (m.fixed_frame_per_rev, m.real_per_rev))
    else:
        modes.sort(key=lambda m: (m.frequency_per_rev, m.real_per_rev))
    _index(modes)
    settings = {"turbine": turbine.name, "elements": model.beam.N, "rotor_speed": omega,
                "method": method, "steps": steps, "fast": bool(use_fast),
                "blades": model.n_blades, "resolution_per_rev": limit,
                "steady_state": "constant" if steady.constant
                else f"periodic ({harmonics} harmonics)", **extra}
    total = time.perf_counter() - t0
    timings["total"] = total
    stage(1.0, "done")
    return ModalResult(modes=modes, settings=settings, floquet=fl, model=model, steady=steady,
                       unresolved=unresolved, compute_time=total, timings=timings)
