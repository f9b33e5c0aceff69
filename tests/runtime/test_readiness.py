"""Start-up readiness: wait until every component has reported, name the ones that did not."""

from bt_runtime.runtime.readiness import wait_until_reported


async def test_waits_for_the_slowest_component(make_runtime):
    rt = make_runtime()
    await rt.start(tick=False)
    try:
        ready = await wait_until_reported(rt.supervisor, rt.clock, timeout=5.0)
        assert ready.ready and ready.silent == []
        assert 0.9 <= ready.waited <= 1.1  # the battery publishes at 1 Hz: its first message at t = 1 s
        assert rt.supervisor.health("battery").value == "ok"
    finally:
        await rt.stop()


async def test_names_a_component_that_never_reports(make_runtime):
    rt = make_runtime(prepare=lambda sim: sim.faults.crash("battery"))
    await rt.start(tick=False)
    try:
        ready = await wait_until_reported(rt.supervisor, rt.clock, timeout=3.0)
        assert not ready.ready and ready.silent == ["battery"]
        assert 3.0 <= ready.waited < 3.1  # kept waiting past the 2 s start-up grace, up to the timeout
        assert "no message yet from battery" in ready.describe()
    finally:
        await rt.stop()
