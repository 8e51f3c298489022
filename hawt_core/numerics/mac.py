"""The modal assurance criterion of complex vectors."""
from __future__ import annotations

import numpy as np

__all__ = ["mac_matrix"]


def mac_matrix(A: np.ndarray, B: np.ndarray, den=None) -> np.ndarray:
    """MAC between the columns of A (m, p) and of B (m, q): ``|A^H B|^2 / (|a|^2 |b|^2)``
    (p, q); ``den`` replaces the denominator (e.g. norms of longer vectors whose slices A and
    B are); a zero denominator gives 0."""
    num = np.abs(np.conj(A).T @ B) ** 2
    if den is None:
        den = np.outer((np.abs(A) ** 2).sum(0), (np.abs(B) ** 2).sum(0))
    return num / np.where(den > 0, den, 1.0)
