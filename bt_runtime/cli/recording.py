"""``run --record/--foxglove``: the CLI's wiring of a recording (the simulator's hooks included,
since the runtime's recorder never imports the simulator)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..runtime.recording.cli import Recording, RecordingError, add_arguments, format_report

__all__ = ["RecordingError", "add_arguments", "format_report", "start_recording"]


def start_recording(args: argparse.Namespace, runtime: Any, driver: Any) -> Recording:
    """Open the bag and/or the Foxglove server and attach them (before ``runtime.start()``)."""
    recording = Recording.from_args(args)
    if not recording.enabled:
        return recording
    hooks = None
    if getattr(driver, "sim", None) is not None:
        from sim.recording import recording_hooks

        hooks = recording_hooks(driver)
    recording.custom_data = {"tree": str(args.tree), "driver": str(args.driver), "world": str(args.world),
                             "robot": str(args.robot), "seed": str(args.seed)}
    recording.start(runtime, hooks)
    if recording.live is not None:
        print(f"foxglove: {recording.live.url} (open it in Foxglove: Open connection -> "
              f"Foxglove WebSocket)", file=sys.stderr, flush=True)
    return recording
