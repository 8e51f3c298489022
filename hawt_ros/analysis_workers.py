"""Floquet modal analyses for the node, run OFF the node's process (no rclpy import here).

Each analysis runs in a worker process forked from a multiprocessing *forkserver* (started
once; it has NumPy/SciPy/hawt_core preloaded, so a worker starts in milliseconds and the node's
DDS threads are never forked). The node's simulation/publishing thread therefore keeps its
cadence during an analysis (the work is on another core and outside the node's GIL), and a
cancellation can always be enforced: the worker is asked through ``cancel()`` (checked by
``modal_analysis`` between stages) and terminated if it does not stop within a grace period.

:class:`AnalysisRunner` queues jobs and runs them one at a time (the machine may have few
cores); results are cached by their resolved settings, and identical *shareable* requests
(services) that arrive while one is running wait for the same job.
"""
from __future__ import annotations

import math
import multiprocessing
import os
import queue
import signal
import threading
import time
import traceback
from collections import OrderedDict
from typing import Any, Callable, Dict, List, Optional

import numpy as np

__all__ = ["AnalysisRunner", "Job", "result_to_plain", "WORKER_NICE"]

#: Niceness added to analysis workers (lower CPU priority than the node's simulation).
WORKER_NICE = 5


# ----------------------------------------------------------------------------- worker side
def _shape(result, mode) -> Optional[Dict[str, Any]]:
    """ModeShape data of a real hawt_core.modal result (x(0) of the Floquet mode), normalized
    so that the largest displacement/rotation component has modulus 1; None if unavailable."""
    col = getattr(mode, "column", -1)
    fl = getattr(result, "floquet", None)
    model = getattr(result, "model", None)
    if fl is None or model is None or col is None or col < 0:
        return None
    x = np.asarray(fl.eigenvectors[:, col])
    lay = model.layout
    nb = model.n_blades
    span = np.asarray(model.beam.props.nodes, float)
    disp, rot = [], []
    for k in range(nb):
        b = lay.blade(k)
        u = np.zeros((len(span), 3), complex)
        th = np.zeros((len(span), 3), complex)
        u[1:] = x[b.u[1:]]
        th[1:] = x[b.theta[1:]]
        disp.append(u)
        rot.append(th)
    disp = np.concatenate(disp)
    rot = np.concatenate(rot)
    yaw = complex(x[lay["yaw"]]) if "yaw" in lay else 0j
    teeter = complex(x[lay["teeter"]]) if "teeter" in lay else 0j
    scale = max(np.abs(disp).max(initial=0.0), np.abs(rot).max(initial=0.0),
                abs(yaw), abs(teeter))
    if not np.isfinite(scale) or scale == 0:
        return None
    # make the largest component real and positive
    flat = np.concatenate([disp.ravel(), rot.ravel(), [yaw, teeter]])
    phase = flat[int(np.argmax(np.abs(flat)))]
    c = np.conj(phase) / abs(phase) / scale
    disp, rot, yaw, teeter = disp * c, rot * c, yaw * c, teeter * c
    return {"blades": nb, "span": span.tolist(),
            "displacement_real": disp.real.tolist(), "displacement_imag": disp.imag.tolist(),
            "rotation_real": rot.real.tolist(), "rotation_imag": rot.imag.tolist(),
            "yaw_real": yaw.real, "yaw_imag": yaw.imag,
            "teeter_real": teeter.real, "teeter_imag": teeter.imag}


