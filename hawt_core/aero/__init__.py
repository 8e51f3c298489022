"""Aerodynamics: airfoil coefficients (polars), blade-element momentum theory (bem), the
unsteady attached-flow airfoil (unsteady: Theodorsen's loads, Wagner's lag as states)."""
from .bem import BemRotor, BemSolution, axial_induction, momentum_thrust
from .polars import AirfoilCurves, HermiteTable, StationPolars
from .unsteady import JONES, QUASI_STEADY, IndicialLag, downwash_34, thin_airfoil_loads

__all__ = ["BemRotor", "BemSolution", "axial_induction", "momentum_thrust", "AirfoilCurves",
           "HermiteTable", "StationPolars", "JONES", "QUASI_STEADY", "IndicialLag",
           "downwash_34", "thin_airfoil_loads"]
