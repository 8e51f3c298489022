"""What the readers of other tools' files share: the import result with its provenance, the
mesh of imported beams, and the IEC blade section frame (BeamDyn's, WindIO's) in hawt's.

Readers: :mod:`hawt_core.io.openfast` (OpenFAST decks) and :mod:`hawt_core.io.windio`
(WindIO turbine files).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np

__all__ = ["ImportResult", "ELEMENTS", "IEC_TO_HAWT", "package_version",
           "iec_axes_to_hawt", "untwist_sections", "sections_from_matrices",
           "interp_stations", "hub_yaw_share", "BladeAxis"]


def package_version(dist: str) -> str:
    """Installed version of a distribution, ``"unknown"`` when it is not installed."""
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "unknown"


#: The mesh of an imported blade and tower (hawt files must name it): elements of the
#: p-version of the paper's mixed element (fem/spectral.py).  3 blade elements of order 6 put
#: the first six frequencies of the NREL 5-MW and IEA 15-MW blades at 0 and rated rpm within
#: 8e-5 of converged (64 of the paper's element: 1.7e-3, bench/discretization.py), and the
#: steady tip deflection within 2e-4 (bench/live_default.py); 2 tower elements of order 4 put
#: the first four tower frequencies within 2e-6 (16 paper elements: 4.7e-3).
ELEMENTS = {"blade": {"elements": 3, "order": 6}, "tower": {"elements": 2, "order": 4}}

#: The IEC blade section frame (x flapwise towards the suction side / the tower of an
#: upwind rotor, y chordwise towards the trailing edge, z along the span), in which BeamDyn
#: and WindIO give section matrices -> hawt's blade frame (b1 span, b2 towards the leading
#: edge = the direction of motion, b3 flapwise downwind): rows are hawt axes, so
#: (b1, b2, b3) = (z, -y, x).
IEC_TO_HAWT = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])


def iec_axes_to_hawt(A: np.ndarray) -> np.ndarray:
    """Section matrices (ns, 6, 6) (stiffness or mass) with their axes renamed from the IEC
    section frame to hawt's (b1, b2, b3) = (z, -y, x); still in the twisted section frame."""
    T = np.zeros((6, 6))
    T[:3, :3] = T[3:, 3:] = IEC_TO_HAWT
    return T @ np.asarray(A, float) @ T.T


