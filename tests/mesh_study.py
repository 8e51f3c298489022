"""Mesh-convergence helpers shared by the beam and blade-mode tests (imported as a plain
module: pytest puts tests/ on sys.path): frequencies at N = 8, 16, 32 elements and their
Richardson extrapolation with the observed O(h^2) convergence of the discretization."""
from __future__ import annotations

import numpy as np

from hawt_core.analyses.blade_modes import blade_modes

MESHES = (8, 16, 32)


def solve(T, N, count=30):
    """Modes at N elements: dense for N < 32, the sparse path (lowest ``count``) beyond."""
    return blade_modes(T, N, method="sparse" if N >= 32 else "dense", count=count)


def by_family(result):
    out = {}
    for m in result.modes:
        out.setdefault(m.family, []).append(m.frequency_rad_s)
    return {k: np.array(v) for k, v in out.items()}


def richardson(f8, f16, f32):
    """Two-level Richardson extrapolation for an error expansion c2 h^2 + c4 h^4."""
    r1 = (4 * f16 - f8) / 3
    r2 = (4 * f32 - f16) / 3
    return (16 * r2 - r1) / 15


def mesh_study(T, family, k, count=30):
    """Lowest ``k`` frequencies of ``family`` [rad/s] at N = 8, 16, 32 (array (3, k))."""
    return np.array([by_family(solve(T, N, count))[family][:k] for N in MESHES])
