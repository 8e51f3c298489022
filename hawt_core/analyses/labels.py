"""Automatic labels of Floquet modes: the family (yaw, teeter, tower, or the strain-energy
dominant flap/lag/torsion/axial/shear), the exponent resolved by the dominant harmonic of
the motion that names the mode, the blade symmetry (symmetric/antisymmetric, collective,
cyclic, differential) and, with three or more blades, the fixed-frame frequency and whirl;
degenerate clusters split along the blade symmetry classes; the index within a group.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
import scipy.linalg as sl

from ..assembly import TurbineModel
from ..assembly.turbine import DRIVETRAIN_COORDINATES
from ..fem.energy import FAMILIES, classify_energy
from ..results.modes import Mode
from .blade_reference import blade_motion
from ..solvers.floquet import dominant_harmonic
from ..solvers.multiblade import fixed_frame_modes

__all__ = ['label_modes', 'separate_degenerate_modes', 'add_fixed_frame', 'family_exponent',
           'exponent_fields', 'number_modes', 'mark_overdamped', 'aerodynamic_lags',
           'OVERDAMPED_ZETA', 'FAMILY_ROWS', 'TOWER_DIRECTIONS', 'STRAIN_KEYS']


#: ``symmetry`` of a tower mode: the dominant tower-top motion
TOWER_DIRECTIONS = ("axial", "side-side", "fore-aft", "torsion")


def _tower_motion(model: TurbineModel, x, strain):
    """Elastic tower motion of eigenvector x as metres: (largest, direction); ``strain``:
    the tower's strain energy by kind (classify_energy of its unknowns).

    The largest of the nodal displacement components (t1 axial, t2 side-side, t3 fore-aft)
    [m] and the torsion (rotation about t1) times the rotor radius (the rotor-tip metres it
    causes); the direction is the one holding most of the tower's strain energy (axial;
    side-side: bending about t3 and shear along t2; fore-aft: bending about t2 and shear
    along t3; torsion), as the blades' families are: a 2nd bending mode twists the tower top
    little but, times the rotor radius, enough to outweigh its displacement (NREL 5-MW:
    2.84 Hz, 97 % fore-aft bending energy, 2 % torsion, was named "torsion")."""
    tl = model.layout.tower()
    R = model.turbine.hub.radius + model.turbine.blade.length
    u = np.abs(x[tl.u[1:]]).max(axis=0)
    parts = np.array([u[0], u[1], u[2], R * np.abs(x[tl.theta[1:, 0]]).max()])
    e = strain                                          # axial, s2, s3, tor, b2, b3
    energy = np.array([e[0], e[1] + e[5], e[2] + e[4], e[3]])
    j = int(np.argmax(energy)) if energy.sum() > 0 else int(np.argmax(parts))
    return float(parts.max()), TOWER_DIRECTIONS[j]


#: Mode.participation's keys of the blades' strain energy by kind (classify_energy's order)
STRAIN_KEYS = ("axial", "shear2", "shear3", "torsion", "flap", "lag")


def label_modes(model: TurbineModel, fl, columns, reference=None, participation=None) -> list:
    """Modes (unsorted indices) labelled from their Floquet eigenvectors x(0); with a
    ``reference`` (blade_reference.BladeReference: the vacuum blade modes, in wind) a blade
    mode takes the family and index of the vacuum mode its blades move most like; with
    ``participation`` (n, columns of fl: the states' participation in each mode, Hill's
    modal basis) a mode is the blades' aerodynamic states' when they hold most of it
    (_aerodynamic_state)."""
    lay = model.layout
    R = model.turbine.hub.radius + model.turbine.blade.length
    sec = model.turbine.blade.sections
    r_g = float(np.sqrt(np.mean(sec.i1) / np.mean(sec.mass)))  # torsion radius of gyration
    nb = model.n_blades
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    # the blades' aerodynamic states' rows, once for every mode
    aero_rows = _aerodynamic_rows(model) if getattr(model, "n_aero", 0) else None
    modes = []
    for i in columns:
        x = fl.eigenvectors[:, i]
        # rigid rotations: RMS over the revolution of the periodic eigenvector (a teeter
        # oscillating at 1/rev may pass through zero at t = 0), as blade-tip metres
        rigid = {nm: R * float(np.sqrt(np.mean(np.abs(fl.periodic_sample(i)[:, pos[lay[nm]]]) ** 2)))
                 if lay[nm] in pos else R * abs(x[lay[nm]])
                 for nm in ("yaw", "teeter") + DRIVETRAIN_COORDINATES if nm in lay}
        # the drivetrain's two angles name one family (tip metres of the rotor's rotation)
        drive = [rigid.pop(nm) for nm in DRIVETRAIN_COORDINATES if nm in rigid]
        if drive:
            rigid["drivetrain"] = max(drive)
        elastic = 0.0
        energy = np.zeros(6)
        for k in range(nb):
            b = lay.blade(k)
            u = x[b.u[1:]]
            th = x[b.theta[1:]]
            elastic = max(elastic, np.abs(u).max(), r_g * np.abs(th[:, 0]).max())
            off = lay.blade_offset(k)
            energy += classify_energy(model.beam, x[off:off + model.beam.n])
        # strain energy in the tower against that in the blades: a tower mode of a large
        # rotor drags long, soft blades along (their tips flap more than the tower top moves)
        # while the tower holds most of the strain energy
        tower, tower_dir, tower_energy = 0.0, None, 0.0
        if lay.has_tower:
            t0 = lay.tower_offset
            strain = classify_energy(model.tower, x[t0:t0 + model.tower.n])
            tower, tower_dir = _tower_motion(model, x, strain)
            tower_energy = float(strain.sum())
        tower_owns = tower > 0 and (tower >= elastic or tower_energy > float(energy.sum()))
        # the shaft spring's strain energy (same scale as classify_energy: no 1/2)
        shaft_energy = (model.rigid.k_shaft * abs(x[lay["shaft_twist"]]) ** 2
                        if "shaft_twist" in lay else 0.0)
        rig_name = None
        if shaft_energy > max(float(energy.sum()), tower_energy):
            rig_name = "drivetrain"
        elif tower_owns and tower >= max([0.0] + [0.25 * r for r in rigid.values()]):
            # the tower's elastic motion dominates: a tower mode (symmetry = direction). A
            # tower torsion under a free yaw bearing turns the yaw angle (relative to the
            # tower top) as much as the tower twists, and tower bending swings a free yaw and
            # the teeter (gyroscopic coupling), all counted in blade-tip metres: hence the
            # factor 0.25 on the rigid rotations (a heuristic, like the 3.0 below)
            rig_name = "tower"
        elif rigid and max(rigid.values()) >= 3.0 * elastic:
            # the free yaw angle alone is the rigid-body yaw mode; any rigid mode in which the
            # hub teeters appreciably is a teeter mode (the paper's labels)
            if rigid.get("drivetrain", 0.0) >= max(rigid.get("yaw", 0.0), rigid.get("teeter", 0.0)):
                rig_name = "drivetrain"
            else:
                rig_name = ("teeter" if rigid.get("teeter", 0.0) >= 0.25 * rigid.get("yaw", 0.0)
                            else "yaw")
        aero_shares = _aerodynamic_shares(aero_rows, None if participation is None
                                          else participation[:, i])
        aero_kind = _aerodynamic_state(model, fl, i, x, aero_shares, aero_rows)
        if aero_kind is not None:        # the blades' inflow or lag states, not a structure's
            rig_name = "aerodynamic"
            family, symmetry, phase = "aerodynamic", aero_kind, None
        elif rig_name == "tower":
            family, symmetry, phase = "tower", tower_dir, None
        elif rig_name is not None:
            family, symmetry, phase = rig_name, None, None
        else:
            family = FAMILIES[int(np.argmax(energy))]
        shares = None
        if rig_name is None and reference is not None:
            shares = reference.shares(blade_motion(model, reference, x))
            if shares.max() > 0:
                family = reference.families[int(np.argmax(shares))]
            else:
                shares = None
        eta = family_exponent(model, fl, i, family)
        if rig_name is None:
            symmetry, phase = _blade_symmetry(model, fl, i, eta)
        modes.append(Mode(family=family, symmetry=symmetry, index=0,
                          **exponent_fields(eta, fl.omega),
                          blade_phase_deg=phase,
                          participation={**{k: float(v) for k, v in rigid.items()},
                                         **({"tower": tower} if lay.has_tower else {}),
                                         "elastic": float(elastic),
                                         **{f: float(e) for f, e in zip(STRAIN_KEYS,
                                                                        energy)}},
                          aerodynamic_share=None if aero_shares is None
                          else sum(aero_shares.values()),
                          column=int(i)))
        if shares is not None:
            _name_after(modes[-1], reference, int(np.argmax(shares)), shares)
    return modes


def _name_after(m: Mode, reference, j: int, shares) -> None:
    """Name the mode ``m`` after the vacuum blade mode ``j`` of ``reference``."""
    m.family = m.vacuum_family = reference.families[j]
    m.vacuum_index = reference.indices[j]
    m.vacuum_share = float(shares[j])
    m.vacuum_shares = shares


#: A mode is one of the blades' inflow states when its largest induction state exceeds this
#: many times its largest structural motion as a fraction of the rotor radius.
AERODYNAMIC_SHARE = 10.0
#: ... or exceeds it once in a mode that does not oscillate: frequency within this fraction of
#: the frame's base frequency from a multiple of it.
NON_OSCILLATORY = 1e-3


def _aerodynamic_rows(model: TurbineModel):
    """The rows of the blades' (induction, lag) states: Oye's inflow and Jones's lags."""
    lay = model.layout
    names = model.aero.state_names

    def rows(group):
        r = [lay.aero_states_of(k, n).ravel() for k in range(model.n_blades) for n in group]
        return np.concatenate(r) if r else np.zeros(0, int)
    return (rows([n for n in names if not n.startswith("alpha")]),
            rows([n for n in names if n.startswith("alpha")]))


