"""Turbine files: reading, validating and writing the YAML turbine description."""
from .turbine_yaml import (
    TurbineFileError,
    TurbineFileWarning,
    default_turbine_path,
    dump_turbine,
    load_turbine,
    turbine_from_dict,
    turbines_equal,
)

__all__ = [
    "TurbineFileError", "TurbineFileWarning", "default_turbine_path", "dump_turbine",
    "load_turbine", "turbine_from_dict", "turbines_equal",
]
