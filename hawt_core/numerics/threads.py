"""BLAS thread limits for hawt's many small dense solves (threadpoolctl).

Floquet marching, the window solver of the simulation and the modal eigenproblems run
thousands of small dense products and solves; a threaded BLAS spends more time waking and
synchronising its threads than computing on them (measured on a loaded 2-core machine: a
dense N = 32 blade-modes run 13 s with the default threads, 0.7 s with one; `hawt simulate`
real-time factor 7.5-9.3 against 17.9).  So hawt's analyses run with one BLAS thread by
default, whatever the environment says; ``HAWT_BLAS_THREADS=k`` chooses another count
(``0``: leave the libraries' own setting).

``blas_threads()`` is a context manager (entered per analysis or per simulation step: about
10 us, a cached threadpoolctl controller); ``limit_blas_threads(n)`` sets the limit for the
rest of the process (worker processes of a sweep).
"""
from __future__ import annotations

import contextlib
import os

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