def _aerodynamic_sizes(model: TurbineModel, X, aero_rows=None):
    """(inflow, airfoil, structure) of the eigenvectors X (n, m) or x (n,): the largest
    induction state (dimensionless), the largest lag state (rad) and the largest structural
    motion as a fraction of the rotor radius (display rows: elastic and rigid tip metres
    over R), per column; ``aero_rows``: _aerodynamic_rows(model), if at hand."""
    X = np.asarray(X)

    def largest(rows):
        return np.abs(X[rows]).max(axis=0) if rows.size else np.zeros(X.shape[1:])

    inflow, airfoil = _aerodynamic_rows(model) if aero_rows is None else aero_rows
    rows, wts = model.display_rows()
    R = model.turbine.hub.radius + model.turbine.blade.length
    W = wts if X.ndim == 1 else wts[:, None]
    return largest(inflow), largest(airfoil), np.abs(X[rows] * W).max(axis=0) / R


#: A mode whose participation (Hill's modal basis: analyses/modal.py) lies more than this
#: share in the blades' aerodynamic states is theirs (the eigenvalue is mostly theirs).
AERODYNAMIC_PARTICIPATION = 0.5


def _aerodynamic_shares(aero_rows, participation) -> Optional[dict]:
    """{"inflow", "airfoil"}: the blades' induction and lag states' (``aero_rows``:
    _aerodynamic_rows) shares of a mode's ``participation`` (n,); None without one (or
    without aerodynamic states: ``aero_rows`` None)."""
    if participation is None or aero_rows is None \
            or not np.all(np.isfinite(participation)):
        return None
    return {kind: float(participation[rows].sum())
            for kind, rows in zip(("inflow", "airfoil"), aero_rows)}


