"""Beams shared by the Jacobian tests of test_beam and test_beam_jacobian (imported as a
plain module: pytest puts tests/ on sys.path)."""
from __future__ import annotations

import numpy as np

from hawt_core.fem.beam import BeamElements
from hawt_core.fem.sections import mesh_beam
from hawt_core.model import Beam, SectionTable


def every_term_beam(elements: int) -> BeamElements:
    """An 8 m beam that exercises every term of the residual: a tapered three-station table
    with pretwist, mass-centre and tension-centre offsets, flexible axial and shear
    directions, prebend and sweep, and a rigid tip body (30 kg, inertia (1, 2, 3) kg m^2)."""
    return BeamElements(mesh_beam(every_term_model(elements)))


def every_term_model(elements: int) -> Beam:
    """The model.Beam of :func:`every_term_beam`."""
    st = np.array([0.0, 0.4, 1.0])
    sec = SectionTable(stations=st, mass=[60.0, 50.0, 30.0], i1=[5.0, 4.0, 2.0],
                       i2=[0.5, 0.4, 0.2], i3=[4.5, 3.6, 1.8], gj=[2e4, 1.5e4, 1e4],
                       ei2=[4e6, 3e6, 1e6], ei3=[2e7, 1.5e7, 8e6], ea=[1e9, 8e8, 5e8],
                       ga2=[3e8, 2e8, 1e8], ga3=[2e8, 1.5e8, 1e8], twist=[0.3, 0.1, -0.2],
                       cg_offset=[[0.05, -0.02], [0.08, 0.01], [0.1, 0.03]],
                       tension_offset=[[0.02, 0.01], [0.0, -0.01], [-0.03, 0.02]],
                       prebend=[0.0, 0.1, 0.4], sweep=[0.0, -0.05, 0.1])
    return Beam(8.0, sec, elements, tip_mass=30.0, tip_inertia=(1.0, 2.0, 3.0))
