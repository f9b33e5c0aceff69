"""The project's tests use the package's own pytest plugin (``bt_runtime.testing.plugin``: the
virtual-time loop, the ``sim_driver``/``make_runtime``/``runtime`` fixtures, quiet logs), as a
user's tests do. On top of it: tests under ``runtime/`` and ``nodes/`` (not ``runtime/ros2/``)
run on the VirtualTimeLoop without a marker. Every other async test keeps the ordinary asyncio
loop (servers, DDS, Groot2) unless marked ``virtual_time``."""

from __future__ import annotations

from importlib.metadata import entry_points
from pathlib import Path

import pytest
import structlog

# installed packages load the plugin through their pytest11 entry point; a bare checkout loads it here
if not any(ep.value == "bt_runtime.testing.plugin" for ep in entry_points(group="pytest11")):
    pytest_plugins = ["bt_runtime.testing.plugin"]

_VIRTUAL_DIRS = ("runtime", "nodes")
_TESTS = Path(__file__).resolve().parent


def _in_virtual_dir(item) -> bool:
    try:
        rel = Path(str(item.path)).resolve().relative_to(_TESTS)
    except ValueError:
        return False
    return rel.parts[0] in _VIRTUAL_DIRS and (len(rel.parts) < 2 or rel.parts[1] != "ros2")


def pytest_asyncio_loop_factories(config, item):
    """Decides before the plugin's hook (first result wins): marker, or the directory."""
    from bt_runtime.testing.plugin import loop_factories, wants_virtual_time  # imported by pytest first

    return loop_factories(wants_virtual_time(item) or _in_virtual_dir(item))


@pytest.fixture(autouse=True)
def _quiet_runtime_logs(request):
    """Quiet logs (the plugin's rule for virtual-time tests) for the directory's tests too."""
    if _in_virtual_dir(request.node):
        request.getfixturevalue("bt_quiet_logs")
    yield


def pytest_collection_finish(session):
    structlog.reset_defaults()  # a module that quietened logging while it was imported


@pytest.fixture(autouse=True)
def _logging_config_does_not_leak():
    """A test that configures structlog (a campaign run in-process quietens it) must not change
    what the next test logs: capture_logs() sees nothing below a filtering level."""
    yield
    structlog.reset_defaults()