def _aerodynamic_state(model: TurbineModel, fl, i: int, x, shares=None,
                       aero_rows=None) -> Optional[str]:
    """"inflow" or "airfoil" for a mode of the blades' aerodynamic states (assembly/
    rotor_aero.py: Oye's inflow, Jones's lag), else None.  With their ``shares`` of the
    mode's participation (_aerodynamic_shares): they hold more than
    AERODYNAMIC_PARTICIPATION of it (scale-free: a heavily damped root where a lag and the
    flap it drags mix is named after the one its eigenvalue belongs to most).  Without: the
    largest induction state of its vector (dimensionless) exceeds AERODYNAMIC_SHARE times
    its largest structural motion as a fraction of the rotor radius (elastic and rigid tip
    metres over R), or the largest aerodynamic state (inductions, lag angles in rad)
    exceeds that motion in a non-oscillatory mode (an inflow mode with the flap it drags).
    Named by the state group that moves (or participates) most; ``aero_rows``:
    _aerodynamic_rows(model), if at hand."""
    if not getattr(model, "n_aero", 0):
        return None
    if shares is not None:
        kind = max(shares, key=shares.get)
        return kind if sum(shares.values()) > AERODYNAMIC_PARTICIPATION else None
    inflow, airfoil, structure = (float(v) for v in _aerodynamic_sizes(model, x, aero_rows))
    size = {"inflow": inflow, "airfoil": airfoil}
    kind = max(size, key=size.get)
    # the inflow states alone: the lag states of a structural mode follow its section
    # velocities (alpha ~ hdot / (Omega r)), large in a fast mode whatever its structure
    if size["inflow"] > AERODYNAMIC_SHARE * structure:
        return "inflow"
    # a non-oscillatory mode (frequency a multiple of the frame's within NON_OSCILLATORY of
    # it) led by its aerodynamic states: an inflow mode dragging the flap along
    eta, w = complex(fl.exponents[i]), float(fl.omega)
    off = abs(eta.imag - w * round(eta.imag / w)) if w > 0 else abs(eta.imag)
    steady = off <= NON_OSCILLATORY * max(w, 1e-12)
    return kind if steady and size[kind] > structure else None


