"""The two discretizations behind one call: the paper's mixed element (order 1,
fem/beam.py) or its p-version (order >= 2, fem/spectral.py) with given damping
coefficients, and the matching Gauss-point Jacobian.  fem/discretization.py (which also
resolves a beam's modal damping) and fem/damping_fit.py (which fits it on a bare beam)
both build through here."""
from __future__ import annotations

from typing import Optional

from ..model import Beam
from .beam import BeamElements
from .beam_jacobian import PointwiseBeamJacobian
from .damping import DampingCoefficients
from .sections import mesh_beam
from .spectral import SpectralBeamElements
from .spectral_jacobian import SpectralPointwiseJacobian

__all__ = ["discretize", "pointwise_jacobian"]


def discretize(beam: Beam, elements: Optional[int] = None, pitch: float = 0.0,
               gauss: int = 3, damping: Optional[DampingCoefficients] = None):
    """The discretized operator of ``beam`` with ``elements`` elements (default
    ``beam.elements``) of its ``order``, turned by ``pitch`` [rad] about b1, damped by
    ``damping`` (resolved coefficients; None: undamped)."""
    n = int(beam.elements if elements is None else elements)
    if int(beam.order) == 1:
        return BeamElements(mesh_beam(beam, n, pitch=pitch), gauss, damping=damping)
    return SpectralBeamElements(beam, n, int(beam.order), pitch=pitch, gauss=gauss,
                                damping=damping)


def pointwise_jacobian(beam, states: int = 0):
    """The Gauss-point complex-step Jacobian of ``beam`` (fem/beam_jacobian.py or
    fem/spectral_jacobian.py) with ``states`` unknowns per Gauss point."""
    if isinstance(beam, SpectralBeamElements):
        return SpectralPointwiseJacobian(beam, states)
    return PointwiseBeamJacobian(beam, states)
