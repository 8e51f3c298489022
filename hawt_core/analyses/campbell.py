"""Campbell diagrams: Floquet modal analysis over a range of rotor speeds, modes tracked.

``campbell(turbine, speeds, ...)`` runs :func:`hawt_core.modal.modal_analysis` once per rotor
speed through any :class:`concurrent.futures.Executor` (default: a ``ProcessPoolExecutor`` with
one worker per CPU; a thread pool, a Dask ``Client.get_executor()`` or a Ray executor work the
same, see docs/campbell.md).  The work unit is the top-level, picklable
:func:`campbell_point`, which takes plain data (a dict holding the Turbine dataclass) and
returns plain data (per-mode dicts and the eigenvectors needed for tracking).

Tracking: at every speed the modes are assigned to the tracks of the previous speeds by the
modal assurance criterion (MAC) of their periodic Floquet eigenvectors on the
displacement-like rows (rigid yaw and teeter angles times the rotor radius, blade u, blade
theta times the blade length: tip metres), compared through their Fourier coefficients over
one revolution (harmonics -4..4) and maximised over re-indexings of the harmonics by
multiples of the blade count under Fast Floquet (the exponent's whole-per-rev ambiguity;
a 2-blade rotor: 0 and +-2 per-rev), solved as a linear assignment (Hungarian
method,
``scipy.optimize.linear_sum_assignment``) on ``1 - MAC`` plus a small frequency-change term
that only breaks near-ties.  Each track keeps the label its mode had at the first speed where
it appeared; a mode no track claims starts a new track, and afterwards a short track whose
speeds another track misses, and whose frequency continues that track's smoothly, is merged
into it (near a coincidence of multipliers two modes' vectors mix for a speed or two and the
MAC cannot match them).

Resolution in absolute frequency: every speed reports the modes below one band in Hz
(``max_hz``, default DEFAULT_MAX_PER_REV at the highest speed), so a mode does not appear or
vanish along the sweep because a per-rev resolution moves with the rotor speed; the Radau
IIA marching gets the steps per period that band needs at each speed, Hill's method /
multi-blade coordinates the band itself.

Frames: tracks carry the rotating-frame dominant frequency of every mode and, with three or
more blades, its fixed-frame frequency (hawt_core.modal.Mode); ``frame`` ("fixed", the
default for three or more blades, or "rotating") chooses what the table, the plot and the
``continuous_*`` arrays show.  The two members of a real exponent pair (the teeter pair, the
free yaw angle's double zero) share a frequency: the plot draws it once (both dampings).
"""
from __future__ import annotations

import concurrent.futures as cf
import math
import os
import time
from typing import Callable, Optional, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..assembly.rotor_aero import description as aero_description
from ..model import Turbine
from ..numerics.mac import mac_matrix
from ..numerics.threads import solver_threads
from ..results.campbell import FRAMES, CampbellResult, Track
from ..results.plotting import mode_label
from .modal import (DEFAULT_MAX_PER_REV, DEFAULT_STEPS, MAX_STEPS, STEPS_PER_CYCLE,
                    modal_analysis, validate_request)

__all__ = ["campbell", "campbell_in_wind", "campbell_point", "track_modes", "unwrap_harmonics", "check_speeds", "default_wind_band", "BAND_OVER_SECOND_FLAP"]


def _aero_description(turbine, inflow: str, airfoil: str) -> str:
    """The settings' description of the aerodynamic model a sweep in wind uses."""
    return aero_description(inflow, airfoil, turbine.aerodynamics.skew_factor,
                            turbine.tower is not None
                            and turbine.tower_aerodynamics is not None)


#: Weight of the relative frequency change (after the harmonic re-indexing found by the MAC)
#: in the assignment cost.
FREQUENCY_WEIGHT = 0.2

#: Below this MAC, an assignment is refused (the mode starts a new track).
MIN_MAC = 0.2

#: A vector matched with a MAC below this does not become the track's reference vector.
KEEP_MAC = 0.95

#: ... unless it is unambiguous: no other MAC of its track or of its mode (in the matrix of
#: the speed) reaches this share of it.  A sweep in wind changes the pitch by degrees between
#: points: every shape drifts (NREL 5-MW drivetrain mode, 11 -> 17 m/s: MAC 0.95 between
#: neighbours but 0.2 against 11 m/s), and a reference held at the last point matched above
#: KEEP_MAC would lose the track.
CLEAR_SHARE = 0.8

#: Largest relative frequency change accepted between a track's consecutive points.
MAX_JUMP = 0.3

#: Fragments of at most this many points are merged into a track that misses those speeds.
FRAGMENT_POINTS = 3

#: A fragment continues a track when its frequency, re-indexed by up to FRAGMENT_SHIFT whole
#: per-rev, is within FRAGMENT_TOL (relative) of the track's interpolated (or extrapolated)
#: frequency there (near a coincidence of two multipliers, e.g. a lag mode 4 per-rev below a
#: torsion mode, the mixed vector takes the other family's harmonic)
FRAGMENT_TOL = 0.03

FRAGMENT_SHIFT = 8

# ---------------------------------------------------------------------------- work unit
#: Harmonics -K..K of the periodic eigenvectors kept for tracking.
TRACK_HARMONICS = 4

#: Largest harmonic re-indexing tried when comparing two modes (per-rev).
MAX_HARMONIC_SHIFT = 3


