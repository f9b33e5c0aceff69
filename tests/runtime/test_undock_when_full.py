"""A robot left on its dock with a full battery (a charge that a new goal or a cancel cut
short, then topped up) undocks before it drives to its next goal (trees/autonomy.xml): its
battery says FULL, not CHARGING, and that still means it stands on the charger. Undocking
backs it straight off the contacts instead of turning on the spot in the dock."""

from __future__ import annotations

import asyncio

import numpy as np

from bt_runtime.runtime.messages import POWER_SUPPLY_FULL, BatteryState, Pose2D
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")
DOCK = (-4.6, -1.0, 3.1416)  # the apartment's dock: the base stands here when docked
GOAL = Pose2D(-2.5, -1.0, 0.0)


async def test_a_full_robot_on_its_dock_undocks_before_driving_to_a_new_goal(runtime):
    from sim.robot import load_profile

    robot = load_profile("burger", **{"battery.capacity_ah": 0.1, "battery.initial_soc": 100.0})
    rt = await runtime(AUTONOMY, robot=robot, seed=3, spawn=DOCK)
    sim, nav = rt.driver.sim, rt.driver.navigation
    undocks: list[float] = []
    undock = nav.undock_robot

    def spy(**kw):
        undocks.append(asyncio.get_running_loop().time())
        return undock(**kw)

    nav.undock_robot = spy
    try:
        await asyncio.sleep(2.0)
        battery = rt.backup.latest("battery")
        assert isinstance(battery, BatteryState) and battery.power_supply_status == POWER_SUPPLY_FULL
        handle = rt.send_goal(GOAL)
        result = await asyncio.wait_for(handle, 60)
        pose = sim.pose
    finally:
        await rt.stop()
    assert result.succeeded, result
    assert len(undocks) == 1, undocks
    speeds = np.asarray(sim.trajectory(), dtype=float)[:, 4]
    first_move = speeds[np.flatnonzero(np.abs(speeds) > 0.02)[0]]
    assert first_move < 0.0  # backed off the contacts first
    assert pose.distance_to(GOAL) < 0.3
