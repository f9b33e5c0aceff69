"""Health nodes against the real supervisor: queries, restarts, speed limit, e-stop."""

from __future__ import annotations

import asyncio

from bt_runtime.runtime.supervisor import Health
from tests.helpers import tree_xml

KEEP = '<KeepRunningUntilFailure><ForceSuccess>{}</ForceSuccess></KeepRunningUntilFailure>'


async def test_components_healthy_reports_the_failed_ones(runtime):
    rt = await runtime(tree_xml(KEEP.format('<ComponentsHealthy unhealthy="{bad}"/>')))
    await asyncio.sleep(2.5)
    assert rt.tree.root_blackboard.get("bad") == []
    rt.driver.sim.crash("imu")
    await asyncio.sleep(1.5)
    assert rt.tree.root_blackboard.get("bad") == ["imu"]
    await rt.stop()


async def test_unknown_at_startup_is_not_ok_and_not_restarted(runtime):
    xml = tree_xml(KEEP.format('<Sequence><RequestRestarts restarting="{r}"/>'
                               '<ComponentsHealthy unhealthy="{bad}"/></Sequence>'))
    rt = await runtime(xml)
    await asyncio.sleep(0.05)  # the battery (1 Hz) has not published yet
    assert rt.supervisor.health("battery") is Health.UNKNOWN
    assert "battery" in rt.tree.root_blackboard.get("bad")  # UNKNOWN is not OK
    assert rt.tree.root_blackboard.get("r") == []  # ... and not a failure to restart
    await asyncio.sleep(2.0)
    assert rt.tree.root_blackboard.get("bad") == []
    assert not [e for e in rt.supervisor.events if e.state is Health.RESTARTING]
    await rt.stop()


async def test_a_component_the_supervisor_does_not_watch_is_not_ok(runtime):
    rt = await runtime(tree_xml(KEEP.format('<ComponentsHealthy components="imu;sonar" unhealthy="{bad}"/>')))
    await asyncio.sleep(1.5)
    assert rt.tree.root_blackboard.get("bad") == ["sonar"]
    await rt.stop()


async def test_request_restarts_restarts_failed_components_in_the_background(runtime):
    rt = await runtime(tree_xml(KEEP.format('<RequestRestarts restarting="{r}"/>')))
    await asyncio.sleep(1.0)
    rt.driver.sim.crash("lidar")
    await asyncio.sleep(1.5)
    assert rt.supervisor.health("lidar") is Health.RESTARTING
    assert rt.tree.root_blackboard.get("r") == ["lidar"]
    await asyncio.sleep(3.0)
    assert rt.supervisor.health("lidar") is Health.OK
    restarts = [e for e in rt.supervisor.events_of("lidar") if e.state is Health.RESTARTING]
    assert len(restarts) == 1  # requested every tick, started once
    await rt.stop()


async def test_dependent_component_waits_for_its_dependency(runtime):
    rt = await runtime(tree_xml(KEEP.format('<RequestRestarts/>')))
    await asyncio.sleep(1.0)
    rt.driver.sim.crash("odom")  # localization stops too: it needs odometry
    await asyncio.sleep(6.0)
    assert rt.supervisor.health("odom") is Health.OK
    assert rt.supervisor.health("localization") is Health.OK
    loc_restarts = [e for e in rt.supervisor.events_of("localization") if e.state is Health.RESTARTING]
    assert loc_restarts == []  # it came back with its dependency, no restart wasted on it
    assert rt.supervisor.failed_restarts("localization") == 0
    await rt.stop()


async def test_restart_component_action_and_speed_limit(runtime):
    xml = tree_xml('<Sequence><SetSpeedLimit linear="0.05" angular="0.3" reason="test"/>'
                   '<RestartComponent component="imu"/><RestoreSpeedLimit/></Sequence>')
    rt = await runtime(xml)
    await asyncio.sleep(0.05)
    assert rt.gate.speed_limit == (0.05, 0.3)
    summary = await rt.run(duration=10)
    assert summary.status == "SUCCESS"
    assert rt.gate.speed_limit is None
    assert [e.state for e in rt.supervisor.events_of("imu")][-2:] == [Health.RESTARTING, Health.OK]
    await rt.stop()


async def test_wait_for_healthy_waits_and_fails_when_the_component_dies(runtime):
    xml = tree_xml('<Sequence><WaitForHealthy components="odom" timeout="30"/></Sequence>')
    rt = await runtime(xml, tick=False)
    sim = rt.driver.sim
    sim.faults.set_restart_policy("odom", delay=0.1, fail_next=5)
    await asyncio.sleep(0.5)
    sim.crash("odom")
    await asyncio.sleep(1.5)
    done = rt.restart_tree()
    await asyncio.sleep(0.5)
    assert not done.done()  # waiting while odom is failed
    await rt.supervisor.restart("odom")
    await rt.supervisor.restart("odom")
    await asyncio.sleep(0.1)
    assert rt.supervisor.health("odom") is Health.DEAD
    assert done.done() and done.result().name == "FAILURE"
    await rt.stop()


async def test_is_safe_to_continue_and_emergency_stop(runtime):
    xml = tree_xml(KEEP.format('<Fallback><IsSafeToContinue/><EmergencyStop reason="unsafe"/></Fallback>'))
    rt = await runtime(xml)
    await asyncio.sleep(0.2)
    assert not rt.gate.estop_active
    rt.gate.emergency_stop("operator")
    await asyncio.sleep(0.05)
    assert set(rt.gate.estop_reasons) == {"operator", "unsafe"}
    await rt.stop()