def _harmonic_coefficients(fl, rows, wts, cols):
    """Fourier coefficients (2K+1, len(rows), len(cols)) over one revolution of the periodic
    eigenvectors p(t) on the display rows (tip metres), harmonics -K..K (K =
    TRACK_HARMONICS); None when the Floquet samples do not cover the display rows."""
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    if not cols or any(int(r) not in pos for r in rows):
        return None
    idx = np.array([pos[int(r)] for r in rows])
    K = TRACK_HARMONICS
    out = np.empty((2 * K + 1, len(rows), len(cols)), complex)
    for j, c in enumerate(cols):
        P = fl.periodic_sample(int(c))[:, idx] * wts[None, :]          # (M, rows)
        F = np.fft.fft(P, axis=0) / P.shape[0]
        out[:, :, j] = F[np.arange(-K, K + 1) % P.shape[0]]
    return out


def campbell_point(task: dict) -> dict:
    """One rotor speed: modal analysis and the plain-data summary used by :func:`campbell`.

    ``task``: ``{"turbine": Turbine, "speed": float [rad/s], "elements", "steps", "method",
    "parent_pid": int}``, and for a sweep in wind ``"wind"`` (aero.wind.Wind), ``"rho"``,
    ``"inflow"``, ``"airfoil"`` (modal_analysis's),
    ``"abscissa"`` (the wind speed: the sweep's variable, default the rotor speed), optionally
    ``"schedule"`` (a checked controller schedule: the pitch of its operating point at the
    wind and the task's rotor speed is found first, analyses/operating_points.py), and
    ``"solver_threads"`` (default 1: the sweep runs a point per CPU).  Top-level and
    picklable (the analysis limits its BLAS threads itself: numerics/threads.py).

    Returns ``{"speed", "modes": [mode dict + "label", ...], "vectors": complex (m, n_modes)
    (x(0) on the display rows, tip metres), "harmonics": complex (2K+1, m, n_modes) (Fourier
    coefficients of the periodic eigenvectors on the same rows) or None, "settings", "unresolved", "compute_time", "warnings" (the
    analysis' warning messages, collected instead of printed), "pid", "pitch_deg" (the
    pitch analysed [deg, towards feather]) and "operating_point" (with a schedule: its
    dict, else None)}``.
    """
    pid = os.getpid()
    import warnings
    turbine, point = task["turbine"], None
    # the sweep runs a point per CPU already: one solver thread per point (``"solver_threads"``
    # overrides it)
    with warnings.catch_warnings(record=True) as caught, \
            solver_threads(int(task.get("solver_threads", 1))):
        warnings.simplefilter("always")
        if task.get("schedule") is not None:
            # a sweep in wind: the operating point's pitch is found here, in the worker (the
            # scheduled rotor speed is the task's): the points' trims run in parallel
            from .operating_points import at_operating_point
            turbine, point = at_operating_point(turbine, task["wind"].speed, task["schedule"],
                                                rotor_speed=float(task["speed"]),
                                                rho=task.get("rho", 1.225))
        res = modal_analysis(turbine, elements=task.get("elements"),
                             rotor_speed=float(task["speed"]), steps=task.get("steps"),
                             method=task.get("method"), max_per_rev=task.get("max_per_rev"),
                             wind=task.get("wind"), rho=task.get("rho", 1.225),
                             inflow=task.get("inflow", "frozen"),
                             airfoil=task.get("airfoil", "quasi-steady"))
    band = task.get("max_hz")
    if band is not None:        # one band in Hz for the whole sweep, in the sweep's frame
        fixed = task.get("frame") == "fixed"
        res.modes = [m for m in res.modes if (m.fixed_frame_hz if fixed and m.fixed_frame_hz
                                              is not None else m.frequency_hz) <= band]
    messages = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught))
    rows, wts = res.model.display_rows()
    fl = res.floquet
    X = fl.eigenvectors
    cols = [m.column for m in res.modes]
    vectors = X[rows][:, cols] * wts[:, None] if cols else np.zeros((len(rows), 0), complex)
    harmonics = _harmonic_coefficients(fl, rows, wts, cols)
    modes = []
    for m in res.modes:
        d = m.to_dict()
        d["label"] = mode_label(m)
        modes.append(d)
    return {"speed": float(res.model.rotor_speed), "modes": modes,
            "abscissa": float(task.get("abscissa", res.model.rotor_speed)),
            "vectors": np.ascontiguousarray(vectors), "harmonics": harmonics,
            "settings": dict(res.settings),
            "unresolved": int(res.unresolved), "compute_time": float(res.compute_time),
            "warnings": messages, "pid": pid,
            "pitch_deg": float(np.degrees(-turbine.rotor.pitch)), "operating_point": point}


# ---------------------------------------------------------------------------- tracking
def shifted_mac(A: np.ndarray, B: np.ndarray, max_shift: int = 0, step: int = 1) -> np.ndarray:
    """MAC between the modes (last axis) of A (H, m, p) and B (H, m, q) -> (p, q); with
    ``max_shift`` > 0 (A, B Fourier coefficients over harmonics -K..K) the best over
    re-indexings of B's harmonics by -max_shift..max_shift, i.e. invariant to the whole-per-rev
    ambiguity of the Floquet exponent (x = p(t) e^{eta t} = (p e^{-ik Omega t}) e^{(eta + ik
    Omega) t}), trying the multiples of ``step`` only (the blade count under Fast Floquet: a
    shift by one harmonic would turn a symmetric two-blade pattern into an antisymmetric-
    looking one).  2-D A, B are single vectors (m, p), (m, q)."""
    if A.ndim == 2:
        A, B = A[None], B[None]
    return _mac_shift(A, B, max_shift, step)[0]


