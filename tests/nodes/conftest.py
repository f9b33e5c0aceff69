"""Node tests run inside the real runtime on the SimDriver, on virtual time."""

from __future__ import annotations

import pytest
import structlog

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import VirtualTimeLoop
from sim.driver import SimDriver


@pytest.fixture(autouse=True)
def _quiet_logs():
    quiet_logging()
    yield
    structlog.reset_defaults()


def pytest_asyncio_loop_factories(config, item):
    return {"virtual_time": VirtualTimeLoop}


def tree_xml(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


@pytest.fixture
def runtime():
    """``await runtime(xml, ...)`` -> a started AutonomyRuntime with the node library."""
    started = []

    async def make(xml: str, *, world="apartment", robot="burger", seed=0, tick=True, **driver_kwargs):
        import nodes

        driver = SimDriver(world, robot, seed=seed, **driver_kwargs)
        rt = AutonomyRuntime(driver, register=[nodes.register_autonomy_nodes])
        rt.load_tree(xml)
        await rt.start(tick=tick)
        started.append(rt)
        return rt

    yield make
