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

import time
import warnings
from typing import Callable, Optional

import numpy as np
import scipy.linalg as sl
from scipy.optimize import linear_sum_assignment

from ..aero.wind import Wind
from ..assembly import TurbineModel
from ..model import Turbine
from ..numerics.checks import check_elements, check_rotor_speed
from ..numerics.limits import MAX_ELEMENTS
from ..numerics.mac import mac_matrix
from ..numerics.pencil import deflate_infinite, equilibrate
from ..numerics.threads import blas_threads
from ..results.modes import ModalResult
from ..solvers.floquet import LinearPeriodicDAE, floquet_analysis, periodic_modes
from ..solvers.hill import hill_modes
from ..solvers.multiblade import MultiBladeTransform
from ..solvers.periodic import PeriodicSteadyState, periodic_steady_state
from ..solvers.steady import constant_steady_state
from .blade_reference import vacuum_blade_reference
from .labels import (add_fixed_frame, aerodynamic_lags, exponent_fields, family_exponent,
                     label_modes, mark_overdamped, number_modes, separate_degenerate_modes)
from .wind_names import name_in_wind

__all__ = ["modal_analysis", "periodic_dae", "validate_request", "Cancelled", "METHODS",
           "DEFAULT_STEPS", "DEFAULT_MAX_PER_REV", "STEPS_PER_CYCLE", "MIN_STEPS", "MAX_STEPS",
           "MAX_ELEMENTS", "MAX_PER_REV"]


#: "auto": Hill's method in multi-blade coordinates where the rotor's symmetry allows them
#: (3+ identical blades on a rigid hub): one eigenproblem when they make the system
#: time-invariant (constant steady state), a few harmonics of Nb per-rev with gravity or
#: tilt (truncation by the exponents' convergence); otherwise Radau IIA monodromy;
#: "radau", "paper": monodromy
#: by time marching; "hill": Hill's method (in multi-blade coordinates where the rotor's
#: symmetry allows it, in the rotating frame otherwise)
METHODS = ("auto", "radau", "paper", "hill")

DEFAULT_STEPS = {"radau": 400, "paper": 1000}

#: Largest frequency [per-rev] reported by Hill's method and multi-blade coordinates (the
#: resolution of the default 400 Radau IIA steps, steps / 8).
DEFAULT_MAX_PER_REV = 50.0

#: Nominal period [s] of the constant-coefficient analysis of a standing rotor (rotor speed
#: 0): there is no revolution, and with T = 1 s the machinery's "per-rev" numbers are Hz.
STANDSTILL_PERIOD = 1.0

#: Default band [Hz] of the analysis of a standing rotor.
STANDSTILL_MAX_HZ = 10.0

#: Relative residual above which the blade-relabelling symmetry is taken not to hold.
SYMMETRY_TOL = 1e-8

#: Resolution limit: reported frequencies below steps / this (per-rev over a full period).
STEPS_PER_CYCLE = {"radau": 8.0, "paper": 12.0}

#: Fewest and most marching steps per period accepted by :func:`validate_request`.
MIN_STEPS = 8
MAX_STEPS = 1_000_000

#: Most samples of the periodic eigenvectors per period (memory: samples x rows x modes).
MAX_SAMPLES = 512


class Cancelled(RuntimeError):
    """The analysis was cancelled through the ``cancel`` callback."""


# ---------------------------------------------------------------------------- validation
#: Largest accepted max_per_rev (Hill's method and multi-blade coordinates).
MAX_PER_REV = 1000.0


