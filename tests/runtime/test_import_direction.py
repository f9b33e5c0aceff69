"""Imports flow one way (docs/architecture.md): the CLI wires the rooms at the edge, and nothing
below it imports the CLI; the engine imports none of the rooms built on it. The pytest plugin
(``bt_runtime.testing``) is an edge like the CLI: it wires the simulator and the node library
into tests."""

from __future__ import annotations

from tests.imports import imported_modules, module_name, within
from tests.paths import ROOT

PACKAGE = sorted((ROOT / "bt_runtime").rglob("*.py"))
EDGES = ("bt_runtime.cli", "bt_runtime.testing", "bt_runtime.__main__")


def _edge(path) -> bool:
    return any(within(module_name(path), edge) for edge in EDGES)


def _offenders(files, forbidden: tuple[str, ...]) -> list[str]:
    return [f"{path.relative_to(ROOT)}:{line} imports {module}" for path in files
            for line, module in imported_modules(path) if any(within(module, f) for f in forbidden)]


def test_the_scan_sees_the_package_and_resolves_relative_imports():
    names = {module_name(p) for p in PACKAGE}
    assert {"bt_runtime.cli.run", "bt_runtime.runtime.ros2.driver", "bt_runtime.tree"} <= names
    main = ROOT / "bt_runtime" / "__main__.py"
    assert any(within(m, "bt_runtime.cli") for _, m in imported_modules(main))  # `from .cli import ...`


def test_nothing_below_the_cli_imports_it():
    below = [p for p in PACKAGE if not _edge(p)]
    assert _offenders(below, ("bt_runtime.cli",)) == []


def test_the_engine_imports_none_of_the_rooms_built_on_it():
    engine = [p for p in PACKAGE if not _edge(p) and not within(module_name(p), "bt_runtime.runtime")]
    assert _offenders(engine, ("bt_runtime.runtime", "bt_runtime.cli", "nodes", "sim", "groot")) == []
