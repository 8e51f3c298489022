"""Tables of numbers (time histories) to CSV or NPZ files."""
from __future__ import annotations

import csv
from typing import Optional, Sequence

import numpy as np

__all__ = ["write_table"]


def write_table(path, columns: Sequence[str], rows: np.ndarray,
                extra: Optional[dict] = None) -> None:
    """Write the (n, len(columns)) array ``rows`` to ``path``.

    ``.csv``: a header of ``columns`` then one line per row, every value as ``repr(float)``
    (round-trips exactly). ``.npz``: each column as an array under its name, ``columns`` (the
    names in order) and the arrays of ``extra``. Any other ending is refused.
    """
    path = str(path)
    rows = np.asarray(rows, dtype=float).reshape(-1, len(columns))
    if path.lower().endswith(".npz"):
        np.savez(path, **(extra or {}), columns=np.array(list(columns)),
                 **{c: rows[:, i] for i, c in enumerate(columns)})
    elif path.lower().endswith(".csv"):
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(list(columns))
            for row in rows:
                w.writerow([repr(float(v)) for v in row])
    else:
        raise ValueError(f"output: {path!r} is not allowed; need a .csv or .npz file name")
