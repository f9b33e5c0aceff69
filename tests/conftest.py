"""Shared fixtures: quiet logs, and the virtual-time loop for tests that run the runtime.

Tests under ``runtime/`` and ``nodes/`` (and any test marked ``virtual_time``) run on the
VirtualTimeLoop: a runtime on the SimDriver then runs many times faster than real time and is
reproducible. Every other async test keeps the ordinary asyncio loop (servers, DDS, Groot2)."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
import structlog

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import VirtualTimeLoop
from bt_runtime.runtime.config import RuntimeConfig
from sim.driver import SimDriver
from tests.helpers import IDLE_TREE

_VIRTUAL_DIRS = ("runtime", "nodes")
_TESTS = Path(__file__).resolve().parent


def _wants_virtual_time(item) -> bool:
    if item.get_closest_marker("virtual_time"):
        return True
    try:
        rel = Path(str(item.path)).resolve().relative_to(_TESTS)
    except ValueError:
        return False
    return rel.parts[0] in _VIRTUAL_DIRS and (len(rel.parts) < 2 or rel.parts[1] != "ros2")


def pytest_configure(config):
    config.addinivalue_line("markers", "virtual_time: run this async test on the VirtualTimeLoop")


def pytest_asyncio_loop_factories(config, item):
    if _wants_virtual_time(item):
        return {"virtual_time": VirtualTimeLoop}
    return {"asyncio": asyncio.new_event_loop}


@pytest.fixture
def _quiet_logs():
    quiet_logging()
    yield
    structlog.reset_defaults()


@pytest.fixture(autouse=True)
def _quiet_runtime_logs(request):
    """The runtime and node tests log through structlog; keep their output quiet."""
    if _wants_virtual_time(request.node):
        request.getfixturevalue("_quiet_logs")
    yield


@pytest.fixture
def make_runtime():
    """Build a runtime on a fresh SimDriver; ``await rt.start()`` is left to the test."""

    def factory(xml: str = IDLE_TREE, *, config: RuntimeConfig | None = None, register=(), world="apartment",
                robot="burger", seed=0, **driver_kwargs):
        driver = SimDriver(world, robot, seed=seed, **driver_kwargs)
        rt = AutonomyRuntime(driver, config, register=register)
        rt.load_tree(xml)
        return rt

    return factory


@pytest.fixture
def runtime():
    """``await runtime(xml, ...)`` -> a started AutonomyRuntime with the node library."""

    async def make(xml: str, *, world="apartment", robot="burger", seed=0, tick=True, **driver_kwargs):
        import nodes

        driver = SimDriver(world, robot, seed=seed, **driver_kwargs)
        rt = AutonomyRuntime(driver, register=[nodes.register_autonomy_nodes])
        rt.load_tree(xml)
        await rt.start(tick=tick)
        return rt

    return make
