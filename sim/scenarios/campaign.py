"""The scenario campaign: every scenario, both modes, many seeded runs, on a backend.

Produces the paper's Table IV (runs, % successful without and with the autonomy layer, and
the paper's figures), a JSON file with every run and its verdicts, and on request a PNG
report per scenario. Runs are independent and reproducible from (base seed, run index).
The plan is a list of self-contained run specs (runspec.py) that a backend executes
(backends.py: a local process pool; ray_backend.py: Ray), streamed to a results file
(results.py) that a later campaign resumes and that ``scenarios merge`` combines.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from .backends import Backend
from .progress import Progress
from .results import Recorded, ResultsError
from .runner import MODES
from .runspec import RunSpec
from .spec import ScenarioSpec

_NUMBER = re.compile(r"-?\d+(\.\d+)?")


@dataclass
class CampaignResult:
    specs: dict[str, ScenarioSpec]
    results: list[dict[str, Any]]
    wall_time: float
    jobs: int
    """CPUs the runs were spread over"""
    trajectories: dict[tuple[str, str, int], Any] = field(default_factory=dict)
    backend: str = "local"
    resumed: int = 0
    """runs taken from the results file of an interrupted campaign, not run again"""

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
                "paper": None if spec.paper is None else {
                    "runs": spec.paper.runs, "without": spec.paper.without, "with": spec.paper.with_,
                    "real_world_without": spec.paper.real_world_without,
                    "real_world_with": spec.paper.real_world_with},
                **{mode: {"runs": len(runs), "success_rate": self.success_rate(name, mode),
                          "failure_reasons": failure_reasons(runs), "results": runs}
                   for mode, runs in modes.items()},
            }
        run_wall = sum(r["wall_time"] for r in self.results)
        return {"meta": {"wall_time_s": round(self.wall_time, 2), "jobs": self.jobs, "runs": len(self.results),
                         "backend": self.backend, "resumed_runs": self.resumed,
                         "sim_time_s": round(self.sim_time, 1),
                         "mean_real_time_factor": round(self.sim_time / run_wall, 1) if run_wall else None},
                "scenarios": scenarios}


def failure_reasons(runs: list[dict[str, Any]]) -> dict[str, int]:
    """How often each failing criterion's reason appears. Reasons that differ only in their
    numbers group together, and each number reads as the range seen ("crashed at 2.1..3.4 s")."""
    groups: dict[str, tuple[str, list[list[str]]]] = {}  # pattern -> (first reason, numbers of each)
    for r in runs:
        for v in r["verdicts"]:
            if not v["passed"]:
                text = f"{v['criterion']}: {v['reason']}"
                first, numbers = groups.setdefault(_NUMBER.sub("#", text), (text, []))
                numbers.append([m.group(0) for m in _NUMBER.finditer(text)])
    counted = sorted(groups.values(), key=lambda item: -len(item[1]))  # stable: first seen first among equals
    return {_with_ranges(first, numbers): len(numbers) for first, numbers in counted}


def _with_ranges(first: str, numbers: list[list[str]]) -> str:
    """``first`` with its k-th number replaced by the value, or the min..max, seen there in all."""
    position = iter(range(len(numbers[0])))

    def ranged(match: re.Match) -> str:
        k = next(position)
        seen = sorted({run[k] for run in numbers}, key=float)
        return seen[0] if len(seen) == 1 else f"{seen[0]}..{seen[-1]}"

    return _NUMBER.sub(ranged, first)


def run_campaign(runs: Sequence[RunSpec], backend: Backend, *, specs: Sequence[ScenarioSpec] | None = None,
                 recorded: Mapping[str, dict[str, Any]] | None = None,
                 on_result: Callable[[dict[str, Any]], Any] | None = None) -> CampaignResult:
    """Execute the planned runs on the backend, skipping those already ``recorded`` (a resumed
    campaign: their recorded results count instead), each counted exactly once.

    ``on_result`` sees every new result line as it arrives (to stream it to a file and move
    the progress bar); the returned result holds the runs in plan order.
    """
    recorded = recorded or {}
    spec_list = list(specs) if specs is not None else list({r.scenario.name: r.scenario for r in runs}.values())
    planned = {r.key: i for i, r in enumerate(runs)}
    results = {key: recorded[key] for key in planned if key in recorded}
    todo = [r for r in runs if r.key not in results]
    trajectories: dict[tuple[str, str, int], Any] = {}
    t0 = time.perf_counter()
    for line, artifacts in backend.run(todo):
        key = line["key"]
        if key in results or key not in planned:
            continue  # a duplicate delivery (or a stray) is never counted twice
        paths = {name: value for name, value in artifacts.items() if isinstance(value, str)}
        if paths:
            line["artifacts"] = paths
        if artifacts.get("trajectory") is not None:
            trajectories[(line["scenario"], line["mode"], line["run"])] = artifacts["trajectory"]
        results[key] = line
        if on_result is not None:
            on_result(line)
    missing = [key for key in planned if key not in results]
    if missing:
        raise RuntimeError(f"{len(missing)} run(s) never reported a result, e.g. {', '.join(missing[:3])}")
    ordered = sorted(results.values(), key=lambda r: planned[r["key"]])
    return CampaignResult({s.name: s for s in spec_list}, ordered, time.perf_counter() - t0, backend.cpus,
                          trajectories, backend=backend.name, resumed=len(runs) - len(todo))


def from_recorded(recorded: Recorded) -> CampaignResult:
    """A campaign's result from result files alone (``scenarios merge``): no wall time."""
    modes = {m: i for i, m in enumerate(MODES)}
    order = {name: i for i, name in enumerate(recorded.specs)}
    unknown = sorted({r["scenario"] for r in recorded.runs.values()} - set(order))
    if unknown:
        raise ResultsError(f"runs of {', '.join(unknown)} but no scenario record for them in the files")
    runs = sorted(recorded.runs.values(), key=lambda r: (order[r["scenario"]], modes.get(r["mode"], 9), r["run"]))
    return CampaignResult(dict(recorded.specs), runs, 0.0, 0, backend="merge")


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
        paper = spec.paper
        theirs = (f"{paper.runs:>11}{paper.without:>9.0f}{paper.with_:>6.0f}" if paper is not None
                  else f"{'-':>11}{'-':>9}{'-':>6}")  # a user's scenario: not in the paper
        lines.append(f"{name:<15}{n:>5}{_pct(without):>11}{_pct(with_):>9}   {theirs}")
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


__all__ = ["CampaignResult", "Progress", "failure_reasons", "format_failures", "format_table", "from_recorded",
           "run_campaign"]
