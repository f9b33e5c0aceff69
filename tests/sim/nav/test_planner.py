"""sim.nav.planner: paths, Nav2 error codes, the fast routes agree with the exact search."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import LaserScan, NavErrorCode, Pose2D
from sim.nav.costmap import INSCRIBED, NO_INFORMATION, GlobalCostmap
from sim.nav.occupancy import OccupancyGrid
from sim.nav.params import PlannerParams
from sim.nav.planner import GridPlanner, path_length
from tests.sim.nav.fixtures import HOUSE, TB3_WORLD, small_world

E = NavErrorCode


def make(grid=None, **params) -> GridPlanner:
    cm = GlobalCostmap(grid or small_world(), 0.1)
    return GridPlanner(cm, PlannerParams(**params))


def assert_valid_path(planner: GridPlanner, res, start: Pose2D, goal: Pose2D):
    assert res.ok, res.message
    pts = res.points
    assert pts.shape[1] == 3
    assert tuple(pts[0, :2]) == pytest.approx((start.x, start.y))
    assert tuple(pts[-1, :2]) == pytest.approx((goal.x, goal.y))
    assert pts[-1, 2] == pytest.approx(goal.yaw)
    step = np.hypot(*np.diff(pts[:, :2], axis=0).T)
    assert step.max() < 0.1  # dense (about a cell per step)
    costs = planner.costmap.costs_at(pts[:, 0], pts[:, 1])
    assert ((costs < INSCRIBED) | (costs == NO_INFORMATION)).all()


def test_plans_through_the_door_of_the_synthetic_map():
    pl = make()
    s, g = Pose2D(1.0, 1.0), Pose2D(7.0, 5.0, 1.2)
    res = pl.plan(s, g)
    assert_valid_path(pl, res, s, g)
    near_wall = res.points[np.abs(res.points[:, 0] - 4.0) < 0.05]
    assert len(near_wall) and (np.abs(near_wall[:, 1] - 3.0) < 0.45).all()  # through the door
    assert math.hypot(6, 4) < path_length(res.points) < 1.4 * math.hypot(6, 4) + 2
    assert pl.is_path_valid(res.points)
    assert 0.11 < pl.path_clearance(res.points) < 0.6


@pytest.mark.skipif(not HOUSE.exists(), reason="shared/reference/worlds not available")
@pytest.mark.parametrize("start,goal", [((-6.3, -1.5), (5.5, -4.3)), ((-4.0, 3.5), (1.2, 3.0)),
                                        ((6.5, 1.0), (-2.0, -0.5))])
def test_plans_in_the_turtlebot3_house(start, goal):
    pl = make(OccupancyGrid.load(HOUSE))
    s, g = Pose2D(*start), Pose2D(*goal)
    res = pl.plan(s, g)
    assert_valid_path(pl, res, s, g)
    again = pl.plan(s, g)
    assert again.method == "cached"
    np.testing.assert_array_equal(again.points, res.points)


@pytest.mark.skipif(not TB3_WORLD.exists(), reason="shared/reference/worlds not available")
def test_plans_in_the_turtlebot3_world():
    pl = make(OccupancyGrid.load(TB3_WORLD))
    s, g = Pose2D(-2.0, -0.5), Pose2D(2.0, 0.5)
    res = pl.plan(s, g)
    assert_valid_path(pl, res, s, g)
    # a pillar (r = 0.15) at (0, 0) sits between: the path keeps its distance from all pillars
    assert pl.path_clearance(res.points) > 0.11


def test_no_valid_path_when_the_door_is_blocked():
    pl = make()
    pl.costmap.add_obstacle(4.0, 3.0, 0.6)  # a map update closing the door
    res = pl.plan(Pose2D(1.0, 1.0), Pose2D(7.0, 5.0))
    assert res.error_code is E.NO_VALID_PATH


def test_no_valid_path_when_a_sensed_obstacle_blocks_the_door():
    pl = make()
    s, g = Pose2D(1.0, 1.0), Pose2D(7.0, 5.0)
    assert pl.plan(s, g).ok
    # a scan from (3, 3) facing the door sees a wall of points across it
    angles = np.linspace(-0.6, 0.6, 121)
    ranges = 1.0 / np.cos(angles)
    n = 360
    r = np.full(n, np.nan)
    idx = np.round(angles / (2 * math.pi / n)).astype(int) % n
    r[idx] = ranges
    pl.costmap.update_from_scan(LaserScan(0, 0.0, 2 * math.pi / n, 0.12, 3.5, r), Pose2D(3.0, 3.0))
    res = pl.plan(s, g)
    assert res.error_code is E.NO_VALID_PATH and res.method == "components"


def test_goal_and_start_errors():
    pl = make(tolerance=0.0)
    free = Pose2D(1.0, 1.0)
    assert pl.plan(free, Pose2D(2.0, 4.5)).error_code is E.GOAL_OCCUPIED  # in the pillar
    assert pl.plan(free, Pose2D(4.0, 1.0)).error_code is E.GOAL_OCCUPIED  # in the wall
    assert pl.plan(free, Pose2D(20.0, 1.0)).error_code is E.GOAL_OUTSIDE_MAP
    assert pl.plan(Pose2D(-3.0, 1.0), free).error_code is E.START_OUTSIDE_MAP
    assert pl.plan(Pose2D(2.0, 4.5), free).error_code is E.START_OCCUPIED
    # Nav2's default (NavFn tolerance 0.5 m): the plan ends at the nearest plannable point in
    # the 0.5 m square around an occupied goal, never inside the obstacle
    tol = make()
    assert tol.params.tolerance == 0.5
    res = tol.plan(free, Pose2D(2.0, 4.5))
    end = res.points[-1]
    assert res.ok and 0.05 < math.hypot(end[0] - 2.0, end[1] - 4.5) <= 0.5 * math.sqrt(2) + 1e-9
    assert tol.costmap.cost_at(end[0], end[1]) < INSCRIBED


def test_start_in_the_inscribed_band_can_escape():
    pl = make()
    s = Pose2D(0.12, 1.0)  # hugging the west wall: cost 253
    assert pl.costmap.cost_at(s.x, s.y) == INSCRIBED
    res = pl.plan(s, Pose2D(2.0, 1.0))
    assert res.ok and res.points[-1, 0] == pytest.approx(2.0)


def test_unknown_space_option():
    grid = OccupancyGrid(np.zeros((60, 100), np.int8), 0.05, (0.0, 0.0, 0.0))
    grid.data[:, 45:55] = -1  # an unknown band across the map
    s, g = Pose2D(0.5, 1.5), Pose2D(4.5, 1.5)
    assert make(grid, allow_unknown=True).plan(s, g).ok
    assert make(grid, allow_unknown=False).plan(s, g).error_code is E.NO_VALID_PATH


def test_planner_timeout():
    pl = make(max_iterations=50, max_python_expansions=50)
    s, g = Pose2D(1.0, 1.0), Pose2D(7.0, 5.0)
    pl.costmap.add_phantom(2.5, 2.5, 0.1)  # the relaxed field knows it: still cached
    assert pl.plan(s, g).ok
    # a sensed obstacle near the route forces a search, which exceeds 50 iterations
    pl.costmap.obstacle[40:80, 40:60] = 254
    pl.costmap._recompute_all()
    assert pl.plan(s, g).error_code is E.PLANNER_TIMEOUT


def test_same_inputs_same_path():
    a = make().plan(Pose2D(1.0, 1.0), Pose2D(7.0, 5.0))
    b = make().plan(Pose2D(1.0, 1.0), Pose2D(7.0, 5.0))
    np.testing.assert_array_equal(a.points, b.points)
    assert a.cost == b.cost


def test_fast_routes_find_optimal_costs():
    """astar / cached / learned against the exact compiled Dijkstra on the same costmap."""
    rng = np.random.default_rng(7)
    pl = make(suboptimality_tolerance=0.0)
    ref = make(max_python_expansions=1)
    s, g = Pose2D(1.0, 1.0), Pose2D(7.0, 5.0)
    for _ in range(6):
        # random sensed blobs (not in the relaxed heuristic) near the route
        x, y = rng.uniform(1.5, 7.0), rng.uniform(0.8, 5.2)
        for cm in (pl.costmap, ref.costmap):
            rows, cols = cm._disc_cells(x, y, 0.2)
            cm.obstacle[rows, cols] = 254
            cm._recompute_all()
        a, b = pl.plan(s, g), ref.plan(s, g)
        ref._learned.clear()
        assert a.error_code == b.error_code
        if a.ok:
            assert a.method in ("cached", "astar", "learned", "dijkstra")
            if a.method == "learned":
                assert a.cost <= 1.2 * b.cost
            else:
                assert a.cost == pytest.approx(b.cost, rel=1e-9), a.method


def test_cached_replan_is_within_tolerance():
    pl = make(suboptimality_tolerance=0.05)
    exact = make(suboptimality_tolerance=0.0, max_python_expansions=1)
    s, g = Pose2D(1.0, 1.0), Pose2D(7.0, 5.0)
    pl.plan(s, g)
    for cm in (pl.costmap, exact.costmap):
        cm.obstacle[62, 70] = 254  # one noisy mark beside the door
        cm._recompute_all()
    a, b = pl.plan(s, g), exact.plan(s, g)
    assert a.ok and b.ok and a.cost <= 1.05 * b.cost + 1e-9


def test_path_validity_and_clearance():
    pl = make()
    res = pl.plan(Pose2D(1.0, 1.0), Pose2D(7.0, 5.0))
    assert pl.is_path_valid(res.points)
    mid = res.points[len(res.points) // 2]
    pl.costmap.add_phantom(mid[0], mid[1], 0.05)
    assert not pl.is_path_valid(res.points)
    assert not pl.is_path_valid(res.points, max_cost=254) or pl.costmap.cost_at(mid[0], mid[1]) < 254
    assert pl.is_path_valid(res.points, start_index=len(res.points) - 5)
    assert pl.path_clearance(res.points) == pytest.approx(0.0, abs=0.051)
    assert not pl.is_path_valid(np.array([[100.0, 100.0]]))


def test_a_path_with_a_non_finite_pose_is_invalid_and_has_no_clearance():
    """A NaN pose (from a NaN localization) is nowhere: never a valid path, never a safe one."""
    pl = make()
    res = pl.plan(Pose2D(1.0, 1.0), Pose2D(7.0, 5.0))
    assert pl.path_clearance(res.points) > 0.0
    bad = res.points.copy()
    bad[len(bad) // 2, 0] = np.nan
    assert not pl.is_path_valid(bad)
    assert pl.path_clearance(bad) == 0.0
    assert pl.path_clearance(np.array([[np.inf, 1.0, 0.0]])) == 0.0


def _two_doors(narrow: float, wide: bool) -> OccupancyGrid:
    """An 8 x 6 m room split at x = 4 by a wall with a door ``narrow`` m wide on the straight
    line at y = 3 and, if ``wide``, a 1 m door at y = 1."""
    segs = [(0.0, 0.0, 8.0, 0.0, 0.1), (8.0, 0.0, 8.0, 6.0, 0.1), (8.0, 6.0, 0.0, 6.0, 0.1),
            (0.0, 6.0, 0.0, 0.0, 0.1), (4.0, 3.0 + narrow / 2, 4.0, 6.0, 0.1)]
    segs += [(4.0, 0.0, 4.0, 0.5, 0.1), (4.0, 1.5, 4.0, 3.0 - narrow / 2, 0.1)] if wide else \
        [(4.0, 0.0, 4.0, 3.0 - narrow / 2, 0.1)]
    return OccupancyGrid.from_shapes([], [], segs, bounds=(-0.5, -0.5, 8.5, 6.5), resolution=0.05)


def _door_used(res) -> float:
    at_wall = res.points[np.abs(res.points[:, 0] - 4.0) < 0.05]
    return float(at_wall[:, 1].mean())


def test_a_plan_keeps_a_margin_beyond_the_inscribed_radius_where_the_map_leaves_room():
    """A door that leaves a 0.11 m robot only 2-3 cm beyond its inscribed radius is a pinch: the
    lidar marks a wall's edge a cell further out than the static map, and the controller then
    refuses the plan. The planner goes round by a wide door when there is one (not too far),
    and still through the pinch when it is the only way."""
    s, g = Pose2D(2.0, 3.0), Pose2D(6.0, 3.0)
    res = make(_two_doors(0.32, wide=True)).plan(s, g)
    assert res.ok and _door_used(res) == pytest.approx(1.0, abs=0.3)
    plain = make(_two_doors(0.32, wide=True), pinch_penalty=0.0).plan(s, g)
    assert plain.ok and _door_used(plain) == pytest.approx(3.0, abs=0.1)
    only = make(_two_doors(0.32, wide=False))
    res = only.plan(s, g)
    assert_valid_path(only, res, s, g)
    assert _door_used(res) == pytest.approx(3.0, abs=0.1)
    roomy = make(_two_doors(0.6, wide=True)).plan(s, g)  # 0.19 m beyond the inscribed radius
    assert roomy.ok and _door_used(roomy) == pytest.approx(3.0, abs=0.1)


def test_a_plan_keeps_a_wider_berth_from_collision_marks_where_it_can():
    """A collision mark covers where a touch was sensed, not the whole obstacle: a plan through
    a 1 m door with a mark near one jamb passes further from the mark than the inflation alone
    would keep it, and still passes a mark when that is the only way."""
    s, g = Pose2D(2.0, 3.0), Pose2D(6.0, 3.0)

    def berth(planner) -> float:
        planner.costmap.add_obstacle(4.0, 3.3, 0.05)
        res = planner.plan(s, g)
        assert res.ok
        return float(np.min(np.hypot(res.points[:, 0] - 4.0, res.points[:, 1] - 3.3)) - 0.05)

    plain = berth(make(_two_doors(1.0, wide=False), mark_penalty=0.0))
    wide = berth(make(_two_doors(1.0, wide=False)))
    assert wide > plain + 0.03, (plain, wide)
    narrow = make(_two_doors(0.6, wide=False))  # a mark in the only door leaves 0.25 m beside it
    narrow.costmap.add_obstacle(4.0, 3.2, 0.05)
    assert_valid_path(narrow, narrow.plan(s, g), s, g)
