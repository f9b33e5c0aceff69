"""Run the same XML with scripted leaves in bt_runtime and in behaviortreepy (BT.CPP 4.8.2).

Leaves are registered under the same IDs in both engines and are driven by their instance
name: each call pops the next status from that name's script (the last one repeats). Every
callback is logged (``tick:X``, ``start:X``, ``run:X``, ``halt:X``), so two engines agree only
if they call the same leaves, in the same order, with the same results, tick after tick.

Leaf IDs: ``C`` condition, ``A`` sync action, ``R`` stateful action (on_start / on_running /
on_halted), ``Fail`` / ``Ok`` constant actions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bt_runtime import BehaviorTreeFactory, NodeStatus

STATUS_NAMES = ("IDLE", "RUNNING", "SUCCESS", "FAILURE", "SKIPPED")


@dataclass
class Case:
    """One differential scenario."""

    name: str
    xml: str
    scripts: dict[str, list[str]] = field(default_factory=dict)  # instance name -> statuses
    ticks: int = 5
    mode: str = "exactly_once"  # or "once"
    keys: dict[str, str] = field(default_factory=dict)  # blackboard key -> 'int' | 'double' | 'string' | 'bool'
    halt_after: int | None = None  # call halt_tree() after this many ticks
    setup: dict[str, Any] = field(default_factory=dict)  # root blackboard values before the first tick


class _Leaves:
    def __init__(self, scripts: dict[str, list[str]]):
        self.scripts = {k: list(v) for k, v in scripts.items()}
        self.pos: dict[str, int] = {}
        self.log: list[str] = []

    def next(self, name: str, default: str = "SUCCESS") -> str:
        seq = self.scripts.get(name)
        if not seq:
            return default
        i = self.pos.get(name, 0)
        self.pos[name] = i + 1
        return seq[min(i, len(seq) - 1)]


def _name(node: Any) -> str:
    name = node.name
    return name() if callable(name) else name  # a method in behaviortreepy


def _register(factory: Any, leaves: _Leaves, status_of) -> None:
    def cond(node):
        leaves.log.append(f"tick:{_name(node)}")
        return status_of(leaves.next(_name(node)))

    def action(node):
        leaves.log.append(f"tick:{_name(node)}")
        return status_of(leaves.next(_name(node)))

    def on_start(node):
        leaves.log.append(f"start:{_name(node)}")
        return status_of(leaves.next(_name(node), "RUNNING"))

    def on_running(node):
        leaves.log.append(f"run:{_name(node)}")
        return status_of(leaves.next(_name(node)))

    def on_halted(node):
        leaves.log.append(f"halt:{_name(node)}")

    def fail(node):
        leaves.log.append(f"tick:{_name(node)}")
        return status_of("FAILURE")

    def ok(node):
        leaves.log.append(f"tick:{_name(node)}")
        return status_of("SUCCESS")

    factory.register_simple_condition("C", cond)
    factory.register_simple_action("A", action)
    factory.register_simple_stateful_action("R", on_start, on_running, on_halted)
    factory.register_simple_action("Fail", fail)
    factory.register_simple_action("Ok", ok)


@dataclass
class Trace:
    statuses: list[str]
    logs: list[list[str]]
    values: list[dict[str, Any]]
    error: str | None = None

    def first_difference(self, other: Trace) -> str | None:
        for i in range(max(len(self.statuses), len(other.statuses))):
            a = (self.statuses[i:i + 1], self.logs[i:i + 1], self.values[i:i + 1])
            b = (other.statuses[i:i + 1], other.logs[i:i + 1], other.values[i:i + 1])
            if a != b:
                return f"tick {i + 1}: ours={a} oracle={b}"
        if (self.error is None) != (other.error is None):
            return f"error: ours={self.error!r} oracle={other.error!r}"
        return None


def _read_ours(bb, key: str, kind: str) -> Any:
    try:
        value = bb.get(key)
    except Exception:
        return None
    if kind == "int":
        return int(value)
    if kind == "double":
        return round(float(value), 9)
    if kind == "bool":
        return bool(value)
    from bt_runtime.ports import value_to_string
    return value_to_string(value)


def run_ours(case: Case) -> Trace:
    factory = BehaviorTreeFactory()
    leaves = _Leaves(case.scripts)
    _register(factory, leaves, lambda s: NodeStatus[s])
    statuses: list[str] = []
    logs: list[list[str]] = []
    values: list[dict[str, Any]] = []
    error = None
    try:
        tree = factory.create_tree_from_text(case.xml)
        for key, value in case.setup.items():
            tree.root_blackboard.set(key, value)
        for i in range(case.ticks):
            leaves.log = []
            if case.halt_after is not None and i == case.halt_after:
                tree.halt_tree()
                statuses.append("HALT")
            else:
                status = tree.tick_exactly_once() if case.mode == "exactly_once" else tree.tick_once()
                statuses.append(status.name)
            logs.append(leaves.log)
            values.append({k: _read_ours(tree.root_blackboard, k, kind) for k, kind in case.keys.items()})
    except Exception as exc:  # noqa: BLE001 - the trace records where the engines diverge
        error = f"{type(exc).__name__}: {exc}"
        logs.append(leaves.log)
    return Trace(statuses, logs, values, error)


def run_oracle(case: Case) -> Trace:
    import behaviortreepy as bt

    factory = bt.BehaviorTreeFactory()
    leaves = _Leaves(case.scripts)
    _register(factory, leaves, lambda s: bt.NodeStatus.__members__[s])
    statuses: list[str] = []
    logs: list[list[str]] = []
    values: list[dict[str, Any]] = []
    error = None
    try:
        tree = factory.create_tree_from_text(case.xml)
        bb = tree.root_blackboard()
        for key, value in case.setup.items():
            if isinstance(value, bool):
                bb.set_bool(key, value)
            elif isinstance(value, int):
                bb.set_int(key, value)
            elif isinstance(value, float):
                bb.set_double(key, value)
            else:
                bb.set_string(key, str(value))
        for i in range(case.ticks):
            leaves.log = []
            if case.halt_after is not None and i == case.halt_after:
                tree.halt_tree()
                statuses.append("HALT")
            else:
                status = tree.tick_exactly_once() if case.mode == "exactly_once" else tree.tick_once()
                statuses.append(STATUS_NAMES[int(status)])
            logs.append(leaves.log)
            row = {}
            for key, kind in case.keys.items():
                getter = {"int": bb.get_int, "double": bb.get_double, "string": bb.get_string,
                          "bool": bb.get_bool}[kind]
                try:
                    v = getter(key)
                    row[key] = round(v, 9) if kind == "double" else v
                except Exception:
                    row[key] = None
            values.append(row)
    except Exception as exc:  # noqa: BLE001
        error = f"{type(exc).__name__}: {exc}"
        logs.append(leaves.log)
    leaves.log = []  # BT.CPP's Tree destructor halts the tree: not part of any tick
    return Trace(statuses, logs, values, error)
