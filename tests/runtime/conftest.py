"""Runtime tests run on the real SimDriver, on virtual time (fast and reproducible)."""

from __future__ import annotations

import pytest
import structlog

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import VirtualTimeLoop
from bt_runtime.runtime.config import RuntimeConfig
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


IDLE_TREE = tree_xml('<KeepRunningUntilFailure><AlwaysSuccess/></KeepRunningUntilFailure>')


@pytest.fixture
def make_runtime():
    """Build a runtime on a fresh SimDriver; ``await rt.start()`` is left to the test."""
    created = []

    def factory(xml: str = IDLE_TREE, *, config: RuntimeConfig | None = None, register=(), world="apartment",
                robot="burger", seed=0, **driver_kwargs):
        driver = SimDriver(world, robot, seed=seed, **driver_kwargs)
        rt = AutonomyRuntime(driver, config, register=register)
        rt.load_tree(xml)
        created.append(rt)
        return rt

    yield factory
