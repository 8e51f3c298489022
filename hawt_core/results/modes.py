"""Result types of the modal analyses: a Floquet mode of the whole turbine (Mode, with its
fixed-frame view for three or more blades) and the analysis result (ModalResult: table,
JSON, mode shapes, pictures); a mode of the clamped blade (BladeMode) and its result
(BladeModesResult).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional

import numpy as np

from ..model import order_text
from .tables import error_cell, error_note, format_table, mode_name, overdamped_pairs

if TYPE_CHECKING:
    from ..assembly.turbine import TurbineModel
    from ..fem.beam import BeamElements

__all__ = ['Mode', 'ModalResult', 'BladeMode', 'BladeModesResult', 'mode_shape']

#: Footer of a result whose turbine has aerodynamics the analysis does not use (yet).
VACUUM_NOTE = ("in a vacuum: the turbine's aerodynamics (blade and airfoil polars) are kept "
               "in the model but not used by this structural analysis (--wind U: in wind)")


def _of_order(settings: dict) -> str:
    """" of order p" for the p-version's elements (settings["order"] > 1), else ""."""
    return order_text(settings.get("order"))


@dataclass
class Mode:
    """One Floquet mode.  ``frequency_per_rev`` (and the other unprefixed fields) are the
    dominant frequency of the motion that names the mode, the paper's convention: the
    blades' deflection in the rotating frame for blade modes, the tower top or the yaw angle
    (fixed frame) for tower and yaw modes.  With three or more blades the fixed-frame view
    (multi-blade coordinates, as OpenFAST's MBC3 or HAWCStab2 report): ``fixed_frame_per_rev``
    / ``fixed_frame_hz`` / ``fixed_frame_damping_ratio`` of the dominant fixed-frame harmonic,
    ``whirl`` (collective, forward, backward, differential) and ``cyclic_order`` (k of the
    dominant cyclic pair cos k psi, sin k psi; 0 collective, Nb/2 differential); None for
    one- and two-bladed rotors."""

    family: str
    symmetry: Optional[str]
    index: int
    frequency_per_rev: float
    real_per_rev: float
    frequency_hz: float
    damping_ratio: float
    blade_phase_deg: Optional[float] = None
    fixed_frame_per_rev: Optional[float] = None
    fixed_frame_hz: Optional[float] = None
    fixed_frame_damping_ratio: Optional[float] = None
    whirl: Optional[str] = None
    cyclic_order: Optional[int] = None
    #: estimated relative discretization error of the frequency (hawt_core.analyses.accuracy;
    #: converged minus reported, over reported), None when not estimated
    frequency_error: Optional[float] = None
    participation: dict = field(default_factory=dict, repr=False)
    column: int = field(default=-1, repr=False)
    #: an overdamped mode (a real exponent in the rotating frame: aerodynamic damping beyond
    #: critical): "slow" or "fast" for the two real roots of a pair that share its index,
    #: "root" for one without its partner in the band; None for an oscillatory mode
    overdamped: Optional[str] = None
    #: in wind, a blade mode's structural origin: the vacuum mode of one blade on the hub
    #: spinning at the same speed whose shape its blades take most (analyses/blade_reference.py)
    #: that names it (family and index), and that share of the blades' motion (0 to 1);
    #: None in a vacuum and for the tower's, the rigid bodies' and the inflow's modes
    vacuum_family: Optional[str] = None
    vacuum_index: Optional[int] = None
    vacuum_share: Optional[float] = None
    #: k >= 2 for the k-th mode of one name (in wind: a mode whose blades move most like a
    #: vacuum mode that names a mode more like it already, analyses/labels.py
    #: name_after_vacuum); None for the first
    duplicate: Optional[int] = None
    #: in wind with the blades' aerodynamic states (Hill's modal basis): the share of the
    #: mode's participation those states hold (0 to 1; above 1/2 the mode is theirs,
    #: family "aerodynamic"); None where not computed
    aerodynamic_share: Optional[float] = None
    #: three or more blades: the blades' fixed-frame energy shares of each whirl class
    #: (collective, forward, backward, differential; sum 1) at the mode's fixed-frame
    #: frequency: a mode that mixes two (a collective and a backward-whirl lag mode coupled
    #: through the tower) shows it here; None for one- and two-bladed rotors
    whirl_shares: Optional[dict] = None
    #: the shares along every vacuum blade mode (the reference's order), for the naming
    vacuum_shares: Optional[np.ndarray] = field(default=None, repr=False, compare=False)

    @property
    def vacuum_mode(self) -> Optional[str]:
        """e.g. '1st torsion' (the vacuum blade mode that names this one), or None."""
        from .tables import ordinal
        if self.vacuum_family is None:
            return None
        return f"{ordinal(self.vacuum_index)} {self.vacuum_family}"

    @property
    def label(self) -> str:
        """e.g. 'flap 1 antisymmetric', 'teeter 1'."""
        return f"{self.family} {self.index} {self.symmetry or ''}".strip()

    def to_dict(self) -> dict:
        return {"family": self.family, "symmetry": self.symmetry, "index": self.index,
                "frequency_per_rev": self.frequency_per_rev, "real_per_rev": self.real_per_rev,
                "frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio,
                "blade_phase_deg": self.blade_phase_deg,
                "fixed_frame_per_rev": self.fixed_frame_per_rev,
                "fixed_frame_hz": self.fixed_frame_hz,
                "fixed_frame_damping_ratio": self.fixed_frame_damping_ratio,
                "whirl": self.whirl, "cyclic_order": self.cyclic_order,
                "frequency_error": self.frequency_error, "overdamped": self.overdamped,
                "vacuum_mode": self.vacuum_mode, "vacuum_share": self.vacuum_share,
                "duplicate": self.duplicate, "aerodynamic_share": self.aerodynamic_share,
                "whirl_shares": self.whirl_shares}


