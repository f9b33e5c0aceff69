"""Goal handling that survives failures: retries paced by health and time with a stated
budget, servers that are down failing nodes (never ticks), safe and stable alternative goals,
and stopping before an obstacle on the scan."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import LaserScan, Pose2D, Twist
from nodes.motion_safety import allowed_speed, free_distances
from tests.helpers import tree_xml

KEEP = '<KeepRunningUntilFailure><ForceSuccess>{}</ForceSuccess></KeepRunningUntilFailure>'
COUNT_ATTEMPT = '<Script code="tries := tries + 1"/>'


def _retry(budget: float, children: str, components: str = "") -> str:
    return tree_xml(KEEP.format(
        f'<Sequence><RetryGoal budget="{budget}" backoff="0.5" max_backoff="2" components="{components}">'
        f'{children}</RetryGoal><Script code="done := true"/></Sequence>'))


async def test_retries_back_off_and_the_goal_is_aborted_only_after_its_budget_with_the_reason(runtime):
    rt = await runtime(_retry(6.0, f'<Sequence>{COUNT_ATTEMPT}<AlwaysFailure/></Sequence>'), tick=False)
    bb = rt.tree.root_blackboard
    bb.set("goal", Pose2D(1.0, 0.0))
    bb.set("goal_status", "ACTIVE")
    bb.set("tries", 0)
    rt.restart_tree()
    await asyncio.sleep(5.5)
    # back-off 0.5, 1, 2, 2 s: a handful of attempts in 5.5 s, not 550
    assert 4 <= bb.get("tries") <= 5
    assert not bb.get("goal_reason", default="")
    await asyncio.sleep(1.0)
    assert "time budget of 6 s used up" in bb.get("goal_reason")
    await rt.stop()


async def test_an_attempt_waits_for_the_components_it_needs(runtime):
    rt = await runtime(_retry(60.0, f'<Sequence>{COUNT_ATTEMPT}<AlwaysFailure/></Sequence>', "lidar"), tick=False)
    bb = rt.tree.root_blackboard
    bb.set("goal", Pose2D(1.0, 0.0))
    bb.set("goal_status", "ACTIVE")
    bb.set("tries", 0)
    await asyncio.sleep(1.0)
    rt.driver.sim.crash("lidar")
    await asyncio.sleep(1.5)
    rt.restart_tree()
    await asyncio.sleep(5.0)
    assert bb.get("tries") == 0  # nothing restarts the lidar here: no attempt is made
    await rt.driver.sim.restart("lidar")
    await asyncio.sleep(0.5)
    assert bb.get("tries") >= 1
    await rt.stop()


async def test_the_budget_belongs_to_the_goal_and_survives_a_halt(runtime):
    rt = await runtime(_retry(4.0, '<AlwaysFailure/>'), tick=False)
    bb = rt.tree.root_blackboard
    bb.set("goal", Pose2D(1.0, 0.0))
    bb.set("goal_status", "ACTIVE")
    rt.restart_tree()
    await asyncio.sleep(2.5)
    rt.tree.halt_tree()  # what the tick loop does after a tick error
    await asyncio.sleep(2.0)
    assert "time budget of 4 s" in bb.get("goal_reason", default="")
    await rt.stop()


async def test_clearing_costmaps_of_a_crashed_server_fails_the_node_not_the_tick(runtime):
    xml = tree_xml("<Fallback><ClearCostmaps which='both'/><Script code=\"cleared := 'no'\"/></Fallback>")
    rt = await runtime(xml, tick=False)
    await asyncio.sleep(0.5)
    rt.driver.navigation.crash("planner_server")
    status = await asyncio.wait_for(rt.restart_tree(), 2.0)
    assert status.name == "SUCCESS"
    assert rt.tree.root_blackboard.get("cleared") == "no"
    assert rt.tick_loop.stats.errors == 0
    await rt.stop()


async def test_alternative_goal_is_safe_kept_and_reported(runtime):
    xml = tree_xml('<FindAlternativeGoal goal="{goal}" max_radius="0.85" alternative="{alt}" detail="{detail}"/>')
    rt = await runtime(xml, tick=False, robot="rosbot2")
    bb = rt.tree.root_blackboard
    await asyncio.sleep(0.5)
    table = Pose2D(0.5, -2.6)
    await rt.driver.navigation.add_obstacle(table.x, table.y, 0.35)
    bb.set("goal", table)
    assert (await asyncio.wait_for(rt.restart_tree(), 10.0)).name == "SUCCESS"
    first = bb.get("alt")
    clearance = rt.driver.navigation.path_clearance(np.array([[first.x, first.y]]))
    assert clearance >= rt.context.robot.radius + 0.1
    assert first.distance_to(table) <= 0.85
    assert "alternative goal" in bb.get("detail") and f"{first.x:.2f}" in bb.get("detail")
    for _ in range(3):  # asked again for the same goal: the same answer while it stays reachable
        assert (await asyncio.wait_for(rt.restart_tree(), 10.0)).name == "SUCCESS"
        assert bb.get("alt") == first
    await rt.stop()


def _scan(ranges_by_angle: dict[float, float], n: int = 360) -> LaserScan:
    ranges = np.full(n, np.inf)
    inc = 2 * math.pi / n
    for angle, r in ranges_by_angle.items():
        ranges[int(round((angle + math.pi) / inc)) % n] = r
    return LaserScan(0.0, -math.pi, inc, 0.12, 3.5, ranges)


def test_free_distance_counts_only_the_swept_corridor():
    scan = _scan({0.0: 0.6, math.pi / 2: 0.3, math.pi: 0.5})
    ahead, behind = free_distances(scan, half_width=0.2, radius=0.15)
    assert abs(ahead - 0.45) < 1e-9
    assert abs(behind - 0.35) < 1e-9  # the point 0.3 m to the left is beside the path, not in it


def test_a_wall_beside_the_body_does_not_stop_it_but_one_ahead_in_the_margin_does():
    """A robot pushed against a wall (the wall 3 cm from its side, inside the side margin) can
    still drive along or away from it; the margin still counts for what lies ahead."""
    wall = {math.atan2(0.23, x): math.hypot(x, 0.23) for x in np.arange(-0.1, 0.1001, 0.01)}
    ahead, behind = free_distances(_scan(wall, n=3600), half_width=0.25, radius=0.2)
    assert ahead == math.inf and behind == math.inf
    ahead, _ = free_distances(_scan({math.atan2(0.23, 0.5): math.hypot(0.5, 0.23)}, n=3600),
                              half_width=0.25, radius=0.2)
    assert ahead == pytest.approx(0.3, abs=0.01)  # in the margin, ahead of the front
    ahead, _ = free_distances(_scan({math.atan2(0.1, 0.5): math.hypot(0.5, 0.1)}, n=3600),
                              half_width=0.25, radius=0.2)
    assert ahead == pytest.approx(0.5 - math.sqrt(0.2**2 - 0.1**2), abs=0.01)  # where the circle meets it


@pytest.mark.filterwarnings("error")  # no numpy warning for inf or NaN ranges on any beam
def test_free_distance_reads_a_beam_straight_ahead_and_ignores_missing_ranges():
    """The ROSbot's lidar starts at angle 0: its first beam has sin exactly 0, and it may read
    inf (nothing hit) or NaN (an invalid reading); neither is an obstacle."""
    n, inc = 400, 2 * math.pi / 400
    ranges = np.full(n, np.inf)
    ranges[n // 2] = 0.5  # straight behind
    ranges[[3, 7]] = np.nan
    ahead, behind = free_distances(LaserScan(0.0, 0.0, inc, 0.12, 3.5, ranges), 0.2, 0.15)
    assert ahead == math.inf and behind == pytest.approx(0.35)
    ranges[0] = 0.6  # straight ahead
    ahead, behind = free_distances(LaserScan(0.0, 0.0, inc, 0.12, 3.5, ranges), 0.2, 0.15)
    assert ahead == pytest.approx(0.45) and behind == pytest.approx(0.35)
    ranges[0] = np.nan
    assert free_distances(LaserScan(0.0, 0.0, inc, 0.12, 3.5, ranges), 0.2, 0.15)[0] == math.inf


def test_allowed_speed_stops_short_of_the_obstacle():
    assert allowed_speed(0.05, 0.5, 0.2, 0.05) == 0.0
    for free in (0.1, 0.3, 1.0):
        v = allowed_speed(free, 0.5, 0.2, 0.05)
        assert abs(v * 0.2 + v * v / (2 * 0.5) - (free - 0.05)) < 1e-9
    assert allowed_speed(0.3, 0.5, 0.2, 0.05) > 0.25  # cruising at 0.25 m/s is not limited 30 cm out


async def test_the_robot_is_held_before_an_obstacle_the_scan_shows(runtime):
    rt = await runtime(tree_xml(KEEP.format('<StopBeforeObstacle/>')), robot="burger")
    await asyncio.sleep(0.5)
    sim = rt.driver.sim
    pose = sim.pose
    sim.faults.block_corridor((pose.x + 0.45, pose.y - 0.5), (pose.x + 0.45, pose.y + 0.5), name="wall")
    t_end = rt.clock() + 6.0
    while rt.clock() < t_end:  # navigation insists on driving straight ahead at 0.2 m/s
        sim.bus.publish("nav_cmd_vel", Twist(0.2, 0.0))
        await asyncio.sleep(0.05)
    front = sim.pose.x + sim.profile.radius
    await rt.stop()
    assert pose.x + 0.45 - 0.05 - 0.15 < front < pose.x + 0.45 - 0.05 + 0.01  # stopped just short of the wall
