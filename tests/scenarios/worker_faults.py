"""An artifact maker that kills its worker process the first time it sees a run, so tests can
check that a backend retries a run whose worker died and still counts it once. Imported by
name ('tests.scenarios.worker_faults:die_once') inside pool and Ray worker processes."""

from __future__ import annotations

import os
from pathlib import Path


def die_once(run, result, marker_dir: str) -> str:
    marker = Path(marker_dir) / run.key.replace("/", "_")
    if not marker.exists():
        marker.touch()
        os._exit(3)  # the worker process dies here, as it would when killed or out of memory
    return "survived a retry"
