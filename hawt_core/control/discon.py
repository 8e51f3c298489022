"""A Bladed-style DISCON controller library (ROSCO's ``libdiscon.so``) called as OpenFAST's
ServoDyn calls it: ``DISCON(avrSWAP, aviFAIL, accINFILE, avcOUTNAME, avcMSG)`` through
``ctypes``, once per controller step.

The swap array ``avrSWAP`` (float32, 1-based indices below as in the Bladed manual and
ROSCO's ReadSetParameters.f90 ``ReadAvrSWAP``) carries the measurements in and the demands
out; ``aviFAIL`` < 0 stops the simulation with the library's message, > 0 is a warning.

Lifecycle: the first call has status 0 (ROSCO reads its DISCON.IN then), later calls 1, the
final call -1 (:meth:`DisconController.close`, also on errors).  ROSCO keeps its state in
module variables and refuses a second initialisation in one process, so every controller
loads its own copy of the library file (a temporary copy; removed on close).  ROSCO's
debug files (``LoggingLevel`` > 0) go next to ``log_root`` (default: a temporary folder).
What the library prints goes to stderr, never into a command's JSON on stdout (file
descriptor 1 is sent to 2 during each call, and the Fortran runtime flushed before it is
given back).
"""
from __future__ import annotations

import ctypes
import os
import shutil
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

__all__ = ["DisconController", "Measurements", "Demands", "ControllerError",
           "rosco_library"]

#: avrSWAP size: ROSCO reads up to index ~1020 (platform motion) and its cable and
#: structural-control groups beyond; OpenFAST's extended array is of this order.
SWAP_SIZE = 3500
MESSAGE_SIZE = 1024


class ControllerError(RuntimeError):
    """The controller library failed (aviFAIL < 0); the message is the library's."""


@dataclass
class Measurements:
    """What the controller reads at one call (SI units, rad, rad/s).

    ``pitch`` (Nb,) [rad, towards feather]; ``generator_speed`` [rad/s, high-speed shaft];
    ``rotor_speed`` [rad/s]; ``generator_torque`` [N m, HSS]; ``electrical_power`` and
    ``shaft_power`` [W]; ``hub_wind`` [m/s] (horizontal wind at the hub); ``yaw_error``
    [rad]; ``azimuth`` [rad]; ``root_out_of_plane`` (Nb,) [N m] blade-root out-of-plane
    bending moments; ``tower_top_acceleration`` (fore-aft, side-side) [m/s^2]."""

    time: float
    pitch: np.ndarray
    generator_speed: float
    rotor_speed: float
    generator_torque: float
    electrical_power: float
    shaft_power: float
    hub_wind: float
    yaw_error: float = 0.0
    azimuth: float = 0.0
    root_out_of_plane: Optional[np.ndarray] = None
    tower_top_acceleration: tuple = (0.0, 0.0)


@dataclass
class Demands:
    """What the controller asks for: ``pitch`` (Nb,) [rad, towards feather], generator
    ``torque`` [N m, HSS], ``yaw_rate`` [rad/s] (read, not applied by hawt: the yaw
    bearing is not driven)."""

    pitch: np.ndarray
    torque: float
    yaw_rate: float = 0.0


def rosco_library() -> Optional[Path]:
    """ROSCO's controller library installed by the ``rosco`` wheel, or None."""
    try:
        import importlib.util
        spec = importlib.util.find_spec("rosco")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    for folder in spec.submodule_search_locations:
        for name in ("libdiscon.so", "libdiscon.dylib", "libdiscon.dll"):
            p = Path(folder) / "lib" / name
            if p.is_file():
                return p
    return None


def _private_copy(lib: Path, folder: Path) -> Path:
    """A copy of ``lib`` under ``folder`` at the same depth below its package folder, with
    the wheel's bundled-library folders (``<site-packages>/*.libs``, found through the
    library's RPATH ``$ORIGIN/../../rosco.libs``) linked beside it."""
    copy = folder / "pkg" / lib.parent.name / lib.name
    copy.parent.mkdir(parents=True)
    shutil.copyfile(lib, copy)
    for libs in lib.parent.parent.parent.glob("*.libs"):
        (folder / libs.name).symlink_to(libs, target_is_directory=True)
    return copy


class _StdoutToStderr:
    """Send file descriptor 1 to 2 while the library runs (Fortran writes to unit 6)."""

    def __enter__(self):
        sys.stdout.flush()
        self._saved = os.dup(1)
        os.dup2(2, 1)

    def __exit__(self, *exc):
        os.dup2(self._saved, 1)
        os.close(self._saved)


