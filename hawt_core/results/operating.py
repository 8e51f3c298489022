"""Aeroelastic operating points against wind speed (``hawt operating-points``)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["OperatingPoints", "POINT_KEYS"]

#: Keys of each point in the JSON, in order.
POINT_KEYS = ("wind_speed", "rotor_speed_rpm", "pitch_deg", "aero_power_kw",
              "generator_power_kw", "thrust_kn", "cp", "ct", "tip_flap_m", "tip_edge_m",
              "converged")


@dataclass
class OperatingPoints:
    """One dict per wind speed with POINT_KEYS (and ``region``: 2 below rated, 3 above);
    ``schedule``: the controller values used; ``settings``: the model's."""

    turbine: str
    points: list
    schedule: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    def column(self, key) -> np.ndarray:
        return np.array([np.nan if p[key] is None else p[key] for p in self.points],
                        dtype=float)

    def to_dict(self) -> dict:
        return {"turbine": self.turbine, "points": self.points, "schedule": self.schedule,
                "settings": self.settings}

    def to_json(self, indent=None) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def table(self) -> str:
        head = (f"{'wind m/s':>8s} {'rpm':>6s} {'pitch':>6s} {'P_aero kW':>9s} {'P_gen kW':>9s} "
                f"{'T kN':>7s} {'Cp':>6s} {'Ct':>6s} {'flap m':>7s} {'edge m':>7s}  ok")
        lines = [f"{self.turbine}: aeroelastic operating points ({self.settings.get('model')})",
                 head]
        formats = (("wind_speed", 8, ".3g"), ("rotor_speed_rpm", 6, ".3f"), ("pitch_deg", 6, ".2f"),
                   ("aero_power_kw", 9, ".1f"), ("generator_power_kw", 9, ".1f"),
                   ("thrust_kn", 7, ".1f"), ("cp", 6, ".3f"), ("ct", 6, ".3f"),
                   ("tip_flap_m", 7, ".3f"), ("tip_edge_m", 7, ".3f"))
        for p in self.points:
            cells = [f"{p[k]:{w}{f}}" if p[k] is not None else f"{'-':>{w}s}"
                     for k, w, f in formats]
            lines.append(" ".join(cells) + ("  yes" if p["converged"] else
                                            f"  NO: {p.get('error', '')}"))
        return "\n".join(lines)

    def plot(self, path) -> Path:
        """Rotor speed, pitch, power, thrust, Cp/Ct and tip deflection against wind speed."""
        from .plotting import _pyplot, save_png
        plt = _pyplot()
        U = self.column("wind_speed")
        fig, axes = plt.subplots(3, 2, figsize=(10, 8.5), sharex=True)
        panels = ((("rotor_speed_rpm", "rotor speed [rpm]"),), (("pitch_deg", "pitch [deg]"),),
                  (("aero_power_kw", "aerodynamic"), ("generator_power_kw", "generator")),
                  (("thrust_kn", "thrust [kN]"),), (("cp", "$C_p$"), ("ct", "$C_t$")),
                  (("tip_flap_m", "flap"), ("tip_edge_m", "edge")))
        ylabels = ("rotor speed [rpm]", "pitch [deg]", "power [kW]", "thrust [kN]",
                   "coefficient [-]", "tip deflection [m]")
        for ax, panel, ylabel in zip(axes.ravel(), panels, ylabels):
            for key, label in panel:
                ax.plot(U, self.column(key), "o-", ms=3, label=label)
            ax.set_ylabel(ylabel)
            ax.grid(True, alpha=0.3)
            if len(panel) > 1:
                ax.legend(fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("wind speed [m/s]")
        fig.suptitle(f"{self.turbine}: aeroelastic operating points", fontsize=11)
        fig.tight_layout()
        return save_png(fig, path)
