"""sim.nav.costmap: Nav2 cost values, inflation, obstacle layer, clearing, rolling window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import LaserScan, Pose2D
from sim.nav.costmap import (
    INSCRIBED,
    LETHAL,
    NO_INFORMATION,
    GlobalCostmap,
    LocalCostmap,
    inflation_cost,
)
from sim.nav.occupancy import OccupancyGrid
from sim.nav.params import CostmapParams

RES = 0.05


def empty_grid(w=8.0, h=6.0) -> OccupancyGrid:
    return OccupancyGrid(np.zeros((int(h / RES), int(w / RES)), np.int8), RES, (0.0, 0.0, 0.0))


def scan(ranges, n=360, range_max=3.5, fill=np.inf) -> LaserScan:
    r = np.full(n, fill)
    for i, v in ranges.items():
        r[i] = v
    return LaserScan(0.0, 0.0, 2 * math.pi / n, 0.12, range_max, r)


def test_nav2_inflation_examples():
    # nav2_notes 4.1: r_inscribed 0.1, inflation 0.55, k = 3: d = 0.2 -> 186, 0.3 -> 138, 0.55 -> 65
    assert inflation_cost(0.2, 0.1, 0.55, 3.0, RES) == 186
    assert inflation_cost(0.3, 0.1, 0.55, 3.0, RES) == 138
    assert inflation_cost(0.55, 0.1, 0.55, 3.0, RES) == 65
    assert inflation_cost(0.0, 0.1, 0.55, 3.0, RES) == LETHAL
    assert inflation_cost(0.1, 0.1, 0.55, 3.0, RES) == INSCRIBED
    assert inflation_cost(0.6, 0.1, 0.55, 3.0, RES) == 0


def test_inflation_matches_formula_around_a_lethal_cell():
    grid = empty_grid()
    grid.data[60, 80] = 100
    cm = GlobalCostmap(grid, robot_radius=0.1)  # TB3 burger: inscribed 0.11, R 0.5, k 5
    r_ins, k, R = 0.11, 5.0, 0.5
    assert cm.inscribed_radius == pytest.approx(r_ins)
    rows, cols = np.mgrid[50:71, 70:91]
    d = np.hypot(rows - 60, cols - 80) * RES
    expected = np.where(d == 0, 254, np.where(d <= r_ins, 253,
                        np.floor(252 * np.exp(-k * (d - r_ins)))))
    expected = np.where(d > R + 1e-9, 0, expected)
    np.testing.assert_array_equal(cm.cost[50:71, 70:91], expected.astype(np.uint8))
    assert cm.cost[60, 80 + 3] == math.floor(252 * math.exp(-5 * (0.15 - 0.11)))
    assert cm.cost[0, 0] == 0


def test_static_layer_values():
    grid = empty_grid()
    grid.data[:, :20] = -1
    grid.data[100, 100] = 100
    cm = GlobalCostmap(grid, 0.1)
    assert cm.cost[50, 5] == NO_INFORMATION and cm.cost[100, 100] == LETHAL and cm.cost[50, 60] == 0
    cm2 = GlobalCostmap(grid, 0.1, CostmapParams(track_unknown_space=False))
    assert cm2.cost[50, 5] == 0


def test_obstacle_layer_marks_and_raytrace_clears():
    cm = GlobalCostmap(empty_grid(), 0.1)
    pose = Pose2D(2.0, 3.0, 0.0)
    assert cm.update_from_scan(scan({0: 1.0, 90: 2.8}), pose)
    assert cm.cost_at(3.0, 3.0) == LETHAL  # hit 1 m ahead
    assert cm.cost_at(2.0, 5.8) != LETHAL  # 2.8 m > obstacle_max_range 2.5: not marked
    assert cm.cost_at(2.4, 3.0) == 0
    # the obstacle moved away: the beam now passes through (inf = clear to raytrace range)
    assert cm.update_from_scan(scan({}), pose)
    assert cm.cost_at(3.0, 3.0) == 0
    assert not cm.cost.any()


def test_a_nan_pose_marks_nothing_and_warns_nothing():
    """A corrupt localization (NaN pose) must not put casts of NaN into cell indices."""
    import warnings

    cm = GlobalCostmap(empty_grid(), 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cm.update_from_scan(scan({0: 1.0, 90: 1.5}), Pose2D(math.nan, 3.0, 0.0))
        local = LocalCostmap(GlobalCostmap(empty_grid(), 0.1), 0.1)
        local.update(Pose2D(2.0, 3.0, 0.0), scan({0: 1.0}))
        local.update(Pose2D(2.0, math.nan, 0.0), scan({90: 1.5}))
    assert not (cm.cost == LETHAL).any()
    assert local.cost_at(3.0, 3.0) == LETHAL  # what it had before the bad pose stays


def test_raytrace_clears_unknown_space():
    grid = empty_grid()
    grid.data[:, 60:] = -1  # unknown beyond x = 3
    cm = GlobalCostmap(grid, 0.1)
    assert cm.cost_at(4.0, 3.0) == NO_INFORMATION
    cm.update_from_scan(scan({0: 2.5}, fill=np.nan), Pose2D(2.0, 3.0, 0.0))
    assert cm.cost_at(3.3, 3.0) == 0  # seen free along the beam
    assert cm.cost_at(4.5, 3.0) == LETHAL
    assert cm.cost_at(4.0, 4.0) == NO_INFORMATION


def test_windowed_reinflation_equals_full_recompute():
    rng = np.random.default_rng(3)
    grid = empty_grid()
    grid.data[:, 0] = grid.data[:, -1] = grid.data[0, :] = grid.data[-1, :] = 100
    cm = GlobalCostmap(grid, 0.1)
    for _ in range(15):
        pose = Pose2D(rng.uniform(1, 7), rng.uniform(1, 5), rng.uniform(-3, 3))
        hits = {int(i): float(rng.uniform(0.3, 3.4)) for i in rng.integers(0, 360, 40)}
        cm.update_from_scan(scan(hits), pose)
    windowed = cm.cost.copy()
    cm._recompute_all()
    np.testing.assert_array_equal(windowed, cm.cost)


def test_clear_drops_obstacles_and_phantoms_but_keeps_added_obstacles():
    cm = GlobalCostmap(empty_grid(), 0.1)
    cm.update_from_scan(scan({0: 1.0}), Pose2D(2.0, 3.0, 0.0))
    cm.add_phantom(5.0, 1.0, 0.3)
    cm.add_obstacle(6.0, 4.0, 0.1)
    assert cm.cost_at(3.0, 3.0) == LETHAL and cm.cost_at(5.0, 1.0) == LETHAL
    assert cm.cost_at(6.0, 4.0) == LETHAL and cm.cost_at(6.12, 4.0) == LETHAL
    v = cm.base_version
    cm.clear()
    assert cm.cost_at(3.0, 3.0) == 0 and cm.cost_at(5.0, 1.0) == 0
    assert cm.cost_at(6.0, 4.0) == LETHAL
    assert cm.base_version > v
    # the relaxed (heuristic) costmap is a lower bound of the master one
    assert (cm.relaxed_cost() <= np.where(cm.cost == NO_INFORMATION, 0, cm.cost)).all()


def test_local_costmap_rolls_with_the_robot_and_forgets():
    gcm = GlobalCostmap(empty_grid(), 0.1)
    lc = LocalCostmap(gcm, 0.1)
    assert (lc.width, lc.height) == (60, 60)
    lc.update(Pose2D(2.0, 3.0, 0.0), scan({0: 1.02}))
    assert lc.cost_at(3.02, 3.0) == LETHAL
    assert lc.in_collision(3.05, 3.0) and not lc.in_collision(2.5, 3.0)
    assert lc.distance_at(2.5, 3.0) == pytest.approx(0.5, abs=0.051)
    lc.update(Pose2D(2.6, 3.1, 0.0))  # moved: the mark stays where it is in the world
    assert lc.cost_at(3.02, 3.0) == LETHAL
    lc.update(Pose2D(6.0, 3.0, 0.0))  # 3 m away: out of the 3 x 3 m window
    assert lc.cost_at(3.02, 3.0) == NO_INFORMATION
    lc.update(Pose2D(2.6, 3.1, 0.0))  # back: forgotten, as Nav2's rolling window does
    assert lc.cost_at(3.02, 3.0) == 0


def test_local_costmap_sees_added_obstacles_and_phantoms():
    gcm = GlobalCostmap(empty_grid(), 0.1)
    lc = LocalCostmap(gcm, 0.1)
    lc.update(Pose2D(2.0, 3.0, 0.0))
    gcm.add_obstacle(2.5, 3.0, 0.05)
    lc.recompose()
    lc.add_phantom(2.0, 3.6, 0.1)
    assert lc.cost_at(2.5, 3.0) == LETHAL and lc.cost_at(2.0, 3.6) == LETHAL
    lc.clear()
    assert lc.cost_at(2.5, 3.0) == LETHAL and lc.cost_at(2.0, 3.6) == 0
    # no static layer in the local costmap (TurtleBot3 configuration)
    grid = empty_grid()
    grid.data[60, 50] = 100
    lc2 = LocalCostmap(GlobalCostmap(grid, 0.1), 0.1)
    lc2.update(Pose2D(2.0, 3.0, 0.0))
    assert lc2.cost_at(2.52, 3.02) == 0