def _mac_shift(A, B, max_shift, step):
    """(best MAC (p, q), the re-indexing s achieving it (p, q)): harmonic k of A against
    harmonic k + s of B, i.e. p_B = p_A e^{i s Omega t} and f_B = f_A - s per-rev."""
    den = np.outer((np.abs(A) ** 2).sum((0, 1)), (np.abs(B) ** 2).sum((0, 1)))
    den = np.where(den > 0, den, 1.0)
    H = A.shape[0]
    best = np.zeros(den.shape)
    arg = np.zeros(den.shape, int)
    for s in sorted(range(-max_shift, max_shift + 1), key=abs):     # ties: smallest |s|
        if abs(s) >= H or s % max(1, step):
            continue
        a = A[max(0, -s):H - max(0, s)]
        b = B[max(0, s):H - max(0, -s)]
        val = mac_matrix(a.reshape(-1, a.shape[-1]), b.reshape(-1, b.shape[-1]), den=den)
        better = val > best * (1 + 1e-9)
        best = np.where(better, val, best)
        arg = np.where(better, s, arg)
    return best, arg


#: per-speed values kept for a track: rotating-frame frequency [per-rev, Hz], real part,
#: damping, MAC, harmonic offset, fixed-frame frequency [per-rev], fixed-frame damping
_COLS = 8