@dataclass
class ModalResult:
    """Result of :func:`modal_analysis`; ``modes`` sorted by frequency then real part."""

    modes: list
    settings: dict
    floquet: object = field(repr=False)
    model: TurbineModel = field(repr=False)
    steady: object = field(repr=False)
    unresolved: int = 0
    compute_time: float = 0.0
    timings: dict = field(default_factory=dict)

    @property
    def standstill(self) -> bool:
        """A standing rotor (rotor speed 0): no revolution, frequencies in Hz only."""
        return self.settings.get("method") == "standstill"

    def to_dict(self) -> dict:
        modes = [m.to_dict() for m in self.modes]
        if self.standstill:          # no per-rev without a revolution: Hz and the real part
            for d in modes:
                d["real_hz"] = d.pop("real_per_rev")
                d["frequency_per_rev"] = None
        return {"settings": self.settings, "modes": modes,
                "unresolved_modes": self.unresolved, "compute_time": self.compute_time}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), **kw)

    def find(self, family: str, symmetry: Optional[str] = None, index: int = 1) -> Mode:
        for m in self.modes:
            if m.family == family and m.index == index and (symmetry is None or m.symmetry == symmetry):
                return m
        raise KeyError(f"mode: no {family} {symmetry or ''} {index} in this result")

    def table(self) -> str:
        s = self.settings
        if self.standstill:
            how = "standing rotor: one eigenproblem about the static equilibrium"
        elif s["method"] in ("radau", "paper"):
            how = f"{s['method']}, {s['steps']} steps/period{', fast Floquet' if s['fast'] else ''}"
        elif s.get("frame") == "multi-blade" and not s.get("hill_harmonics"):
            how = "multi-blade coordinates, time-invariant: one eigenproblem"
        else:
            H = s.get("hill_harmonics", 0)
            how = (f"Hill's method, {s.get('frame', 'rotating')} frame, "
                   f"{H} harmonic{'' if H == 1 else 's'}")
            if s.get("hill_relative_change") is not None:
                # the exponents' move from one harmonic fewer: a bound on the truncation error
                how += f", truncation change {s['hill_relative_change']:.1e}"
        kind = "Modes" if self.standstill else "Dominant frequencies"
        header = (f"{kind} of the turbine '{s['turbine']}' ({'' if self.standstill else 'Floquet, '}{how}), "
                  f"{s['elements']} elements per blade{_of_order(s)}, rotor speed "
                  f"{s['rotor_speed']:.4g} rad/s")
        if s.get("wind_speed") is not None:
            header += (f", in wind {s['wind_speed']:.4g} m/s (pitch {s['pitch_deg']:.3g} deg; "
                       f"{s['aerodynamics']})")
        if s.get("structural_damping"):
            header += f"; {s['structural_damping']}"
        footer = []
        if self.unresolved:
            if s["method"] in ("radau", "paper"):
                footer.append(f"({self.unresolved} mesh modes above the temporal resolution "
                              f"{s['resolution_per_rev']:.0f} per-rev not shown: raise --steps)")
            else:
                unit = "Hz" if self.standstill else "per-rev"
                footer.append(f"({self.unresolved} modes above {s['resolution_per_rev']:g} "
                              f"{unit} not shown: raise --max-per-rev)")
        if s.get("error_estimate"):
            footer.append(error_note(s["error_estimate"], "elements per blade"))
        if s.get("in_vacuum"):
            footer.append(VACUUM_NOTE)
        # the blades' inflow and lag states' own (non-oscillatory) modes: counted, not listed
        aero = [m for m in self.modes if m.family == "aerodynamic"]
        if aero:
            w0 = s["rotor_speed"]
            decay = [-m.real_per_rev * w0 for m in aero]
            footer.append(f"({len(aero)} non-oscillatory modes of the blades' aerodynamic "
                          f"states (inflow, airfoil lag), decay rates {min(decay):.3g} to "
                          f"{max(decay):.3g} 1/s, not listed: --json has them)")
        w0 = s["rotor_speed"]
        for a, b, zeta, f0 in (overdamped_pairs(self.modes, w0) if w0 > 0 else ()):
            footer.append(f"({mode_name(a).split(' (')[0]}: overdamped, real roots "
                          f"{a.real_per_rev * w0:.4g} and {b.real_per_rev * w0:.4g} 1/s, damping "
                          f"ratio {zeta:.3g} of an undamped {f0:.4g} Hz)")
        footer.append(f"computed in {self.compute_time:.2f} s")
        return format_table(header, [m for m in self.modes if m.family != "aerodynamic"],
                            footer, unit="Hz" if self.standstill else "per-rev")

    def shape_samples(self, mode: Mode):
        """Periodic eigenvector of ``mode`` over one revolution: (times (M,), states (M, n)).

        Marching the real Floquet solution from x(0) would grow with exp(eta t); these are the
        periodic parts p(t) on every state row (complex), from the Floquet result samples.
        """
        fl = self.floquet
        rows = fl.sample_rows
        P = np.zeros((len(fl.sample_times), self.model.n), complex)
        P[:, rows] = fl.periodic_sample(mode.column)
        return fl.sample_times, P

    def plot(self, path, modes=None):
        """Mode-shape pictures (like the paper's Figs. 1-12) to a PNG file."""
        from .plotting import plot_turbine_modes
        return plot_turbine_modes(self, path, modes=modes)