def _num(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def result_to_plain(result) -> Dict[str, Any]:
    """A ModalResult as plain data (picklable, JSON-able apart from NaN)."""
    modes = []
    for m in result.modes:
        try:
            shape = _shape(result, m)
        except Exception:  # noqa: BLE001 - shapes are optional
            shape = None
        modes.append({
            "family": str(getattr(m, "family", "") or ""),
            "symmetry": getattr(m, "symmetry", None),
            "index": int(getattr(m, "index", 0) or 0),
            "frequency_per_rev": _num(m.frequency_per_rev),
            "real_per_rev": _num(m.real_per_rev),
            "frequency_hz": _num(m.frequency_hz),
            "damping_ratio": _num(m.damping_ratio),
            "fixed_frame_per_rev": _num(getattr(m, "fixed_frame_per_rev", None) or 0.0),
            "fixed_frame_hz": _num(getattr(m, "fixed_frame_hz", None) or 0.0),
            "fixed_frame_damping_ratio": _num(getattr(m, "fixed_frame_damping_ratio", None)
                                              or 0.0),
            "whirl": str(getattr(m, "whirl", None) or ""),
            "shape": shape,
        })
    settings = dict(getattr(result, "settings", {}) or {})
    return {"modes": modes, "settings": settings,
            "unresolved": int(getattr(result, "unresolved", 0) or 0),
            "compute_time": _num(getattr(result, "compute_time", math.nan))}


def _die_with_node(node_pid: int) -> None:
    """Make sure a worker never outlives the node, even after a SIGKILL of the node.

    The worker's parent is the forkserver, not the node, and the forkserver stays alive as
    long as any of its children holds the "alive" pipe multiprocessing hands every child: so
    watching the parent (PR_SET_PDEATHSIG, getppid) alone leaves the worker and the forkserver
    running forever once the node is killed.  The worker therefore watches the node itself:
    a pidfd (Linux >= 5.3) wakes a thread the instant the node ends; elsewhere the thread
    polls the node's pid every 0.2 s.  Either way the worker exits, and the forkserver, its
    last child gone, exits too.  PR_SET_PDEATHSIG stays for a forkserver that dies first."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)           # PR_SET_PDEATHSIG
    except Exception:  # noqa: BLE001 - not Linux
        pass

    def node_alive() -> bool:
        try:
            os.kill(node_pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True

    pidfd = None
    try:
        pidfd = os.pidfd_open(node_pid)
    except (AttributeError, OSError):
        pass
    if not node_alive():
        os._exit(1)

    def watch():
        if pidfd is not None:
            import select
            select.select([pidfd], [], [])               # readable when the node has ended
            os._exit(1)
        while node_alive():
            time.sleep(0.2)
        os._exit(1)

    threading.Thread(target=watch, name="node-watch", daemon=True).start()


def _worker_main(conn, turbine, kwargs, cancel_event, node_pid) -> None:
    """Entry point of an analysis worker process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)     # the node decides when we stop
    _die_with_node(node_pid)
    try:  # background work: the node's real-time simulation wins any contention for a core
        os.nice(WORKER_NICE)
    except OSError:
        pass
    try:
        from hawt_ros.backend import load_backend

        be = load_backend("modal")
    except Exception as exc:  # noqa: BLE001
        conn.send(("error", f"modal analysis not available: {type(exc).__name__}: {exc}"))
        return

    def progress(fraction, message):
        try:
            conn.send(("progress", float(fraction), str(message)))
        except (OSError, ValueError):
            pass

    from hawt_core.numerics.threads import solver_thread_count, solver_threads
    try:
        t0 = time.perf_counter()
        # one CPU stays with the node's real-time simulation: the analysis' solver threads
        # (Hill's windows) use the others, at least one
        with solver_threads(max(1, solver_thread_count() - 1)):
            if kwargs.get("wind_speed"):
                # the node runs in wind: the aeroelastic analysis at its operating point
                from hawt_core.analyses.modal import modal_at_operating_point
                kw = dict(kwargs)
                result = modal_at_operating_point(
                    turbine, kw.pop("wind_speed"), kw.pop("discon"),
                    wind_direction=kw.pop("wind_direction", 0.0),
                    rotor_speed=kw.pop("rotor_speed", None) or None, progress=progress,
                    cancel=cancel_event.is_set, **kw)
            else:
                result = be.modal_analysis(turbine, progress=progress,
                                           cancel=cancel_event.is_set, **kwargs)
        plain = result_to_plain(result)
        if not math.isfinite(plain["compute_time"]):
            plain["compute_time"] = time.perf_counter() - t0
        conn.send(("result", plain))
    except be.Cancelled as exc:
        conn.send(("cancelled", str(exc) or "cancelled"))
    except (ValueError, TypeError) as exc:
        conn.send(("invalid", str(exc)))
    except Exception as exc:  # noqa: BLE001
        conn.send(("error", f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=3)}"))
    finally:
        try:
            conn.close()
        except Exception:  # noqa: BLE001
            pass