def track_modes(points: Sequence[dict], min_mac: float = MIN_MAC,
                frequency_weight: float = FREQUENCY_WEIGHT, keep_mac: float = KEEP_MAC,
                max_jump: float = MAX_JUMP) -> list:
    """Tracks from per-speed outputs of :func:`campbell_point` (sorted by speed).  A track's
    reference vector is its latest one matched with MAC >= ``keep_mac``; an assignment is
    refused when the MAC is below ``min_mac`` or the frequency moves by more than
    ``max_jump`` (relative, after the allowed whole-per-rev re-indexings) from the track's
    previous value.  Then fragments (at most FRAGMENT_POINTS speeds) are merged into a
    track that misses their speeds and whose frequency they continue (FRAGMENT_TOL), and
    the members of real exponent pairs are marked as twins."""
    S = len(points)
    tracks: list = []   # dicts: label info, per-speed values, reference vector and its offset
    speeds = np.array([float(p.get("speed", np.nan)) for p in points])
    # the sweep's variable (the rotor speed, or the wind speed of a sweep in wind): curves
    # are continued and interpolated along it; per-rev values convert with the speeds
    x = np.array([float(p.get("abscissa", p.get("speed", np.nan))) for p in points])
    in_wind = bool(np.any(np.isfinite(x) & (x != speeds)))

    def new_track(m, v):
        t = {"label": m["label"], "family": m["family"], "symmetry": m["symmetry"],
             "index": m["index"], "vals": np.full((S, _COLS), np.nan), "vec": v, "off": 0,
             "f": m["frequency_hz"], "whirl": m.get("whirl"), "names": [None] * S}
        tracks.append(t)
        return t

    def put(t, i, m, v, mac, off, w, clear=False):
        # off: whole per-rev added to the reported frequency to continue the track (the
        # harmonic re-indexing found by the MAC, accumulated from the track's first point)
        ff = m.get("fixed_frame_per_rev")
        fz = m.get("fixed_frame_damping_ratio")
        t["names"][i] = (m["label"], m["family"], m["symmetry"], m["index"], m.get("whirl"))
        t["vals"][i] = (m["frequency_per_rev"], m["frequency_hz"], m["real_per_rev"],
                        m["damping_ratio"], mac, off, np.nan if ff is None else ff,
                        np.nan if fz is None else fz)
        t["f"] = m["frequency_hz"] + off * w / (2 * np.pi) if np.isfinite(w) else \
            m["frequency_hz"]
        t["w"] = w
        if not mac < keep_mac or clear:
            # a poorly matching vector (two nearly equal multipliers whose eigenvectors mix)
            # does not replace the track's reference: the next clean speed matches the clean
            # one; a clear match (CLEAR_SHARE) does: the shape drifts along the sweep
            t["vec"], t["off"] = v, off

    # harmonic coefficients when every point has them, else the eigenvectors x(0)
    use_h = all(p.get("harmonics") is not None or not p["modes"] for p in points)
    st = next((p["settings"] for p in points if p.get("settings")), {})
    step = int(st.get("blades", 1)) if st.get("fast") else 1
    max_shift = max(MAX_HARMONIC_SHIFT, step) if use_h else 0
    for i, p in enumerate(points):
        # the blades' aerodynamic states' own lags are not drawn (the mode tables count them)
        keep = [j for j, m in enumerate(p["modes"]) if m.get("family") != "aerodynamic"]
        modes = [p["modes"][j] for j in keep]
        if not modes:
            continue
        V = (p["harmonics"] if use_h else p["vectors"][None])[..., keep]
        w = float(p.get("speed", np.nan))
        if not tracks:
            for j, m in enumerate(modes):
                put(new_track(m, V[..., j]), i, m, V[..., j], 1.0, 0, w)
            continue
        if V.shape[:-1] != tracks[0]["vec"].shape:
            raise ValueError("campbell: the eigenvectors of different speeds have different "
                             "sizes (same turbine and elements needed)")
        Tv = np.stack([t["vec"] for t in tracks], -1)
        ft = np.array([t["f"] for t in tracks])
        fm = np.array([m["frequency_hz"] for m in modes])
        rev = w / (2 * np.pi) if np.isfinite(w) else 0.0
        floor = 0.1 * rev if rev > 0 else 1e-3

        def continuation(sh):
            """(offsets, relative frequency change) of every pairing re-indexed by sh."""
            off = np.array([t["off"] for t in tracks])[:, None] + sh     # continuing offsets
            cont = fm[None, :] + off * rev                               # continued Hz
            rel = np.abs(cont - ft[:, None]) / np.maximum(np.abs(ft[:, None]), floor)
            if in_wind and rev > 0:
                # a sweep in wind moves the rotor speed in large steps: a mode that stays at
                # the same per-rev (a teeter mode at 1 per-rev) continues its track
                prev = np.array([t["w"] for t in tracks]) / (2 * np.pi)
                pr_t = ft / np.where(prev > 0, prev, np.nan)
                rel_pr = (np.abs(cont / rev - pr_t[:, None])
                          / np.maximum(np.abs(pr_t[:, None]), 0.1))
                rel = np.fmin(rel, rel_pr)
            return off, rel
        mac, sh = _mac_shift(Tv, V, max_shift, step)                  # (tracks, modes)
        off, rel = continuation(sh)
        if max_shift:
            # the reported frequencies follow the motion that names a mode, so a re-indexing
            # of the vectors' harmonics (the Floquet exponent found one per-rev off: IEA
            # 15-MW side-side tower, 11 -> 13 m/s) need not move them: the frequency continues
            # with the offset or without it, whichever is nearer
            off0, rel0 = continuation(np.zeros_like(sh))
            plain = rel0 < rel
            off, rel = np.where(plain, off0, off), np.where(plain, rel0, rel)
        cost = (1.0 - mac) + frequency_weight * np.minimum(rel, 1.0)
        ti, mj = linear_sum_assignment(cost)
        taken = set()
        for a, b in zip(ti, mj):
            if mac[a, b] >= min_mac and rel[a, b] <= max_jump:
                others = max(np.delete(mac[a], b).max(initial=0.0),
                             np.delete(mac[:, b], a).max(initial=0.0))
                put(tracks[a], i, modes[b], V[..., b], float(mac[a, b]), int(off[a, b]), w,
                    clear=in_wind or bool(others < CLEAR_SHARE * mac[a, b]))
                taken.add(b)
        for j, m in enumerate(modes):
            if j not in taken:
                put(new_track(m, V[..., j]), i, m, V[..., j], float("nan"), 0, w)
    tracks = _merge_fragments(tracks, speeds, step, x)
    if in_wind:
        for t in tracks:
            _majority_name(t)
    # unique labels (a label reused by a track born later gets a suffix: the next free one,
    # a label that is a point's "X #2" already included)
    used: set = set()
    out = []
    for t in tracks:
        lab = t["label"]
        if lab in used:
            base, k = lab.split(" #")[0], 2
            while f"{base} #{k}" in used:
                k += 1
            lab = f"{base} #{k}"
        used.add(lab)
        v = t["vals"]
        # the offsets that keep the curve continuous, from the values themselves (the MAC's
        # re-indexings only decide the assignment: reported frequencies follow the motion
        # that names a mode, and a re-indexing the MAC prefers between two mixed vectors
        # would put a spike into a smooth curve)
        shift = unwrap_harmonics(speeds, v[:, 0], abscissa=x)
        sh0 = np.nan_to_num(shift)
        rev_hz = speeds / (2 * np.pi)
        cont = v[:, 0] + sh0
        fixed = np.any(np.isfinite(v[:, 6]))
        # the fixed frame's curve is made continuous on its own values (a rotating-frame
        # jump of the naming harmonic need not be one in the fixed frame)
        shift6 = unwrap_harmonics(speeds, v[:, 6], abscissa=x) if fixed else None
        sh6 = np.nan_to_num(shift6) if fixed else sh0
        out.append(Track(label=lab, family=t["family"], symmetry=t["symmetry"],
                         index=t["index"], frequency_per_rev=v[:, 0], frequency_hz=v[:, 1],
                         real_per_rev=v[:, 2], damping_ratio=v[:, 3], mac=v[:, 4],
                         shift=shift, continuous_per_rev=cont,
                         continuous_hz=np.where(sh0 == 0, v[:, 1], cont * rev_hz),
                         fixed_frame_per_rev=v[:, 6] if fixed else None,
                         fixed_frame_hz=v[:, 6] * rev_hz if fixed else None,
                         fixed_frame_damping_ratio=v[:, 7] if fixed else None,
                         fixed_continuous_hz=(v[:, 6] + sh6) * rev_hz if fixed else None,
                         whirl=t.get("whirl"), fixed_shift=shift6,
                         names=[n[0] if n else None for n in t["names"]]))
    _mark_twins(out, speeds)
    return out


def _track_hz(t: dict, speeds: np.ndarray) -> np.ndarray:
    """A working track's continuous frequency [Hz] (NaN where absent)."""
    v = t["vals"]
    return (v[:, 0] + np.nan_to_num(v[:, 5])) * speeds / (2 * np.pi)


def _majority_name(track: dict) -> None:
    """Name a track in wind after the name its points carry most often (ties: the first of
    them along the sweep), not after its first point: a heavily damped flap mode's shape
    mixes the first two vacuum flap modes, and the one it starts with need not be the one it
    keeps."""
    names = [n for n in track["names"] if n is not None]
    if not names:
        return
    count: dict = {}
    for n in names:
        count[n[0]] = count.get(n[0], 0) + 1
    best = max(count.values())
    label, family, symmetry, index, whirl = next(n for n in names if count[n[0]] == best)
    track.update(label=label, family=family, symmetry=symmetry, index=index, whirl=whirl)


