"""``python -m bt_runtime config``: print the runtime configuration's defaults as YAML, each
setting with what it does; ``--check FILE`` loads a file and reports every problem.

Save the output, keep the keys you change, and pass it to ``run --config FILE``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("config", help="print the runtime configuration's defaults as YAML",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--check", type=Path, default=None, metavar="FILE",
                   help="load FILE as run --config does and report its problems")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..runtime.config_file import ConfigError, defaults_yaml, load_runtime_config

    if args.check is not None:
        try:
            load_runtime_config(args.check)
        except ConfigError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        print(f"{args.check}: OK")
        return 0
    sys.stdout.write(defaults_yaml())
    return 0
