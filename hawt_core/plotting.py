"""Pictures (matplotlib, Agg backend, imported lazily so that hawt_core never needs a display).

``plot_blade_modes(result, path, count=6)``: mode shapes of a BladeModesResult, one subplot per
mode: flap ``u3``, lead-lag ``u2`` and twist ``theta1`` (times the blade length, so that the
three curves share one scale) against the span.
"""
from __future__ import annotations

import math
from pathlib import Path


def _pyplot():
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


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
    path = Path(path)
    fig.savefig(path, format="png", dpi=100)
    plt.close(fig)
    return path