def _merge_fragments(tracks: list, speeds: np.ndarray, step: int, x=None) -> list:
    """Merge every short track (at most FRAGMENT_POINTS speeds) into the longer track that
    misses all of its speeds and whose frequency there (interpolated linearly in Hz between
    its neighbouring speeds, or extrapolated from its last two) the fragment continues within
    FRAGMENT_TOL, allowing whole re-indexings by multiples of ``step`` per-rev (up to
    FRAGMENT_SHIFT); the merged points keep their values with MAC NaN.  ``x``: the sweep's
    variable (default the speeds), along which the frequencies are interpolated."""
    rev = speeds / (2 * np.pi)
    x = speeds if x is None else np.asarray(x, float)
    kept = list(tracks)
    for frag in sorted(tracks, key=lambda t: np.isfinite(t["vals"][:, 0]).sum()):
        have = np.isfinite(frag["vals"][:, 0])
        if not 0 < have.sum() <= FRAGMENT_POINTS or not any(frag is k for k in kept):
            continue
        idx = np.flatnonzero(have)
        best = None
        for cand in kept:
            if cand is frag:
                continue
            ok = np.isfinite(cand["vals"][:, 0])
            if ok[idx].any() or ok.sum() <= have.sum() or ok.sum() < 2:
                continue
            f = _track_hz(cand, speeds)
            pred = np.interp(x[idx], x[ok], f[ok])
            # beyond the ends: linear extrapolation from the two nearest points
            for j, i in enumerate(idx):
                if i < np.flatnonzero(ok)[0] or i > np.flatnonzero(ok)[-1]:
                    near = np.flatnonzero(ok)[:2] if i < np.flatnonzero(ok)[0] \
                        else np.flatnonzero(ok)[-2:]
                    (a, b) = near
                    pred[j] = f[b] + (f[b] - f[a]) / (x[b] - x[a]) * (x[i] - x[b])
            for k in range(-FRAGMENT_SHIFT, FRAGMENT_SHIFT + 1):
                if k % max(1, step):
                    continue
                got = (frag["vals"][idx, 0] + np.nan_to_num(frag["vals"][idx, 5]) + k) * rev[idx]
                err = float(np.max(np.abs(got - pred) / np.maximum(np.abs(pred), 0.1 * rev[idx])))
                if err <= FRAGMENT_TOL and (best is None or err < best[0]):
                    best = (err, cand, k)
        if best is None:
            continue
        _, cand, k = best
        for i in idx:
            cand["names"][i] = frag["names"][i]
            cand["vals"][i] = frag["vals"][i]
            cand["vals"][i, 4] = np.nan
            cand["vals"][i, 5] = np.nan_to_num(frag["vals"][i, 5]) + k
        kept = [k for k in kept if k is not frag]
    return kept


def _mark_twins(tracks: list, speeds: np.ndarray) -> None:
    """Mark pairs of tracks of the same family that share a frequency at every speed where
    either is present (to 1e-6 of it, or of 1e-6 per-rev) and whose real parts are opposite
    or both zero: the members of a real exponent pair (a divergence and its decaying twin,
    or a free angle's double zero), drawn once."""
    rev = speeds / (2 * np.pi)
    for i, a in enumerate(tracks):
        if a.twin is not None:
            continue
        for b in tracks[i + 1:]:
            if b.twin is not None or b.family != a.family:
                continue
            pa, pb = a.present(), b.present()
            if not np.array_equal(pa, pb) or not pa.any():
                continue
            fa, fb = a.continuous_hz[pa], b.continuous_hz[pa]
            if np.max(np.abs(fa - fb) / np.maximum(np.abs(fa), 1e-6 * rev[pa])) > 1e-6:
                continue
            ra, rb = a.real_per_rev[pa], b.real_per_rev[pa]
            if (np.max(np.abs(ra + rb)) <= 1e-3 * max(np.max(np.abs(ra)), 1e-6)
                    or np.max(np.abs(ra) + np.abs(rb)) < 1e-6):
                a.twin, b.twin = b.label, a.label
                break


#: unwrap_harmonics in a sweep in wind: a shifted value within this many per-rev of the
#: prediction (a whole-per-rev slip of the reported harmonic lands on it; a physical bend
#: of the curve does not).
WIND_UNWRAP_TOL = 0.1


#: unwrap_harmonics: a value closer than this [per-rev] to the last point's is not a
#: harmonic slip (a slip moves the reported frequency by a whole per-rev).
SLIP = 0.5