# ----------------------------------------------------------------------------- node side
class Job:
    """One analysis job. ``status``: 'queued', 'running', then 'ok', 'cancelled', 'invalid'
    or 'error'; ``result`` (plain dict, see result_to_plain) when ok; ``message``."""

    def __init__(self, key, kwargs: dict):
        self.key = key
        self.kwargs = kwargs
        self.status = "queued"
        self.result: Optional[Dict[str, Any]] = None
        self.message = ""
        self.cached = False
        self.wall_time = 0.0
        self.last_progress = -1.0
        self._done = threading.Event()
        self._cancel = threading.Event()
        self._lock = threading.Lock()
        self._progress_callbacks: List[Callable[[float, str], None]] = []

    # -- callbacks
    def add_progress_callback(self, fn: Callable[[float, str], None]) -> None:
        with self._lock:
            self._progress_callbacks.append(fn)

    def _progress(self, fraction: float, message: str) -> None:
        self.last_progress = float(fraction)
        with self._lock:
            cbs = list(self._progress_callbacks)
        for fn in cbs:
            try:
                fn(fraction, message)
            except Exception:  # noqa: BLE001 - a listener's problem is not the job's
                pass

    def _finish(self, status: str, message: str = "", result=None) -> None:
        with self._lock:
            if self._done.is_set():
                return
            self.status, self.message, self.result = status, message, result
            self._done.set()

    # -- control
    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    def done(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: Optional[float] = None) -> bool:
        return self._done.wait(timeout)


