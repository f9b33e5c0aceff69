"""trees/autonomy.xml with goals it cannot reach as given: a goal outside the map is refused at
once with its reason (no restarts, no motion); a goal inside an obstacle, which Nav2's planner
tolerance would answer with a plan to a point right beside the obstacle, ends at a safe
alternative instead."""

from __future__ import annotations

import asyncio
import math

from bt_runtime.runtime.messages import Pose2D
from bt_runtime.runtime.supervisor import Health
from sim.faults import parse_fault
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")
TERMINAL = ("SUCCEEDED", "ABORTED", "REFUSED")


async def _outcome(bb, timeout: float) -> str:
    async def done():
        while bb.get("goal_status", default="") not in TERMINAL:
            await asyncio.sleep(0.05)
    await asyncio.wait_for(done(), timeout)
    return bb.get("goal_status")


async def test_a_goal_outside_the_map_is_refused_at_once_with_its_reason_and_no_restarts(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)  # components report
        bb = rt.tree.root_blackboard
        before = rt.driver.sim.pose
        sent = asyncio.get_running_loop().time()
        bb.set("goal", Pose2D(100.0, 100.0, 0.0))
        bb.set("goal_status", "PENDING")
        assert await _outcome(bb, 10.0) == "REFUSED"
        took = asyncio.get_running_loop().time() - sent
        await asyncio.sleep(2.0)  # nothing happens afterwards either
    finally:
        await rt.stop()
    assert took < 0.5
    assert "GOAL_OUTSIDE_MAP (204)" in bb.get("goal_reason")
    assert not [e for e in rt.supervisor.events if e.state is Health.RESTARTING]
    after = rt.driver.sim.pose
    assert math.hypot(after.x - before.x, after.y - before.y) < 0.05


async def test_a_client_is_told_why_a_goal_outside_the_map_was_refused(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)
        result = await asyncio.wait_for(rt.send_goal(Pose2D(100.0, 100.0, 0.0)), 10)
    finally:
        await rt.stop()
    assert result.outcome == "REFUSED"
    assert result.error_msg.startswith("refused: GOAL_OUTSIDE_MAP (204)")


async def test_a_goal_inside_an_obstacle_ends_at_a_safe_alternative_not_beside_it(runtime):
    radius = 0.25  # small: Nav2's 0.5 m planner tolerance finds a plannable cell right beside it
    table = {"kind": "obstacle_at", "x": 0.0, "y": -2.0, "radius": radius, "name": "table"}
    rt = await runtime(AUTONOMY, seed=2, prepare=lambda sim: sim.faults.apply(parse_fault(dict(table))))
    try:
        await asyncio.sleep(1.0)
        bb = rt.tree.root_blackboard
        bb.set("goal", Pose2D(0.0, -2.0, 0.0))
        bb.set("goal_status", "PENDING")
        outcome = await _outcome(bb, 60.0)
        end = rt.driver.sim.pose  # the truth, for judging only
    finally:
        await rt.stop()
    assert outcome == "SUCCEEDED", bb.get("goal_reason", default="")
    assert "alternative goal" in bb.get("goal_detail")
    gap = math.hypot(end.x, end.y + 2.0) - radius - rt.driver.robot_info().radius
    assert 0.08 <= gap <= 0.85  # clear of the obstacle (radius + 0.1 floor, less the goal tolerance), near it
