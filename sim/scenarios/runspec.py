"""A campaign as a list of self-contained run specs, and the one function that executes a spec.

A :class:`RunSpec` carries everything a worker needs (the validated scenario itself, not its
file name; the mode, seed, run index, the artifacts to make, keyword options for
``run_scenario``), so any backend runs it the same way: inline, in a process pool, or as a Ray
task on another host. Flags that change what a run does (a scenario from ``--file``, generated
variants, recording) change the specs, never the backends.
"""

from __future__ import annotations

import socket
import time
import traceback
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from .artifacts import make_artifact
from .runner import MODES, run_scenario, scenario_seed
from .spec import ScenarioSpec

DEFAULT_RUNS = 20  # --paper-runs for a scenario the paper does not have


@dataclass(frozen=True)
class RunSpec:
    scenario: ScenarioSpec
    mode: str
    run: int
    seed: int
    artifacts: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    """artifact makers to call on the finished run, with their keyword options (artifacts.py);
    makers are named by a short name or 'module:function'"""
    options: Mapping[str, Any] = field(default_factory=dict)
    """extra keyword arguments for run_scenario"""

    @property
    def key(self) -> str:
        """The run's identity in result files: a resumed or merged campaign counts it once."""
        return run_key(self.scenario.name, self.mode, self.run)


def run_key(scenario: str, mode: str, run: int) -> str:
    return f"{scenario}/{mode}/{run}"


def plan_runs(specs: Sequence[ScenarioSpec], runs: int | None, seed: int, modes: Iterable[str] = MODES, *,
              artifacts: Mapping[str, Mapping[str, Any]] | None = None, options: Mapping[str, Any] | None = None) -> list[RunSpec]:
    """``runs`` per scenario and mode (the paper's number when None), in table order.

    Run ``i`` of every scenario and mode gets the seed ``scenario_seed(seed, i)``, whatever the
    backend, shard or resume: the same arguments give the same runs.
    """
    modes = tuple(modes)
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"two scenarios share the name(s) {', '.join(dup)}: results would mix")
    out = []
    for spec in specs:
        n = runs if runs is not None else spec.paper.runs if spec.paper is not None else DEFAULT_RUNS
        for mode in modes:
            for i in range(n):
                out.append(RunSpec(spec, mode, i, scenario_seed(seed, i), dict(artifacts or {}), dict(options or {})))
    return out


def parse_shard(text: str) -> tuple[int, int]:
    """'K/N' (1 <= K <= N) -> (K, N)."""
    try:
        k, n = (int(p) for p in text.split("/"))
    except ValueError:
        raise ValueError(f"--shard {text!r}: expected K/N, e.g. 2/4") from None
    if not 1 <= k <= n:
        raise ValueError(f"--shard {text!r}: K must be between 1 and N")
    return k, n


def shard_runs(runs: Sequence[RunSpec], k: int, n: int) -> list[RunSpec]:
    """Shard K of N: every N-th run from the K-th, so each shard gets a share of every scenario
    and mode (costly scenarios do not pile up on one shard); the N shards cover the plan once."""
    return list(runs[k - 1::n])


def execute_run(run: RunSpec) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run one spec (on whichever worker): its result line and its artifacts.

    An exception inside the run becomes a failed run with the reason, so one broken run does
    not lose a 10 000-run campaign; the traceback's last line says where.
    """
    from bt_runtime.logging_setup import quiet_logging

    quiet_logging("critical")
    result = None
    cpu0 = time.process_time()
    try:
        result = run_scenario(run.scenario, run.mode, run.seed, keep_record=bool(run.artifacts), **run.options)
        line = result.to_dict()
    except Exception as exc:  # noqa: BLE001 - recorded as the run's failure, see docstring
        where = traceback.extract_tb(exc.__traceback__)[-1]
        line = {"scenario": run.scenario.name, "mode": run.mode, "seed": run.seed, "success": False,
                "sim_time": 0.0, "wall_time": 0.0,
                "verdicts": [{"criterion": "run_completed", "passed": False,
                              "reason": f"{type(exc).__name__}: {exc} ({where.filename}:{where.lineno})"}]}
    line = {"type": "run", "key": run.key, "run": run.run, **line,
            "cpu_time": round(time.process_time() - cpu0, 4), "host": socket.gethostname()}
    artifacts: dict[str, Any] = {}
    if result is not None:
        for name, kwargs in run.artifacts.items():
            artifacts[name] = make_artifact(name, run, result, **kwargs)
    return line, artifacts


__all__ = ["RunSpec", "execute_run", "parse_shard", "plan_runs", "run_key", "shard_runs"]
