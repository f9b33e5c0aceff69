"""The supervisor: detection timing, restart and give-up paths, queries, the event log."""

from __future__ import annotations

import asyncio

import pytest

from bt_runtime.runtime.config import RuntimeConfig, SupervisorConfig
from bt_runtime.runtime.supervisor import Health


async def test_crashed_sensor_detected_within_timeout_plus_one_tick(make_runtime):
    rt = make_runtime()
    sim = rt.driver.sim
    last_scan = []
    sim.subscribe("scan", lambda m: last_scan.append(rt.clock()))
    await rt.start()
    await asyncio.sleep(1.05)
    sim.crash("lidar")
    crashed_at = rt.clock()
    await asyncio.sleep(1.5)
    failed = [e for e in rt.supervisor.events_of("lidar") if e.state is Health.FAILED]
    await rt.stop()
    assert len(failed) == 1
    last = max(t for t in last_scan if t <= crashed_at)
    detection = failed[0].t - last
    timeout, tick = 1.0, 1.0 / rt.config.tick.rate_hz
    assert timeout < detection <= timeout + tick + 1e-9, detection
    assert "silent" in failed[0].reason


async def test_query_api_reads_failed_the_instant_the_timeout_expires(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(1.0)
    rt.driver.sim.crash("imu")
    last = rt.supervisor.components["imu"].last_seen
    await asyncio.sleep(last + 1.0 + 1e-6 - rt.clock())
    assert rt.supervisor.health("imu") is Health.FAILED  # before the watchdog task noticed
    assert not rt.supervisor.is_healthy("imu")
    assert "imu" in rt.supervisor.unhealthy()
    await rt.stop()


async def test_restart_brings_component_back_to_ok(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(1.0)
    rt.driver.sim.crash("lidar")
    await asyncio.sleep(1.5)
    assert rt.supervisor.health("lidar") is Health.FAILED
    ok = await rt.supervisor.restart("lidar")
    assert ok and rt.supervisor.health("lidar") is Health.OK
    states = [e.state for e in rt.supervisor.events_of("lidar")]
    assert states[-3:] == [Health.FAILED, Health.RESTARTING, Health.OK]
    assert rt.supervisor.failed_restarts("lidar") == 0
    assert not rt.gate.estop_active
    await rt.stop()


async def test_two_failed_restarts_make_it_dead_and_stop_the_robot(make_runtime):
    rt = make_runtime()
    await rt.start()
    sim = rt.driver.sim
    sim.faults.set_restart_policy("odom", delay=0.2, fail_next=5)
    await asyncio.sleep(0.5)
    sim.crash("odom")
    await asyncio.sleep(1.2)
    assert await rt.supervisor.restart("odom") is False
    assert rt.supervisor.health("odom") is Health.FAILED
    assert not rt.gate.estop_active
    assert await rt.supervisor.restart("odom") is False
    assert rt.supervisor.health("odom") is Health.DEAD
    assert rt.gate.estop_active and "odom dead" in rt.gate.estop_reasons
    await asyncio.sleep(0.05)
    assert rt.gate.last_output.is_zero and rt.gate.source == "estop"
    assert await rt.supervisor.restart("odom") is False  # a dead component is not restarted again
    await rt.stop()


async def test_automatic_restart_policy(make_runtime):
    config = RuntimeConfig(supervisor=SupervisorConfig(auto_restart=True))
    rt = make_runtime(config=config)
    await rt.start()
    await asyncio.sleep(0.5)
    rt.driver.sim.crash("imu")
    await asyncio.sleep(4.0)
    states = [e.state for e in rt.supervisor.events_of("imu")]
    assert states[-3:] == [Health.FAILED, Health.RESTARTING, Health.OK]
    await rt.stop()


async def test_navigation_servers_watched_through_heartbeats(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(0.5)
    rt.driver.navigation.hang("planner_server")  # alive process, no heartbeat, no answers
    await asyncio.sleep(1.5)
    assert rt.supervisor.health("planner_server") is Health.FAILED
    assert await rt.supervisor.restart("planner_server")
    assert rt.supervisor.health("planner_server") is Health.OK
    await rt.stop()


@pytest.mark.parametrize("name", ["lidar", "imu", "odom", "localization", "battery", "bumper"])
async def test_every_sensor_component_is_watched(make_runtime, name):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(2.5)
    assert rt.supervisor.health(name) is Health.OK
    rt.driver.sim.crash(name)
    await asyncio.sleep(2.5)
    assert rt.supervisor.health(name) is Health.FAILED
    await rt.stop()
