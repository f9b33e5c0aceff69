"""The Nav2 stand-in's docking server on the full simulator (virtual time): staging pose,
approach, contacts touching, charging sensed from the battery messages, undock, and the
error codes of opennav_docking."""

from __future__ import annotations

import asyncio
import math

from bt_runtime.runtime.messages import POWER_SUPPLY_CHARGING, ActionStatus, BatteryState, Pose2D
from sim.driver import SimDriver
from sim.nav.docking import DOCK_NOT_IN_DB, DOCK_NOT_VALID, FAILED_TO_CHARGE
from sim.testing import run_virtual
from sim.world import load_world


def _driver(world="apartment", spawn=(-2.0, -2.0, 0.0), soc=30.0):
    driver = SimDriver(world, "rosbot2", seed=1, spawn=spawn)
    sim = driver.sim
    sim.subscribe("nav_cmd_vel", lambda t: sim.command(t.linear, t.angular))  # no gate here: straight to the base
    return driver, soc


def test_dock_charges_and_undock_backs_out_to_the_staging_pose():
    async def main():
        driver, soc = _driver()
        sim = driver.sim
        battery: list[BatteryState] = []
        sim.subscribe("battery", battery.append)
        await driver.start()
        sim.faults.set_battery(soc)
        await asyncio.sleep(1.0)
        states = []
        result = await driver.navigation.dock_robot(dock_id="home_dock", feedback=lambda fb: states.append(fb.state))
        assert result.status is ActionStatus.SUCCEEDED, result
        dock = sim.dock_contacts
        assert dock.touching(sim.pose.x, sim.pose.y, sim.pose.yaw)  # the truth: contacts touch
        assert {1, 3, 4} <= set(states)  # staging, controlling, waiting for charge
        soc_docked = sim.battery.soc
        await asyncio.sleep(20.0)
        assert sim.battery.soc > soc_docked  # charging
        assert battery[-1].power_supply_status == POWER_SUPPLY_CHARGING and battery[-1].current < 0
        result = await driver.navigation.undock_robot()
        assert result.status is ActionStatus.SUCCEEDED, result
        staging = driver.navigation.docking.staging_pose(sim.dock)
        assert sim.pose.distance_to(staging) < 0.15
        assert not sim.battery.docked and not battery[-1].on_charger
        kinds = [e.kind for e in sim.events if e.kind in ("docked", "undocked")]
        assert kinds == ["docked", "undocked"]
        await driver.stop()
    run_virtual(main)


def test_unknown_dock_and_no_dock_information():
    async def main():
        driver, _ = _driver()
        await driver.start()
        await asyncio.sleep(0.5)
        result = await driver.navigation.dock_robot(dock_id="kitchen_dock")
        assert (result.status, result.error_code) == (ActionStatus.ABORTED, DOCK_NOT_IN_DB)
        assert "home_dock" in result.error_msg
        result = await driver.navigation.undock_robot()  # not on the charger: nothing to do
        assert result.status is ActionStatus.SUCCEEDED
        await driver.stop()

        data = load_world("apartment").model_dump()
        data["dock"] = None
        from sim.world import World

        driver = SimDriver(World.model_validate(data), "rosbot2", seed=1)
        await driver.start()
        await asyncio.sleep(0.5)
        result = await driver.navigation.undock_robot()
        assert (result.status, result.error_code) == (ActionStatus.ABORTED, DOCK_NOT_VALID)
        result = await driver.navigation.dock_robot(dock_id="home_dock")
        assert result.error_code == DOCK_NOT_IN_DB
        await driver.stop()
    run_virtual(main)


def test_a_dock_pose_without_a_charger_is_retried_then_fails_to_charge():
    async def main():
        driver, _ = _driver(spawn=(-1.0, -2.0, 0.0))
        docking = driver.navigation.docking
        docking.params.max_retries = 1
        await driver.start()
        await asyncio.sleep(0.5)
        fake = Pose2D(0.2, -2.0, 0.0)  # open floor: no contacts there
        result = await driver.navigation.dock_robot(use_dock_id=False, dock_pose=fake)
        assert (result.status, result.error_code, result.num_retries) == (ActionStatus.ABORTED, FAILED_TO_CHARGE, 1)
        assert driver.sim.pose.distance_to(fake) < 0.1  # it did drive up to the pose
        assert math.isfinite(driver.sim.battery.soc) and not driver.sim.battery.docked
        await driver.stop()
    run_virtual(main)


def test_every_shipped_dock_has_a_free_staging_pose():
    from sim.nav.docking import DockingParams

    offset = DockingParams().staging_x_offset
    for name in ("apartment", "round_obstacles"):
        world = load_world(name)
        dock = world.dock
        staging = (dock.x + math.cos(dock.yaw) * offset, dock.y + math.sin(dock.yaw) * offset)
        assert world.clearance(dock.x, dock.y) >= 0.3, name
        assert world.clearance(*staging) >= 0.3, (name, staging)  # the robot fits there, and turns
