"""One status line on a terminal: the progress of ``hawt`` commands and the live status of
the ROS node (hawt_ros) share it.

On a terminal the line is redrawn in place (carriage return, cleared to the end of the line,
cut to the terminal width); elsewhere every update is a plain line.  A closed or broken
stream silences it (a status line never takes a program down)."""
from __future__ import annotations

import shutil
import sys
import threading

__all__ = ["stream_is_tty", "StatusWriter", "ProgressLine"]


def stream_is_tty(stream=None) -> bool:
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


class StatusWriter:
    """Writes a status line to ``stream`` (default stderr): :meth:`show` redraws it in place
    on a terminal (``tty``) or writes a plain line, :meth:`end_line` terminates a redrawn
    line before other output; thread-safe."""

    def __init__(self, stream=None, tty=None):
        self.stream = stream if stream is not None else sys.stderr
        self.tty = stream_is_tty(self.stream) if tty is None else bool(tty)
        self.pending = False            # a redrawn line without its newline
        self.broken = False
        self._lock = threading.Lock()

    def write(self, text: str) -> None:
        if self.broken:
            return
        try:
            with self._lock:
                self.stream.write(text)
                self.stream.flush()
        except (OSError, ValueError):           # closed or broken stream: stop quietly
            self.broken = True

    def show(self, text: str) -> None:
        if self.tty:
            width = shutil.get_terminal_size((120, 24)).columns - 1
            if width > 10 and len(text) > width:
                text = text[:width - 1] + "~"
            self.write("\r\x1b[K" + text)
            self.pending = True
        else:
            self.write(text + "\n")

    def end_line(self) -> None:
        if self.pending:
            self.pending = False
            self.write("\n")

    def clear(self) -> None:
        """Erase a redrawn line (a terminal's line is reused by what follows)."""
        if self.pending:
            self.pending = False
            self.write("\r\x1b[K")


class ProgressLine:
    """A ``progress(fraction, message)`` callback for long commands: a bar and the message,
    on a terminal only unless ``force`` (then plain lines, e.g. into a log file)."""

    def __init__(self, enabled: bool, stream=None, force: bool = False):
        self.writer = StatusWriter(stream)
        self.enabled = bool(enabled) and (self.writer.tty or force)

    def __call__(self, fraction: float, message: str) -> None:
        if self.enabled:
            bar = "#" * int(20 * fraction)
            self.writer.show(f"[{bar:<20}] {100 * fraction:5.1f} % {message}")

    def close(self) -> None:
        """Erase the line on a terminal (the command's output follows)."""
        if self.enabled:
            self.writer.clear()
