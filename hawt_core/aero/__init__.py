"""Aerodynamics: the wind (wind: shear, misalignment, tower shadow, steps, ramps, the IEC
gust), airfoil coefficients (polars), blade-element momentum theory (bem), dynamic inflow
(inflow: Oye's filter), the unsteady attached-flow airfoil (unsteady: Theodorsen's loads,
Wagner's lag as states)."""
from .inflow import OYE_K, oye_rates, oye_steady, oye_time_constants
from .wind import ExtremeOperatingGust, Wind
from .bem import BemRotor, BemSolution, axial_induction, momentum_thrust
from .polars import AirfoilCurves, HermiteTable, StationPolars
from .unsteady import JONES, QUASI_STEADY, IndicialLag, downwash_34, thin_airfoil_loads

__all__ = ["BemRotor", "BemSolution", "axial_induction", "momentum_thrust", "AirfoilCurves",
           "HermiteTable", "StationPolars", "JONES", "QUASI_STEADY", "IndicialLag",
           "downwash_34", "thin_airfoil_loads", "OYE_K", "oye_rates", "oye_steady",
           "oye_time_constants", "ExtremeOperatingGust", "Wind"]
