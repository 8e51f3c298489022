"""Result types of a Campbell sweep: one Track per mode followed over the rotor speeds, in
both frames, and the CampbellResult (table, CSV, plot).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

__all__ = ['CSV_COLUMNS', 'FRAMES', 'Track', 'CampbellResult']


CSV_COLUMNS = ("speed_rad_s", "speed_rpm", "track", "family", "symmetry", "index",
               "frequency_per_rev", "frequency_hz", "real_per_rev", "damping_ratio", "mac",
               "harmonic_shift", "continuous_hz", "fixed_frame_per_rev", "fixed_frame_hz",
               "fixed_frame_damping_ratio", "whirl", "frame", "point_label")


FRAMES = ("fixed", "rotating")

# ---------------------------------------------------------------------------- result
@dataclass
class Track:
    """One mode followed over the speeds; arrays have one entry per speed (NaN where the mode
    was not found, e.g. above the band at that speed).  ``frequency_*``, ``real_per_rev``,
    ``damping_ratio``: the mode's dominant (rotating-frame for blade modes) values;
    ``fixed_frame_*``: the fixed-frame ones (three or more blades; NaN otherwise)."""

    label: str
    family: str
    symmetry: Optional[str]
    index: int
    frequency_per_rev: np.ndarray
    frequency_hz: np.ndarray
    real_per_rev: np.ndarray
    damping_ratio: np.ndarray
    mac: np.ndarray = field(repr=False)
    #: integer per-rev added to the dominant frequency for a continuous curve (the harmonic
    #: re-indexing found by the MAC, or :func:`unwrap_harmonics`); NaN where absent
    shift: np.ndarray = field(repr=False)
    #: frequency_per_rev + shift, and the same in Hz (continuous_per_rev times the speed in
    #: rev/s): the rotating-frame curve of the Campbell plot and table
    continuous_per_rev: np.ndarray = field(repr=False)
    continuous_hz: np.ndarray = field(repr=False)
    fixed_frame_per_rev: Optional[np.ndarray] = field(default=None, repr=False)
    fixed_frame_hz: Optional[np.ndarray] = field(default=None, repr=False)
    fixed_frame_damping_ratio: Optional[np.ndarray] = field(default=None, repr=False)
    #: fixed-frame curve (fixed_frame_per_rev + shift, in Hz)
    fixed_continuous_hz: Optional[np.ndarray] = field(default=None, repr=False)
    whirl: Optional[str] = None
    #: label of the other member of a real exponent pair with the same frequency (the plot
    #: draws that frequency once); None otherwise
    twin: Optional[str] = None
    #: the whole per-rev added to the fixed-frame frequency for its continuous curve (the
    #: fixed frame is unwrapped on its own values); None: ``shift``
    fixed_shift: Optional[np.ndarray] = field(default=None, repr=False)
    #: the name each point gives its own mode (mode_label; None where the track is absent):
    #: where it differs from ``label`` the mode changes character along the sweep
    names: Optional[list] = field(default=None, repr=False)

    def frame_shift(self, frame: str = "rotating") -> np.ndarray:
        """The per-rev shifts of the continuous curve in ``frame`` (circled in the plot)."""
        if frame == "fixed" and self.fixed_shift is not None:
            return self.fixed_shift
        return self.shift

    def present(self) -> np.ndarray:
        return np.isfinite(self.frequency_hz)

    def hz(self, frame: str = "rotating") -> np.ndarray:
        """The continuous frequency [Hz] in ``frame`` ("fixed" needs fixed-frame values)."""
        if frame == "fixed":
            if self.fixed_continuous_hz is None:
                raise ValueError("frame: 'fixed' is not allowed for this rotor (fewer than "
                                 "three blades); use 'rotating'")
            return self.fixed_continuous_hz
        return self.continuous_hz

    def damping(self, frame: str = "rotating") -> np.ndarray:
        """Damping ratios in ``frame`` (they differ where the frequencies do)."""
        if frame == "fixed":
            return self.fixed_frame_damping_ratio
        return self.damping_ratio


@dataclass
class CampbellResult:
    """Result of :func:`campbell`: ``speeds`` [rad/s] ascending, ``tracks`` (Track list in the
    order of their first-speed frequencies), ``points`` (the raw per-speed outputs),
    ``frame`` ("fixed" or "rotating": what the table and plot show)."""

    speeds: np.ndarray
    tracks: list
    points: list = field(repr=False)
    settings: dict = field(default_factory=dict)
    compute_time: float = 0.0
    frame: str = "rotating"
    #: a sweep in wind (analyses/campbell.campbell_in_wind): the wind speed [m/s] of every
    #: point (``speeds`` are then the operating points' rotor speeds); None: a rotor-speed sweep
    wind_speeds: Optional[np.ndarray] = None

    @property
    def columns(self) -> tuple:
        """The CSV columns (CSV_COLUMNS, and the wind speed and pitch of a sweep in wind)."""
        return CSV_COLUMNS + (("wind_speed_m_s", "pitch_deg") if self.wind_speeds is not None
                              else ())

    @property
    def failed(self) -> list:
        """(speed, error message) of the speeds whose analysis failed."""
        return [(p["speed"], p["error"]) for p in self.points if p.get("error")]

    @property
    def rpm(self) -> np.ndarray:
        return self.speeds * 60.0 / (2.0 * np.pi)

    def track(self, label: str) -> Track:
        for t in self.tracks:
            if t.label == label:
                return t
        raise KeyError(f"campbell: no track labelled {label!r}")

    def rows(self) -> list:
        """One dict per (speed, track) where the track has a mode, in speed order."""
        out = []
        nan = float("nan")
        for i, (w, n) in enumerate(zip(self.speeds, self.rpm)):
            for t in self.tracks:
                if not np.isfinite(t.frequency_hz[i]):
                    continue
                fixed = t.fixed_frame_hz is not None
                out.append({"speed_rad_s": float(w), "speed_rpm": float(n), "track": t.label,
                            "family": t.family, "symmetry": t.symmetry or "",
                            "index": t.index,
                            "frequency_per_rev": float(t.frequency_per_rev[i]),
                            "frequency_hz": float(t.frequency_hz[i]),
                            "real_per_rev": float(t.real_per_rev[i]),
                            "damping_ratio": float(t.damping_ratio[i]),
                            "mac": float(t.mac[i]), "harmonic_shift": int(t.shift[i]),
                            "continuous_hz": float(t.continuous_hz[i]),
                            "fixed_frame_per_rev": float(t.fixed_frame_per_rev[i]) if fixed else nan,
                            "fixed_frame_hz": float(t.fixed_continuous_hz[i]) if fixed else nan,
                            "fixed_frame_damping_ratio":
                                float(t.fixed_frame_damping_ratio[i]) if fixed else nan,
                            "whirl": t.whirl or "", "frame": self.frame,
                            "point_label": (t.names[i] or "") if t.names else ""})
                if self.wind_speeds is not None:
                    out[-1]["wind_speed_m_s"] = float(self.wind_speeds[i])
                    out[-1]["pitch_deg"] = float(self.settings["pitch_deg"][i])
        return out

    def to_csv(self, path) -> str:
        """Write the CSV (header + one row per speed and track); returns the path."""
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(self.columns))
            w.writeheader()
            for r in self.rows():
                w.writerow({k: (f"{v:.12g}" if isinstance(v, float) else v) for k, v in r.items()})
        return str(path)

    def plot(self, path, max_hz: Optional[float] = None, tracks="table2",
             frame: Optional[str] = None):
        """Campbell diagram (frequency [Hz] vs rotor speed [rpm], 1P..nP rays) and the damping
        ratios, to a PNG file; ``tracks``: "table2" (default), "all" or a list of labels;
        ``frame``: "fixed" or "rotating" (default: the result's)."""
        from .plotting import plot_campbell
        return plot_campbell(self, path, max_hz=max_hz, tracks=tracks,
                             frame=frame or self.frame)

    def table(self) -> str:
        """The frequencies [Hz] the plot draws (the continuous ones, in the result's frame)."""
        lines = [f"Campbell diagram of '{self.settings.get('turbine', '')}': "
                 f"{len(self.speeds)} speeds, {self.settings.get('elements')} elements, "
                 f"{self.settings.get('method')}; {self.frame}-frame frequencies [Hz]"]
        wind = self.wind_speeds is not None
        head = (f"{'m/s':>7}" if wind else "") + f"{'rad/s':>8}{'rpm':>8} " + \
            "".join(f"{t.label[:14]:>15}" for t in self.tracks)
        lines.append(head)
        curves = [t.hz(self.frame) for t in self.tracks]
        for i, (w, n) in enumerate(zip(self.speeds, self.rpm)):
            vals = "".join(f"{c[i]:>15.4f}" if np.isfinite(c[i]) else f"{'-':>15}"
                           for c in curves)
            lines.append((f"{self.wind_speeds[i]:>7.2f}" if wind else "")
                         + f"{w:>8.3f}{n:>8.2f} {vals}")
        if wind:
            lines.append("damping ratios [-]")
            lines.append(head)
            for i, (w, n) in enumerate(zip(self.speeds, self.rpm)):
                vals = "".join(f"{d[i]:>15.4f}" if np.isfinite(d[i]) else f"{'-':>15}"
                               for d in (t.damping(self.frame) for t in self.tracks))
                lines.append(f"{self.wind_speeds[i]:>7.2f}{w:>8.3f}{n:>8.2f} {vals}")
        for w, msg in self.failed:
            lines.append(f"analysis failed at {w:.4g} rad/s: {msg}")
        warned = [f"{p['speed']:.4g}" for p in self.points if p.get("warnings")]
        if warned:
            lines.append(f"warnings from the Floquet analysis at {len(warned)} speed(s) "
                         f"({', '.join(warned)} rad/s): see points[i]['warnings']")
        lines.append(f"computed in {self.compute_time:.2f} s")
        return "\n".join(lines)
