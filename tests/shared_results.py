"""Expensive analyses that several test files check, computed once per pytest process
(imported as a plain module: pytest puts tests/ on sys.path).  The results are shared:
tests only read them."""
from __future__ import annotations

import functools

from hawt_core.io import load_turbine
from hawt_core.analyses.modal import modal_analysis


@functools.lru_cache(maxsize=None)
def paper_modal_analysis():
    """Floquet modal analysis of the default (paper, rigid-tower) turbine: N = 4 elements,
    Radau IIA, 400 steps per period: the Table 2 configuration."""
    return modal_analysis(load_turbine(), elements=4, steps=400)
