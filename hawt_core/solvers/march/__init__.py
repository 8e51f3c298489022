"""Nonlinear time simulation by the implicit midpoint rule ("finite elements in time"): the
initial state, the step solver and the time-parallel window solver (docs/simulation.md)."""
from .initial import NAMED, PERTURBABLE, consistent_state, parse_perturb
from .simulator import SimulationError, Simulator

__all__ = ["Simulator", "SimulationError", "NAMED", "PERTURBABLE", "consistent_state",
           "parse_perturb"]
