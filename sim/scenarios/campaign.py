"""The scenario campaign: every scenario, both modes, many seeded runs, in parallel processes.

Produces the paper's Table IV (runs, % successful without and with the autonomy layer, and
the paper's figures), a JSON file with every run and its verdicts, and on request a PNG
report per scenario. Runs are independent and reproducible from (base seed, run index).
"""

from __future__ import annotations

import collections
import multiprocessing
import os
import re
import sys
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

from .runner import MODES, run_scenario, scenario_seed
from .spec import ScenarioSpec, load_scenario

_NUMBER = re.compile(r"-?\d+(\.\d+)?")


@dataclass(frozen=True)
class Task:
    scenario: str
    mode: str
    run: int
    seed: int


@dataclass
class CampaignResult:
    specs: dict[str, ScenarioSpec]
    results: list[dict[str, Any]]
    wall_time: float
    jobs: int
    trajectories: dict[tuple[str, str, int], Any] = field(default_factory=dict)

    def by_scenario(self) -> dict[str, dict[str, list[dict[str, Any]]]]:
        table: dict[str, dict[str, list[dict[str, Any]]]] = {n: {m: [] for m in MODES} for n in self.specs}
        for r in self.results:
            table[r["scenario"]][r["mode"]].append(r)
        return table

    def success_rate(self, scenario: str, mode: str) -> float:
        runs = self.by_scenario()[scenario][mode]
        return 100.0 * sum(r["success"] for r in runs) / len(runs) if runs else float("nan")

    @property
    def sim_time(self) -> float:
        return sum(r["sim_time"] for r in self.results)

    def to_dict(self) -> dict[str, Any]:
        scenarios = {}
        for name, modes in self.by_scenario().items():
            spec = self.specs[name]
            scenarios[name] = {
                "table": spec.table, "requirements": spec.requirements, "description": spec.description,
                "paper": {"runs": spec.paper.runs, "without": spec.paper.without, "with": spec.paper.with_,
                          "real_world_without": spec.paper.real_world_without,
                          "real_world_with": spec.paper.real_world_with},
                **{mode: {"runs": len(runs), "success_rate": self.success_rate(name, mode),
                          "failure_reasons": failure_reasons(runs), "results": runs}
                   for mode, runs in modes.items()},
            }
        return {"meta": {"wall_time_s": round(self.wall_time, 2), "jobs": self.jobs, "runs": len(self.results),
                         "sim_time_s": round(self.sim_time, 1),
                         "mean_real_time_factor": round(self.sim_time / (self.wall_time * self.jobs), 1)
                         if self.wall_time else None},
                "scenarios": scenarios}


def failure_reasons(runs: list[dict[str, Any]]) -> dict[str, int]:
    """How often each failing criterion's reason appears (numbers replaced so they group)."""
    counter: collections.Counter[str] = collections.Counter()
    for r in runs:
        for v in r["verdicts"]:
            if not v["passed"]:
                counter[f"{v['criterion']}: {_NUMBER.sub('#', v['reason'])}"] += 1
    return dict(counter.most_common())


def plan(names: Iterable[str], runs: int | None, seed: int, modes: Iterable[str] = MODES) -> list[Task]:
    """``runs`` per scenario and mode, or the paper's number of runs when None."""
    tasks = []
    for name in names:
        spec = load_scenario(name)
        n = spec.paper.runs if runs is None else runs
        for mode in modes:
            for i in range(n):
                tasks.append(Task(name, mode, i, scenario_seed(seed, i)))
    return tasks


def _run_task(task: Task, keep_trajectory: bool) -> tuple[dict[str, Any], Any]:
    from bt_runtime.logging_setup import quiet_logging

    quiet_logging("critical")
    result = run_scenario(task.scenario, task.mode, task.seed, keep_record=keep_trajectory)
    out = result.to_dict()
    out["run"] = task.run
    traj = None
    if keep_trajectory and result.record is not None:
        rec = result.record
        traj = {"trajectory": rec.trajectory[:, :3].copy(),
                "marks": [(r.goal.x, r.goal.y) for r in rec.nav_requests if r.method == "add_obstacle"],
                "faults": [(f.t, f.kind) for f in rec.fault_log],
                "collisions": [tuple(map(float, e.data["point"])) for e in rec.sim_events
                               if e.kind == "collision" and e.data.get("point") is not None],
                "goals": [(g.pose.x, g.pose.y) for g in rec.goals]}
    return out, traj


