"""The result of a flutter sweep (``hawt flutter``): the aeroelastic modes' frequencies and
damping against the flow speed, the flutter point (and static divergence) found in the band.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

__all__ = ["FlutterResult", "TurbineFlutterResult"]


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


@dataclass
class TurbineFlutterResult:
    """Overspeed flutter of a turbine in wind (analyses/turbine_flutter.py): the Campbell
    result of the rotor-speed sweep in wind (``campbell``), and the lowest rotor speed
    ``flutter_speed`` [rad/s] where a mode's damping crosses below -DAMPING_TOL, that mode's
    label and frequency [Hz] (None when no mode does in the range); ``unstable_at_start``:
    the mode is already unstable at the first speed (the crossing is below the range)."""

    turbine: str
    campbell: object
    wind_speed: float
    pitch_deg: float
    flutter_speed: Optional[float]
    flutter_mode: Optional[str]
    flutter_frequency_hz: Optional[float]
    unstable_at_start: bool = False

    def to_dict(self) -> dict:
        c = self.campbell
        tracks = [{"label": t.label, "frequency_hz": [None if not np.isfinite(v) else float(v)
                                                      for v in t.hz("rotating")],
                   "damping_ratio": [None if not np.isfinite(v) else float(v)
                                     for v in t.damping_ratio]} for t in c.tracks]
        return {"case": self.turbine, "wind_speed": self.wind_speed, "pitch_deg": self.pitch_deg,
                "flutter_rotor_speed": self.flutter_speed,
                "flutter_rotor_speed_rpm": None if self.flutter_speed is None
                else self.flutter_speed * 30 / np.pi,
                "flutter_mode": self.flutter_mode,
                "flutter_frequency_hz": self.flutter_frequency_hz,
                "unstable_at_start": self.unstable_at_start,
                "rotor_speeds": [float(w) for w in c.speeds], "tracks": tracks,
                "settings": {k: v for k, v in c.settings.items() if k != "speeds"}}

    def to_json(self, indent=None) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def table(self) -> str:
        c = self.campbell
        rpm = c.speeds * 30 / np.pi
        lines = [f"{self.turbine} in {self.wind_speed:g} m/s wind, pitch {self.pitch_deg:.3g} "
                 f"deg: {len(c.speeds)} rotor speeds from {rpm[0]:.4g} to {rpm[-1]:.4g} rpm "
                 f"({c.settings.get('elements')} elements, {c.settings.get('method')}, "
                 "frozen-wake blade-element loads)"]
        if self.flutter_speed is None:
            lines.append("no mode loses its damping in the range")
        elif self.unstable_at_start:
            lines.append(f"{self.flutter_mode} is unstable already at {rpm[0]:.4g} rpm "
                         f"({self.flutter_frequency_hz:.4g} Hz): lower the first speed")
        else:
            lines.append(f"flutter at {self.flutter_speed * 30 / np.pi:.4g} rpm "
                         f"({self.flutter_speed:.4g} rad/s): {self.flutter_mode}, "
                         f"{self.flutter_frequency_hz:.4g} Hz")
        lines.append("damping ratios [-] of the least damped modes")
        order = sorted(c.tracks, key=lambda t: np.nanmin(t.damping_ratio))[:6]
        lines.append(f"{'rpm':>8} " + "".join(f"{t.label[:20]:>22}" for t in order))
        for i, n in enumerate(rpm):
            lines.append(f"{n:>8.3f} " + "".join(
                f"{t.damping_ratio[i]:>22.4f}" if np.isfinite(t.damping_ratio[i])
                else f"{'-':>22}" for t in order))
        lines.append(f"computed in {c.compute_time:.2f} s")
        return "\n".join(lines)

    def plot(self, path):
        """Frequency and damping of the tracked modes against rotor speed (PNG)."""
        return self.campbell.plot(path, tracks="all", frame="rotating")
