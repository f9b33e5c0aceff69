"""The world's map raster is made once per process, yet equals a fresh rasterization and stays
each caller's own (campaign runs share the cache)."""

from __future__ import annotations

import numpy as np

from sim.driver import occupancy_from_world
from sim.simulator import Simulator
from sim.world import CircleObstacle, SegmentObstacle, rasterize_obstacles


def _fresh(sim: Simulator, **kw):
    return rasterize_obstacles(sim.obstacles(dynamic=True), sim.world.bounds, 0.05, **kw)


def test_cached_raster_with_run_time_obstacles_equals_a_fresh_one() -> None:
    sim = Simulator("apartment", "burger", seed=0)
    sim.rasterize(0.05)  # fills the cache
    sim.add_obstacle(CircleObstacle(center=(1.0, 1.0), radius=0.3), "box")
    sim.add_obstacle(SegmentObstacle(a=(-1.0, 2.0), b=(0.5, 2.5), thickness=0.0), "thin")
    sim.add_obstacle(CircleObstacle(center=(2.0, -1.0), radius=0.2, blocks_lidar=False), "low")
    for layer in ("lidar", "body", "any"):
        cached = sim.rasterize(0.05, layer=layer, dynamic=True)
        assert np.array_equal(cached.data, _fresh(sim, layer=layer).data), layer
    assert not np.array_equal(sim.rasterize(0.05, dynamic=True).data, sim.rasterize(0.05).data)
    inflated = sim.rasterize(0.05, dynamic=True, inflate=0.2, padding=0.5)
    assert np.array_equal(inflated.data, _fresh(sim, inflate=0.2, padding=0.5).data)


def test_a_caller_changing_its_map_leaves_the_next_run_s_map_alone() -> None:
    first = Simulator("round_obstacles", "burger", seed=0).rasterize(0.05)
    expected = first.data.copy()
    first.data[:] = 1
    again = Simulator("round_obstacles", "burger", seed=1)
    assert np.array_equal(again.rasterize(0.05).data, expected)
    grid = occupancy_from_world(again)
    assert np.array_equal(grid.data, np.where(expected > 0, 100, 0).astype(np.int8))


def test_a_world_with_other_shapes_gets_its_own_raster() -> None:
    sim = Simulator("apartment", "burger", seed=0)
    before = sim.rasterize(0.05).data
    sim.world.obstacles.append(CircleObstacle(center=(0.0, 0.0), radius=0.5))
    assert np.array_equal(sim.rasterize(0.05).data, _fresh(sim).data)
    assert not np.array_equal(sim.rasterize(0.05).data, before)
