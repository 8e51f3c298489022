"""The generator torque of a free drivetrain, trimmed by the steady state (OpenFAST's
linearization with CalcSteady, TrimCase 2: the rotor held at its speed by a constant
generator torque found with the steady state).

A free generator (model.Drivetrain.generator "free") makes the gearbox-input azimuth a
degree of freedom.  In wind the rotor's mean aerodynamic torque accelerates it unless a
generator torque balances it; with the torque unknown the steady state is one more
unknown (the torque) and one more equation (the generator azimuth, ignorable, held at its
start).  The steady-state solvers pass them to Newton as a border
(numerics/newton.py ``border``): the column is the residual's derivative with respect to
the torque (it enters the generator-speed row only, linearly), and each step's multiplier
updates the torque.  The model keeps the trimmed torque in its controls
(rigid.actuators.ControlInputs), so the linearization about that steady state holds the
torque constant, as OpenFAST's does.

A model with its controls already set (the closed loop: the controller's torque) is not
trimmed; neither is one whose generator turns at the prescribed speed.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..rigid.actuators import ControlInputs

__all__ = ["GeneratorTrim", "generator_trim"]


class GeneratorTrim:
    """The torque unknown of a model's steady state: ``index`` of the generator azimuth in
    the unknowns, ``torque`` [N m, HSS] (the current value; the model's controls hold it)."""

    def __init__(self, model, index: int):
        self.index = int(index)
        self.controls = ControlInputs(model.n_blades, pitch=-float(model.turbine.rotor.pitch),
                                      torque=0.0)
        model.set_controls(self.controls)

    @property
    def torque(self) -> float:
        return float(self.controls.generator_torque(0.0))

    def set(self, torque: float) -> None:
        self.controls.hold_torque(float(torque))

    def update(self, mu: float) -> None:
        """Newton's border multiplier: the torque moves by ``-mu``."""
        self.set(self.torque - float(mu))

    def column(self, residual, y) -> np.ndarray:
        """d(residual)/d(torque) at ``y`` (exact: the torque enters linearly)."""
        t0 = self.torque
        r0 = residual(y)
        self.set(t0 + 1.0)
        r1 = residual(y)
        self.set(t0)
        return r1 - r0

    def border(self, fixed, residual, y):
        """(fixed, border) for Newton: the held unknowns ``fixed`` with the generator
        azimuth added (in gravity or shear it is not ignorable, but a constant shift of it
        is a shift of the periodic solution in time: held, it fixes the phase), and the
        torque's border on it."""
        fixed = np.asarray(fixed, int)
        if self.index not in fixed:
            fixed = np.sort(np.append(fixed, self.index))
        j = int(np.flatnonzero(fixed == self.index)[0])
        return fixed, {j: (self.column(residual, y), self.update)}


def generator_trim(model) -> Optional[GeneratorTrim]:
    """A GeneratorTrim when ``model`` (a TurbineModel) has a free generator whose torque
    is to be trimmed (in wind, no controls of its own), else None.  Idempotent: the trim
    already set up is returned (the model's ``generator_trim``)."""
    existing = getattr(model, "generator_trim", None)
    if existing is not None:
        return existing
    rigid = getattr(model, "rigid", None)
    if rigid is None or not getattr(rigid, "generator_free", False):
        return None
    if getattr(model, "aero", None) is None or rigid.controls is not None:
        return None
    trim = GeneratorTrim(model, model.layout["generator_azimuth"])
    model.generator_trim = trim
    return trim
