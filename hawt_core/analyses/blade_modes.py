"""Modes of one blade clamped to a hub spinning at constant speed (the symmetric modes of the
paper's Table 2).

The blade root sits at radius ``e`` on a hub spinning about ``b3`` at ``Omega0``: in the root
frame the root velocity is ``v = e Omega0 b2`` and the angular velocity ``omega = Omega0 b3``
(plus gravity, if enabled, which then makes the problem periodic: not handled here - the
blade is analysed in its rotating-frame steady state without gravity).
Steps: nonlinear steady state (Newton), exact linearization ``E ydot = A y``
(``E = dR/dydot``, ``A = -dR/dy``), generalized eigen-analysis of the pencil ``(A, E)``,
selection of the physical (finite, in-band) eigenvalues, classification by strain energy.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..assembly import SpinningBlade
from ..fem.energy import FAMILIES, classify_energy, frequency_bound
from ..model import Turbine
from ..numerics.pencil import finite_modes, sparse_modes
from ..numerics.threads import blas_threads
from ..results.modes import BladeMode, BladeModesResult, mode_shape

__all__ = ["blade_modes", "spinning_modes", "energy_names", "SPARSE_THRESHOLD",
           "DEFAULT_SPARSE_COUNT"]


#: Above this many unknowns, ``method="auto"`` uses the sparse shift-invert path.
SPARSE_THRESHOLD = 600

#: Default number of modes returned by the sparse path.
DEFAULT_SPARSE_COUNT = 30


def blade_modes(turbine: Turbine, elements: Optional[int] = None,
                rotor_speed: Optional[float] = None, count: Optional[int] = None,
                method: str = "auto", band_factor: float = 100.0,
                max_hz: Optional[float] = None) -> BladeModesResult:
    """Modes of one blade clamped on the spinning hub, sorted by frequency.

    ``elements`` (default: the turbine's), ``rotor_speed`` [rad/s] (default: the turbine's).
    ``method``: "dense" (deflation of the infinite eigenvalues + QZ: every finite mode, 3N for
    a rigid-axial, shear-rigid blade), "sparse" (shift-invert Arnoldi about 0 with a sparse LU:
    the lowest ``count`` modes), or "auto" (sparse above SPARSE_THRESHOLD unknowns).
    ``count``: how many of the lowest modes to return (default: all for dense,
    DEFAULT_SPARSE_COUNT for sparse).  ``band_factor``: modes above this many times the
    element-level frequency bound (:func:`frequency_bound`) are discarded as numerical.
    ``max_hz``: keep only the modes at or below this frequency [Hz] (of the lowest
    ``count``).
    """
    if method not in ("auto", "dense", "sparse"):
        raise ValueError(f"method: {method!r} is not allowed; use 'auto', 'dense' or 'sparse'")
    if count is not None:
        if isinstance(count, bool) or int(count) != count or count < 1:
            raise ValueError(f"count: {count!r} is not allowed; need an integer >= 1")
        count = int(count)
    if max_hz is not None and not (isinstance(max_hz, (int, float)) and max_hz > 0
                                   and np.isfinite(max_hz)):
        raise ValueError(f"max_hz: {max_hz!r} is not allowed; need a frequency > 0 [Hz]")
    with blas_threads():
        return _blade_modes(turbine, elements, rotor_speed, count, method, band_factor, max_hz)


def spinning_modes(model: SpinningBlade, count: Optional[int], method: str,
                   band_factor: float) -> tuple:
    """(y0, lam, X, order, method) of the blade ``model`` (a SpinningBlade): its steady state,
    the finite eigenpairs of its linearization (``method`` as blade_modes', "auto" resolved),
    and their order: oscillatory modes by frequency, then the real exponents (the overdamped
    branch of structural damping, near -1/mu) by decay rate, so that "1st flap" is a
    vibration; the first ``count`` of them (all: None)."""
    y0 = model.steady_state()
    Jy, Jd = model.jacobians(np.zeros(model.n), y0)
    band = band_factor * frequency_bound(model.beam.props)
    if method == "auto":
        method = "sparse" if model.n > SPARSE_THRESHOLD else "dense"
    if method == "sparse":
        k = DEFAULT_SPARSE_COUNT if count is None else count
        lam, X = sparse_modes(-Jy, Jd, k, band=band)
    else:
        lam, X = finite_modes(-Jy.toarray(), Jd.toarray(), band)
    real = np.abs(lam.imag) <= 1e-3 * np.abs(lam)
    order = np.lexsort((lam.real, np.abs(lam.imag), np.abs(lam.real) * real, real))
    if count is not None:
        order = order[:count]
    return y0, lam, X, order, method


def energy_names(beam, X: np.ndarray) -> tuple:
    """(families, indices) of the modes X's columns, in their order: each mode's family the
    one holding most of its strain energy (classify_energy), counted within the family."""
    families, indices, counts = [], [], {}
    for j in range(X.shape[1]):
        fam = FAMILIES[int(np.argmax(classify_energy(beam, X[:, j])))]
        counts[fam] = counts.get(fam, 0) + 1
        families.append(fam)
        indices.append(counts[fam])
    return families, indices


def _blade_modes(turbine, elements, rotor_speed, count, method, band_factor, max_hz=None):
    model = SpinningBlade(turbine, elements, rotor_speed)
    y0, lam, X, order, method = spinning_modes(model, count, method, band_factor)
    om = model.rotor_speed
    if max_hz is not None:
        order = order[np.abs(lam[order].imag) / (2 * np.pi) <= max_hz]
    modes = []
    for j, fam, index in zip(order, *energy_names(model.beam, X[:, order])):
        x = X[:, j]
        w = abs(lam[j])
        modes.append(BladeMode(family=fam, index=index,
                          frequency_per_rev=float(lam[j].imag / om) if om > 0 else float("nan"),
                          frequency_hz=float(lam[j].imag / (2 * np.pi)),
                          damping_ratio=float(-lam[j].real / w) if w > 0 else 0.0,
                          eigenvalue=complex(lam[j]), shape=mode_shape(model.beam, x)))
    settings = {"turbine": turbine.name, "elements": model.beam.elements,
                "order": model.beam.order, "rotor_speed": om,
                "structural_damping": turbine.structural_damping_text(),
                "hub_radius": float(turbine.hub.radius), "method": method,
                "count": count, "max_hz": max_hz, "unknowns": model.n,
                "in_vacuum": turbine.aerodynamics is not None}
    return BladeModesResult(rotor_speed=om, elements=model.beam.elements, modes=modes,
                            root_force=y0[0:3].copy(), settings=settings)
