"""A campaign worker's per-process caches (world, map raster, planner graph, inflated static costmap) never change a run:
the same seed gives the same trajectory and verdicts with cold and with warm caches."""

from __future__ import annotations

import sys

import numpy as np

from sim import raster_cache, world
from sim.nav import costmap, planner
from sim.scenarios.runner import run_scenario
from sim.scenarios.spec import load_scenario


def _cold() -> None:
    world._LOADED.clear()
    raster_cache._CACHE.clear()
    planner._GRAPHS.clear()
    costmap._INFLATED.clear()


def test_cold_and_warm_caches_give_the_same_run() -> None:
    spec = load_scenario("Lidar_2")
    _cold()
    cold = run_scenario(spec, "with", 7)
    warm = run_scenario(spec, "with", 7)
    assert cold.record is not None and warm.record is not None
    assert len(cold.record.trajectory) > 10
    assert np.array_equal(cold.record.trajectory, warm.record.trajectory)
    assert [(v.criterion, v.passed, v.reason) for v in cold.verdicts] == \
           [(v.criterion, v.passed, v.reason) for v in warm.verdicts]
    assert np.array_equal(cold.record.map_grid.data, warm.record.map_grid.data)


def test_a_campaign_parent_fills_the_caches_its_workers_inherit() -> None:
    from sim.scenarios.runspec import plan_runs
    from sim.scenarios.warm import warm_caches

    _cold()
    plan = plan_runs([load_scenario("Lidar_2"), load_scenario("NoPathFound_1")], 2, 0)
    assert warm_caches(plan) == 2  # two set-ups (world, robot, map obstacles), not one per run
    assert len(world._LOADED) == 2 and len(raster_cache._CACHE) == 2 and "nodes" in sys.modules
    assert planner._GRAPHS and costmap._INFLATED
