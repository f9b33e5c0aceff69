"""``scenarios --record DIR``: one rosbag2 bag per run, named by scenario, mode and seed, so a
failure in a long campaign can be opened in Foxglove or replayed with ``ros2 bag play``.
With ``--record-failures`` the bag of a run that passed is deleted once it is judged."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any


def bag_path(root: str | Path, scenario: str, mode: str, seed: int) -> Path:
    return Path(root) / f"{scenario}_{mode}_seed{seed}"


def start_bag(runtime: Any, driver: Any, path: Path, **custom_data: str) -> Any:
    """Attach a recording to a loaded, not yet started runtime; call ``.stop()`` after the run."""
    from bt_runtime.runtime.recording.cli import Recording

    from ..recording import recording_hooks

    recording = Recording(bag=path, custom_data={k: str(v) for k, v in custom_data.items()})
    return recording.start(runtime, recording_hooks(driver))


def discard(path: Path) -> None:
    shutil.rmtree(path, ignore_errors=True)
