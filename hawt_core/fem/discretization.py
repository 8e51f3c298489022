"""Which discretization a beam gets: the paper's mixed element (order 1, fem/beam.py) or
its p-version (order >= 2, fem/spectral.py), and the matching Gauss-point Jacobian.  The
assemblies build their beams here, so every analysis takes either."""
from __future__ import annotations

from typing import Optional

from ..model import Beam
from .beam import BeamElements
from .beam_jacobian import PointwiseBeamJacobian
from .damping import DampingCoefficients, modal_families
from .damping_fit import fit_modal
from .sections import mesh_beam
from .spectral import SpectralBeamElements
from .spectral_jacobian import SpectralPointwiseJacobian

__all__ = ["beam_elements", "pointwise_jacobian"]


def beam_elements(beam: Beam, elements: Optional[int] = None, pitch: float = 0.0,
                  gauss: int = 3):
    """The discretized operator of ``beam`` (model.Beam) with ``elements`` elements
    (default ``beam.elements``) of its ``order``, turned by ``pitch`` [rad] about b1."""
    n = int(beam.elements if elements is None else elements)
    order = int(beam.order)
    damping = DampingCoefficients.of(beam.damping)
    if modal_families(beam.damping):
        damping = fit_modal(beam, gauss) + damping
    if order == 1:
        return BeamElements(mesh_beam(beam, n, pitch=pitch), gauss, damping=damping)
    return SpectralBeamElements(beam, n, order, pitch=pitch, gauss=gauss, damping=damping)


def pointwise_jacobian(beam, states: int = 0):
    """The Gauss-point complex-step Jacobian of ``beam`` (fem/beam_jacobian.py or
    fem/spectral_jacobian.py) with ``states`` unknowns per Gauss point."""
    if isinstance(beam, SpectralBeamElements):
        return SpectralPointwiseJacobian(beam, states)
    return PointwiseBeamJacobian(beam, states)
