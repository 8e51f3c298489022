"""Flexible-tower turbines shared by test_tower and test_assembly (imported as a plain module:
pytest puts tests/ on sys.path)."""
from __future__ import annotations

import dataclasses as dc

from hawt_core.io import load_turbine
from hawt_core.model import Beam, SectionTable


def tower_beam(L, m, ei2, ei3, gj, i1, elements, tiny_i23=True):
    """A uniform tower: section rotary inertias i2 = i3 = 1e-6 (``tiny_i23``) or i1 / 2."""
    sec = SectionTable.uniform(mass=m, i1=i1, i2=1e-6 if tiny_i23 else i1 / 2,
                               i3=1e-6 if tiny_i23 else i1 / 2, gj=gj, ei2=ei2, ei3=ei3)
    return Beam(L, sec, elements)


def soft_tower_turbine():
    """The paper's rotor (hub 1000 kg, nacelle 3000 kg) on a soft 25 m tower (400 kg/m,
    EI = 6e8 N m^2, GJ = 1.5e9 N m^2)."""
    paper = load_turbine()
    return dc.replace(paper, tower=tower_beam(25.0, 400.0, 6e8, 6e8, 1.5e9, 300.0, 4, False),
                      hub=dc.replace(paper.hub, mass=1000.0),
                      nacelle=dc.replace(paper.nacelle, mass=3000.0, inertia_pitch=2000.0,
                                         inertia_roll=1500.0))
