"""Pictures (matplotlib, Agg backend, imported lazily so that hawt_core never needs a display).

``plot_blade_modes(result, path, count=6)``: mode shapes of a BladeModesResult, one subplot per
mode: flap ``u3``, lead-lag ``u2`` and twist ``theta1`` (times the blade length, so that the
three curves share one scale) against the span.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .tables import duplicate_text, ordinal, overdamped_text


def _pyplot():
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def save_png(fig, path, dpi: int = 100) -> Path:
    """Write the figure ``fig`` to the PNG file ``path`` and close it."""
    path = Path(path)
    fig.savefig(path, format="png", dpi=dpi)
    _pyplot().close(fig)
    return path


def plot_blade_modes(result, path, count: int = 6) -> Path:
    """Write the first ``count`` mode shapes of ``result`` to the PNG file ``path``."""
    plt = _pyplot()
    modes = list(result.modes)[:max(1, int(count))]
    if not modes:
        raise ValueError("plot: the result has no modes to plot")
    ncol = 2 if len(modes) > 1 else 1
    nrow = math.ceil(len(modes) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.5 * ncol, 2.6 * nrow), squeeze=False,
                             sharex=True)
    for ax in axes.ravel()[len(modes):]:
        ax.set_visible(False)
    for ax, m in zip(axes.ravel(), modes):
        s = m.shape
        span = s["span"]
        L = span[-1] if span[-1] else 1.0
        ax.plot(span, s["flap"], "o-", label="flap $u_3$")
        ax.plot(span, s["lag"], "s-", label="lead-lag $u_2$")
        ax.plot(span, [L * t for t in s["twist"]], "^-", label=r"twist $\ell\,\theta_1$")
        pr = m.frequency_per_rev
        freq = (f"{pr:.4f}/rev, " if pr == pr else "") + f"{m.frequency_hz:.4g} Hz"
        ax.set_title(f"{m.family} {m.index}: {freq}", fontsize=10)
        ax.axhline(0.0, color="0.7", lw=0.5)
        ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("span from the root [m]")
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle(f"Blade modes at {result.rotor_speed:.4g} rad/s, {result.elements} elements",
                 fontsize=11)
    fig.tight_layout()
    return save_png(fig, path)


# ============================================================================ turbine modes
# ``plot_turbine_modes(result, path_or_dir, modes=None)``: Floquet mode shapes of a ModalResult
# drawn like the paper's Figs. 1-12 (see the function's docstring).

#: Instants of the modal oscillation drawn in each picture (phases 0, 90, 180, 270 deg).
MODE_INSTANTS = 4
#: Largest drawn displacement, as a fraction of the rotor radius.
MODE_AMPLITUDE = 0.12
#: Largest drawn twist in the rod illustration [rad].
TWIST_AMPLITUDE = math.radians(60.0)


def mode_label(mode) -> str:
    """'1st antisymmetric flap', 'teeter', 'yaw 2', ... (the paper's figure captions)."""
    if mode.family in ("yaw", "teeter") or not mode.symmetry:
        text = mode.family if mode.index == 1 else f"{mode.family} {mode.index}"
    else:
        text = f"{ordinal(mode.index)} {mode.symmetry} {mode.family}"
    # "1st collective flap (overdamped, slow)", "1st backward-whirl flap #2"
    return text + overdamped_text(mode) + duplicate_text(mode)


def mode_file_stem(position: int, mode) -> str:
    """'03_flap_antisymmetric_1' (position counts from 1 in the selection)."""
    parts = [f"{position:02d}", mode.family]
    if mode.symmetry:
        parts.append(mode.symmetry)
    parts.append(str(mode.index))
    return "_".join(parts)


def table2_modes(result) -> list:
    """The modes of the paper's Table 2: the rigid teeter and yaw modes (index 1) and the first
    two of every elastic (family, symmetry) pair, in the result's (frequency) order."""
    out = []
    for m in result.modes:
        if m.family in ("yaw", "teeter"):
            if m.index == 1:
                out.append(m)
        elif m.index <= 2:
            out.append(m)
    return out


def _select_modes(result, modes):
    if modes is None:
        return table2_modes(result)
    out = []
    for m in modes:
        if isinstance(m, (int,)) and not isinstance(m, bool):
            out.append(result.modes[m])
        elif isinstance(m, (tuple, list)):
            out.append(result.find(*m))
        elif isinstance(m, str):
            words = m.replace("_", " ").split()
            idx = int(words[-1]) if words and words[-1].isdigit() else 1
            words = [w for w in words if not w.isdigit()]
            out.append(result.find(words[0], words[1] if len(words) > 1 else None, idx))
        else:
            out.append(m)
    return out


class _ModeGeometry:
    """Exact rigid-body + blade kinematics of a TurbineModel, linearized about the undeformed
    rotor, in the nominal rotating shaft frame (s1: blade 0's span at rest, s2: lateral, s3:
    along the shaft); used to turn a periodic eigenvector into drawn displacements."""

    def __init__(self, model):
        self.model = model
        self.rigid = model.rigid
        self.lay = model.layout
        self.nb = model.n_blades
        self.nodes = np.asarray(model.beam.props.nodes, float)      # (N+1,) span from root
        self.line = model.beam.props.node_positions()              # (N+1, 3) in b
        self.coords = [c for c in self.rigid.coordinates]
        self.R = float(model.turbine.hub.radius + model.turbine.blade.length)
        self.tower = None
        if getattr(self.rigid, "flexible_tower", False):
            try:
                self.tower = self.lay.tower()       # tower-top motion moves the whole rotor
            except (AttributeError, ValueError):
                self.tower = None

    def points(self, q, u, t, tower=None):
        """(Nb, N+1, 3) blade axis points and (3,) teeter-axis point, shaft-frame coordinates;
        ``q`` rigid coordinates (n_q,), ``u`` (Nb, N+1, 3) blade displacements (root frame);
        ``tower``: None or the tower-top (u, theta) (2, 3) in the inertial frame."""
        rg = self.rigid
        if tower is not None:
            state = np.zeros((5, 3))
            state[0] = np.asarray(tower)[1]              # tower-top rotation (Rodrigues)
            fr = rg.frames(np.asarray(q, float), t, tower=state)
            top = np.asarray(tower)[0]
        else:
            fr = rg.frames(np.asarray(q, float), t)
            top = np.zeros(3)
        S0 = rg.frames(np.zeros(rg.n_q), t)["S"]
        H, B = fr["H"], fr["B"]
        hub = top + rg.teeter_point(fr)
        pts = np.empty((self.nb, len(self.nodes), 3))
        for k in range(self.nb):
            root = hub + H @ rg.root_offset_hub[k]
            local = self.line + u[k]
            pts[k] = root[None, :] + local @ B[k].T
        return pts @ S0, hub @ S0

    def root_bases(self, t):
        """(Nb, 3, 3) blade root bases at rest in the shaft frame (columns b1, b2, b3)."""
        rg = self.rigid
        fr = rg.frames(np.zeros(rg.n_q), t)
        return np.einsum("ji,kjl->kil", fr["S"], fr["B"])

    def split(self, x):
        """Rigid coordinates (n_q,) and blade u, theta (Nb, N+1, 3) of a real state vector."""
        q = np.array([x[self.lay[c]] for c in self.coords], float)
        u = np.zeros((self.nb, len(self.nodes), 3))
        th = np.zeros_like(u)
        for k in range(self.nb):
            b = self.lay.blade(k)
            u[k, 1:] = x[b.u[1:]]
            th[k, 1:] = x[b.theta[1:]]
        tw = None
        if self.tower is not None:
            tw = np.array([x[self.tower.u[-1]], x[self.tower.theta[-1]]], float)
        return q, u, th, tw

    def displacement(self, x, t):
        """Linearized displacement of the blade axes (Nb, N+1, 3), of the hub (3,), and the
        twist theta1 (Nb, N+1) for the real perturbation ``x`` at time t."""
        q, u, th, tw = self.split(x)
        size = max(np.abs(q).max(initial=0.0) * self.R, np.abs(u).max(initial=0.0),
                   0.0 if tw is None else np.abs(tw[0]).max() + self.R * np.abs(tw[1]).max(),
                   1e-300)
        eps = 1e-6 / size                        # a perturbation of ~1 micrometre
        P0, h0 = self.points(np.zeros_like(q), np.zeros_like(u), t)
        P1, h1 = self.points(eps * q, eps * u, t, None if tw is None else eps * tw)
        return (P1 - P0) / eps, (h1 - h0) / eps, th[:, :, 0]


def mode_snapshots(result, mode, instants: int = MODE_INSTANTS):
    """Real motions of ``mode`` at ``instants`` evenly spaced phases from 0 to 180 deg of one
    cycle of its dominant frequency (over one rotor period for a non-oscillating mode).

    x(t) = Re(p(t) exp(i Im(eta) t)) with p the periodic Floquet eigenvector (Fourier-
    interpolated from the result's samples) and eta its characteristic exponent; the growth
    or decay exp(Re(eta) t) is left out, and the complex phase is chosen so that the largest
    displacement-like entry is at its maximum at the first instant. Returns (times (J,),
    phases_deg (J,), states (J, n) real)."""
    fl = result.floquet
    model = result.model
    times, P = result.shape_samples(mode)
    M = P.shape[0]
    omega0 = model.rotor_speed
    c = np.fft.fft(P, axis=0) / M
    k = np.fft.fftfreq(M, 1.0 / M)
    eta = complex(fl.exponents[mode.column])
    w_mode = mode.frequency_per_rev * omega0
    J = max(1, int(instants))
    if abs(w_mode) > 1e-6 * omega0:
        # phases 0 .. 180 deg (0, 60, 120, 180 for four instants): a standing (real) mode shows
        # four different amplitudes, a travelling one its motion
        tj = np.arange(J) * (np.pi / abs(w_mode)) / max(1, J - 1)
    else:
        tj = np.arange(J) * model.period / J
    pj = np.exp(1j * np.outer(tj, k) * omega0) @ c             # (J, n) periodic part
    xj = pj * np.exp(1j * eta.imag * tj)[:, None]
    # the phase: largest displacement-like entry (tip metres) real at t = 0
    rows, wts = model.display_rows()
    z = xj[0, rows] * wts
    i = int(np.argmax(np.abs(z)))
    if abs(z[i]) > 0:
        xj = xj * (abs(z[i]) / z[i])
    phases = np.degrees(np.angle(np.exp(1j * w_mode * tj))) % 360.0 if abs(w_mode) > 1e-6 * omega0 \
        else 360.0 * np.arange(J) / J
    return tj, phases, np.real(xj)


def _draw_rotor(ax, pts, hub, root_pts, view, **kw):
    """One rotor picture in ``view`` ('front': s2 right, s1 up; 'side': s3 right, s1 up)."""
    ix = 1 if view == "front" else 2
    lines = []
    for k in range(pts.shape[0]):
        lines += ax.plot(pts[k, :, ix], pts[k, :, 0], **kw)
        lines += ax.plot([hub[ix], root_pts[k, ix]], [hub[0], root_pts[k, 0]], **kw)
    return lines


def _draw_mode(axes, result, mode, instants=MODE_INSTANTS):
    """Front view, side view (and the twist illustration for torsion modes) on ``axes``."""
    geom = _ModeGeometry(result.model)
    tj, phases, X = mode_snapshots(result, mode, instants)
    P0, h0 = geom.points(np.zeros(len(geom.coords)), np.zeros((geom.nb, len(geom.nodes), 3)), 0.0)
    disp = [geom.displacement(X[j], tj[j]) for j in range(len(tj))]
    big = max(max(np.abs(d[0]).max(), np.abs(d[1]).max()) for d in disp)
    twist = max(np.abs(d[2]).max() for d in disp)
    # one amplification for displacements and twist: the largest displacement is 12 % of R or
    # the largest twist 60 deg, whichever comes first (a torsion mode's tiny bending stays tiny)
    amp = min(MODE_AMPLITUDE * geom.R / big if big > 0 else np.inf,
              TWIST_AMPLITUDE / twist if twist > 0 else np.inf)
    amp = amp if np.isfinite(amp) else 1.0
    cmap = _pyplot().get_cmap("viridis")
    # a non-oscillating mode (free yaw) is drawn at rotor azimuths over one revolution
    what = "phase" if abs(mode.frequency_per_rev) > 1e-6 else "azimuth"
    R = geom.R
    for ax, view in zip(axes[:2], ("front", "side")):
        _draw_rotor(ax, P0, h0, P0[:, 0], view, color="0.55", ls="--", lw=1.0)
        ax.plot([0.0, h0[1 if view == "front" else 2]], [0.0, h0[0]], color="0.75", lw=3,
                solid_capstyle="round", zorder=0)                       # shaft to the yaw axis
        for j, (dP, dh, _) in enumerate(disp):
            col = cmap(j / max(1, len(disp) - 1) * 0.9)
            pts, hub = P0 + amp * dP, h0 + amp * dh
            ln = _draw_rotor(ax, pts, hub, pts[:, 0], view, color=col, lw=1.8)
            ln[0].set_label(f"{what} {phases[j]:.0f}°")
            ix = 1 if view == "front" else 2
            ax.plot([hub[ix]], [hub[0]], "o", color=col, ms=5)
        ax.plot([h0[1 if view == "front" else 2]], [h0[0]], "o", mfc="none", mec="0.4", ms=9)
        ax.set_aspect("equal", adjustable="box")
        ax.set_ylim(-1.1 * R, 1.1 * R)
        ax.grid(True, alpha=0.25)
    half = 0.45 * R if geom.nb == 2 else 1.1 * R          # blades off the vertical: wider
    axes[0].set_xlim(-half, half)
    axes[0].set_title("rotor plane (looking upwind), rotating with the rotor", fontsize=9)
    axes[0].set_xlabel("lateral $s_2$ [m]")
    axes[0].set_ylabel("blade 1 span $s_1$ [m]")
    axes[1].set_xlim(h0[2] - 0.45 * R, h0[2] + 0.45 * R)
    axes[1].set_title("side view", fontsize=9)
    axes[1].set_xlabel("shaft axis $s_3$ [m]")
    axes[0].legend(fontsize=7, loc="lower left")
    if len(axes) > 2 and axes[2] is not None:
        _draw_twist(axes[2], geom, disp[0][2], P0, amp)
    return amp


def _draw_twist(ax, geom, theta1, P0, amp):
    """The paper's torsion illustration: a straight line drawn on a circular rod along each
    blade (front view), twisted by the mode's theta1 (amplified to TWIST_AMPLITUDE)."""
    R = geom.R
    rho = 0.06 * R
    shown = np.degrees(amp * np.abs(theta1).max())
    bases = geom.root_bases(0.0)
    s = np.linspace(0.0, 1.0, 200)
    for k in range(geom.nb):
        span = np.interp(s, np.linspace(0, 1, len(geom.nodes)), geom.nodes)
        axis_pts = np.array([np.interp(span, geom.nodes, P0[k, :, c]) for c in range(3)]).T
        phi = amp * np.interp(span, geom.nodes, theta1[k])
        b2, b3 = bases[k][:, 1], bases[k][:, 2]
        d = np.sin(phi)[:, None] * b2[None] - np.cos(phi)[:, None] * b3[None]
        x0, y0 = axis_pts[:, 1], axis_pts[:, 0]
        ax.plot(x0 - rho, y0, color="0.3", lw=1)
        ax.plot(x0 + rho, y0, color="0.3", lw=1)
        ax.plot([x0[0] - rho, x0[0] + rho], [y0[0], y0[0]], color="0.3", lw=1)
        ax.plot([x0[-1] - rho, x0[-1] + rho], [y0[-1], y0[-1]], color="0.3", lw=1)
        ax.plot(x0, y0, color="0.55", ls="--", lw=1, label="untwisted line" if k == 0 else None)
        vis = (-d[:, 2]) >= 0
        xl = x0 + rho * d[:, 1]
        ax.plot(np.where(vis, xl, np.nan), y0, color="C3", lw=2,
                label="twisted line" if k == 0 else None)
        ax.plot(np.where(~vis, xl, np.nan), y0, color="C3", lw=1, ls=":")
    ax.set_xlim(-4 * rho, 4 * rho)
    ax.set_ylim(-1.1 * R, 1.1 * R)
    ax.set_title(f"twist: line on a rod (phase 0, max {shown:.0f}° shown)",
                 fontsize=9)
    ax.set_xlabel("lateral [m]")
    ax.legend(fontsize=7, loc="lower left")


def _mode_title(mode) -> str:
    pr = mode.frequency_per_rev
    digits = 4 if mode.family == "torsion" else 2
    return f"{mode_label(mode)} ({pr:.{digits}f} /rev)"


def plot_turbine_modes(result, path_or_dir, modes=None) -> list:
    """Mode-shape pictures of a ModalResult like the paper's Figs. 1-12.

    ``modes``: None (the Table 2 modes: teeter, yaw and the first two of each (family,
    symmetry)), or a list of Mode objects, indices into ``result.modes``, (family, symmetry,
    index) tuples or strings like "flap antisymmetric 1".  ``path_or_dir``: an existing
    directory (or a path without a suffix, created) gets one PNG per mode named
    ``NN_family[_symmetry]_index.png``; otherwise one PNG file with a row per mode.

    Each picture shows the two-bladed (any-bladed) rotor seen with the rotor (the camera
    turns with the shaft, blade 1 up): the rotor-plane view and a side view, the undeformed
    rotor dashed and the deformed one solid at four phases of one cycle of the mode's dominant
    frequency, from the periodic Floquet eigenvector (yaw, teeter and blade u in the exact
    kinematics of hawt_core.rigid, linearized), amplified so that the largest displacement is
    12 % of the rotor radius. Yaw shows as a displacement and rotation of the hub, teeter as a
    rigid rotation of the rotor. Torsion modes get a third panel: the paper's straight line on a
    circular rod along each blade, twisted by theta1. Returns the written paths."""
    plt = _pyplot()
    sel = _select_modes(result, modes)
    if not sel:
        raise ValueError("plot: no modes to plot")
    target = Path(path_or_dir)
    per_mode = target.is_dir() or target.suffix == ""
    written = []
    if per_mode:
        target.mkdir(parents=True, exist_ok=True)
        for pos, m in enumerate(sel, 1):
            ncol = 3 if m.family == "torsion" else 2
            fig, axes = plt.subplots(1, ncol, figsize=(4.2 * ncol, 5.2), squeeze=False)
            amp = _draw_mode(list(axes[0]), result, m)
            fig.suptitle(f"{_mode_title(m)}\n{m.frequency_hz:.4g} Hz, damping "
                         f"{m.damping_ratio:.2e}, displacements x{amp:.3g}", fontsize=11)
            fig.tight_layout()
            written.append(save_png(fig, target / f"{mode_file_stem(pos, m)}.png", dpi=90))
        return written
    nrow = len(sel)
    fig, axes = plt.subplots(nrow, 3, figsize=(12.6, 5.0 * nrow), squeeze=False)
    for row, m in zip(axes, sel):
        if m.family != "torsion":
            row[2].set_visible(False)
        _draw_mode(list(row) if m.family == "torsion" else list(row[:2]), result, m)
        row[0].text(0.02, 0.98, _mode_title(m), transform=row[0].transAxes,
                    va="top", fontsize=10, fontweight="bold")
    fig.tight_layout()
    save_png(fig, target, dpi=80)
    return [target]


# ============================================================================ Campbell diagram
def _spread(y: np.ndarray, gap: float, lo: float, hi: float) -> np.ndarray:
    """Label positions: ``y`` moved apart to at least ``gap`` (order kept) and into [lo, hi],
    each as little as possible: overlapping labels form clusters spread evenly (``gap``
    apart) about their mean, clamped into the bounds; clusters that then overlap merge, until
    none do.  Labels that overlap nothing stay where they are."""
    y = np.asarray(y, float)
    order = np.argsort(y)
    ys = np.clip(y[order], lo, hi)
    clusters = [[v] for v in ys]               # original positions per cluster
    pos = [v for v in ys]                      # first (lowest) label position per cluster

    def place(c):
        size = gap * (len(c) - 1)
        start = float(np.mean(c)) - size / 2
        return min(max(start, lo), hi - size) if hi - lo >= size else lo

    changed = True
    while changed:
        changed = False
        for i in range(1, len(clusters)):
            top_prev = pos[i - 1] + gap * (len(clusters[i - 1]) - 1)
            if pos[i] < top_prev + gap - 1e-12:
                clusters[i - 1] += clusters.pop(i)
                pos.pop(i)
                pos[i - 1] = place(clusters[i - 1])
                changed = True
                break
    z = np.concatenate([p + gap * np.arange(len(c)) for p, c in zip(pos, clusters)])
    out = np.empty_like(z)
    out[order] = z
    return out


#: plot_campbell's default tracks: a second track of one name ('#2') is drawn when its
#: damping ratio falls below this somewhere (IEA 15-MW in wind: a forward-whirl flap mode
#: at 1.5-2 Hz damped 0.19-0.35; the heavily damped ones, 0.98 and more, are left out).
DRAWN_DUPLICATE_ZETA = 0.3


def plot_campbell(result, path, max_hz=None, max_rays: int = 12, tracks="table2",
                  frame: str = "rotating") -> Path:
    """Campbell diagram of a CampbellResult: frequency [Hz] of the tracks against the rotor
    speed [rpm] with the 1P..nP excitation rays (n <= max_rays), and the damping ratios below.
    ``tracks``: "table2" (default: the rigid yaw/teeter tracks and the first two of each
    elastic (family, symmetry), as in the paper's Table 2), "all", or a list of labels.
    ``frame``: "rotating" or "fixed" (three or more blades: multi-blade coordinates).
    The curves are the tracks' continuous frequencies (the dominant frequency plus the integer
    per-rev that keeps a track continuous; such points are circled), each labelled at its
    right end (labels pushed apart so that none overlaps); the two members of a real pair
    (Track.twin) are drawn once, their dampings both.  A sweep in wind (result.wind_speeds)
    is drawn against the wind speed, the nP lines following the operating points' rotor
    speeds.  PNG."""
    any_shift = False
    plt = _pyplot()
    rpm = np.asarray(result.rpm, float)
    wind = getattr(result, "wind_speeds", None)
    # the abscissa: rotor speed [rpm], or the wind speed [m/s] of a sweep in wind
    xs = rpm if wind is None else np.asarray(wind, float)
    if tracks == "all":
        tracks = list(result.tracks)
    elif tracks == "table2":
        # a track labelled "X #k" (a label reused by a later track, or a second mode named
        # after one vacuum mode) is left to "all" unless it is damped less than
        # DRAWN_DUPLICATE_ZETA somewhere: a mode that matters for stability is drawn
        tracks = [t for t in result.tracks if (t.family in ("yaw", "teeter") or t.index <= 2)
                  and ("#" not in t.label or np.any(t.damping_ratio < DRAWN_DUPLICATE_ZETA))]
    else:
        wanted = list(tracks)
        tracks = [t for t in result.tracks if t.label in wanted]
    if not tracks:
        raise ValueError("plot: no tracks to plot")
    curve = {id(t): t.hz(frame) for t in tracks}
    fmax = max([np.nanmax(curve[id(t)]) for t in tracks if np.any(t.present())] or [1.0])
    top = float(max_hz) if max_hz else 1.05 * fmax
    fig, (ax, axd) = plt.subplots(2, 1, figsize=(10, 9), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 1.2]})
    if wind is None:
        x = np.array([0.0, rpm.max() * 1.02 if len(rpm) else 1.0])
    else:
        x = np.array([xs.min(), xs.max() + 0.02 * max(np.ptp(xs), 1.0)])
    nmax = min(max_rays, max(1, int(math.ceil(top * 60.0 / max(rpm.max(), 1e-12)))))
    for n in range(1, nmax + 1):
        if wind is None:
            ax.plot(x, n * x / 60.0, color="0.85", lw=0.8, zorder=0)
            # the label inside the panel where the ray leaves it (top or right edge)
            xe = min(x[1], top * 60.0 / n)
            ax.text(xe, min(n * xe / 60.0, top), f"{n}P ", color="0.55", fontsize=6,
                    va="top" if xe < x[1] else "bottom", ha="right", zorder=0)
        else:
            ax.plot(xs, n * rpm / 60.0, color="0.85", lw=0.8, zorder=0)
            if n * rpm[-1] / 60.0 <= top:
                ax.text(xs[-1], n * rpm[-1] / 60.0, f"{n}P ", color="0.55", fontsize=6,
                        va="bottom", ha="right", zorder=0)
    styles = {"symmetric": "-", "collective": "-", "antisymmetric": "--", "cyclic": "--",
              "backward-whirl": "--", "forward-whirl": ":", "differential": "-."}
    markers = {"flap": "o", "lag": "s", "torsion": "^", "teeter": "D", "yaw": "v",
               "axial": "x", "shear": "+", "tower": "P"}
    drawn = set()
    ends = []                                   # (y at the right end, label, colour)
    for i, t in enumerate(tracks):
        ok = t.present()
        c = curve[id(t)]
        col = f"C{i % 10}"
        ls = styles.get((t.symmetry or "").split("-whirl")[0] + ("-whirl" if "whirl" in
                                                                  (t.symmetry or "") else ""),
                        "-")
        mk = markers.get(t.family, ".")
        axd.plot(xs, t.damping(frame), ls=ls, marker=mk, ms=3, color=col)
        if not ok.any() or np.nanmin(c) > top or t.twin in drawn:
            continue
        drawn.add(t.label)
        ax.plot(xs, c, ls=ls, marker=mk, ms=3, color=col)
        shifted = np.nan_to_num(t.frame_shift(frame)) != 0
        if shifted.any():
            ax.plot(xs[shifted], c[shifted], ls="none", marker="o", ms=8, mfc="none", mec=col)
            any_shift = True
        j = np.flatnonzero(ok)[-1]
        if c[j] <= top:
            ends.append((c[j], t.label + (" (\u00b1 pair)" if t.twin else ""), col))
    if ends:
        gap = top / 58.0                        # about one 7-point text line of the panel
        ys = _spread(np.array([e[0] for e in ends]), gap, 0.0, top)
        xl = x[1]
        for (y0, lab, col), y in zip(ends, ys):
            ax.annotate(lab, xy=(xs.max(), y0), xytext=(xl + 0.02 * (xl - xs.min()), y),
                        fontsize=7, color=col, va="center", ha="left",
                        arrowprops=dict(arrowstyle="-", color=col, lw=0.5, alpha=0.6),
                        annotation_clip=False)
    ax.set_ylim(0.0, top)
    lo = xs.min() if len(xs) else 0.0
    span = (xs.max() - lo) if len(xs) else 1.0
    ax.set_xlim(max(0.0, lo - 0.05 * max(span, 1e-9 + lo * 0.1)), x[1])
    if any_shift:
        ax.text(0.01, 0.99, "circled: dominant harmonic moved by whole per-rev for continuity",
                transform=ax.transAxes, ha="left", va="top", fontsize=7, color="0.4")
    ax.set_ylabel(f"{frame}-frame frequency [Hz]")
    st = result.settings
    rng = st.get("steps_range") or (st.get("steps"), st.get("steps"))
    how = ((f"{st.get('method')} {rng[0]}" + (f"-{rng[1]}" if rng[1] != rng[0] else "")
            + " steps/period") if st.get("method") in ("radau", "paper")
           else f"{st.get('method')}")
    aero = st.get("aerodynamics", "")
    model = ", ".join(["BEM", "Oye's inflow" if "Oye" in aero else "frozen wake"]
                      + (["Jones's airfoils"] if "Jones" in aero else []))
    ax.set_title(f"Campbell diagram: {st.get('turbine', '')}"
                 + (f" in wind ({model})" if wind is not None else "") + "\n"
                 f"{st.get('elements')} elements, {how}, {frame} frame", fontsize=10)
    ax.grid(True, alpha=0.3)
    axd.axhline(0.0, color="0.5", lw=0.8)
    axd.set_xlabel("rotor speed [rpm]" if wind is None else
                   "wind speed [m/s] (rotor speed and pitch: the operating points)")
    axd.set_ylabel("damping ratio")
    axd.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.subplots_adjust(right=0.78)
    return save_png(fig, path)


