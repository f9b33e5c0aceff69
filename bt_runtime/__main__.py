"""``python -m bt_runtime COMMAND ...``: the command-line entry point.

Each command is a module of ``bt_runtime.cli`` with ``add_parser(subparsers)`` (which sets
``func=run`` on its parser) and ``run(args) -> int`` (the exit code). To add a command, write
the module and list its name in ``bt_runtime.cli.COMMANDS``.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .cli import COMMANDS


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m bt_runtime",
        description="bt_runtime: BehaviorTree.CPP v4 trees in pure Python, an autonomy layer for mobile "
                    "robots, a simulator and the paper's failure scenarios.")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.cli.{name}").add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