#: An averaged mode in multi-blade coordinates is a lag of the blades' aerodynamic states
#: (kept out of Hill's modal basis) when it does not oscillate in the blade frame (its
#: frequency within LAG_OSCILLATION x its decay rate of a multiple of the rotor speed: a
#: cyclic order's, or a Hill copy's) and its largest aerodynamic state exceeds
#: AERODYNAMIC_SHARE times its structural motion.  Measured on the IEA 15-MW at 11 m/s with
#: Oye's inflow and Jones's lags (3 elements of order 6): the structural modes' ratio at
#: most 7.4 (the overdamped cyclic flap 6.5-8.4), the aerodynamic states' own modes 8.2 ..
#: 1e10.  At 3 m/s Oye's slow lags of neighbouring elements (decay 0.009-0.044 1/s, ratio
#: 400-600) couple into nearly degenerate clusters that beat at 0.13-0.28 of their decay
#: rate; the structural modes there reach a ratio of 7.2.
LAG_OSCILLATION = 0.5


def aerodynamic_lags(model: TurbineModel):
    """A test ``(lam (m,), X (n, m)) -> bool (m,)`` of a system's modes in multi-blade
    coordinates (rotor speed model.rotor_speed): True for the blades' inflow and lag states'
    own modes (see LAG_OSCILLATION); None for a model without aerodynamic states.  Hill's
    modal basis leaves them out and takes their response whole (solvers/hill_reduced.py)."""
    if not getattr(model, "n_aero", 0):
        return None
    Omega = float(model.rotor_speed)

    def lags(lam, X):
        inflow, airfoil, structure = _aerodynamic_sizes(model, X)
        lam = np.asarray(lam)
        # the cyclic orders (0 .. Nb/2) and the Hill copies (multiples of Nb) together reach
        # every multiple of the rotor speed
        off = np.abs(lam.imag - Omega * np.round(lam.imag / Omega))
        steady = off <= LAG_OSCILLATION * np.abs(lam.real)
        return steady & (np.maximum(inflow, airfoil) > AERODYNAMIC_SHARE * structure)
    return lags


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


