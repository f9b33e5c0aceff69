"""Every run a Ray task: on a local Ray started for the campaign, or on a cluster (``address``).

Runs are submitted all at once (so an autoscaling cluster sees the whole demand) and
collected as they finish. A worker process or node that dies is retried by Ray
(``max_retries``); a run whose worker dies on every attempt is recorded as a failed run
naming the error, so the campaign still counts every run exactly once.

Ray never phones home from here: usage statistics are off and no dashboard is started. On a
cluster the project's code travels with the job as Ray's runtime environment
(``working_dir`` = this checkout, without virtualenvs, git data and results); a local Ray
shares this machine's files and needs no upload.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from .runspec import RunSpec, execute_run

ROOT = Path(__file__).resolve().parents[2]
EXCLUDES = [".git", ".venv", "venv", ".ci", "**/__pycache__", "*.jsonl", "results", "bench/out", "*.mcap"]
MAX_RETRIES = 3


def runtime_env(root: Path = ROOT) -> dict[str, Any]:
    """How the project's code reaches the workers of a remote cluster: this checkout as the job's
    working directory (workers import bt_runtime, nodes, sim, groot and read trees/ from it)."""
    return {"working_dir": str(root), "excludes": list(EXCLUDES)}


class RayBackend:
    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None, ship_code: bool | None = None):
        os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # before ray is imported
        try:
            import ray
        except ImportError:
            raise RuntimeError("--backend ray needs Ray: pip install 'bt_runtime[cluster]'") from None
        self._ray = ray
        ship = address is not None if ship_code is None else ship_code
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                  "logging_level": logging.ERROR, "configure_logging": False}
        if ship:
            kwargs["runtime_env"] = runtime_env()
        if address is None:
            kwargs.update(num_cpus=num_cpus or os.cpu_count() or 1, _node_ip_address="127.0.0.1")
        self._owner = not ray.is_initialized()  # else: this process already runs Ray (a notebook, a test)
        if self._owner:
            try:
                ray.init(address=address, **kwargs)
            except ConnectionError as exc:
                raise RuntimeError(f"--ray-address {address}: cannot reach the Ray cluster ({exc}); is "
                                   f"'ray start --head' running there, and does this machine hold its token "
                                   f"(docs/cluster.md)?") from None
        self.cpus = int(ray.cluster_resources().get("CPU", 0)) or 1
        self._task = ray.remote(execute_run).options(num_cpus=1, max_retries=MAX_RETRIES)

    def run(self, runs: Sequence[RunSpec]) -> Iterator[tuple[dict[str, Any], dict[str, Any]]]:
        ray = self._ray
        by_ref = {self._task.remote(spec): spec for spec in runs}
        pending = list(by_ref)
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            if pending:  # and whatever else has finished meanwhile, in one call
                more, pending = ray.wait(pending, num_returns=len(pending), timeout=0)
                ready += more
            for ref in ready:
                spec = by_ref.pop(ref)
                try:
                    yield ray.get(ref)
                except ray.exceptions.RayError as exc:  # the worker died on every attempt
                    yield _lost(spec, exc), {}

    def close(self) -> None:
        """Disconnect (and stop a local Ray this backend started); a Ray someone else started stays."""
        if self._owner:
            self._ray.shutdown()


def _lost(spec: RunSpec, exc: Exception) -> dict[str, Any]:
    reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return {"type": "run", "key": spec.key, "scenario": spec.scenario.name, "mode": spec.mode, "run": spec.run,
            "seed": spec.seed, "success": False, "sim_time": 0.0, "wall_time": 0.0, "host": None,
            "verdicts": [{"criterion": "run_completed", "passed": False,
                          "reason": f"worker lost {MAX_RETRIES + 1} times: {type(exc).__name__}: {reason}"}]}