def _json_number(x):
    x = float(x)
    return x if np.isfinite(x) else None


@dataclass
class BladeMode:
    """One mode of a blade clamped on the spinning hub. ``frequency_per_rev`` is None (NaN in memory) when not spinning."""

    family: str
    index: int
    frequency_per_rev: float
    frequency_hz: float
    damping_ratio: float
    eigenvalue: complex
    shape: dict = field(repr=False)
    #: estimated relative discretization error of the frequency, None when not estimated
    frequency_error: Optional[float] = None

    @property
    def frequency_rad_s(self) -> float:
        return float(self.eigenvalue.imag)

    def to_dict(self) -> dict:
        return {"family": self.family, "index": self.index,
                "frequency_per_rev": _json_number(self.frequency_per_rev),
                "frequency_hz": _json_number(self.frequency_hz),
                "damping_ratio": _json_number(self.damping_ratio),
                "frequency_error": self.frequency_error, "shape": self.shape}


@dataclass
class BladeModesResult:
    rotor_speed: float
    elements: int
    modes: list
    root_force: np.ndarray
    settings: dict

    def to_dict(self) -> dict:
        return {"settings": self.settings, "root_force": [float(f) for f in self.root_force],
                "modes": [m.to_dict() for m in self.modes]}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, **kw)

    def frequencies(self, family: Optional[str] = None) -> np.ndarray:
        """Frequencies [rad/s] of the modes (of one family), ascending."""
        return np.array([m.frequency_rad_s for m in self.modes
                         if family is None or m.family == family])

    def table(self) -> str:
        lines = [f"Blade modes, clamped on the hub at {self.rotor_speed:.4g} rad/s, "
                 f"{self.elements} elements{_of_order(self.settings)} "
                 f"({self.settings.get('method', '')})"
                 + (f"; {self.settings['structural_damping']}"
                    if self.settings.get("structural_damping") else ""),
                 f"{'mode':<16}{'per-rev':>12}{'Hz':>12}{'damping':>12}"
                 + (f"{'est. error':>12}" if self.estimated else "")]
        for m in self.modes:
            pr = (f"{m.frequency_per_rev:>12.5f}" if np.isfinite(m.frequency_per_rev)
                  else f"{'-':>12}")
            lines.append(f"{m.family + ' ' + str(m.index):<16}{pr}"
                         f"{m.frequency_hz:>12.5f}{m.damping_ratio:>12.2e}"
                         + (error_cell(m.frequency_error) if self.estimated else ""))
        if self.estimated:
            lines.append(error_note(self.settings["error_estimate"]))
        if self.settings.get("in_vacuum"):
            lines.append(VACUUM_NOTE)
        return "\n".join(lines)

    @property
    def estimated(self) -> bool:
        return bool(self.settings.get("error_estimate"))

    def plot(self, path, count: int = 6):
        """Mode shapes (flap u3, lead-lag u2, twist theta1 along the span) to a PNG file."""
        from .plotting import plot_blade_modes
        return plot_blade_modes(self, path, count=count)


def mode_shape(beam: BeamElements, x: np.ndarray) -> dict:
    """Real, normalized nodal shape of an eigenvector.

    ``span`` [m]; ``displacement`` u (N+1, 3) and ``rotation`` theta (N+1, 3) in the root
    frame b, scaled so that the largest of |u| and L |theta| is 1 (L the blade length, so that
    units do not decide) and turned to be real there; ``flap`` (u3), ``lag`` (u2) and
    ``twist`` (theta1) repeat the columns used for plotting.
    """
    u, th, _, _, _, _ = beam.nodal(x[None])
    u, th = u[0], th[0]
    L = beam.props.nodes[-1]
    z = np.concatenate([u.ravel(), L * th.ravel()])
    k = np.argmax(np.abs(z))
    phase = z[k] / abs(z[k]) if abs(z[k]) > 0 else 1.0
    scale = abs(z[k]) if abs(z[k]) > 0 else 1.0
    u = np.real(u / phase) / scale
    th = np.real(th / phase) / scale
    return {"span": beam.props.nodes.tolist(), "displacement": u.tolist(),
            "rotation": th.tolist(), "flap": u[:, 2].tolist(), "lag": u[:, 1].tolist(),
            "twist": th[:, 0].tolist()}
