"""Where a sweep's points run: a local process pool, or a Dask ``distributed`` cluster.

``--scheduler tcp://HOST:PORT`` (or the environment variable HAWT_SCHEDULER) sends the points
of a Campbell sweep to the workers of a running Dask scheduler (``dask scheduler`` and ``dask
worker tcp://HOST:PORT`` on the machines; hawt must be importable on every worker); the work
unit (analyses/campbell.campbell_point) takes and returns plain, picklable data.
"""
from __future__ import annotations

import concurrent.futures as cf
import os
from contextlib import contextmanager
from typing import Optional

__all__ = ["sweep_executor", "SCHEDULER_ENV"]

#: Environment variable naming the Dask scheduler when --scheduler is not given.
SCHEDULER_ENV = "HAWT_SCHEDULER"

#: Seconds to wait for the scheduler to answer.
CONNECT_TIMEOUT = 20


@contextmanager
def sweep_executor(scheduler: Optional[str] = None, workers: Optional[int] = None):
    """Yield (executor, description): a Dask cluster's executor when ``scheduler`` (or
    HAWT_SCHEDULER) names one, else a ProcessPoolExecutor of ``workers`` processes (default:
    one per CPU); closed on exit."""
    address = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if address is None:
        n = workers or os.cpu_count() or 1
        with cf.ProcessPoolExecutor(max_workers=n) as pool:
            yield pool, f"{n} local worker processes"
        return
    if "://" not in address:
        raise ValueError(f"--scheduler: {address!r} is not allowed; need a Dask scheduler "
                         "address such as tcp://HOST:8786")
    try:
        from distributed import Client
    except ImportError:
        raise ValueError("--scheduler: the Dask 'distributed' package is not installed "
                         "(pip install 'hawt[cluster]')") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as exc:
        raise ValueError(f"--scheduler: no Dask scheduler answered at {address!r} within "
                         f"{CONNECT_TIMEOUT} s ({exc})") from None
    try:
        n = len(client.scheduler_info().get("workers", {}))
        yield client.get_executor(pure=False), f"Dask scheduler {address} ({n} workers)"
    finally:
        client.close()
