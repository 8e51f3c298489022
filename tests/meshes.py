"""The paper's element on a real turbine, for tests of algorithms (solvers, Hill's method,
harmonic balance, aerodynamics, I/O) that chose a small mesh for speed (imported as a plain
module: pytest puts tests/ on sys.path).

The shipped NREL 5-MW and IEA 15-MW files name the p-version (3 blade elements of order 6, 2
tower elements of order 4: converged to 1e-4).  A test whose subject is not the
discretization and whose tolerances were measured on N of the paper's elements keeps that
mesh explicitly: the blades' ``elements`` of order 1 (default 64) and the tower's 16 of
order 1 (the meshes the shipped files named before).  Tests of the discretization itself use the
files' mesh or say which.
"""
from __future__ import annotations

import dataclasses as dc

from hawt_core.io.catalog import load_any

BLADE_ELEMENTS = 64
TOWER_ELEMENTS = 16


def paper_mesh(turbine, elements=BLADE_ELEMENTS, tower_elements=TOWER_ELEMENTS):
    """``turbine`` with the paper's element (order 1) on its blades (``elements`` per blade)
    and on its tower (``tower_elements``)."""
    blade = dc.replace(turbine.blade, order=1, elements=int(elements))
    tower = None if turbine.tower is None else dc.replace(turbine.tower, order=1,
                                                          elements=int(tower_elements))
    return dc.replace(turbine, blade=blade, tower=tower)


def load_paper_mesh(name, elements=BLADE_ELEMENTS, tower_elements=TOWER_ELEMENTS):
    """The shipped turbine ``name`` (hawt turbines) on the paper's element (paper_mesh)."""
    return paper_mesh(load_any(name), elements, tower_elements)
