"""The supervisor fails a component that publishes bad data, not only a silent one: stale
timestamps, one frozen scan repeated with fresh stamps, NaN or out-of-range readings. Each is
reported with its reason, and the usual restart brings the component back."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from bt_runtime.runtime.data_checks import DataCheck
from bt_runtime.runtime.messages import Imu, LaserScan
from bt_runtime.runtime.supervisor import Health


@pytest.mark.parametrize(("component", "fault", "phrase"), [
    ("lidar", {"kind": "stall", "mode": "stale"}, "stale data: timestamps not advancing"),
    ("lidar", {"kind": "stall", "mode": "frozen"}, "stale data: identical scans repeated"),
    ("imu", {"kind": "stall", "mode": "frozen"}, "stale data: identical readings repeated"),
    ("lidar", {"kind": "corrupt", "mode": "nan"}, "invalid data"),
    ("lidar", {"kind": "corrupt", "mode": "garbage"}, "out of range"),
    ("imu", {"kind": "corrupt", "mode": "nan"}, "invalid data: non-finite values"),
    ("odom", {"kind": "stall", "mode": "stale"}, "stale data"),
])
async def test_bad_data_fails_the_component_with_its_reason_and_a_restart_cures_it(
        make_runtime, component, fault, phrase):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(1.0)
    rt.driver.sim.faults.apply({**fault, "component": component, "duration": 60.0})
    await asyncio.sleep(1.6)
    failed = [e for e in rt.supervisor.events_of(component) if e.state is Health.FAILED]
    assert len(failed) == 1, rt.supervisor.events_of(component)
    assert phrase in failed[0].reason, failed[0].reason
    assert 1.0 < failed[0].t - 1.0 < 1.0 + 0.35  # within the timeout plus one publish period
    assert await rt.supervisor.restart(component)
    assert rt.supervisor.health(component) is Health.OK
    await rt.stop()


async def test_healthy_streams_are_never_flagged(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(5.0)
    assert not [e for e in rt.supervisor.events if e.state is Health.FAILED]
    await rt.stop()


def _scan(stamp: float, ranges) -> LaserScan:
    return LaserScan(stamp, 0.0, 0.1, 0.12, 3.5, np.asarray(ranges, dtype=float))


def test_scan_checks_count_nan_and_out_of_range_but_not_inf():
    check = DataCheck(invalid_share=0.3)
    assert check(_scan(1.0, [1.0, np.inf, -np.inf, 2.0])) is None  # REP 117: inf = no return
    assert "50%" in check(_scan(2.0, [1.0, np.nan, 9.0, 2.0]))
    assert check(_scan(3.0, [1.0, np.nan, 1.5, 2.5])) is None  # 25 % is below the threshold


def test_scalar_streams_must_be_finite_and_advance():
    check = DataCheck()
    assert check(Imu(1.0, 0.0, 0.1, 0.0)) is None
    assert check(Imu(1.0, 0.0, 0.1, 0.0)) == "stale data: timestamps not advancing"
    assert check(Imu(2.0, float("nan"), 0.1, 0.0)) == "invalid data: non-finite values"


async def test_one_pass_queries_agree_with_the_per_component_ones(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(1.0)
    sup = rt.supervisor
    assert sup.failed_among() == [] and not sup.any_dead()
    rt.driver.sim.crash("lidar")
    await asyncio.sleep(1.2)
    assert sup.failed_among() == [n for n in sup.components if n != "tree" and sup.is_failed(n)] == ["lidar"]
    assert sup.failed_among(["imu", "lidar"]) == ["lidar"]
    rt.driver.sim.faults.set_restart_policy("lidar", delay=0.1, fail_next=5)
    await sup.restart("lidar")
    await sup.restart("lidar")
    assert sup.any_dead() and sup.any_dead(["lidar"]) and not sup.any_dead(["imu"])
    await rt.stop()


async def test_the_kept_not_ok_answer_always_agrees_with_each_components_health(make_runtime):
    rt = make_runtime()
    await rt.start()
    sup = rt.supervisor

    def agree() -> None:
        expected = [n for n in sup.components if n != "tree" and sup.health(n) is not Health.OK]
        assert sup.not_ok_among() == expected
        assert sup.not_ok_among(["imu", "lidar"]) == [n for n in ("imu", "lidar") if n in expected]

    try:
        for step in range(400):  # 4 s at the tick's pace: start-up, a crash, its timeout, a restart
            if step == 100:
                rt.driver.sim.crash("imu")
            if step == 250:
                asyncio.get_running_loop().create_task(sup.restart("imu"))
            agree()
            await asyncio.sleep(0.01)
        assert sup.health("imu") is Health.OK
    finally:
        await rt.stop()
