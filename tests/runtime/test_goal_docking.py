"""A goal the battery cannot make, on a robot with a dock (trees/autonomy.xml, virtual time):
refused at first and kept (state CHARGING), the robot docks, charges, undocks and reaches it.
Charging is judged here from the simulator's truth (contacts, state of charge); the robot
itself only ever saw its battery messages."""

from __future__ import annotations

import asyncio

from bt_runtime.runtime.goal_intake import GoalState
from bt_runtime.runtime.messages import Pose2D
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")
GOAL = Pose2D(-1.0, -2.0, 0.0)


async def test_a_low_battery_goal_is_kept_docked_for_charged_and_then_reached(runtime):
    from sim.robot import load_profile

    robot = load_profile("burger", **{"battery.capacity_ah": 0.1, "battery.initial_soc": 10.0,
                                      "battery.charge_power_w": 60.0})
    rt = await runtime(AUTONOMY, robot=robot, seed=2, spawn=(-3.6, -1.0, 3.1416))  # 1 m in front of the dock
    sim = rt.driver.sim
    states: list[str] = []
    try:
        await asyncio.sleep(1.5)
        handle = rt.send_goal(GOAL)

        async def watch():
            while not handle.done:
                if not states or states[-1] != handle.state:
                    states.append(handle.state)
                await asyncio.sleep(0.1)

        watcher = asyncio.ensure_future(watch())
        result = await asyncio.wait_for(handle, 150)
        await watcher
        pose = sim.pose
    finally:
        await rt.stop()
    assert result.succeeded, result
    assert handle.refusals == 1
    assert states[-2:] == [GoalState.CHARGING, GoalState.EXECUTING], states  # kept, then resumed
    kinds = [e.kind for e in sim.events if e.kind in ("docked", "charging_started", "charging_stopped", "undocked")]
    assert kinds[:2] == ["docked", "charging_started"] and "undocked" in kinds
    started = next(e for e in sim.events if e.kind == "charging_started")
    stopped = next(e for e in sim.events if e.kind == "charging_stopped")
    assert stopped.data["soc"] > started.data["soc"] + 5.0  # it charged
    assert pose.distance_to(GOAL) < 0.3