def validate_request(elements=None, rotor_speed=None, steps=None, method=None,
                     max_per_rev=None):
    """Check analysis overrides; raises ValueError naming the field, value and what's allowed."""
    if elements is not None:
        check_elements(elements)
    if rotor_speed is not None:
        check_rotor_speed(rotor_speed)
    if steps is not None:
        if isinstance(steps, bool) or not float(steps).is_integer() or not MIN_STEPS <= int(steps) <= MAX_STEPS:
            raise ValueError(f"steps: {steps!r} is not allowed; need an integer from {MIN_STEPS} "
                             f"to {MAX_STEPS}")
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
    t = T/5 (a generic azimuth on the Fourier sampler's first grid, so that its
    linearization is reused and only E(t + T/Nb) is an extra one); if it does not hold
    to SYMMETRY_TOL, S is dropped with a RuntimeWarning and the full period is used (a
    wrong symmetry would give wrong exponents)."""
    cache = {}

    def jac(t):
        t = float(t)
        # keyed by the exact time: a neighbour's linearization differs in round-off, and
        # the Fourier sampler's error estimate (which picks its truncation) would see it
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
        # a time on the Fourier sampler's first grid (its linearization is reused)
        err = dae.check_symmetry(model.period * np.array([0.2]))
        dae.symmetry_error = err
        if not err <= SYMMETRY_TOL:
            warnings.warn(f"blade-relabelling symmetry: residual {err:.1e} > {SYMMETRY_TOL:.0e}"
                          "; using the full period (no Fast Floquet, no multi-blade "
                          "coordinates)", RuntimeWarning, stacklevel=2)
            dae = LinearPeriodicDAE(dae.E, dae.A, model.period, model.differential)
            dae.symmetry_error = err
    return dae


def _standstill_dae(model: TurbineModel):
    """The static equilibrium of a standing rotor (gravity included) and its linearization as
    a constant-coefficient DAE with the nominal period STANDSTILL_PERIOD."""
    y = constant_steady_state(model)
    steady = PeriodicSteadyState(times=np.array([0.0]), states=y[None],
                                 period=STANDSTILL_PERIOD, iterations=0, constant=True)
    Jy, Jd = model.jacobians(np.zeros(model.n), y, 0.0)
    A = -Jy
    return steady, LinearPeriodicDAE(lambda t: Jd, lambda t: A, STANDSTILL_PERIOD,
                                     model.differential)


def dynamic_dimension(dae: LinearPeriodicDAE) -> int:
    """Number of dynamic states (finite eigenvalues of the pencil at t = 0), found by exact
    deflation of the infinite eigenvalues (blade_modes.deflate_infinite): the dimension of the
    consistent subspace.  O(n^3): the analyses use TurbineModel.dynamic_dimension (a count)
    instead, which tests/test_assembly.py checks against this."""
    Ar, _, _ = deflate_infinite(dae.A(0.0).toarray(), dae.E(0.0).toarray())
    return int(Ar.shape[0])


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


#: The relative accuracy asked of the Fourier series of the linearization E(t), A(t), as a
#: share of the periodic steady state's own interpolation tolerance (the orbit it is taken
#: about is no more accurate): 1e-10 in a vacuum; 1e-8 in wind, where the C1 airfoil tables
#: make the series decay algebraically (NREL 5-MW at 15 m/s, 4 elements, multi-blade
#: coordinates: 6.7e-8, 4.0e-9, 1.1e-9, 1.6e-10 with 2, 7, 22, 67 harmonics; 1e-10 was not
#: reached at the 67 allowed and cost 135 linearizations, 1e-8 takes 15; the exponents below
#: 50 per-rev move by 4.5e-6 relative, within Hill's 5e-5).
FOURIER_SHARE = 1e-2
#: ... in wind, 1e-7: above rated the pitched blades' tables need 120 samples for 1e-8 (IEA
#: 15-MW at 25 m/s with Oye and Jones: 250 linearizations, 26 of the point's 51 s) and 30 to
#: 60 for 1e-7 (27 s), while the exponents move by at most 4e-6 of w (NREL 5-MW at 15 m/s,
#: frozen wake: 1.7e-5 of w, 6e-5 rad/s on the 48 rad/s torsion modes; Hill's tolerance is
#: 5e-5).
FOURIER_SHARE_IN_WIND = 1e-1


def _fourier_tol(model: TurbineModel) -> float:
    """The relative tolerance of the linearization's Fourier series (FOURIER_SHARE, or
    FOURIER_SHARE_IN_WIND for a model in wind)."""
    share = FOURIER_SHARE if getattr(model, "wind", None) is None else FOURIER_SHARE_IN_WIND
    return share * float(model.interpolation_tol)


def _family_exponent_fields(model: TurbineModel, fl, m) -> None:
    """Set the mode ``m``'s exponent fields (exponent_fields) from the dominant harmonic of
    its family's motion in ``fl``'s column ``m.column`` (family_exponent)."""
    for name, value in exponent_fields(family_exponent(model, fl, m.column, m.family),
                                        fl.omega).items():
        setattr(m, name, value)


def _monodromy_modes(model: TurbineModel, dae: LinearPeriodicDAE, method: str, steps: int,
                     use_fast: bool, rows, wts, d: int, reference=None):
    """Floquet by time marching (Radau IIA or the paper's central differencing): the
    FloquetResult, the labelled resolved modes (named after the vacuum blade ``reference``'s
    modes, label_modes), the count of unresolved ones and the resolution limit [per-rev]."""
    # samples of the periodic eigenvectors per period: the dominant harmonic is resolved up
    # to samples / 2 per-rev, so the reported band is also capped at samples / 2.5
    samples = int(min(MAX_SAMPLES, max(128, 2 ** np.ceil(np.log2(2.5 * steps / STEPS_PER_CYCLE[method])))))
    fl = floquet_analysis(dae, method=method, steps=steps, fast=use_fast, samples=samples,
                          observed=rows, weights=wts ** 2, dynamic_dim=d,
                          fourier_tol=_fourier_tol(model))
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
        mac = mac_matrix(v[:, None], X0)[0]
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
                               observed=rows, weights=wts ** 2, dynamic_dim=d,
                               fourier_tol=_fourier_tol(model))
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
        modes = label_modes(model, ref, [b for _, b in pairs], reference)
        for m, (a, _) in zip(modes, pairs):
            m.column = int(a)
            _family_exponent_fields(model, fl, m)
    else:
        separate_degenerate_modes(model, fl, resolved)
        modes = label_modes(model, fl, resolved, reference)
    return fl, modes, unresolved, limit


def _hill_floquet(model: TurbineModel, dae: LinearPeriodicDAE, transform, max_per_rev: float,
                  rows, wts, d: int):
    """Floquet modes by Hill's method (hawt_core.hill) on ``dae``: the rotating-frame system,
    or with ``transform`` (a MultiBladeTransform) the system in multi-blade coordinates
    (constant for an isotropic rotor without gravity: one eigenproblem).  Returns the
    rotating-frame FloquetResult (samples x(t) = T(t) q(t) e^{eta t} over a revolution, so that
    labels, shapes and Campbell tracking work as for the marching), the HillModes and the
    states' participation (n, columns of the FloquetResult) in its modes (None when Hill's
    method searched the whole pencil)."""
    # the rotor period (a multi-blade DAE's own period is T / Nb), nominal at standstill
    T = model.period if np.isfinite(model.period) else STANDSTILL_PERIOD
    omega = 2 * np.pi / T
    # the sample rows in the observed rows' order when they are distinct (periodic_modes then
    # reads them as a slice, not a gathered copy of every sample)
    srows = np.asarray(rows) if len(np.unique(rows)) == len(rows) else np.unique(rows)
    pos = {int(r): i for i, r in enumerate(srows)}
    obs = np.array([pos[int(r)] for r in rows])
    frame_rows = rows
    # multi-blade coordinates of an isotropic rotor are periodic only through gravity and
    # tilt (weakly): the truncation is chosen by the exponents' convergence (hill_modes)
    hm = hill_modes(dae, max_per_rev * omega, observed=frame_rows, weights=wts ** 2,
                    truncation="converged" if transform is not None else "tail",
                    fourier_tol=_fourier_tol(model),
                    internal=aerodynamic_lags(model) if transform is not None else None)
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
    # the states' participation per column of fl (its uppers, their conjugates, the reals)
    part = None
    if hm.participation is not None:
        part = hm.participation[:, order[:len(upper)] * 2 + order[len(upper):]]
    return fl, hm, part


def modal_analysis(turbine: Turbine, elements: Optional[int] = None,
                   rotor_speed: Optional[float] = None, steps: Optional[int] = None,
                   method: Optional[str] = None, fast: Optional[bool] = None,
                   harmonics: int = 8, max_per_rev: Optional[float] = None,
                   progress: Optional[Callable[[float, str], None]] = None,
                   cancel: Optional[Callable[[], bool]] = None,
                   wind: Optional[Wind] = None, rho: float = 1.225,
                   inflow: str = "frozen", airfoil: str = "quasi-steady") -> ModalResult:
    """Floquet modal analysis of ``turbine``; overrides for elements, rotor speed [rad/s],
    marching steps per period, method (METHODS; default "auto": multi-blade coordinates where
    they make the system time-invariant, otherwise Radau IIA) and ``max_per_rev`` (the band
    of Hill's method / multi-blade coordinates, default DEFAULT_MAX_PER_REV).  ``harmonics``:
    of the periodic steady state.  Three or more blades: every mode also carries its
    fixed-frame frequency and whirl.  ``progress(fraction, message)`` is called between
    stages; ``cancel()`` returning True raises Cancelled.  ``wind`` (aero.wind.Wind): the
    aeroelastic analysis in that steady wind (blade-element loads: see
    assembly/rotor_aero.py; air density ``rho`` [kg/m^3]; ``inflow`` "frozen" (wake) or
    "oye" (dynamic inflow states), ``airfoil`` "quasi-steady" or "jones" (unsteady-airfoil
    states)) at the given rotor speed and the turbine's pitch; None: in a vacuum."""
    method = method or "auto"
    validate_request(elements, rotor_speed, steps, method, max_per_rev)
    with blas_threads():
        return _modal_analysis(turbine, elements, rotor_speed, steps, method, fast, harmonics,
                               max_per_rev, progress, cancel, wind, rho, inflow, airfoil)


def modal_at_operating_point(turbine: Turbine, wind_speed: float, discon,
                             wind_direction: float = 0.0, rotor_speed: Optional[float] = None,
                             **kwargs) -> ModalResult:
    """The aeroelastic modal analysis of ``turbine`` where it operates in a steady wind of
    ``wind_speed`` [m/s] and ``wind_direction`` [rad]: rotor speed and pitch of the
    schedule's operating point there (the DISCON.IN ``discon``'s schedule, as ``hawt
    operating-points`` and the closed loop use it; ``rotor_speed`` given [rad/s]: that speed
    with the schedule's pitch); ``kwargs``: those of :func:`modal_analysis`.  What the ROS
    node's modal_analysis service answers while the node runs in wind."""
    from ..io.discon import discon_schedule
    from .operating_points import at_operating_point
    at, point = at_operating_point(turbine, wind_speed, discon_schedule(discon), rotor_speed)
    result = modal_analysis(at, wind=Wind(float(wind_speed), direction=float(wind_direction)),
                            **kwargs)
    result.settings["operating_point"] = point
    return result


def _modal_analysis(turbine, elements, rotor_speed, steps, method, fast, harmonics,
                    max_per_rev, progress, cancel, wind=None, rho=1.225, inflow="frozen",
                    airfoil="quasi-steady") -> ModalResult:
    t0 = time.perf_counter()
    timings = {}

    def stage(frac, msg):
        if cancel is not None and cancel():
            raise Cancelled(f"modal analysis cancelled during: {msg}")
        if progress is not None:
            progress(frac, msg)

    stage(0.0, "building the model")
    if wind is not None and (rotor_speed if rotor_speed is not None
                             else turbine.rotor.speed) == 0.0:
        raise ValueError("rotor_speed: 0 is not allowed in wind (the frozen wake is that of "
                         "a turning rotor); need a rotor speed > 0 [rad/s]")
    if wind is not None:
        stage(0.0, f"building the model (blade-element momentum at {wind.speed:g} m/s)")
    model = TurbineModel(turbine, elements=elements, rotor_speed=rotor_speed, wind=wind,
                         rho=rho, inflow=inflow, airfoil=airfoil)
    standstill = model.rotor_speed == 0.0
    stage(0.05, "steady state")
    if standstill:
        if method in ("radau", "paper"):
            raise ValueError(f"method: {method!r} is not allowed for a standing rotor (rotor "
                             "speed 0, no period to march over); use auto or hill")
        steady, dae = _standstill_dae(model)
    else:
        steady = periodic_steady_state(model, harmonics=harmonics)
    timings["steady_state"] = time.perf_counter() - t0
    stage(0.2, "linearization")
    # in wind the blade modes are named after the vacuum blade's (analyses/blade_reference.py)
    reference = vacuum_blade_reference(model) if wind is not None else None
    if not standstill:
        dae = periodic_dae(model, steady)
    # a standing rotor is time-invariant as it is: its rotating frame is the fixed frame
    transform = MultiBladeTransform(model) if model.n_blades >= 3 and not standstill else None
    mbc = transform.dae(dae) if transform is not None and dae.S is not None else None
    if method == "auto":
        method = "hill" if mbc is not None or standstill else "radau"
    use_fast = dae.S is not None if fast is None else (bool(fast) and dae.S is not None)
    rows, wts = model.display_rows()
    # the dominant harmonic is judged on displacement-like rows weighted to tip metres
    d = model.dynamic_dimension()
    t1 = time.perf_counter()
    omega = model.rotor_speed
    extra = {}
    if method in ("radau", "paper"):
        steps = int(steps) if steps is not None else DEFAULT_STEPS[method]
        stage(0.3, f"monodromy ({method}, {steps} steps)")
        fl, modes, unresolved, limit = _monodromy_modes(model, dae, method, steps, use_fast,
                                                        rows, wts, d, reference)
    else:
        limit = (float(max_per_rev) if max_per_rev is not None
                 else STANDSTILL_MAX_HZ if standstill else DEFAULT_MAX_PER_REV)
        frame = "multi-blade" if mbc is not None else ("fixed" if standstill else "rotating")
        stage(0.3, f"Hill's method ({frame} frame, modes below {limit:g} per-rev)")
        fl, hm, participation = _hill_floquet(model, mbc if mbc is not None else dae,
                                              transform if mbc is not None else None, limit,
                                              rows, wts, d)
        use_fast, steps = False, None
        separate_degenerate_modes(model, fl, fl.modes())
        modes = label_modes(model, fl, fl.modes(), reference, participation)
        unresolved = max(0, d - int(fl.exponents.size))     # above the band
        extra = {"frame": frame, "hill_harmonics": hm.harmonics,
                 "hill_size": hm.size, "coefficient_harmonics": hm.coefficient_harmonics}
        if hm.change is not None:
            # the exponents' relative move from H - 1 to H harmonics: a bound on the
            # truncation error
            extra["hill_relative_change"] = hm.change
    timings["floquet"] = time.perf_counter() - t1
    stage(0.85, "labelling modes")
    if transform is not None:
        add_fixed_frame(model, transform, fl, modes, rows, wts)
        modes.sort(key=lambda m: (m.fixed_frame_per_rev, m.real_per_rev))
    else:
        modes.sort(key=lambda m: (m.frequency_per_rev, m.real_per_rev))
    mark_overdamped(modes)
    renamed = []
    if reference is not None:
        renamed = name_in_wind(model, fl, modes, reference)
    for m in renamed:
        # a new family: its own motion's dominant harmonic and whirl
        _family_exponent_fields(model, fl, m)
        if transform is not None:
            add_fixed_frame(model, transform, fl, [m], rows, wts)
    number_modes(modes)
    settings = {"turbine": turbine.name, "elements": model.beam.elements,
                "order": model.beam.order, "rotor_speed": omega,
                "structural_damping": turbine.structural_damping_text(),
                "in_vacuum": wind is None and turbine.aerodynamics is not None,
                "method": "standstill" if standstill else method, "steps": steps,
                "fast": bool(use_fast),
                "blades": model.n_blades, "resolution_per_rev": limit,
                "steady_state": "constant" if steady.constant
                else f"periodic ({harmonics} harmonics)", **extra}
    if model.generator_trim is not None:
        # a free generator held by the torque the steady state trimmed (solvers/trim.py)
        settings["generator_torque"] = model.generator_trim.torque
    if wind is not None:
        a, ap = model.aero.inductions
        settings.update({"wind_speed": float(wind.speed),
                         "wind_direction_deg": float(np.degrees(wind.direction)),
                         "air_density": float(rho),
                         "pitch_deg": float(np.degrees(-turbine.rotor.pitch)),
                         "aerodynamics": model.aero_description,
                         "inflow": model.aero.inflow, "airfoil": model.aero.airfoil,
                         "mean_axial_induction": float(np.mean(a))})
    total = time.perf_counter() - t0
    timings["total"] = total
    stage(1.0, "done")
    return ModalResult(modes=modes, settings=settings, floquet=fl, model=model, steady=steady,
                       unresolved=unresolved, compute_time=total, timings=timings)
