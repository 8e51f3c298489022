"""Turbine files: reading, validating and writing the YAML turbine description."""
from .turbine_writer import dump_turbine, turbines_equal
from .turbine_yaml import (
    TurbineFileError,
    TurbineFileWarning,
    default_turbine_path,
    load_turbine,
    turbine_from_dict,
)

__all__ = [
    "TurbineFileError", "TurbineFileWarning", "default_turbine_path", "dump_turbine",
    "load_turbine", "turbine_from_dict", "turbines_equal",
]