def unwrap_harmonics(speeds: np.ndarray, per_rev: np.ndarray, tol: float = 0.25,
                     abscissa=None) -> np.ndarray:
    """Integer per-rev shifts that make a track continuous.

    A Floquet exponent is defined up to i k Omega; modal_analysis reports the dominant
    harmonic, which can jump by an integer per-rev from one speed to the next (e.g. where two
    multipliers nearly coincide and the eigenvectors mix).  Going up in speed, each value is
    compared with the prediction from the track's previous (continuous) values, linear in Hz
    from the last two (constant Hz from one); the nearest integer shift is applied when it
    brings the value within ``tol`` per-rev of the prediction.  The first value is never
    shifted.  NaN where the track is absent; all zeros when the speeds are unknown.
    ``abscissa``: the sweep's variable (default the speeds; a sweep in wind: the wind
    speeds), along which the Hz are extrapolated; in a sweep in wind (an abscissa other than
    the speeds) the shifted value must land within WIND_UNWRAP_TOL instead: few points, a
    rotor speed that changes the per-rev's size along the sweep and modes that bend sharply
    near rated make a linear prediction poorer, and a physical drop of 0.6 per-rev (IEA
    15-MW 2nd collective flap from 7 to 10 m/s, 1P = 0.1 Hz) must not read as a slip."""
    per_rev = np.asarray(per_rev, float)
    shift = np.where(np.isfinite(per_rev), 0.0, np.nan)
    if not np.all(np.isfinite(speeds)):
        return shift
    xs = speeds if abscissa is None else np.asarray(abscissa, float)
    if abscissa is not None and np.any(xs != speeds):
        tol = min(tol, WIND_UNWRAP_TOL)
    hist = []                                   # (abscissa, continuous Hz)
    for i, (w, f) in enumerate(zip(speeds, per_rev)):
        if not np.isfinite(f):
            continue
        xi = xs[i]
        if hist:
            if len(hist) >= 2 and hist[-1][0] != hist[-2][0]:
                (wa, ca), (wb, cb) = hist[-2], hist[-1]
                pred_hz = cb + (cb - ca) / (wb - wa) * (xi - wb)
            else:
                pred_hz = hist[-1][1]
            pred = pred_hz * 2 * np.pi / w
            last = hist[-1][1] * 2 * np.pi / w          # constant Hz from the last point
            k = float(np.round(pred - f))
            # a value within half a per-rev of the last point's (constant Hz) is not a
            # jump (a slip moves it by a whole one): a linear prediction over coarse steps
            # (a sweep in wind) would otherwise shift a mode that merely levels off, and the
            # next prediction run away by a per-rev a step (IEA 15-MW, a track that fell
            # 0.23 Hz from 10 to 11 m/s and moved 0.15 per-rev to 12 m/s: -2 per-rev a step
            # from there, to -1.7 Hz at 25 m/s, with a tolerance of WIND_UNWRAP_TOL here)
            if k != 0 and abs(f + k - pred) < tol and abs(f - last) >= SLIP:
                shift[i] = k
        hist.append((xi, (f + shift[i]) * w / (2 * np.pi)))
    return shift