def exponent_fields(eta: complex, w0: float) -> dict:
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
    if family == "drivetrain":
        names = [nm for nm in DRIVETRAIN_COORDINATES if nm in lay]
        return [lay[nm] for nm in names], [1.0] * len(names)
    if family == "tower":
        tl = lay.tower()
        return (list(tl.u[-1]) + list(tl.theta[-1]), [1.0] * 3 + [R] * 3)
    if family == "aerodynamic":         # the blades' inflow and lag states
        rows = [int(r) for k in (range(model.n_blades) if blade is None else [blade])
                for nm in lay.aero_states for r in lay.aero_states_of(k, nm).ravel()]
        return rows, [1.0] * len(rows)
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


def family_exponent(model: TurbineModel, fl, i: int, family: str) -> complex:
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
    best = dominant_harmonic(energy, k, eta.imag, fl.omega, tie=1e-9)
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


#: A structural mode whose (rotating-frame) damping ratio is at least this is overdamped: its
#: exponent is real to 0.1 % (aerodynamic flap damping beyond critical: IEA 15-MW above
#: 10 m/s).
OVERDAMPED_ZETA = 0.999

#: Families whose modes can be overdamped (an inflow or lag state's real exponent is not).
_STRUCTURAL = ("flap", "lag", "torsion", "axial", "shear", "tower", "drivetrain")


def _root_pairs(roots: list) -> list:
    """Real roots of one family and symmetry, sorted by decay rate, in consecutive pairs
    (roots 1 and 2, 3 and 4, ...; a last one alone)."""
    roots = sorted(roots, key=lambda m: -m.real_per_rev)
    return [roots[j:j + 2] for j in range(0, len(roots), 2)]


def mark_overdamped(modes) -> None:
    """Mark the overdamped modes (OVERDAMPED_ZETA) and pair their real roots: within a
    family and symmetry, sorted by decay rate, roots 1 and 2 are one mode's "slow" and
    "fast" roots, 3 and 4 the next mode's, ...; an odd one out is a "root" (its partner
    decays beyond the band).  A cyclic mode's real root has no whirl (the fixed frame sees
    its tilt turn with the rotor at 1P: MBC3's "forward" at 1P): its symmetry becomes
    "cyclic" ("cyclic-k" for the k-th pair)."""
    groups: dict = {}
    for m in modes:
        m.overdamped = None
        if m.family in _STRUCTURAL and abs(m.real_per_rev) > 0 and \
                -m.real_per_rev >= OVERDAMPED_ZETA * np.hypot(m.real_per_rev,
                                                              m.frequency_per_rev):
            if m.whirl in ("forward", "backward"):
                m.symmetry = "cyclic" if (m.cyclic_order or 1) == 1 else f"cyclic-{m.cyclic_order}"
            groups.setdefault((m.family, m.symmetry), []).append(m)
    for group in groups.values():
        for pair in _root_pairs(group):
            for m, root in zip(pair, ("slow", "fast") if len(pair) == 2 else ("root",)):
                m.overdamped = root


def _natural(m) -> float:
    """A mode's natural frequency [per-rev] (rotating frame): |eta|."""
    return float(np.hypot(m.real_per_rev, m.frequency_per_rev))


