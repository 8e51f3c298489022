"""Names of the blade modes in wind: each after the vacuum blade mode its blades move most
like (blade_reference.py; label_modes gives every mode its best match), made one name per
vacuum mode and whirl where the shapes allow, the tower's modes that drag the blades along
given back to the tower, and the second modes of a name ('#2') moved to a free name that
fits them.  The order (name_in_wind): name_after_vacuum, hand_over_blade_names,
name_tower_hybrids, promote_second_modes.
"""

from __future__ import annotations

import numpy as np

from ..assembly import TurbineModel
from ..fem.energy import classify_energy
from ..results.modes import Mode
from .labels import (STRAIN_KEYS, _blade_symmetry, _name_after, _natural, _nonnegative,
                     _tower_motion, exponent_fields)

__all__ = ["name_in_wind", "name_after_vacuum", "hand_over_blade_names", "name_tower_hybrids",
           "promote_second_modes", "tower_shares", "VACUUM_NEXT", "NEAR_CRITICAL", "TOWER_HYBRID",
           "WHIRL_TAKEN"]


def name_in_wind(model: TurbineModel, fl, modes, reference) -> list:
    """Apply the rules of this module to ``modes`` (labelled, fixed-frame fields set,
    overdamped roots marked); returns the modes whose family changed (their exponent and
    fixed-frame fields are the caller's to update)."""
    renamed = name_after_vacuum(modes, reference)
    towers = tower_shares(model, fl, modes)          # once: the renaming leaves them as they are
    for m in (hand_over_blade_names(model, fl, modes, reference, towers)
              + name_tower_hybrids(model, fl, modes, towers)):
        if all(m is not r for r in renamed):
            renamed.append(m)
    promote_second_modes(modes, reference)
    return renamed


#: A blade mode in wind whose most alike vacuum mode names another mode of the same symmetry
#: already (one more like it) takes its next match if that holds at least this fraction of
#: its best share (a cyclic 1st torsion mode of a large blade moves as much like the 3rd flap
#: near it, whose own cyclic modes are named after it); else both keep the name (a second
#: mode of one name: an aerodynamic state's mode that drags the blades along).
VACUUM_NEXT = 0.5


#: A blade mode in wind damped at least this much (damping ratio, rotating frame: a root
#: near the real axis, the IEA 15-MW's forward-whirl flap root at 0.1 Hz, 0.98-0.998, above
#: 12 m/s) is the last of the modes of its name, after the oscillating ones (0.45-0.76).
NEAR_CRITICAL = 0.95


def name_after_vacuum(modes, reference) -> list:
    """One name per vacuum mode and symmetry where the shapes allow: within each symmetry
    (collective, each whirl, symmetric, ...), the oscillatory blade modes in the order of
    their best share take their most alike vacuum mode still free (VACUUM_NEXT); overdamped
    roots keep theirs (a pair's two roots share one name).  Of the modes left with one name,
    the first is the one of the lowest natural frequency (number_modes' order; those
    NEAR_CRITICAL last), the others '#2', '#3', ...  Returns the modes whose family changed
    (their exponent and fixed-frame fields are the caller's to update)."""
    groups: dict = {}
    for m in modes:
        if m.vacuum_shares is not None and not m.overdamped:
            groups.setdefault(m.symmetry, []).append(m)
    changed = []
    for group in groups.values():
        named: dict = {}                 # vacuum mode -> modes named after it so far
        for m in sorted(group, key=lambda m: -float(m.vacuum_shares.max())):
            s = m.vacuum_shares
            order = np.argsort(-s)
            j = next((int(k) for k in order if k not in named
                      and s[k] >= VACUUM_NEXT * s[order[0]]), int(order[0]))
            named.setdefault(j, []).append(m)
            before = m.family
            _name_after(m, reference, j, s)
            if m.family != before:
                changed.append(m)
        for ms in named.values():
            ms.sort(key=_dealt)
            for k, m in enumerate(ms):
                m.duplicate = k + 1 if k else None
    return changed


#: A mode named after a vacuum blade mode whose tower holds at least this many times the
#: blades' strain energy is the tower's when it is a second mode of its name ('#2',
#: name_tower_hybrids) or when a blade mode the name fits takes it (hand_over_blade_names):
#: a tower bending mode whose long blades follow in a shape of their own (IEA 15-MW
#: 1.78-1.84 Hz, 0.75-0.87; the NREL 5-MW near 3 Hz above 13 m/s, 0.76-0.80).  A mode
#: first of its name with no blade mode to take it keeps it: the IEA 15-MW's 2nd collective
#: lag at 2.6 Hz (0.58-0.63, that tower mode's partner of the coupling), the NREL 5-MW's
#: collective lag at 25 m/s (1.03, beside the 2nd fore-aft tower); most blade modes stay
#: below 0.3.
TOWER_HYBRID = 0.5