# ---------------------------------------------------------------------------- driver
def check_speeds(speeds) -> np.ndarray:
    """Validated rotor speeds [rad/s] (finite, > 0, at least one) as a float array."""
    try:
        arr = np.atleast_1d(np.asarray(speeds, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"speeds: {speeds!r} is not allowed; need numbers > 0 [rad/s]")
    if arr.ndim != 1 or arr.size < 1:
        raise ValueError(f"speeds: {speeds!r} is not allowed; need at least one speed [rad/s]")
    bad = [float(s) for s in arr if not (math.isfinite(s) and s > 0)]
    if bad:
        raise ValueError(f"speeds: {bad[0]!r} is not allowed; need finite numbers > 0 [rad/s]")
    return arr


def _failed_point(speed: float, exc: BaseException, rows: int) -> dict:
    return {"speed": float(speed), "modes": [], "vectors": np.zeros((rows, 0), complex),
            "harmonics": None,
            "settings": {}, "unresolved": 0, "compute_time": 0.0, "warnings": [],
            "error": f"{type(exc).__name__}: {' '.join(str(exc).split())}", "pid": None}


def _check_sweep(turbine, errors: str, frame: Optional[str]) -> str:
    """Validate ``errors`` and ``frame`` (default: fixed for 3+ blades); returns the frame."""
    if errors not in ("skip", "raise"):
        raise ValueError(f"errors: {errors!r} is not allowed; use 'skip' or 'raise'")
    blades = int(turbine.rotor.blades)
    if frame is None:
        frame = "fixed" if blades >= 3 else "rotating"
    if frame not in FRAMES:
        raise ValueError(f"frame: {frame!r} is not allowed; use 'fixed' or 'rotating'")
    if frame == "fixed" and blades < 3:
        raise ValueError(f"frame: 'fixed' is not allowed for {blades} blade(s); multi-blade "
                         "coordinates need three or more (use 'rotating')")
    return frame


def _sweep_band(speeds, steps, method, max_hz):
    """(marching method, steps at the top speed, band [Hz]): the band defaults to what the
    top rotor speed resolves with the steps asked for."""
    rev_max = float(np.max(speeds)) / (2 * np.pi)
    march = method if method in ("radau", "paper") else "radau"
    base = int(steps) if steps is not None else DEFAULT_STEPS[march]
    if max_hz is None:
        max_hz = min(DEFAULT_MAX_PER_REV, base / STEPS_PER_CYCLE[march]) * rev_max
    if not (math.isfinite(float(max_hz)) and float(max_hz) > 0):
        raise ValueError(f"max_hz: {max_hz!r} is not allowed; need a finite number > 0 [Hz]")
    return march, base, float(max_hz)


#: The default band of a sweep in wind: this many times the 2nd flap frequency of one blade
#: clamped on the hub at the sweep's top rotor speed, plus that speed's 1P (the forward
#: whirl of the 2nd flap in the fixed frame): two flap modes and the first edge mode of every
#: whirl, the first tower modes and the drivetrain: ~3 Hz for multi-MW turbines (NREL 5-MW
#: 3.2 Hz, IEA 15-MW 2.6 Hz), as in HAWCStab2's and OpenFAST's Campbell diagrams.
BAND_OVER_SECOND_FLAP = 1.5


def default_wind_band(turbine: Turbine, top_speed: float) -> Optional[float]:
    """The default band [Hz] of a sweep in wind (BAND_OVER_SECOND_FLAP): None when the
    blade has fewer than two flap modes among its lowest twelve (the per-rev default then)."""
    from .blade_modes import blade_modes
    res = blade_modes(turbine, rotor_speed=float(top_speed), count=12)
    flap = [m.frequency_hz for m in res.modes if m.family == "flap" and m.frequency_hz > 0]
    if len(flap) < 2:
        return None
    return BAND_OVER_SECOND_FLAP * sorted(flap)[1] + float(top_speed) / (2 * np.pi)


def campbell(turbine: Turbine, speeds, elements: Optional[int] = None,
             steps: Optional[int] = None, method: Optional[str] = None,
             executor: Optional[cf.Executor] = None,
             progress: Optional[Callable[[float, str], None]] = None,
             errors: str = "skip", frame: Optional[str] = None,
             max_hz: Optional[float] = None, wind=None, rho: float = 1.225,
             inflow: str = "frozen", airfoil: str = "quasi-steady") -> CampbellResult:
    """Floquet modal analysis of ``turbine`` at every rotor speed of ``speeds`` [rad/s]
    (run as :func:`campbell_point` tasks on ``executor``; default a ProcessPoolExecutor with
    ``os.cpu_count()`` workers, shut down afterwards; a given executor is left running), modes
    tracked by MAC + Hungarian assignment.  ``progress(fraction, message)`` is called as
    speeds complete.  The speeds are analysed and reported in ascending order.

    ``max_hz``: the band [Hz] reported at every speed (default: DEFAULT_MAX_PER_REV per-rev
    at the highest speed); the marching steps per period (``steps``: those at the highest
    speed, default the method's) grow at lower speeds so that the band stays resolved.
    ``frame``: "fixed" (default for three or more blades) or "rotating" (default otherwise).
    ``errors``: "skip" (default) keeps going when the analysis fails at a speed (e.g. a steady
    state that does not converge): that point gets no modes and an ``"error"`` message
    (``CampbellResult.failed``); if every speed fails the first error is raised.  "raise"
    raises the first failure.  ``wind`` (aero.wind.Wind): every speed in that wind at the
    turbine's pitch (inductions of each rotor speed's own BEM state; air density ``rho``;
    ``inflow``, ``airfoil``: modal_analysis's): the overspeed sweep of a turbine flutter
    analysis."""
    frame = _check_sweep(turbine, errors, frame)
    arr = np.sort(check_speeds(speeds))
    validate_request(elements, None, steps, method)
    march, base, max_hz = _sweep_band(arr, steps, method, max_hz)
    max_hz = float(max_hz)
    t0 = time.perf_counter()
    tasks = [{"turbine": turbine, "speed": float(w), "elements": elements, "method": method,
              "wind": wind, "rho": rho, "inflow": inflow, "airfoil": airfoil,
              **_band(w, march, base, max_hz, frame)} for w in arr]
    results, failures, workers = _run(tasks, executor, progress, "speeds",
                                      lambda i: f"{arr[i]:.4g} rad/s done", errors)
    extra = None if wind is None else {
        "wind_speed": float(wind.speed), "wind_direction_deg": float(np.degrees(wind.direction)),
        "air_density": rho, "pitch_deg": float(np.degrees(-turbine.rotor.pitch)),
        "aerodynamics": _aero_description(turbine, inflow, airfoil)}
    return _assemble(turbine, arr, results, failures, errors, max_hz, frame, workers, t0,
                     extra=extra)


def _band(speed: float, march: str, base: int, max_hz: float, frame: str) -> dict:
    """A task's band entries: the marching steps per period that resolve ``max_hz`` [Hz] at
    the rotor ``speed`` [rad/s] (at least ``base``), and the band itself."""
    rev = speed / (2 * np.pi)
    need = int(math.ceil(STEPS_PER_CYCLE[march] * max_hz / rev - 1e-9))
    return {"steps": int(min(MAX_STEPS, max(base, need))), "max_per_rev": 1.05 * max_hz / rev,
            "max_hz": max_hz, "frame": frame, "parent_pid": os.getpid()}


def _expected_cost(task: dict) -> float:
    """A rank of a point's cost: the wind speed of a point in wind, else 0 (same cost)."""
    return float(task.get("abscissa", 0.0)) if task.get("wind") is not None else 0.0


def _run(tasks, executor, progress, what: str, done_message, errors: str = "skip"):
    """Run :func:`campbell_point` on every task (``executor``: default a process pool of
    one worker per CPU, shut down afterwards; ``errors="raise"``: the first failure cancels
    the rest and is raised); returns (results with None where a task
    failed, [(index, exception)], the executor's worker count)."""
    own = executor is None
    if own:
        executor = cf.ProcessPoolExecutor(max_workers=os.cpu_count() or 1)
    results: list = [None] * len(tasks)
    failures = []
    try:
        if progress is not None:
            progress(0.0, f"0/{len(tasks)} {what}")
        # longest first (a point in wind costs more the higher the wind: 12 s at 3 m/s,
        # 25 s at 25 m/s for the IEA 15-MW), so no long point is left to run alone at the end
        order = sorted(range(len(tasks)), key=lambda i: -_expected_cost(tasks[i]))
        futures = {executor.submit(campbell_point, tasks[i]): i for i in order}
        if all(isinstance(f, cf.Future) for f in futures):
            done_iter = cf.as_completed(futures)
        else:  # foreign futures: wait in order
            done_iter = iter(futures)
        for n, f in enumerate(done_iter, 1):
            i = futures[f]
            try:
                results[i] = f.result()
            except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
                if errors == "raise":
                    raise
                failures.append((i, exc))
            if progress is not None:
                progress(n / len(tasks), f"{n}/{len(tasks)} {what} ({done_message(i)})")
    except BaseException:
        for f in futures if "futures" in locals() else ():
            try:
                f.cancel()
            except Exception:
                pass
        raise
    finally:
        if own:
            executor.shutdown(wait=True, cancel_futures=True)
    return results, failures, getattr(executor, "_max_workers", None)


def _assemble(turbine, speeds, results, failures, errors, max_hz, frame, workers, t0,
              wind_speeds=None, extra=None) -> CampbellResult:
    """Failed points, tracks and settings of a finished sweep (``errors`` as campbell's)."""
    if failures and errors == "raise":
        raise failures[0][1]
    ok = [r for r in results if r is not None]
    if not ok:
        raise failures[0][1]
    rows = ok[0]["vectors"].shape[0]
    for i, exc in failures:
        results[i] = _failed_point(speeds[i], exc, rows)
        if wind_speeds is not None:
            results[i]["abscissa"] = float(wind_speeds[i])
    tracks = track_modes(results)
    s0 = ok[0]["settings"]
    steps_used = sorted({r["settings"]["steps"] for r in ok if r["settings"].get("steps")})
    settings = {"turbine": turbine.name, "elements": s0["elements"], "method": s0["method"],
                "steps": s0["steps"], "steps_range": (steps_used[0], steps_used[-1])
                if steps_used else None, "fast": s0["fast"], "speeds": list(map(float, speeds)),
                "max_hz": max_hz, "frame": frame, "workers": workers, **(extra or {})}
    return CampbellResult(speeds=np.asarray(speeds, float), tracks=tracks, points=results,
                          settings=settings, compute_time=time.perf_counter() - t0,
                          frame=frame, wind_speeds=None if wind_speeds is None
                          else np.asarray(wind_speeds, float))


def campbell_in_wind(turbine: Turbine, wind_speeds, schedule: dict,
                     elements: Optional[int] = None, steps: Optional[int] = None,
                     method: Optional[str] = None, executor: Optional[cf.Executor] = None,
                     progress: Optional[Callable[[float, str], None]] = None,
                     errors: str = "skip", frame: Optional[str] = None,
                     max_hz: Optional[float] = None, rho: float = 1.225,
                     direction: float = 0.0, inflow: str = "frozen",
                     airfoil: str = "quasi-steady") -> CampbellResult:
    """The aeroelastic Campbell diagram: at every wind speed [m/s] of ``wind_speeds`` the
    operating point of ``schedule`` (analyses/operating_points.py: rotor speed and pitch),
    then the Floquet analysis in that wind (modal_analysis(wind=..., inflow=..., airfoil=...)) as a
    :func:`campbell_point` task on ``executor``; modes tracked along the wind speed.  The
    result's ``speeds`` are the rotor speeds [rad/s] of the points, ``wind_speeds`` the
    wind speeds; ``direction`` [rad]: the wind's yaw misalignment.  Other arguments as
    :func:`campbell`'s, but ``max_hz`` defaults to :func:`default_wind_band` (a few modes
    per blade family); a point whose operating point or analysis fails is kept with its
    error (``errors="skip"``)."""
    from dataclasses import replace
    from ..aero.wind import Wind
    from .operating_points import check_schedule, scheduled_rotor_speed
    frame = _check_sweep(turbine, errors, frame)
    winds = np.sort(np.atleast_1d(np.asarray(wind_speeds, float)))
    if winds.ndim != 1 or winds.size < 1 or not np.all(np.isfinite(winds) & (winds > 0)):
        raise ValueError("wind_speeds: need finite wind speeds > 0 [m/s]")
    validate_request(elements, None, steps, method)
    schedule = check_schedule(schedule)
    t0 = time.perf_counter()
    # the rotor speeds are the schedule's; each point's pitch (its trim) is found in its task
    speeds = np.array([scheduled_rotor_speed(turbine, U, schedule) for U in winds])
    if max_hz is None and np.any(speeds > 0):
        max_hz = default_wind_band(turbine, float(np.max(speeds)))
    march, base, max_hz = _sweep_band(speeds, steps, method, max_hz)
    tasks = [{"turbine": replace(turbine, rotor=replace(turbine.rotor, speed=float(speeds[i]))),
              "schedule": schedule, "speed": float(speeds[i]), "elements": elements,
              "method": method, "wind": Wind(float(U), direction=direction), "rho": rho,
              "inflow": inflow, "airfoil": airfoil, "abscissa": float(U),
              **_band(speeds[i], march, base, max_hz, frame)} for i, U in enumerate(winds)]
    results, failures, workers = _run(tasks, executor, progress, "wind speeds",
                                      lambda j: f"{winds[j]:.4g} m/s done", errors)
    failures.sort(key=lambda f: f[0])       # the lowest wind's error first
    return _assemble(turbine, speeds, results, failures, errors, max_hz, frame, workers, t0,
                     wind_speeds=winds, extra={
                         "wind_speeds": winds.tolist(), "air_density": rho,
                         "wind_direction_deg": float(np.degrees(direction)),
                         "pitch_deg": [r["pitch_deg"] if r is not None else float("nan")
                                       for r in results],
                         "aerodynamics": _aero_description(turbine, inflow, airfoil)})
