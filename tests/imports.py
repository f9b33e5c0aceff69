"""Which modules a source file imports (absolute names, relative imports resolved), for the
tests that hold the rooms' one-way dependencies (docs/architecture.md)."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.paths import ROOT


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, module) for every import in ``path``, at any depth (also inside functions); for
    ``from pkg import name`` both ``pkg`` and ``pkg.name`` are listed (``name`` may be a module)."""
    package = module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    out: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            out.append((node.lineno, module))
            out += [(node.lineno, f"{module}.{a.name}") for a in node.names]
    return out


def within(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")