def name_tower_hybrids(model: TurbineModel, fl, modes, towers=None) -> list:
    """The modes named '#2' (or later) after a vacuum blade mode (name_after_vacuum) whose
    tower holds at least TOWER_HYBRID times their blades' strain energy become tower modes
    (the direction of most of the tower's strain energy); returns them (their exponent and
    fixed-frame fields are the caller's to update).  ``towers``: tower_shares', if at
    hand."""
    if not model.layout.has_tower:
        return []
    towers = tower_shares(model, fl, modes) if towers is None else towers
    changed = []
    for m in modes:
        if m.duplicate and m.vacuum_family is not None \
                and towers[m.column][0] >= TOWER_HYBRID:
            _make_tower(m, towers[m.column][1])
            changed.append(m)
    return changed


def tower_shares(model: TurbineModel, fl, modes) -> dict:
    """{column: (tower strain energy / the blades', the tower's direction)} of the modes
    named after a vacuum blade mode (label_modes' blade energies, Mode.participation);
    empty without a tower."""
    if not model.layout.has_tower:
        return {}
    t0 = model.layout.tower_offset
    out = {}
    for m in modes:
        if m.vacuum_family is None:
            continue
        x = fl.eigenvectors[:, m.column]
        strain = classify_energy(model.tower, x[t0:t0 + model.tower.n])
        blades = sum(m.participation[k] for k in STRAIN_KEYS)
        out[m.column] = (float(strain.sum()) / max(blades, 1e-300),
                         _tower_motion(model, x, strain)[1])
    return out


def _make_tower(m: Mode, direction: str) -> None:
    """Name the mode ``m`` a tower mode of ``direction``, no longer a blade mode."""
    m.family, m.symmetry = "tower", direction
    m.blade_phase_deg = m.duplicate = None
    m.vacuum_family = m.vacuum_index = m.vacuum_share = m.vacuum_shares = None


#: A mode of a whirl that two modes of one vacuum blade mode share may take another whirl of
#: it (hand_over_blade_names) when its blades hold at least this share of that whirl (the
#: fixed frame's per-blade energies, Mode.whirl_shares).
WHIRL_TAKEN = 0.25

#: Rotating-frame frequency minus fixed-frame frequency [per-rev] of a blade mode of each
#: whirl class (first cyclic order).
_WHIRL_SHIFT = {"collective": 0, "differential": 0, "backward": 1, "forward": -1}


def hand_over_blade_names(model: TurbineModel, fl, modes, reference, towers=None) -> list:
    """A mode named after a vacuum blade mode (name_after_vacuum, not a '#2') whose tower
    holds at least TOWER_HYBRID times its blades' strain energy hands the name to a blade
    mode (tower below TOWER_HYBRID) the name fits, and becomes the tower's (its tower's
    direction); returns the modes that became the tower's (their exponent and fixed-frame
    fields are the caller's to update).  The name fits

    - a second mode ('#2') of the same whirl named after the vacuum mode one index lower in
      the same family, at a lower natural frequency (the highest of them);
    - else a mode of the same vacuum mode in a whirl that another of its modes holds too,
      whose blades hold at least WHIRL_TAKEN of the name's whirl (3 or 4 blades, where each
      whirl class has one mode per blade mode; the one with the largest share; its
      rotating-frame exponent and blade phase follow the new whirl, the whirl it leaves is
      renumbered).

    Why: an edgewise blade mode's collective and backward-whirl members, close in the fixed
    frame, mix through the tower (IEA 15-MW at 6 m/s: 0.63 and 0.66 Hz, both backward whirl,
    55/45 and 71/29 backward/collective), while the 2nd side-side tower bending at 1.8 Hz,
    its blades swinging collectively in the 1st lag's shape (tower/blades 0.83), takes the
    collective name; and a heavily damped 2nd flap mode whose blades bend like the 1st flap
    (1.15 Hz, damping 0.28) is the 1st flap's '#2' while the 2nd fore-aft tower bending
    (1.89 Hz, tower/blades 0.90) takes the 2nd flap's name.  ``towers``: tower_shares', if
    at hand."""
    if not model.layout.has_tower:
        return []
    nb = model.n_blades
    named = [m for m in modes if m.vacuum_family is not None and not m.overdamped]
    towers = tower_shares(model, fl, modes) if towers is None else towers

    def same_name(m, d):
        return (m.vacuum_family, m.vacuum_index, m.symmetry) == \
            (d.vacuum_family, d.vacuum_index, d.symmetry)

    changed = []
    for h in sorted(named, key=lambda m: -towers[m.column][0]):
        if h.duplicate or towers[h.column][0] < TOWER_HYBRID:
            continue
        blades = [d for d in named if d is not h and towers[d.column][0] < TOWER_HYBRID
                  and all(d is not c for c in changed)]
        fits = [(_natural(d), d) for d in blades
                if d.duplicate and d.vacuum_family == h.vacuum_family
                and d.symmetry == h.symmetry and d.vacuum_index == h.vacuum_index - 1
                and _natural(d) < _natural(h)]
        fits = fits or [(d.whirl_shares[h.whirl], d) for d in blades
                if nb in (3, 4) and h.whirl in _WHIRL_SHIFT and d.whirl in _WHIRL_SHIFT
                and d.whirl != h.whirl and d.whirl_shares is not None
                and (d.vacuum_family, d.vacuum_index) == (h.vacuum_family, h.vacuum_index)
                and sum(same_name(m, d) for m in named) > 1
                and d.whirl_shares[h.whirl] >= WHIRL_TAKEN]
        if not fits:
            continue
        d = max(fits, key=lambda f: f[0])[1]
        left = sorted((m for m in named if m is not d and same_name(m, d)), key=_dealt)
        if d.whirl != h.whirl:
            eta = _nonnegative(complex(d.real_per_rev, d.fixed_frame_per_rev) * fl.omega
                               + 1j * _WHIRL_SHIFT[h.whirl] * fl.omega)
            for name, value in exponent_fields(eta, fl.omega).items():
                setattr(d, name, value)
            d.blade_phase_deg = _blade_symmetry(model, fl, d.column, eta)[1]
            d.whirl, d.cyclic_order = h.whirl, h.cyclic_order
        d.symmetry = h.symmetry
        _name_after(d, reference, _positions(reference)[(h.vacuum_family, h.vacuum_index)],
                    d.vacuum_shares)
        d.duplicate = None
        for k, m in enumerate(left):                # the name d leaves, renumbered
            m.duplicate = k + 1 if k else None
        _make_tower(h, towers[h.column][1])
        changed.append(h)
    return changed


