"""``--register tests.safety.recording:register`` for CLI runs under test: the fault nodes, and
a record of every command the simulated base received, written as JSON at exit to the file
named by ``SAFETY_BASE_LOG`` (the test reads it after signalling the process)."""

from __future__ import annotations

import atexit
import json
import os
from pathlib import Path

from tests.safety.support import BaseRecorder, register_fault_nodes


def register(factory) -> None:
    register_fault_nodes(factory)
    path = os.environ.get("SAFETY_BASE_LOG")
    sim = getattr(getattr(factory.context, "driver", None), "sim", None)
    if path and sim is not None:
        recorder = BaseRecorder(sim)

        def dump() -> None:
            rows = [(r.wall, r.linear, r.angular) for r in recorder.received]
            Path(path).write_text(json.dumps(rows), encoding="utf-8")

        atexit.register(dump)
