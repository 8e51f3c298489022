"""BLAS thread limits for hawt's many small dense solves (threadpoolctl).

Floquet marching, the window solver of the simulation and the modal eigenproblems run
thousands of small dense products and solves; a threaded BLAS spends more time waking and
synchronising its threads than computing on them (measured on a loaded 2-core machine: a
dense N = 32 blade-modes run 13 s with the default threads, 0.7 s with one; `hawt simulate`
real-time factor 7.5-9.3 against 17.9).  So hawt's analyses run with one BLAS thread by
default, whatever the environment says; ``HAWT_BLAS_THREADS=k`` chooses another count
(``0``: leave the libraries' own setting).

Independent sparse eigen searches (Hill's windows and per-mode refinements: SuperLU and
ARPACK release the GIL) run on a few Python threads instead: ``solver_thread_count()``, from
HAWT_SOLVER_THREADS, default the CPUs this process may use; ``solver_threads(n)`` sets it
inside a block (a sweep's worker processes, one per CPU already, use 1; the ROS node's
analysis worker leaves a CPU to the publishing process); ``thread_map(f, items)`` maps on
them, in order.

``blas_threads()`` is a context manager (entered per analysis or per simulation step: about
10 us, a cached threadpoolctl controller); ``limit_blas_threads(n)`` sets the limit for the
rest of the process (worker processes of a sweep).
"""
from __future__ import annotations

import contextlib
import os
import threading

_CONTROLLER = None


def _controller():
    """A threadpoolctl controller over every BLAS loaded once numpy and scipy are (created
    on first use, when scipy's own OpenBLAS is loaded too)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        import scipy.linalg  # noqa: F401  (loads scipy's BLAS before the libraries are listed)
        from threadpoolctl import ThreadpoolController
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def thread_count() -> int:
    """The BLAS thread count hawt uses: HAWT_BLAS_THREADS (0 = unlimited), default 1."""
    text = os.environ.get("HAWT_BLAS_THREADS", "1").strip()
    try:
        n = int(text)
    except ValueError:
        raise ValueError(f"HAWT_BLAS_THREADS: {text!r} is not allowed; need an integer >= 0 "
                         "(0: the BLAS libraries' own thread count)") from None
    if n < 0:
        raise ValueError(f"HAWT_BLAS_THREADS: {n} is not allowed; need an integer >= 0")
    return n


def blas_threads(n=None):
    """Context manager: BLAS limited to ``n`` threads (default :func:`thread_count`) inside."""
    n = thread_count() if n is None else int(n)
    if n == 0:
        return contextlib.nullcontext()
    return _controller().limit(limits=n, user_api="blas")


def limit_blas_threads(n=None) -> int:
    """Limit every loaded BLAS to ``n`` threads (default :func:`thread_count`) for the rest
    of the process; returns how many libraries were limited."""
    n = thread_count() if n is None else int(n)
    if n == 0:
        return 0
    ctl = _controller()
    ctl.limit(limits=n, user_api="blas")
    return len(ctl.select(user_api="blas").lib_controllers)


# solver_threads() overrides the environment per calling thread (analyses run concurrently
# on threads of one process: a sweep on a thread pool, the tests)
_LOCAL = threading.local()


def solver_thread_count() -> int:
    """Threads for independent sparse solves: the innermost :func:`solver_threads` value of
    the calling thread, else HAWT_SOLVER_THREADS (an integer >= 1), else the CPUs this
    process may run on."""
    n = getattr(_LOCAL, "n", None)
    if n is not None:
        return n
    text = os.environ.get("HAWT_SOLVER_THREADS", "").strip()
    if text:
        try:
            n = int(text)
        except ValueError:
            n = 0
        if n < 1:
            raise ValueError(f"HAWT_SOLVER_THREADS: {text!r} is not allowed; need an integer "
                             ">= 1")
        return n
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:          # not on Linux
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def solver_threads(n: int):
    """Context manager: :func:`solver_thread_count` is ``n`` (>= 1) inside, in the calling
    thread."""
    n = int(n)
    if n < 1:
        raise ValueError(f"solver threads: {n} is not allowed; need an integer >= 1")
    previous = getattr(_LOCAL, "n", None)
    _LOCAL.n = n
    try:
        yield n
    finally:
        _LOCAL.n = previous


def thread_map(fn, items) -> list:
    """``[fn(x) for x in items]``, on up to :func:`solver_thread_count` threads (in order;
    the first exception is raised). For calls that spend their time outside the GIL."""
    items = list(items)
    n = min(solver_thread_count(), len(items))
    if n <= 1:
        return [fn(x) for x in items]
    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(max_workers=n, thread_name_prefix="hawt-solver") as pool:
        return list(pool.map(fn, items))