class Progress:
    """A one-line progress bar on a terminal (a line every 10 % otherwise)."""

    def __init__(self, total: int, stream=sys.stderr):
        self.total = total
        self.stream = stream
        self.done = 0
        self.ok = 0
        self.t0 = time.perf_counter()
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self._last_decile = -1

    def update(self, success: bool) -> None:
        self.done += 1
        self.ok += int(success)
        elapsed = time.perf_counter() - self.t0
        eta = elapsed / self.done * (self.total - self.done)
        width = 30
        filled = int(width * self.done / self.total)
        line = (f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} runs  "
                f"{self.ok} ok  {elapsed:5.1f} s  eta {eta:5.1f} s")
        if self.tty:
            self.stream.write("\r" + line)
            if self.done == self.total:
                self.stream.write("\n")
            self.stream.flush()
        elif self.done * 10 // self.total != self._last_decile:
            self._last_decile = self.done * 10 // self.total
            self.stream.write(line + "\n")
            self.stream.flush()


def run_campaign(names: list[str], *, runs: int | None, seed: int = 0, jobs: int | None = None,
                 keep_trajectories: bool = False, modes: Iterable[str] = MODES,
                 on_result: Callable[[dict[str, Any]], Any] | None = None) -> CampaignResult:
    specs = {n: load_scenario(n) for n in names}
    tasks = plan(names, runs, seed, modes)
    jobs = jobs or os.cpu_count() or 1
    t0 = time.perf_counter()
    results: list[dict[str, Any]] = []
    trajectories: dict[tuple[str, str, int], Any] = {}

    def collect(task: Task, out: dict[str, Any], traj: Any) -> None:
        results.append(out)
        if traj is not None:
            trajectories[(task.scenario, task.mode, task.run)] = traj
        if on_result is not None:
            on_result(out)

    if jobs <= 1:
        for task in tasks:
            collect(task, *_run_task(task, keep_trajectories))
    else:
        ctx = multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            futures = {pool.submit(_run_task, t, keep_trajectories): t for t in tasks}
            for future in as_completed(futures):
                collect(futures[future], *future.result())
    order = {(t.scenario, t.mode, t.run): i for i, t in enumerate(tasks)}
    results.sort(key=lambda r: order[(r["scenario"], r["mode"], r["run"])])
    return CampaignResult(specs, results, time.perf_counter() - t0, jobs, trajectories)


def format_table(result: CampaignResult) -> str:
    """Table IV: runs, % successful without and with the autonomy layer, and the paper's."""
    head = (f"{'Scenario':<15}{'Runs':>5}{'Without %':>11}{'With %':>9}   "
            f"{'Paper: runs':>11}{'without':>9}{'with':>6}")
    lines = [head, "-" * len(head)]
    for name, modes in result.by_scenario().items():
        spec = result.specs[name]
        n = max(len(modes["with"]), len(modes["without"]))
        without = result.success_rate(name, "without")
        with_ = result.success_rate(name, "with")
        lines.append(f"{name:<15}{n:>5}{_pct(without):>11}{_pct(with_):>9}   "
                     f"{spec.paper.runs:>11}{spec.paper.without:>9.0f}{spec.paper.with_:>6.0f}")
    return "\n".join(lines)


def _pct(rate: float) -> str:
    return "-" if rate != rate else f"{rate:.0f}"  # NaN: that mode was not run


def format_failures(result: CampaignResult) -> str:
    """Why runs failed: with the layer (should be empty) and without (the real reasons)."""
    lines = []
    for name, modes in result.by_scenario().items():
        for mode in ("with", "without"):
            reasons = failure_reasons(modes[mode])
            if reasons:
                top = "; ".join(f"{k} (x{v})" for k, v in list(reasons.items())[:2])
                lines.append(f"  {name:<15}{mode:<8} {top}")
    return "\n".join(lines)
