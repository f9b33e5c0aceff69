"""Navigation log events carry ``sim_time`` (loop time), so they line up with the runtime's."""

from structlog.testing import capture_logs

from bt_runtime.runtime.clock import run
from sim.driver import SimDriver


def test_nav_events_carry_sim_time():
    async def main():
        driver = SimDriver("apartment", "burger")
        await driver.start()
        with capture_logs() as logs:
            await driver.navigation.clear_costmaps("both")
            driver.navigation.crash("planner_server")
        await driver.stop()
        return logs

    logs = run(main, virtual=True)
    events = {e["event"]: e for e in logs if e["event"].startswith("nav_")}
    assert {"nav_costmaps_cleared", "nav_component_crashed"} <= set(events)
    assert all(isinstance(e["sim_time"], float) for e in events.values())
