"""Wiring recording and the live view into a command line (``run --record/--foxglove``).

    add_arguments(run_parser)
    recording = Recording.from_args(args)      # nothing opened yet
    recording.start(runtime, hooks)            # after load_tree, before runtime.start()
    ...
    await runtime.stop()
    report = recording.stop()                  # drains the queue, closes the bag and server
"""

from __future__ import annotations

import argparse
import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .config import RecordingOptions
from .hooks import RecordingHooks
from .live import DEFAULT_PORT

if TYPE_CHECKING:
    from ..app import AutonomyRuntime
    from .recorder import Recorder


class RecordingError(Exception):
    """A recording that cannot start (bad folder, port in use, missing package): for people."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("recording and live view")
    group.add_argument("--record", type=Path, default=None, metavar="DIR",
                       help="write a rosbag2 bag (MCAP storage) to DIR (a new or empty folder)")
    group.add_argument("--record-flush", type=float, default=None, metavar="S",
                       help="wall seconds between bag segment closes (default 5): a killed run keeps "
                            "everything up to the last one")
    group.add_argument("--record-config", type=Path, default=None, metavar="FILE",
                       help="topic names, frames, queue size (YAML, see docs/recording.md)")
    group.add_argument("--foxglove", nargs="?", type=int, const=DEFAULT_PORT, default=None, metavar="PORT",
                       help=f"serve the same topics to Foxglove over WebSocket on PORT (default {DEFAULT_PORT})")
    group.add_argument("--foxglove-host", default="127.0.0.1", metavar="HOST",
                       help="address for --foxglove (default 127.0.0.1; 0.0.0.0 for all)")


def load_options(path: Path | None) -> RecordingOptions:
    if path is None:
        return RecordingOptions()
    import yaml
    from pydantic import ValidationError

    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        return RecordingOptions.model_validate(data)
    except FileNotFoundError:
        raise RecordingError(f"recording config not found: {path}") from None
    except (yaml.YAMLError, ValidationError) as exc:
        raise RecordingError(f"{path}: {exc}") from None


@dataclass
class Recording:
    bag: Path | None = None
    foxglove_port: int | None = None
    foxglove_host: str = "127.0.0.1"
    options: RecordingOptions = field(default_factory=RecordingOptions)
    custom_data: dict[str, str] = field(default_factory=dict)
    recorder: Recorder | None = None
    live: Any = None
    writer: Any = None
    report: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_args(cls, args: Any) -> Recording:
        options = load_options(getattr(args, "record_config", None))
        flush = getattr(args, "record_flush", None)
        if flush is not None:
            if not flush > 0:
                raise RecordingError(f"--record-flush must be a positive number of seconds, got {flush}")
            options = options.model_copy(update={"flush_interval_s": flush})
        return cls(bag=getattr(args, "record", None), foxglove_port=getattr(args, "foxglove", None),
                   foxglove_host=getattr(args, "foxglove_host", "127.0.0.1"), options=options)

    @property
    def enabled(self) -> bool:
        return self.bag is not None or self.foxglove_port is not None

    def start(self, runtime: AutonomyRuntime, hooks: RecordingHooks | None = None) -> Recording:
        if not self.enabled:
            return self
        from ..clock import is_virtual
        from .convert import ConvertState
        from .pipeline import RecordPipeline
        from .recorder import Recorder

        opts = self.options
        try:
            import foxglove  # noqa: F401 - the extra's packages are there

            from .channels import ChannelSet
        except ImportError as exc:
            raise RecordingError(f"recording needs the [record] extra (pip install 'bt_runtime[record]'): "
                                 f"{exc}") from None
        try:
            if self.bag is not None:
                from .bag import Rosbag2Bag

                self.writer = Rosbag2Bag(self.bag, ChannelSet(), compression=opts.compression,
                                         custom_data=self.custom_data)
            if self.foxglove_port is not None:
                from .live import FoxgloveLive

                self.live = FoxgloveLive(ChannelSet(), self.foxglove_port, self.foxglove_host)
        except (OSError, RuntimeError) as exc:
            if self.writer is not None:  # the bag folder was made for nothing: leave no empty bag
                with contextlib.suppress(OSError):
                    self.writer.path.rmdir()
                self.writer = None
            raise RecordingError(f"{exc}") from None
        state = ConvertState(frames=opts.frames, tf_topic=opts.topics.tf, robot_time=robot_clock(runtime.driver))
        pipeline = RecordPipeline(bag=self.writer, live=self.live, state=state, live_rate_hz=opts.live_rate_hz,
                                  queue_size=opts.queue_size, flush_interval_s=opts.flush_interval_s,
                                  latched_topics=tuple(t for t in (opts.topics.tf_static, opts.topics.map) if t))
        self.recorder = Recorder(runtime, pipeline, opts, hooks)
        # drained on the loop on virtual time, and for a live view alone (pipeline.py says why)
        pipeline.start(on_loop=is_virtual() or self.writer is None)
        self.recorder.attach()
        return self

    def stop(self) -> dict[str, Any]:
        """Detach, write everything queued, close; returns what was recorded and dropped."""
        if self.recorder is None:
            return self.report
        recorder, self.recorder = self.recorder, None
        recorder.detach()
        pipeline = recorder.pipeline
        pipeline.stop()
        counts = self.writer.message_counts() if self.writer is not None else dict(pipeline.written)
        self.report = {"path": str(self.bag) if self.bag is not None else None,
                       "foxglove": self.live.url if self.live is not None else None,
                       "messages": counts, "message_count": sum(counts.values()),
                       "dropped": dict(pipeline.dropped), "errors": pipeline.errors,
                       "max_queued": pipeline.max_queued, "writer_cpu_s": round(pipeline.cpu_s, 3),
                       "max_flush_step_ms": round(pipeline.max_flush_step_s * 1e3, 2)}
        return self.report


def robot_clock(driver: Any) -> Any:
    """The driver's ``robot_time`` (loop time -> the robot's own clock, ROS time under
    ``--driver ros2``) for the writer thread, or None when the loop clock is the robot's clock
    (the simulator). A translation that fails keeps the loop time (the stamp of a message never
    costs the message)."""
    robot_time = getattr(driver, "robot_time", None)
    if not callable(robot_time):
        return None

    def to_robot(t: float) -> float | None:
        try:
            return robot_time(t)
        except Exception:  # e.g. no event loop to ask yet, from the writer thread
            return None

    return to_robot


def format_report(report: dict[str, Any]) -> str:
    if not report:
        return ""
    where = report["path"] or report["foxglove"]
    dropped = sum(report["dropped"].values())
    text = f"recording: {where}: {report['message_count']} messages on {len(report['messages'])} topics"
    if dropped:
        text += f", {dropped} DROPPED (" + ", ".join(f"{k}={v}" for k, v in sorted(report["dropped"].items())) + ")"
    if report["errors"]:
        text += f", {report['errors']} conversion errors"
    return text
