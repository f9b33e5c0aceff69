"""``python -m bt_runtime models``: node models for Groot2.

    python -m bt_runtime models [--out FILE] [--builtin]       # TreeNodesModel of every node type
    python -m bt_runtime models --embed TREE.xml [...]         # add/refresh a tree file's section

Node types come from a fresh factory (the builtins), the project's ``nodes`` package
(``nodes.register_all(factory)``, when it exists) and every ``--register MODULE:FUNC``
(called as ``FUNC(factory)``). ``--models FILE`` also registers the node types declared in
another TreeNodesModel file (e.g. Nav2's), so trees using them can be embedded too.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .registration import RegistrationError, add_registration_arguments, register

HELP = "print node models (TreeNodesModel XML) for Groot2, or embed them into tree files"


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser("models", help=HELP, description=HELP)
    configure(p)
    p.set_defaults(func=run)
    return p


def configure(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", "-o", default=None, help="write the models XML here instead of stdout")
    p.add_argument("--builtin", action="store_true",
                   help="include the builtin node types (Groot2 already knows them)")
    add_registration_arguments(p)
    p.add_argument("--models", action="append", default=[], metavar="FILE",
                   help="register the node types declared in a TreeNodesModel file (repeatable)")
    p.add_argument("--embed", nargs="+", default=None, metavar="TREE.xml",
                   help="add or refresh the <TreeNodesModel> of these tree files in place; only the "
                        "node types each file uses are written, everything else is kept byte for byte")
    p.add_argument("--prune", action="store_true",
                   help="with --embed: drop kept model entries that the file does not use")
    p.add_argument("--check", action="store_true",
                   help="with --embed: change nothing, exit 1 if a file's models are missing or stale")


def build_factory(args: argparse.Namespace) -> Any:
    from bt_runtime.factory import BehaviorTreeFactory

    factory = BehaviorTreeFactory()
    try:
        register(factory, args)
    except RegistrationError as exc:
        raise SystemExit(f"error: {exc}") from None
    for path in args.models:
        factory.register_models_from_file(path)
    return factory


def run(args: argparse.Namespace) -> int:
    from groot.models import XMLScanError, embed_models, models_xml

    factory = build_factory(args)
    if args.embed is None:
        xml = models_xml(factory, include_builtin=args.builtin)
        if args.out:
            with open(args.out, "w", encoding="utf-8") as fh:
                fh.write(xml)
        else:
            sys.stdout.write(xml)
        return 0

    status = 0
    for path in args.embed:
        try:
            result = embed_models(path, factory, include_builtin=args.builtin, prune=args.prune,
                                  write=not args.check)
        except (OSError, UnicodeDecodeError, XMLScanError) as exc:
            print(f"{path}: error: {exc}", file=sys.stderr)
            status = 2
            continue
        except Exception as exc:  # an XMLLoadError from the final well-formedness check
            print(f"{path}: error: {exc}", file=sys.stderr)
            status = 2
            continue
        if result.missing:
            print(f"{path}: warning: no model for node types {', '.join(result.missing)} "
                  "(not registered; use --register or --models)", file=sys.stderr)
        if args.check:
            if result.changed:
                print(f"{path}: models are missing or out of date", file=sys.stderr)
                status = max(status, 1)
        else:
            state = "updated" if result.changed else "unchanged"
            print(f"{path}: {state} ({len(result.generated)} generated, {len(result.kept)} kept)",
                  file=sys.stderr)
    return status


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bt_runtime models", description=HELP)
    configure(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
