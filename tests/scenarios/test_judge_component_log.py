"""A component restart is judged from the simulator's own component log, not the layer's."""

from __future__ import annotations

import asyncio

import numpy as np

from sim.component_log import ComponentLogEntry as E
from sim.driver import SimDriver
from sim.scenarios.judge import component_reset
from sim.scenarios.record import RunRecord
from sim.scenarios.spec import ComponentReset
from sim.testing import run_virtual


def _record(log, state="active", supervisor_events=()):
    return RunRecord(scenario="t", mode="with", seed=0, duration=10.0, trajectory=np.zeros((0, 7)), goals=[],
                     supervisor_events=list(supervisor_events), final_health={"lidar": "ok"},
                     component_states={"lidar": state}, nav_requests=[], fault_log=[], sim_events=[],
                     obstacles={}, gate_switches=[], component_log=list(log))


CRASH_RESTART = [E(2.0, "lidar", "crashed", "fault"), E(3.0, "lidar", "restarting"), E(4.0, "lidar", "running")]


def test_restarted_and_published_again_passes():
    v = component_reset(_record([*CRASH_RESTART, E(4.1, "lidar", "published")]), ComponentReset(kind="component_reset", component="lidar"))
    assert v.passed and "crashed at 2.00 s" in v.reason and "publishing again at 4.10 s" in v.reason


def test_running_but_silent_is_not_a_reset():
    v = component_reset(_record(CRASH_RESTART), ComponentReset(kind="component_reset", component="lidar"))
    assert not v.passed and "never published again" in v.reason


def test_the_layers_own_log_does_not_count():
    class Claim:  # what a supervisor might believe
        component, state, t = "lidar", "ok", 5.0

    v = component_reset(_record([E(2.0, "lidar", "crashed")], state="inactive", supervisor_events=[Claim()]),
                        ComponentReset(kind="component_reset", component="lidar"))
    assert not v.passed and "never restarted" in v.reason and "inactive" in v.reason


def test_the_simulator_logs_sensor_and_navigation_restarts_with_their_first_message():
    driver = SimDriver("apartment", "burger", seed=0)

    async def main():
        await driver.start()
        await asyncio.sleep(0.5)
        driver.sim.crash("lidar")
        driver.navigation.fail_until_restart("planner_server")
        await asyncio.sleep(0.5)
        await driver.restart("lidar")
        await driver.restart("planner_server")
        await asyncio.sleep(0.5)
        await driver.stop()

    run_virtual(main)
    log = driver.sim.component_log
    for name, fault in (("lidar", "crashed"), ("planner_server", "failing")):
        assert [e.event for e in log if e.component == name] == [fault, "restarting", "running", "published"]


def test_hit_once_counts_runs_into_an_obstacle_not_bounces():
    from sim.scenarios.judge import hit_once
    from sim.scenarios.spec import HitOnce
    from sim.simulator import SimEvent

    def rec(times):
        events = []
        for start, end in times:
            events += [SimEvent(start, "collision", {"obstacle": "dyn:box"}),
                       SimEvent(end, "collision_end", {"obstacle": "dyn:box"})]
        r = _record([])
        r.sim_events = events
        return r

    c = HitOnce(kind="hit_once", obstacle="box")
    assert hit_once(rec([(2.0, 2.1), (2.2, 3.0)]), c).passed  # a bounce: one hit
    v = hit_once(rec([(2.0, 3.0), (9.0, 9.5)]), c)
    assert not v.passed and "hit 2x" in v.reason