class DisconController:
    """One instance of a DISCON library with its input file.

    ``library``: the shared library (default: ROSCO's from the ``rosco`` wheel);
    ``infile``: its DISCON.IN; ``dt`` [s]: the communication interval (the controller's
    step); ``n_blades``; ``log_root``: root name of the library's output files."""

    def __init__(self, infile, dt: float, n_blades: int, library=None,
                 log_root: Optional[str] = None):
        lib = Path(library) if library is not None else rosco_library()
        if lib is None or not lib.is_file():
            raise ValueError(f"controller library: {library or 'rosco/lib/libdiscon.so'!s} "
                             "not found; install the rosco wheel (scripts/bootstrap.sh does) "
                             "or give the library's path")
        infile = Path(infile)
        if not infile.is_file():
            raise ValueError(f"controller input file: {infile} not found (a DISCON.IN)")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt: {dt!r} is not allowed; need the controller's time step "
                             "> 0 [s]")
        if int(n_blades) != 3:
            # ROSCO reads and writes three pitch channels (avrSWAP 4, 33, 34 / 42-44)
            raise ValueError(f"n_blades: {n_blades} is not allowed; the DISCON interface "
                             "carries three blades' pitch")
        # gfortran's preconnected units unbuffered: what the library prints appears while
        # stdout is redirected (read when the runtime loads, hence before the first load)
        os.environ.setdefault("GFORTRAN_UNBUFFERED_PRECONNECTED", "y")
        self._tmp = tempfile.mkdtemp(prefix="hawt-discon-")
        copy = _private_copy(lib, Path(self._tmp))
        self._lib = ctypes.CDLL(str(copy), mode=getattr(ctypes, "RTLD_LOCAL", 0))
        self._fn = self._lib.DISCON
        self._fn.restype = None
        self._fn.argtypes = [ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_int),
                             ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p]
        # the Fortran runtime's FLUSH (all units), found through the library's dependencies:
        # when another package loaded that runtime first (SciPy bundles the same one), its
        # preconnected units are buffered and would reach stdout after the redirection
        try:
            self._flush = self._lib._gfortran_flush_i4
            self._flush.restype = None
            self._flush.argtypes = [ctypes.c_void_p]
        except AttributeError:
            self._flush = None
        self.dt = float(dt)
        self.n_blades = int(n_blades)
        self.infile = infile
        self._in = str(infile.resolve()).encode() + b"\0"
        root = log_root if log_root is not None else str(Path(self._tmp) / "hawt")
        self._out = root.encode() + b"\0"
        self._msg = ctypes.create_string_buffer(MESSAGE_SIZE)
        self.swap = np.zeros(SWAP_SIZE, dtype=np.float32)
        self._fail = ctypes.c_int(0)
        self.calls = 0
        self.closed = False
        #: the library reported a failure: no more calls (not even the final one)
        self.failed = False
        self.warnings = []

    # ------------------------------------------------------------------ calls
    def _call(self, status: int) -> None:
        s = self.swap
        s[0] = status
        s[48] = MESSAGE_SIZE                        # avrSWAP(49): message buffer size
        s[49] = len(self._in)                       # avrSWAP(50): infile name + NUL
        s[50] = len(self._out)                      # avrSWAP(51): root name + NUL
        self._fail.value = 0
        self._msg.value = b""
        with _StdoutToStderr():
            self._fn(s.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                     ctypes.byref(self._fail), self._in, self._out, self._msg)
            if self._flush is not None:
                self._flush(None)
        self.calls += 1
        msg = self._msg.value.decode(errors="replace").strip()
        if self._fail.value < 0:
            self.failed = True
            raise ControllerError(f"controller {self.infile.name}: {msg or 'failed'} "
                                  f"(aviFAIL = {self._fail.value}, call {self.calls})")
        if self._fail.value > 0 and msg:
            self.warnings.append(msg)
            warnings.warn(f"controller {self.infile.name}: {msg}", RuntimeWarning,
                          stacklevel=3)

    def step(self, m: Measurements) -> Demands:
        """One controller call (the first one initialises the library)."""
        if self.closed or self.failed:
            raise ControllerError("controller: already closed" if self.closed else
                                  "controller: the library failed before; no more calls")
        s = self.swap
        pitch = np.broadcast_to(np.asarray(m.pitch, float), (self.n_blades,))
        values = {2: m.time, 3: self.dt, 4: pitch[0], 33: pitch[1], 34: pitch[2],
                  10: 0.0,                  # pitch actuator: position demands
                  14: m.shaft_power, 15: m.electrical_power,
                  20: m.generator_speed, 21: m.rotor_speed, 23: m.generator_torque,
                  24: m.yaw_error, 27: m.hub_wind,
                  28: 1.0,                  # individual pitch demands (42-44) read back
                  35: 1.0,                  # generator contactor on
                  37: 0.0, 53: m.tower_top_acceleration[0],
                  54: m.tower_top_acceleration[1], 60: m.azimuth, 61: self.n_blades}
        if m.root_out_of_plane is not None:
            for i, k in enumerate((30, 31, 32)):
                values[k] = m.root_out_of_plane[i]
        for k, v in values.items():
            if not np.isfinite(v):
                raise ControllerError(f"controller: measurement avrSWAP({k}) = {v!r} is not "
                                      "finite")
            s[k - 1] = v
        self._call(0 if self.calls == 0 else 1)
        out = Demands(pitch=np.array([s[41], s[42], s[43]], float), torque=float(s[46]),
                      yaw_rate=float(s[47]))
        if not (np.all(np.isfinite(out.pitch)) and np.isfinite(out.torque)):
            raise ControllerError(f"controller {self.infile.name}: non-finite demands (pitch "
                                  f"{out.pitch.tolist()}, torque {out.torque})")
        return out

    def close(self) -> None:
        """The final call (status -1; skipped after a failure, and a failure of its own is
        a warning) and the library's copy removed; idempotent, never raises."""
        if self.closed:
            return
        self.closed = True
        try:
            if self.calls and not self.failed:
                self._call(-1)
        except ControllerError as exc:
            warnings.warn(f"{exc} (final call)", RuntimeWarning, stacklevel=2)
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
