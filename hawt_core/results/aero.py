"""The rigid rotor's aerodynamic coefficient surfaces (``hawt aero-table``): Cp, Ct, Cq against
tip-speed ratio and collective pitch, as JSON, as ROSCO's ``Cp_Ct_Cq`` text file (what
ROSCO's tuning and its DISCON controller's wind-speed estimator read) and as a picture.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["AeroTable"]


@dataclass
class AeroTable:
    """``tsr`` (n,) [-], ``pitch_deg`` (m,) [deg, towards feather]; ``cp``, ``ct``, ``cq``
    (n, m) indexed [tsr][pitch]; ``wind_speed`` [m/s] of the evaluation; ``residual`` (n, m):
    the largest BEM residual over the stations (convergence); ``settings``: the model
    options."""

    turbine: str
    tsr: np.ndarray
    pitch_deg: np.ndarray
    cp: np.ndarray
    ct: np.ndarray
    cq: np.ndarray
    wind_speed: float
    residual: np.ndarray
    settings: dict = field(default_factory=dict)

    def optimum(self) -> dict:
        """The largest Cp of the grid and where it is (tsr, pitch_deg)."""
        i, j = np.unravel_index(int(np.argmax(self.cp)), self.cp.shape)
        return {"cp": float(self.cp[i, j]), "tsr": float(self.tsr[i]),
                "pitch_deg": float(self.pitch_deg[j]), "ct": float(self.ct[i, j])}

    def to_dict(self) -> dict:
        return {"turbine": self.turbine, "wind_speed": self.wind_speed,
                "tsr": self.tsr.tolist(), "pitch_deg": self.pitch_deg.tolist(),
                "cp": self.cp.tolist(), "ct": self.ct.tolist(), "cq": self.cq.tolist(),
                "optimum": self.optimum(), "max_residual": float(np.max(self.residual)),
                "settings": dict(self.settings)}

    def to_json(self, indent=None) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def save_rosco(self, path) -> Path:
        """ROSCO's rotor-performance text file (rosco.toolbox.utilities.
        write_rotor_performance's layout: pitch vector [deg], TSR vector, wind speed, then
        the Cp, Ct and Cq matrices, rows = TSR, columns = pitch)."""
        path = Path(path)
        lines = [f"# ----- Rotor performance tables for the {self.turbine} wind turbine ----- ",
                 f"# ------------ Written on {time.strftime('%b-%d-%y')} using hawt "
                 "aero-table ------------ ", "",
                 f"# Pitch angle vector, {self.pitch_deg.size} entries - x axis (matrix "
                 "columns) (deg)",
                 "   ".join(f"{p:.4g}" for p in self.pitch_deg),
                 f"# TSR vector, {self.tsr.size} entries - y axis (matrix rows) (-)",
                 "    ".join(f"{t:.4g}" for t in self.tsr),
                 "# Wind speed vector - z axis (m/s)", f"{self.wind_speed:.4g}", ""]
        for title, table in (("# Power coefficient", self.cp), ("#  Thrust coefficient",
                                                                 self.ct),
                             ("# Torque coefficient", self.cq)):
            lines += [title, ""]
            lines += ["   ".join(f"{v:.6f}" for v in row) for row in table]
            lines += ["", ""]
        path.write_text("\n".join(lines))
        return path

    def plot(self, path) -> Path:
        """Cp and Ct contours against tip-speed ratio and pitch, the optimum marked."""
        from .plotting import _pyplot, save_png
        plt = _pyplot()
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), sharey=True)
        P, T = np.meshgrid(self.pitch_deg, self.tsr)
        opt = self.optimum()
        for ax, data, name, levels in (
                (axes[0], self.cp, "$C_p$", np.linspace(0.0, max(0.05, self.cp.max()), 12)),
                (axes[1], self.ct, "$C_t$", np.linspace(0.0, max(0.05, self.ct.max()), 12))):
            filled = ax.contourf(P, T, np.maximum(data, 0.0), levels=levels, cmap="viridis")
            lines = ax.contour(P, T, data, levels=levels[1::2], colors="white",
                               linewidths=0.5)
            ax.clabel(lines, fontsize=7, fmt="%.2f")
            fig.colorbar(filled, ax=ax, label=name)
            ax.plot(opt["pitch_deg"], opt["tsr"], "r*", ms=12,
                    label=f"max $C_p$ {opt['cp']:.3f} at TSR {opt['tsr']:.3g}, "
                          f"pitch {opt['pitch_deg']:.3g} deg")
            ax.set_xlabel("collective pitch [deg, towards feather]")
            ax.set_title(f"{name} of the rigid rotor (BEM)")
        axes[0].set_ylabel("tip-speed ratio [-]")
        axes[0].legend(fontsize=8, loc="upper right")
        fig.suptitle(f"{self.turbine}: aerodynamic coefficients", fontsize=11)
        fig.tight_layout()
        return save_png(fig, path)

