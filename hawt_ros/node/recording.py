"""Recording every published topic into an MCAP file or rosbag2 folder (parameter
``record``, changeable while the node runs)."""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from ..bag import BagWriter, type_name_of, unfinalized_recordings
from .config import STATE_QOS

__all__ = ["Recording"]


class Recording:
    """Part of :class:`~hawt_ros.node.turbine_node.HawtNode`: start and stop recordings."""

    def _start_recording(self, path: str) -> None:
        p = Path(path).expanduser()
        if p.exists() and (p.is_file() or any(p.iterdir())):
            raise ValueError(f"{p} exists; choose a new file name (recordings are never overwritten)")
        try:
            turbine_yaml = Path(self.turbine_path).read_text()
        except OSError:
            turbine_yaml = None
        s = self.settings
        settings = {"node": self.get_fully_qualified_name(), "turbine": self.turbine_path,
                    "elements": self.model.beam.elements,
                    "order": int(self.turbine.blade.order), "step_deg": s.step_deg,
                    "publish_rate": s.publish_rate, "real_time_factor": s.real_time_factor,
                    "perturb": dict(s.perturb), "marker_frame": s.marker_frame,
                    "simulation": self.sim_source, "wind": s.wind,
                    "wind_series": None if not s.wind_series else {
                        "points": [list(p) for p in s.wind_series.points],
                        "gust_start": s.wind_series.gust_start},
                    "controller": s.controller if s.wind > 0 else None}
        self._name_crashed_recordings(p.parent)
        self.recorder = BagWriter(p, turbine_yaml=turbine_yaml, settings=settings)
        for pub in self._publishers_list():
            self.recorder.add_topic(pub.topic_name, type_name_of(pub.msg_type), qos=STATE_QOS)
        self.record_path = str(p)

    def _name_crashed_recordings(self, folder: Path) -> None:
        """Warn about the unfinalized recordings (a node killed, a machine that lost power)
        in the folder the new recording goes to, and say how to recover them."""
        try:
            crashed = unfinalized_recordings(folder)
        except OSError:
            return
        if not crashed:
            return
        names = ", ".join(p.name for p in crashed[:5]) + (
            f" and {len(crashed) - 5} more" if len(crashed) > 5 else "")
        self.get_logger().warning(
            f"{len(crashed)} unfinalized recording(s) in {folder} (a node was killed?): "
            f"{names}; other readers need them finalized: hawt recover {crashed[0]} "
            "(writes <name>-recovered.mcap)")

    def _stop_recording(self, failure: Optional[str] = None) -> None:
        """Drop the recorder and clear ``record_path`` and ``settings.record`` (so setting
        ``record`` again starts a new recording). Normally finalize the file and log it; with
        ``failure`` (a write failed) log that and close the file quietly."""
        rec, path = self.recorder, self.record_path
        self.recorder = None
        self.record_path = ""
        if self.settings.record:
            self.settings = self.settings.replace(record="")
        if rec is None:
            return
        if failure is not None:
            self.get_logger().error(f"recording to {path} failed ({failure}); recording stopped")
            try:
                rec.close()
            except Exception:  # noqa: BLE001
                pass
            return
        try:
            rec.close()
            self.get_logger().info(f"recording finalized: {path} ({rec.message_count} messages)")
        except Exception as exc:  # noqa: BLE001
            self.get_logger().error(f"closing the recording {path} failed: {exc}")
