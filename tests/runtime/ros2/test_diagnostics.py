"""Component health as diagnostics: levels and values from the supervisor's records, published
at once on a change (without DDS; the DDS path is in test_e2e.py)."""

from __future__ import annotations

import asyncio

import pytest

from bt_runtime.runtime.diagnostics import ERROR, OK, STALE, WARN, DiagnosticsPublisher, component_diagnostics
from bt_runtime.runtime.supervisor import Health
from tests.helpers import IDLE_TREE

pytest.importorskip("cyclonedds")  # the [ros2] extra

from bt_runtime.runtime.ros2 import Ros2Config  # noqa: E402


@pytest.mark.virtual_time
async def test_levels_follow_health_and_changes_are_published_at_once(make_runtime) -> None:
    rt = make_runtime(IDLE_TREE)
    published: list[tuple[float, list]] = []
    await rt.start()
    pub = DiagnosticsPublisher(rt.supervisor, lambda d, now: published.append((now, d)), rt.clock)
    task = asyncio.get_running_loop().create_task(pub.run())
    try:
        await asyncio.sleep(2.0)
        latest = {d.hardware_id: d for d in published[-1][1]}
        assert latest["lidar"].level == OK and dict(latest["lidar"].values)["state"] == "ok"
        assert float(dict(latest["lidar"].values)["last_seen_age_s"]) < 0.5
        beats = len(published)
        rt.driver.sim.crash("lidar")
        crash = rt.clock()
        await asyncio.sleep(1.3)
        down = [(t, {d.hardware_id: d for d in ds}["lidar"]) for t, ds in published[beats:]]
        first = next(t for t, d in down if d.level in (WARN, ERROR))
        assert first - crash <= 1.1
        assert any("failed" in d.message or "restart" in d.message for _, d in down)
    finally:
        pub.close()
        task.cancel()
        await rt.stop()


def test_component_levels() -> None:
    class Rec:
        def __init__(self, state):
            self.state, self.last_seen, self.restarts, self.failed_restarts = state, None, 0, 0
            self.failures, self.kind, self.critical, self.problem = 0, "sensor", True, ""

    class Sup:
        components = {s.value: Rec(s) for s in Health}
        events: list = []

    levels = {d.hardware_id: d.level for d in component_diagnostics(Sup(), 0.0)}
    assert levels == {"ok": OK, "restarting": WARN, "failed": ERROR, "dead": ERROR, "unknown": STALE}


def test_a_robot_without_a_bumper_neither_reads_nor_watches_one() -> None:
    config = Ros2Config().without_components("bumper")
    assert config.topics.bumper is None and "bumper" not in config.components
    assert "bumper" in Ros2Config().components  # the original is unchanged
