"""Names for the turbine state vector: the rigid unknowns, then each blade's beam block (and
its aerodynamic states, in wind with dynamic inflow or unsteady airfoils), then the tower's
(docs/ARCHITECTURE.md, "Turbine state layout").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..fem.beam import BLOCK_SIZE, ROOT_SIZE, BeamElements, F_, M_, OM_, TH_, U_, V_
from ..rigid import RigidSystem

__all__ = ['BladeLayout', 'StateLayout']


@dataclass(frozen=True)
class BladeLayout:
    """Index arrays of one blade's unknowns in the turbine state vector.

    ``u``, ``theta``: (N+1, 3), row 0 is -1 (clamped root, not an unknown);
    ``V``, ``Omega``: (N+1, 3); ``F``, ``M``: (N, 3); ``root_force``, ``root_moment``: (3,).
    """

    u: np.ndarray
    theta: np.ndarray
    V: np.ndarray
    Omega: np.ndarray
    F: np.ndarray
    M: np.ndarray
    root_force: np.ndarray
    root_moment: np.ndarray


class StateLayout:
    """Names for the turbine state vector: ``layout["teeter"]`` (an int index),
    ``layout.blade(k)`` (a BladeLayout), ``layout.names()`` (one name per unknown)."""

    def __init__(self, rigid: RigidSystem, n_blades: int, beam: BeamElements,
                 tower: Optional[BeamElements] = None, aero_states: tuple = ()):
        self.rigid_names = tuple(rigid.coordinates) + tuple(rigid.speeds)
        self.n_rigid = len(self.rigid_names)
        self.n_blades = n_blades
        self.n_beam = beam.n
        self.N = beam.N
        #: the aerodynamic unknowns per Gauss point after each blade's beam unknowns
        #: (assembly/rotor_aero.py: state-major over (element, Gauss point))
        self.aero_states = tuple(aero_states)
        self.gauss = beam.xg.shape[1]
        self.n_aero = len(self.aero_states) * beam.N * self.gauss
        #: unknowns per blade
        self.blade_size = beam.n + self.n_aero
        self.n = self.n_rigid + n_blades * self.blade_size
        #: offset of the tower unknowns (after the blades), None for a rigid tower
        self.tower_offset = self.n if tower is not None else None
        self.n_tower = tower.n if tower is not None else 0
        self.N_tower = tower.N if tower is not None else 0
        self.n += self.n_tower
        self._index = {name: i for i, name in enumerate(self.rigid_names)}
        if "teeter_speed" in self._index:   # the name simulate's perturbations use
            self._index["teeter_rate"] = self._index["teeter_speed"]
        self._blades = [self._blade_layout(k) for k in range(n_blades)]
        self._tower = (self._blade_layout(None) if tower is not None else None)

    @property
    def has_tower(self) -> bool:
        """Whether the tower is flexible (its unknowns follow the last blade)."""
        return self._tower is not None

    def tower(self) -> BladeLayout:
        """Index arrays of the flexible tower's unknowns (BladeLayout fields; ``u``,
        ``theta`` in the inertial tower root frame t: t1 up, t2 lateral, t3 downwind;
        ``root_force``/``root_moment``: the loads the tower exerts on the ground)."""
        if self._tower is None:
            raise ValueError("tower: this turbine's tower is rigid (no tower unknowns)")
        return self._tower

    def _blade_layout(self, k) -> BladeLayout:
        if k is None:   # the tower
            off, N = self.tower_offset, self.N_tower
        else:
            off, N = self.blade_offset(k), self.N
        blk = off + ROOT_SIZE + np.arange(N * BLOCK_SIZE).reshape(N, BLOCK_SIZE)
        neg = -np.ones((1, 3), int)
        return BladeLayout(
            u=np.concatenate([neg, blk[:, U_]]), theta=np.concatenate([neg, blk[:, TH_]]),
            V=np.concatenate([off + 6 + np.arange(3)[None], blk[:, V_]]),
            Omega=np.concatenate([off + 9 + np.arange(3)[None], blk[:, OM_]]),
            F=blk[:, F_], M=blk[:, M_], root_force=off + np.arange(3),
            root_moment=off + 3 + np.arange(3))

    def blade_offset(self, k: int) -> int:
        """Index of blade k's first unknown (its root force)."""
        return self.n_rigid + k * self.blade_size

    def aero_states_of(self, k: int, name: str) -> np.ndarray:
        """Indices (N, G) of blade k's aerodynamic unknown ``name`` at its elements' Gauss
        points."""
        if name not in self.aero_states:
            raise KeyError(f"aerodynamic state: {name!r} is not in this model; available: "
                           f"{list(self.aero_states)}")
        j = self.aero_states.index(name)
        start = self.blade_offset(k) + self.n_beam + j * self.N * self.gauss
        return start + np.arange(self.N * self.gauss).reshape(self.N, self.gauss)

    def blade(self, k: int) -> BladeLayout:
        """Index arrays of blade k's unknowns (u, theta in its root frame b; V, Omega, F, M
        in the deformed section frames; the root loads on the hub in frame b)."""
        if not 0 <= k < self.n_blades:
            raise IndexError(f"blade: {k} is not allowed; this turbine has blades 0..{self.n_blades - 1}")
        return self._blades[k]

    def __contains__(self, name: str) -> bool:
        return name in self._index

    def __getitem__(self, name: str) -> int:
        try:
            return self._index[name]
        except KeyError:
            raise KeyError(f"state name: {name!r} is not in this model; available: "
                           f"{sorted(self._index)}") from None

    def names(self) -> list:
        """Name of every unknown in order, e.g. ``yaw``, ``blade0.root_force.1``, ``blade0.u[1].3``."""
        out = list(self.rigid_names)
        for k in range(self.n_blades):
            out += self._beam_names(self._blades[k], self.blade_offset(k), self.n_beam,
                                    f"blade{k}")
            out += [f"blade{k}.aero.{name}[{e + 1}].{g + 1}" for name in self.aero_states
                    for e in range(self.N) for g in range(self.gauss)]
        if self._tower is not None:
            out += self._beam_names(self._tower, self.tower_offset, self.n_tower, "tower")
        return out

    @staticmethod
    def _beam_names(bl, off, n, prefix):
        loc = [""] * n
        for field in ("u", "theta", "V", "Omega", "F", "M"):
            for i, row in enumerate(getattr(bl, field)):
                for c, j in enumerate(row):
                    if j >= 0:
                        lbl = f"{field}[{i + (field in ('F', 'M'))}]"
                        loc[j - off] = f"{prefix}.{lbl}.{c + 1}"
        for c in range(3):
            loc[c] = f"{prefix}.root_force.{c + 1}"
            loc[3 + c] = f"{prefix}.root_moment.{c + 1}"
        return loc
