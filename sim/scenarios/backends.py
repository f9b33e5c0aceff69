"""Where a campaign's runs execute. A backend takes run specs and yields each run's outcome
as it finishes, in any order; it knows nothing about scenarios, flags or files.

* ``LocalBackend``: this machine, a process per CPU (fork), or inline for one job.
* ``RayBackend`` (ray_backend.py): every run a Ray task, on a local Ray or a cluster.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
from collections.abc import Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from .runspec import RunSpec, execute_run

Outcome = tuple[dict[str, Any], dict[str, Any]]  # (result line, artifacts)


class Backend(Protocol):
    name: str
    cpus: int
    """CPUs the runs are spread over (the cluster's, for Ray)"""

    def run(self, runs: Sequence[RunSpec]) -> Iterator[Outcome]: ...

    def close(self) -> None: ...


class LocalBackend:
    """A process pool on this machine. A worker process that dies (killed, out of memory)
    breaks the pool: the pool is rebuilt and the runs without a result are submitted again,
    up to ``max_retries`` times, as Ray does with its tasks."""

    name = "local"

    def __init__(self, jobs: int | None = None, max_retries: int = 3):
        self.cpus = max(1, jobs or os.cpu_count() or 1)
        self.max_retries = max_retries

    def run(self, runs: Sequence[RunSpec]) -> Iterator[Outcome]:
        if self.cpus == 1:
            for spec in runs:
                yield execute_run(spec)
            return
        pending = list(runs)
        for attempt in range(self.max_retries + 1):
            try:
                yield from self._pool(pending)
                return
            except BrokenProcessPool:
                if attempt == self.max_retries:
                    raise
                pending = list(self._unfinished.values())

    def _pool(self, runs: list[RunSpec]) -> Iterator[Outcome]:
        self._unfinished = {spec.key: spec for spec in runs}
        fork = sys.platform.startswith("linux")
        ctx = multiprocessing.get_context("fork" if fork else "spawn")
        if fork:
            from .warm import warm_caches

            warm_caches(runs)  # the workers inherit the filled caches
        with ProcessPoolExecutor(max_workers=self.cpus, mp_context=ctx) as pool:
            futures = {pool.submit(execute_run, spec): spec for spec in runs}
            for future in as_completed(futures):
                outcome = future.result()  # BrokenProcessPool if a worker died
                del self._unfinished[futures[future].key]
                yield outcome

    def close(self) -> None:
        pass


def make_backend(name: str, *, jobs: int | None = None, ray_address: str | None = None) -> Backend:
    if name == "local":
        return LocalBackend(jobs)
    if name == "ray":
        from .ray_backend import RayBackend

        return RayBackend(address=ray_address, num_cpus=jobs)
    raise ValueError(f"unknown backend {name!r} (local, ray)")
