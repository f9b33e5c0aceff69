"""Small campaigns for the campaign tests: cheap scenarios (about a second per run), and the
comparison of two campaigns run by run."""

from __future__ import annotations

from sim.scenarios.runspec import RunSpec, plan_runs
from sim.scenarios.spec import load_scenario

CHEAP = ("Lidar_1", "NoPathFound_2")  # the quickest runs without the layer


def cheap_plan(runs: int = 2, seed: int = 5, modes=("without",), **kwargs) -> list[RunSpec]:
    return plan_runs([load_scenario(n) for n in CHEAP], runs, seed, modes, **kwargs)


def by_key(lines) -> dict[str, tuple]:
    """What must be equal between two campaigns of the same plan, per run."""
    return {r["key"]: (r["seed"], r["success"], r["sim_time"], [(v["criterion"], v["passed"], v["reason"])
                                                                   for v in r["verdicts"]]) for r in lines}