def number_modes(modes):
    """The index of every mode within its family and symmetry, in the order of the natural
    frequencies |eta| (a heavily damped mode keeps its place although its damped frequency
    falls below the next one's); an overdamped pair (mark_overdamped) is one mode at the
    geometric mean of its roots, and a cyclic pair counts in both whirls of its order (its
    backward and forward members merged into real roots; a root without its partner only
    in its own group)."""
    units: list = []                        # (natural, family, symmetry, members)
    pairs: dict = {}
    for m in modes:
        if m.overdamped in ("slow", "fast"):
            pairs.setdefault((m.family, m.symmetry), []).append(m)
        else:
            units.append((_natural(m), m.family, m.symmetry, [m]))
    for (fam, sym), ms in pairs.items():
        for a, b in _root_pairs(ms):
            units.append((float(np.sqrt(_natural(a) * _natural(b))), fam, sym, [a, b]))
    counts: dict = {}
    # equal natural frequencies (a pair of exponents mirrored about the imaginary axis, the
    # unstable teeter's; a free yaw angle's double zero, 1e-9 per-rev apart) keep the list's
    # order: compared to 1e-8 per-rev
    for _, fam, sym, members in sorted(units, key=lambda u: round(u[0], 8)):
        keys = [(fam, sym)]
        if sym and sym.startswith("cyclic") and len(members) == 2:
            k = sym[len("cyclic"):]
            keys += [(fam, f"backward-whirl{k}"), (fam, f"forward-whirl{k}")]
        if all(m.vacuum_index is not None for m in members):
            for m in members:           # named after its vacuum blade mode
                m.index = m.vacuum_index
            continue
        index = max(counts.get(key, 0) for key in keys) + 1
        for key in keys:
            counts[key] = index
        for m in members:
            m.index = index
    return modes


_WHIRL_SYMMETRY = {"collective": "collective", "forward": "forward-whirl",
                   "backward": "backward-whirl", "differential": "differential"}


def add_fixed_frame(model, transform, fl, modes, rows, wts):
    """Fixed-frame fields of every mode (three or more blades); the blade modes' symmetry
    becomes their whirl: collective, backward-whirl, forward-whirl (-k for the k-th cyclic
    pair, k >= 2), differential.  The frequency and the whirl of a blade mode come from the
    motion that names it (as its rotating-frame frequency does: hawt_core.modal
    FAMILY_ROWS), the whirl of a yaw, teeter or tower mode from all blade motion."""
    blade_rows = [(r, w) for r, w in zip(rows, wts) if r >= model.layout.blade_offset(0)
                  and r < model.layout.blade_offset(0) + model.n_blades * model.blade_size]
    br, bw = [r for r, _ in blade_rows], [w for _, w in blade_rows]
    specs = {}
    for m in modes:
        if m.family == "aerodynamic":       # its states are not sampled: the blades' motion
            specs[m.column] = (br, bw, br, bw)
            continue
        fr, fw = _family_rows(model, m.family)
        specs[m.column] = (fr, fw, fr, fw) if m.family in FAMILY_ROWS else (fr, fw, br, bw)
    ff = fixed_frame_modes(transform, fl, specs)
    for m in modes:
        f = ff[m.column]
        x = exponent_fields(f.exponent, fl.omega)
        m.fixed_frame_per_rev = x["frequency_per_rev"]
        m.fixed_frame_hz = x["frequency_hz"]
        m.fixed_frame_damping_ratio = x["damping_ratio"]
        m.whirl = f.whirl
        m.cyclic_order = f.order
        m.whirl_shares = dict(f.shares)
        # rigid-body, tower and drivetrain modes keep their own symmetry (a drivetrain mode
        # turns the rotor as a whole: its blades' residual whirl does not name it)
        if m.family not in ("yaw", "teeter", "tower", "aerodynamic", "drivetrain"):
            sym = _WHIRL_SYMMETRY[f.whirl]
            if f.whirl in ("forward", "backward") and f.order > 1:
                sym = f"{sym}-{f.order}"
            m.symmetry = sym
