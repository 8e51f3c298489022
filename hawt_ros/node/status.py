"""The node's live status line on stderr (parameter ``status``)."""
from __future__ import annotations

import math
import threading
import time
from collections import deque
from pathlib import Path
from typing import Optional

from hawt_core.cli.status import StatusWriter

from .config import STATUS_PLAIN_PERIOD, STATUS_TTY_PERIOD, wrap_pi

__all__ = ["StatusLine"]


def _num(x, fmt: str, missing: str = "--") -> str:
    """``format(x, fmt)``, or ``missing`` when x is None or not finite (never 'nan')."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return missing
    if not math.isfinite(x):
        return missing
    text = format(x, fmt)
    return format(0.0, fmt) if float(text) == 0 else text   # no '-0.0'


class StatusLine:
    """The node's live status on stderr (parameter ``status``), e.g.

    ``hawt | t 12.35 s | rtf 1.00 | teeter +0.42 deg | yaw +0.00 deg | tip flap +41.3 mm,
    lag -2.1 mm | rec hawt-20261124-010203.mcap 1024 msgs | analyses 1``

    A daemon thread samples the node every STATUS_TTY_PERIOD s; on a terminal it redraws the
    line in place (``\\r``, cleared to the end of the line, cut to the terminal width), else it
    writes a plain line every STATUS_PLAIN_PERIOD s. The real-time factor is simulation time
    advanced / wall time elapsed over the last ~2 s (terminal) or the last period (plain).
    It only reads attributes the node replaces whole (no lock), and a write that fails or
    blocks never holds up the node: :meth:`close` waits at most ``timeout`` s for the thread.
    """

    def __init__(self, node, stream=None, tty: Optional[bool] = None):
        self.node = node
        self.out = StatusWriter(stream, tty)
        self.tty = self.out.tty
        self.period = STATUS_TTY_PERIOD if self.tty else STATUS_PLAIN_PERIOD
        self.window = 2.0 if self.tty else STATUS_PLAIN_PERIOD
        self._samples: deque = deque()          # (monotonic, sim t) of published instants
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None

    # ------------------------------------------------------------------ content
    def _sample(self) -> None:
        st = self.node.last_state
        if st is None:
            return
        mono, t = st[0], st[1]
        if not self._samples or mono > self._samples[-1][0]:
            self._samples.append((mono, t))
        horizon = time.monotonic() - self.window - self.period
        while len(self._samples) > 2 and self._samples[1][0] < horizon:
            self._samples.popleft()

    def real_time_factor(self, now: Optional[float] = None) -> Optional[float]:
        """Simulation time / wall time over the sampled window (None before two samples).
        When nothing new has been published for over a second, the window extends to now (a
        stalled simulation heads to 0 instead of showing its last pace)."""
        if len(self._samples) < 2:
            return None
        (m0, t0), (m1, t1) = self._samples[0], self._samples[-1]
        now = time.monotonic() if now is None else now
        if now - m1 > 1.0:
            m1 = now
        if m1 - m0 < 0.2:
            return None
        return (t1 - t0) / (m1 - m0)

    def line(self) -> str:
        node = self.node
        st = node.last_state
        parts = ["hawt"]
        if st is None:
            parts.append("t -- s (starting)")
        else:
            _, t, yaw, teeter, flap, lag = st
            parts += [f"t {_num(t, '.2f')} s",
                      f"rtf {_num(self.real_time_factor(), '.2f')}"]
            rotor = getattr(node, "last_rotor", None)
            if rotor is not None:
                # in wind: (wind [m/s], rotor [rpm], generator power [kW], pitch [deg])
                wind, rpm, power, pitch = rotor
                parts += [f"wind {_num(wind, '.1f')} m/s", f"rotor {_num(rpm, '.2f')} rpm",
                          f"power {_num(power, '.0f')} kW", f"pitch {_num(pitch, '.2f')} deg",
                          f"yaw {_num(math.degrees(wrap_pi(yaw)), '+.2f')} deg",
                          f"tip flap {_num(flap, '+.2f')} m, lag {_num(lag, '+.2f')} m"]
            else:
                parts += [f"teeter {_num(math.degrees(teeter), '+.2f')} deg",
                          f"yaw {_num(math.degrees(wrap_pi(yaw)), '+.2f')} deg",
                          f"tip flap {_num(flap * 1e3, '+.1f')} mm, "
                          f"lag {_num(lag * 1e3, '+.1f')} mm"]
        rec = node.recorder
        if rec is not None:
            parts.append(f"rec {Path(node.record_path).name} {rec.message_count} msgs")
        else:
            parts.append("rec off")
        waiting = node.analyses_waiting
        parts.append(f"analyses {node.analyses_served}" + (f" (+{waiting} running)"
                                                          if waiting else ""))
        if node._failed:
            parts.append("SIMULATION STOPPED")
        return " | ".join(parts)

    # ------------------------------------------------------------------ output
    def show(self) -> None:
        """Write the status once (redraw in place on a terminal)."""
        self.out.show(self.line())

    def end_line(self) -> None:
        """Terminate a redrawn line (before other output, at the end)."""
        self.out.end_line()

    def _run(self) -> None:
        next_show = time.monotonic() + (self.period if not self.tty else 0.0)
        while not self._stop.wait(STATUS_TTY_PERIOD):
            try:
                self._sample()
                if not self.node.status_enabled:
                    self.end_line()
                    continue
                now = time.monotonic()
                if now >= next_show:
                    next_show = now + self.period - 0.05
                    self.show()
            except Exception:  # noqa: BLE001 - the status line never takes the node down
                pass

    def start(self) -> "StatusLine":
        self._thread = threading.Thread(target=self._run, name="hawt-status", daemon=True)
        self._thread.start()
        return self

    def close(self, timeout: float = 1.0) -> None:
        """Stop the thread; on a terminal keep the last line visible (final redraw + newline)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        if self.out.pending and self.node.status_enabled and not self.out.broken:
            try:
                self._sample()
                self.show()
            except Exception:  # noqa: BLE001
                pass
        self.end_line()
