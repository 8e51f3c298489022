"""Solver threads (numerics/threads.py): Hill's windows and refinements on several threads.

References and tolerances (each test says which):
- the same Hill analysis on one thread (HAWT_SOLVER_THREADS=1 semantics via solver_threads):
  the same exponents to 1e-10 relative (ARPACK's own tolerance is 1e-13; both runs converge
  the same windows, only their order of execution differs) and the same count of
  factorizations (one per window);
- thread_map keeps the order of its items and raises the first exception.
"""
import warnings

import numpy as np
import pytest

from hawt_core.numerics import threads
from hawt_core.numerics.threads import solver_thread_count, solver_threads, thread_map


def test_thread_map_keeps_order_and_raises():
    """Reference: the list comprehension it replaces."""
    with solver_threads(2):
        assert thread_map(lambda x: x * x, range(7)) == [x * x for x in range(7)]
        with pytest.raises(ZeroDivisionError):
            thread_map(lambda x: 1 / x, [1, 0, 2])


def test_the_override_belongs_to_the_calling_thread():
    """Reference: concurrent analyses on threads of one process (a sweep on a thread pool):
    one thread's solver_threads(1) is not seen by another, and each is restored on exit
    whatever the order the threads leave in."""
    import threading
    inside, release, seen = threading.Event(), threading.Event(), []

    def other():
        with solver_threads(5):
            inside.set()
            release.wait(5)
            seen.append(solver_thread_count())

    worker = threading.Thread(target=other)
    worker.start()
    inside.wait(5)
    with solver_threads(1):
        release.set()
        worker.join(5)
        assert solver_thread_count() == 1
    assert seen == [5]
    assert getattr(threads._LOCAL, "n", None) is None


def test_solver_thread_count_from_the_environment(monkeypatch):
    """Reference: the documented rules (environment, context, bad values named)."""
    monkeypatch.setenv("HAWT_SOLVER_THREADS", "3")
    assert solver_thread_count() == 3
    with solver_threads(1):
        assert solver_thread_count() == 1
    assert solver_thread_count() == 3
    for bad in ("0", "two"):
        monkeypatch.setenv("HAWT_SOLVER_THREADS", bad)
        with pytest.raises(ValueError, match="HAWT_SOLVER_THREADS"):
            solver_thread_count()
    with pytest.raises(ValueError, match="solver threads"):
        with solver_threads(0):
            pass


def test_hill_on_two_threads_equals_one():
    """A rotating three-bladed rotor's (yaw locked: a free yaw's double zero exponent is
    found once or twice, depending on round-off) Hill analysis in the rotating frame (several windows,
    searched concurrently; 4 harmonics) against the same on one thread: exponents 1e-10
    relative, the same factorization count."""
    import dataclasses as dc

    from hawt_core.assembly import TurbineModel
    from hawt_core.io import load_turbine
    from hawt_core.analyses.modal import periodic_dae
    from hawt_core.solvers.hill import hill_modes
    from hawt_core.solvers.periodic import periodic_steady_state
    paper = load_turbine()
    t = dc.replace(paper, rotor=dc.replace(paper.rotor, blades=3),
                   hub=dc.replace(paper.hub, teeter=False),
                   nacelle=dc.replace(paper.nacelle, yaw_free=False),
                   gravity=dc.replace(paper.gravity, enabled=True))
    model = TurbineModel(t, elements=3)
    dae = periodic_dae(model, periodic_steady_state(model))
    band = 6.0 * model.rotor_speed
    with warnings.catch_warnings():
        # 4 harmonics leave 7e-11 of a mode's energy in the outermost: warned, the same twice
        warnings.simplefilter("ignore", RuntimeWarning)
        with solver_threads(1):
            one = hill_modes(dae, band, harmonics=4)
        with solver_threads(2):
            two = hill_modes(dae, band, harmonics=4)
    assert one.exponents.size >= 6
    assert two.exponents.size == one.exponents.size
    scale = np.maximum(np.abs(one.exponents), model.rotor_speed)
    assert (np.abs(two.exponents - one.exponents) / scale).max() < 1e-10
    # (solve counts vary with ARPACK's random start vectors, run to run)
    assert two.timings["factorizations"] == one.timings["factorizations"] >= 3
    assert getattr(threads._LOCAL, "n", None) is None       # restored on exit