def _positions(reference) -> dict:
    """{(family, index): position in ``reference``} of its vacuum blade modes."""
    return {fi: j for j, fi in enumerate(zip(reference.families, reference.indices))}


def _natural_hz(m: Mode) -> float:
    """A mode's natural frequency [Hz] (rotating frame): damped frequency / sqrt(1 - zeta^2)."""
    return m.frequency_hz / np.sqrt(max(1.0 - m.damping_ratio ** 2, 1e-12))


def _dealt(m: Mode):
    """The order of the modes of one name: NEAR_CRITICAL ones last, then natural frequency."""
    return (m.damping_ratio >= NEAR_CRITICAL, _natural(m))


def promote_second_modes(modes, reference) -> None:
    """A second mode of a vacuum blade mode's name ('#2', the rules above done), not
    NEAR_CRITICAL, whose natural frequency (rotating frame) lies nearer the next vacuum mode
    of the family (one index up) than its own name's, takes that next name in its whirl when
    no mode holds it: the IEA 15-MW at 3-4 m/s, a heavily damped 2nd flap mode whose blades
    bend like the 1st flap (1.14 Hz, damping 0.29, 1st flap share 0.81) with no other mode
    named 2nd flap in its whirl.  A forward-whirl mode at 2 Hz like the 1st and 2nd flap is
    no 3rd flap (3.3 Hz).  (Exchanging names with a holder of higher natural frequency was
    tried: at 10 m/s it set two forward-whirl flap modes in their tracks' order, above 12 m/s
    it put the 2nd flap's name on the '#2' track: damping 0.27 against 0.74, natural
    frequencies 1.68 and 2.07 Hz.)"""
    where = _positions(reference)
    groups: dict = {}
    for m in modes:
        if m.vacuum_family is not None and not m.overdamped:
            groups.setdefault((m.symmetry, m.vacuum_family), []).append(m)
    for group in groups.values():
        for m in sorted((m for m in group if m.duplicate == 2), key=lambda m: m.vacuum_index):
            if m.duplicate != 2:                    # dealt again by an earlier promotion
                continue
            k = m.vacuum_index
            j, up = where[(m.vacuum_family, k)], where.get((m.vacuum_family, k + 1))
            f = _natural_hz(m)
            if (up is None or m.damping_ratio >= NEAR_CRITICAL
                    or abs(f - reference.frequencies_hz[up])
                    >= abs(f - reference.frequencies_hz[j])):
                continue
            if any(o.vacuum_index == k + 1 for o in group):
                continue
            left = [o for o in group if o is not m and o.vacuum_index == k]
            _name_after(m, reference, up, m.vacuum_shares)
            m.duplicate = None
            for n, o in enumerate(sorted(left, key=_dealt)):
                o.duplicate = n + 1 if n else None