class AnalysisRunner:
    """Runs modal analyses of one turbine in worker processes, one at a time.

    ``submit(kwargs, shareable)`` returns a :class:`Job` at once. ``kwargs`` are the
    overrides of ``modal_analysis`` (elements, rotor_speed, steps, method)."""

    def __init__(self, turbine, cache_size: int = 32, cancel_grace: float = 1.0,
                 logger: Optional[Callable[[str], None]] = None):
        self.turbine = turbine
        self.cache_size = int(cache_size)
        self.cancel_grace = float(cancel_grace)
        self._log = logger or (lambda msg: None)
        self._ctx = multiprocessing.get_context("forkserver")
        self._jobs: "queue.Queue[Optional[Job]]" = queue.Queue()
        self._cache: "OrderedDict[Any, Dict[str, Any]]" = OrderedDict()
        self._inflight: Dict[Any, Job] = {}
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._current: Optional[Job] = None
        self._proc = None
        self._thread = threading.Thread(target=self._loop, name="hawt-analysis", daemon=True)
        self._thread.start()

    @staticmethod
    def prepare_forkserver() -> None:
        """Start the forkserver with the analysis code preloaded (call before threads that
        matter exist; optional: it starts on first use otherwise)."""
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["__main__", "hawt_ros.analysis_workers", "hawt_ros.backend",
                                    "numpy", "scipy.sparse", "scipy.linalg",
                                    "hawt_core.assembly", "hawt_core.analyses.modal"])
        from multiprocessing import forkserver

        forkserver.ensure_running()

    def submit(self, kwargs: dict, shareable: bool = True) -> Job:
        key = tuple(sorted(kwargs.items()))
        with self._lock:
            if self._stopping.is_set():
                job = Job(key, kwargs)
                job._finish("error", "the node is shutting down")
                return job
            cached = self._cache.get(key)
            if cached is not None:
                self._cache.move_to_end(key)
                job = Job(key, kwargs)
                job.cached = True
                job._finish("ok", "cached result", cached)
                return job
            if shareable:
                running = self._inflight.get(key)
                if running is not None and not running.done():
                    return running
            job = Job(key, kwargs)
            if shareable:
                self._inflight[key] = job
        self._jobs.put(job)
        return job

    def _loop(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                return
            if self._stopping.is_set():
                self._complete(job, "error", "the node is shutting down")
                continue
            if job.cancel_requested:
                self._complete(job, "cancelled", "cancelled before it started")
                continue
            self._current = job
            try:
                self._run(job)
            except Exception as exc:  # noqa: BLE001
                self._complete(job, "error", f"{type(exc).__name__}: {exc}")
            finally:
                self._current = None

    def _complete(self, job: Job, status: str, message: str = "", result=None) -> None:
        """Cache the result and retire the job BEFORE waking its waiters, so that a request
        sent right after the answer finds the cached result."""
        with self._lock:
            if self._inflight.get(job.key) is job:
                del self._inflight[job.key]
            if status == "ok" and result is not None:
                self._cache[job.key] = result
                self._cache.move_to_end(job.key)
                while len(self._cache) > self.cache_size:
                    self._cache.popitem(last=False)
        job._finish(status, message, result)

    def _run(self, job: Job) -> None:
        job.status = "running"
        t0 = time.monotonic()
        parent, child = self._ctx.Pipe(duplex=False)
        cancel_ev = self._ctx.Event()
        proc = self._ctx.Process(target=_worker_main, name="hawt-modal-worker",
                                 args=(child, self.turbine, job.kwargs, cancel_ev, os.getpid()),
                                 daemon=True)
        proc.start()
        child.close()
        self._proc = proc
        cancel_sent = None
        outcome = None
        try:
            while outcome is None:
                if (job.cancel_requested or self._stopping.is_set()) and cancel_sent is None:
                    cancel_ev.set()
                    cancel_sent = time.monotonic()
                if parent.poll(0.05):
                    try:
                        msg = parent.recv()
                    except (EOFError, OSError):
                        msg = None
                    if msg is None:
                        proc.join(1.0)
                        outcome = ("error", f"analysis worker exited unexpectedly "
                                            f"(exit code {proc.exitcode})", None)
                    elif msg[0] == "progress":
                        job._progress(msg[1], msg[2])
                    elif msg[0] == "result":
                        outcome = ("ok", "", msg[1])
                    else:
                        outcome = (msg[0], msg[1], None)
                    if outcome is not None or cancel_sent is None:
                        continue
                if cancel_sent is not None and time.monotonic() - cancel_sent > self.cancel_grace:
                    proc.terminate()
                    proc.join(2.0)
                    outcome = ("cancelled", "cancelled (worker stopped)", None)
                elif not proc.is_alive() and not parent.poll(0):
                    outcome = ("error", f"analysis worker exited unexpectedly "
                                        f"(exit code {proc.exitcode})", None)
        finally:
            parent.close()
            if proc.is_alive():
                proc.join(0.5)
            if proc.is_alive():
                proc.terminate()
                proc.join(1.0)
            if proc.is_alive():
                proc.kill()
                proc.join(1.0)
            self._proc = None
        job.wall_time = time.monotonic() - t0
        status, message, result = outcome
        if status == "cancelled" and not (job.cancel_requested or self._stopping.is_set()):
            status = "error"
        if status == "ok" and job.last_progress < 1.0:
            job._progress(1.0, "done")
        self._complete(job, status, message, result)

    def shutdown(self, timeout: float = 3.0) -> None:
        """Cancel everything, stop the worker (terminate if needed) and the runner thread."""
        self._stopping.set()
        cur = self._current
        if cur is not None:
            cur.cancel()
        self._jobs.put(None)
        self._thread.join(timeout)
        proc = self._proc
        if proc is not None and proc.is_alive():
            proc.kill()
        # jobs still queued
        while True:
            try:
                job = self._jobs.get_nowait()
            except queue.Empty:
                break
            if job is not None:
                job._finish("error", "the node is shutting down")
