"""What the analyses return: mode and track result types, their tables, CSV and JSON, and the
pictures drawn from them (plotting.py).  Imports only numerics, NumPy and matplotlib: the
objects carry their model, whose methods the pictures use."""
from .campbell import CSV_COLUMNS, CampbellResult, Track
from .modes import BladeMode, BladeModesResult, ModalResult, Mode, mode_shape
from .tables import format_table, mode_name, ordinal

__all__ = ["CSV_COLUMNS", "CampbellResult", "Track", "BladeMode", "BladeModesResult",
           "ModalResult", "Mode", "mode_shape", "format_table", "mode_name", "ordinal"]
