"""The pytest plugin (entry point ``pytest11: bt_runtime``); see ``bt_runtime.testing``.

Fixtures:
  ``sim_driver``   -> ``make(world="apartment", robot="burger", seed=0, **kw)``: a SimDriver
  ``make_runtime`` -> ``make(xml, config=None, register=(), world=..., robot=..., seed=0, **kw)``:
                      an AutonomyRuntime with the tree loaded (start it yourself)
  ``runtime``      -> ``await make(xml, world=..., robot=..., seed=0, tick=True, register=None,
                      config=None, **kw)``: a started runtime with the whole node library
                      (``nodes.register_all``: the behaviours and the Nav2-named nodes) registered
Marker: ``virtual_time`` (run this async test on the VirtualTimeLoop). Ini options:
``bt_runtime_virtual_time`` (every async test on virtual time), ``bt_runtime_quiet_logs``
(warnings and errors only in virtual-time tests and tests using these fixtures; default true).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Mapping

import pytest
import structlog

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.clock import VirtualTimeLoop


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("bt_runtime_virtual_time", "run every async test on the bt_runtime VirtualTimeLoop",
                  type="bool", default=False)
    parser.addini("bt_runtime_quiet_logs", "structlog warnings and errors only in tests that run the "
                  "runtime (virtual time or the bt_runtime fixtures)", type="bool", default=True)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "virtual_time: run this async test on the bt_runtime VirtualTimeLoop "
                                       "(simulated time jumps ahead whenever the loop is idle)")


def wants_virtual_time(item: pytest.Item) -> bool:
    """Marked ``virtual_time``, or every async test when the ini option says so."""
    return bool(item.get_closest_marker("virtual_time")) or bool(item.config.getini("bt_runtime_virtual_time"))


def loop_factories(virtual: bool) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]]:
    """What ``pytest_asyncio_loop_factories`` returns for a test on virtual or ordinary time."""
    return {"virtual_time": VirtualTimeLoop} if virtual else {"asyncio": asyncio.new_event_loop}


@pytest.hookimpl(optionalhook=True, trylast=True)
def pytest_asyncio_loop_factories(config, item):
    """pytest-asyncio asks which loop an async test runs on (a conftest may decide first)."""
    return loop_factories(wants_virtual_time(item))


def quiet_logs() -> None:
    """structlog: warnings and errors only, on stderr."""
    quiet_logging()


@pytest.fixture
def bt_quiet_logs(request):
    """Quiet structlog for this test; the defaults are restored afterwards."""
    if request.config.getini("bt_runtime_quiet_logs"):
        quiet_logs()
        yield
        structlog.reset_defaults()
    else:
        yield


@pytest.fixture(autouse=True)
def _bt_quiet_virtual_time_logs(request):
    if wants_virtual_time(request.node):
        request.getfixturevalue("bt_quiet_logs")
    yield


@pytest.fixture
def sim_driver(bt_quiet_logs):
    """``make(world, robot, seed, **kw)`` -> a SimDriver (the simulated robot behind the driver interface)."""
    from sim.driver import SimDriver

    def make(world="apartment", robot="burger", seed=0, **driver_kwargs):
        return SimDriver(world, robot, seed=seed, **driver_kwargs)

    return make


@pytest.fixture
def make_runtime(sim_driver):
    """Build a runtime on a fresh SimDriver; ``await rt.start()`` is left to the test."""
    from bt_runtime.runtime.app import AutonomyRuntime

    idle = ('<root BTCPP_format="4"><BehaviorTree ID="Main"><KeepRunningUntilFailure><AlwaysSuccess/>'
            '</KeepRunningUntilFailure></BehaviorTree></root>')

    def factory(xml: str = idle, *, config=None, register=(), world="apartment", robot="burger", seed=0,
                **driver_kwargs):
        rt = AutonomyRuntime(sim_driver(world, robot, seed, **driver_kwargs), config, register=register)
        rt.load_tree(xml)
        return rt

    return factory


@pytest.fixture
def runtime(sim_driver):
    """``await runtime(xml, ...)`` -> a started AutonomyRuntime with the node library."""
    from bt_runtime.runtime.app import AutonomyRuntime

    async def make(xml: str, *, world="apartment", robot="burger", seed=0, tick=True, register=None, config=None,
                   **driver_kwargs):
        import nodes

        rt = AutonomyRuntime(sim_driver(world, robot, seed, **driver_kwargs), config,
                             register=[nodes.register_all] if register is None else register)
        rt.load_tree(xml)
        await rt.start(tick=tick)
        return rt

    return make
