"""Which node types a command's factory gets: the project's node library (``nodes.register_all``,
unless ``--no-nodes``) and any ``--register MODULE:FUNC``. Shared by run, validate and models."""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from typing import Any


class RegistrationError(Exception):
    """A bad ``--register`` argument (reported without a traceback)."""


def add_registration_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--register", action="append", default=[], metavar="MODULE:FUNC",
                        help="call FUNC(factory) from MODULE to register more node types (repeatable)")
    parser.add_argument("--no-nodes", action="store_true",
                        help="do not register the project's node library (nodes.register_all)")


def registrations(args: argparse.Namespace) -> list[Callable[[Any], Any]]:
    """The registration functions ``args`` asks for, in order."""
    found: list[Callable[[Any], Any]] = []
    if not getattr(args, "no_nodes", False):
        try:
            nodes = importlib.import_module("nodes")
        except ImportError:
            nodes = None
        register_all = getattr(nodes, "register_all", None)
        if callable(register_all):
            found.append(register_all)
    for spec in getattr(args, "register", []):
        module_name, sep, func_name = spec.partition(":")
        if not sep or not module_name or not func_name:
            raise RegistrationError(f"--register expects MODULE:FUNC, got {spec!r}")
        try:
            found.append(getattr(importlib.import_module(module_name), func_name))
        except (ImportError, AttributeError) as exc:
            raise RegistrationError(f"--register {spec!r}: {exc}") from None
    return found


def register(factory: Any, args: argparse.Namespace) -> Any:
    for registration in registrations(args):
        registration(factory)
    return factory