def plot_time_history(history: dict, path, title: str = "") -> Path:
    """Summary of a closed-loop run (control/loop.py ClosedLoop.history(): arrays by column
    name) to the PNG file ``path``: wind and rotor speed, generator power, blade pitch and
    generator torque, blade-tip flap deflections, against time."""
    plt = _pyplot()
    t = np.asarray(history["time"])
    fig, axes = plt.subplots(4, 1, figsize=(8.0, 9.0), sharex=True)
    ax = axes[0]
    ax.plot(t, history["wind_speed"], color="tab:blue", label="hub wind [m/s]")
    ax.set_ylabel("wind [m/s]")
    ax2 = ax.twinx()
    ax2.plot(t, history["rotor_speed_rpm"], color="tab:red", label="rotor [rpm]")
    ax2.set_ylabel("rotor speed [rpm]", color="tab:red")
    axes[1].plot(t, history["generator_power_kw"] / 1e3, color="tab:green")
    axes[1].set_ylabel("generator power [MW]")
    pitches = sorted(k for k in history if k.startswith("pitch") and k.endswith("_deg"))
    for k in pitches:
        axes[2].plot(t, history[k], label=k.replace("_deg", ""))
    axes[2].set_ylabel("pitch [deg]")
    ax3 = axes[2].twinx()
    ax3.plot(t, history["generator_torque_knm"], color="k", lw=0.8, ls="--")
    ax3.set_ylabel("generator torque [kN m] (dashed)")
    for k in sorted(k for k in history if k.endswith("_flap_m")):
        axes[3].plot(t, history[k], label=k.replace("_flap_m", ""))
    axes[3].set_ylabel("tip flap [m]")
    axes[3].set_xlabel("time [s]")
    for a in axes:
        a.grid(alpha=0.3)
    if len(pitches) > 1:
        axes[2].legend(fontsize=7, loc="lower right")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save_png(fig, path)