def untwist_sections(A: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """Section matrices (ns, 6, 6) in the twisted section frame -> hawt's untwisted blade
    frame b: R6 A R6^T with R6 = diag(R, R), R = rot1(twist) per station.  ``twist`` [rad]
    is hawt's (positive from b2 towards b3; BeamDyn's initial twist and WindIO's twist,
    positive towards feather, are minus it)."""
    from ..numerics.rotations import rot1

    R6 = np.zeros(np.shape(A))
    R6[:, :3, :3] = R6[:, 3:, 3:] = rot1(np.asarray(twist, float))
    return R6 @ A @ np.swapaxes(R6, -1, -2)


def interp_stations(x, xp, fp) -> np.ndarray:
    """Linear interpolation of per-station arrays ``fp`` (len(xp), ...) to the stations x."""
    fp = np.asarray(fp, float)
    flat = fp.reshape(len(xp), -1)
    return np.stack([np.interp(x, xp, flat[:, j]) for j in range(flat.shape[1])],
                    -1).reshape((len(x),) + fp.shape[1:])


def hub_yaw_share(hub, tilt: float, along: float) -> float:
    """The hub's inertia about the yaw axis [kg m^2], which hawt's nacelle yaw inertia
    includes (hawt_core.rigid.kane): its lateral and longitudinal inertias on a shaft tilted
    by ``tilt`` [rad], and its mass at ``along`` [m] from the yaw axis along the shaft."""
    ct, st = np.cos(tilt), np.sin(tilt)
    return float(hub.inertia_lateral * ct ** 2 + hub.inertia_longitudinal * st ** 2
                 + hub.mass * (along * ct) ** 2)


class BladeAxis:
    """A blade's reference axis from another tool's file, in hawt's blade axes.

    ``points`` (K, 3): the axis in the IEC blade frame (x towards the suction side, i.e.
    downwind; y towards the trailing edge; z along the pitch axis), root first;
    ``parameter`` (K,): the coordinate the file's section stations refer to at those
    points, 0 at the root and 1 at the tip.
    hawt's blade frame has b1 = z, b2 = -y, b3 = x (IEC_TO_HAWT), so the prebend (along b3)
    is x and the sweep (along b2) is -y, both from the root point.
    """

    def __init__(self, points, parameter):
        p = np.asarray(points, float)
        self.points = (p - p[0]) @ IEC_TO_HAWT.T
        self.parameter = np.asarray(parameter, float)
        #: span along b1 [m]
        self.length = float(self.points[-1, 0])
        #: largest offset of the axis from the straight b1 line [m] (0: straight)
        self.bend = float(np.abs(self.points[:, 1:]).max())

    def stations(self, s):
        """hawt's station fractions (of the span along b1) and the sweep and prebend [m]
        (None, None for a straight axis) at the file's station coordinates ``s``: PCHIP
        along the axis (as WindIO asks), so the line between its points stays smooth and
        never overshoots."""
        from scipy.interpolate import PchipInterpolator

        s = np.asarray(s, float)
        if len(self.parameter) > 2:
            at = PchipInterpolator(self.parameter, self.points, axis=0)(s)
        else:
            at = np.stack([np.interp(s, self.parameter, self.points[:, j])
                           for j in range(3)], -1)
        if np.allclose(self.points[:, 0] / self.length, self.parameter, rtol=0, atol=1e-14):
            span = s.copy()        # the parameter is the span fraction: exactly the file's
        else:
            span = at[:, 0] / self.length
            span[s <= self.parameter[0]] = 0.0      # root and tip exactly (the end stations
            span[s >= self.parameter[-1]] = 1.0     # of the format), not to round-off
        if self.bend == 0:
            return span, None, None
        return span, at[:, 1], at[:, 2]


def sections_from_matrices(stations, K: np.ndarray, M: np.ndarray, prebend=None,
                           sweep=None):
    """A SectionTable from full 6x6 stiffness and mass matrices in hawt's untwisted blade
    frame (the scalar properties are their diagonals, as the turbine loader derives them),
    with the reference line's ``prebend`` and ``sweep`` [m] (None: straight)."""
    from ..model import SectionTable

    return SectionTable(stations=stations, mass=M[:, 0, 0], i1=M[:, 3, 3], i2=M[:, 4, 4],
                        i3=M[:, 5, 5], ea=K[:, 0, 0], ga2=K[:, 1, 1], ga3=K[:, 2, 2],
                        gj=K[:, 3, 3], ei2=K[:, 4, 4], ei3=K[:, 5, 5],
                        stiffness_6x6=K, mass_6x6=M, prebend=prebend, sweep=sweep)


@dataclass
class ImportResult:
    """A turbine read from another tool's files, with what the reader had to say about it.

    ``warnings``: data read but not modelled, or estimated (each names the file and key);
    ``notes``: what was taken from where; ``sources``: the files read, by role (the main
    file under ``main_role``); ``importer``: the reader and the library it runs on;
    ``packages``: distribution whose installed data files are named by it in the header
    (the folder inside site-packages -> the distribution, e.g. ``Examples`` -> ``rosco``).
    """

    turbine: object
    importer: str
    main_role: str
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    sources: dict = field(default_factory=dict)
    packages: dict = field(default_factory=dict)

    def header(self) -> str:
        """Provenance lines for a converted file's header comment."""
        main = Path(self.sources.get(self.main_role, "?"))
        shown = str(main)
        if "site-packages" in main.parts:          # a file from an installed wheel
            rel = main.parts[main.parts.index("site-packages") + 1:]
            shown = f"<site-packages>/{'/'.join(rel)}"
            if rel and rel[0] in self.packages:
                dist = self.packages[rel[0]]
                shown += f" (installed by {dist} {package_version(dist)})"
        lines = [f"Converted by {self.importer} from {shown}"]
        lines += [f"  {role}: {os.path.relpath(path, main.parent)}"
                  for role, path in self.sources.items() if role != self.main_role]
        lines += [f"note: {n}" for n in self.notes]
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)
