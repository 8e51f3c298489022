"""Which discretization a beam gets: the paper's mixed element (order 1, fem/beam.py) or
its p-version (order >= 2, fem/spectral.py), with the beam's structural damping resolved
(modal ratios fitted: fem/damping_fit.py), and the matching Gauss-point Jacobian.  The
assemblies build their beams here, so every analysis takes either."""
from __future__ import annotations

from typing import Optional

from ..model import Beam
from .damping import DampingCoefficients, modal_families
from .damping_fit import fit_modal
from .elements import discretize, pointwise_jacobian

__all__ = ["beam_elements", "pointwise_jacobian"]


def beam_elements(beam: Beam, elements: Optional[int] = None, pitch: float = 0.0,
                  gauss: int = 3):
    """The discretized operator of ``beam`` (model.Beam) with ``elements`` elements
    (default ``beam.elements``) of its ``order``, turned by ``pitch`` [rad] about b1, with
    its structural damping."""
    damping = DampingCoefficients.of(beam.damping)
    if modal_families(beam.damping):
        damping = fit_modal(beam, gauss) + damping
    return discretize(beam, elements, pitch=pitch, gauss=gauss, damping=damping)
