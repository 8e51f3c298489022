"""The result of a flutter sweep (``hawt flutter``): the aeroelastic modes' frequencies and
damping against the flow speed, the flutter point (and static divergence) found in the band.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

__all__ = ["FlutterResult"]


@dataclass
class FlutterResult:
    """``speeds`` (S,) [m/s]; ``frequency`` (S, K) [rad/s] and ``damping_ratio`` (S, K) of the
    K lowest oscillatory modes at each speed (sorted by frequency); ``flutter_speed`` [m/s]
    and ``flutter_frequency`` [rad/s]: where the first of them loses its damping (None when
    none does in the range); ``divergence_speed``: where a real eigenvalue turns positive
    (static divergence; None in the range)."""

    case: str
    speeds: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    flutter_speed: Optional[float]
    flutter_frequency: Optional[float]
    divergence_speed: Optional[float]
    settings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        clean = lambda a: [[None if not np.isfinite(v) else float(v) for v in row] for row in a]
        return {"case": self.case, "flutter_speed": self.flutter_speed,
                "flutter_frequency_rad_s": self.flutter_frequency,
                "flutter_frequency_hz": None if self.flutter_frequency is None
                else self.flutter_frequency / (2 * np.pi),
                "divergence_speed": self.divergence_speed, "speeds": self.speeds.tolist(),
                "frequency_rad_s": clean(self.frequency),
                "damping_ratio": clean(self.damping_ratio), "settings": dict(self.settings)}

    def to_json(self, indent=None) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def table(self) -> str:
        lines = [f"{self.case}: {len(self.speeds)} speeds from {self.speeds[0]:g} to "
                 f"{self.speeds[-1]:g} m/s ({self.settings.get('elements')} elements, "
                 f"{self.settings.get('aerodynamics')})"]
        if self.flutter_speed is not None:
            lines.append(f"flutter at {self.flutter_speed:.4g} m/s, {self.flutter_frequency:.4g} "
                         f"rad/s ({self.flutter_frequency / (2 * np.pi):.4g} Hz)")
        else:
            lines.append("no flutter in the range")
        if self.divergence_speed is not None:
            lines.append(f"static divergence at {self.divergence_speed:.4g} m/s")
        head = "speed m/s " + " ".join(f"{'mode ' + str(k + 1) + ' rad/s, zeta':>22s}"
                                       for k in range(self.frequency.shape[1]))
        lines.append(head)
        for U, f, z in zip(self.speeds, self.frequency, self.damping_ratio):
            lines.append(f"{U:9.4g} " + " ".join(f"{fi:11.4g} {zi:10.3g}" for fi, zi in zip(f, z)))
        return "\n".join(lines)

    def plot(self, path) -> Path:
        """Frequency and damping ratio against speed, the flutter point marked."""
        from .plotting import _pyplot, save_png
        plt = _pyplot()
        fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
        for k in range(self.frequency.shape[1]):
            a1.plot(self.speeds, self.frequency[:, k], "o-", ms=3, label=f"mode {k + 1}")
            a2.plot(self.speeds, self.damping_ratio[:, k], "o-", ms=3)
        a2.axhline(0.0, color="k", lw=0.8)
        if self.flutter_speed is not None:
            for ax in (a1, a2):
                ax.axvline(self.flutter_speed, color="r", ls="--", lw=1)
            a1.plot(self.flutter_speed, self.flutter_frequency, "r*", ms=12,
                    label=f"flutter {self.flutter_speed:.4g} m/s, "
                          f"{self.flutter_frequency:.4g} rad/s")
        a1.set_ylabel("frequency [rad/s]")
        a2.set_ylabel("damping ratio [-]")
        a2.set_xlabel("flow speed [m/s]")
        a1.legend(fontsize=8)
        a1.set_title(f"{self.case}: aeroelastic modes")
        for ax in (a1, a2):
            ax.grid(True, alpha=0.3)
        fig.tight_layout()
        return save_png(fig, path)
