"""Run the same XML with scripted leaves in bt_runtime and in behaviortreepy (BT.CPP 4.8.2).

Leaves are registered under the same IDs in both engines and are driven by their instance
name: each call pops the next status from that name's script (the last one repeats). Every
callback is logged (``tick:X``, ``start:X``, ``run:X``, ``halt:X``), so two engines agree only
if they call the same leaves, in the same order, with the same results, tick after tick.

Leaf IDs: ``C`` condition, ``A`` sync action, ``R`` stateful action (on_start / on_running /
on_halted; on_start defaults to RUNNING, on_running to SUCCESS), ``Fail`` / ``Ok`` constant
actions; ``D`` is a simple decorator (``register_simple_decorator``) that logs the child's
status and returns its own script, else the child's status.

Per step the trace records: the value returned by the tick (or ``HALT`` for a ``halt_tree()``
step), the leaf callbacks, the root node's stored status afterwards (a control node that
returned SKIPPED stays RUNNING, spec 13.1), and the chosen blackboard values. Errors are
compared by *where* they happen (``build`` or the step number), not by text: 4.10 wraps tick
errors in NodeExecutionError and 4.8.2 does not.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from bt_runtime import BehaviorTreeFactory, NodeStatus

STATUS_NAMES = ("IDLE", "RUNNING", "SUCCESS", "FAILURE", "SKIPPED")


def tree(body: str, extra: str = "", main: str = "Main") -> str:
    """A v4 document whose main tree ``main`` is ``body``; ``extra`` adds more top-level elements."""
    return (f'<root BTCPP_format="4" main_tree_to_execute="{main}">'
            f'<BehaviorTree ID="{main}">{body}</BehaviorTree>{extra}</root>')


@dataclass
class Case:
    """One differential scenario.

    ``mode``: ``"exactly_once"``, ``"once"``, or one of them per step (a sequence).
    ``halt_after``: step index (or indices) at which ``halt_tree()`` replaces the tick.
    ``setup``: root blackboard values written after the tree is built, before the first step.
    ``between``: ``{step: {key: value}}`` root blackboard writes made just before that step.
    ``error``: the expected error location (``None``, ``"build"``, ``"setup"`` or ``"tick"``); only used to
    check that a case really exercises what it claims, the engines are compared in any case.
    """

    name: str
    xml: str
    scripts: dict[str, list[str]] = field(default_factory=dict)  # instance name -> statuses
    ticks: int = 5
    mode: str | Sequence[str] = "exactly_once"
    keys: dict[str, str] = field(default_factory=dict)  # key -> 'int' | 'double' | 'string' | 'bool'
    halt_after: int | Sequence[int] | None = None
    setup: dict[str, Any] = field(default_factory=dict)
    between: dict[int, dict[str, Any]] = field(default_factory=dict)
    error: str | None = None

    def mode_at(self, step: int) -> str:
        return self.mode if isinstance(self.mode, str) else self.mode[step]

    def halts_at(self, step: int) -> bool:
        if self.halt_after is None:
            return False
        if isinstance(self.halt_after, int):
            return step == self.halt_after
        return step in self.halt_after


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

    def deco(child_status, node):  # a simple decorator: its script, else the child's status
        leaves.log.append(f"deco:{_name(node)}:{child_status.name}")
        return status_of(leaves.next(_name(node), child_status.name))

    factory.register_simple_condition("C", cond)
    factory.register_simple_decorator("D", deco)
    factory.register_simple_action("A", action)
    factory.register_simple_stateful_action("R", on_start, on_running, on_halted)
    factory.register_simple_action("Fail", fail)
    factory.register_simple_action("Ok", ok)


@dataclass
class Trace:
    statuses: list[str] = field(default_factory=list)
    logs: list[list[str]] = field(default_factory=list)
    values: list[dict[str, Any]] = field(default_factory=list)
    root_status: list[str] = field(default_factory=list)
    error: str | None = None
    error_at: str | None = None  # 'build', 'setup' or 'step N' (1-based)

    def rows(self) -> list[tuple]:
        return [(self.statuses[i:i + 1], self.logs[i:i + 1], self.root_status[i:i + 1], self.values[i:i + 1])
                for i in range(max(len(self.statuses), len(self.logs)))]

    def first_difference(self, other: Trace) -> str | None:
        mine, theirs = self.rows(), other.rows()
        for i in range(max(len(mine), len(theirs))):
            a = mine[i] if i < len(mine) else None
            b = theirs[i] if i < len(theirs) else None
            if a != b:
                return (f"step {i + 1}: ours={a} oracle={b}\n  ours error={self.error!r} at {self.error_at}"
                        f"\n  oracle error={other.error!r} at {other.error_at}")
        if self.error_at != other.error_at:
            return f"error: ours={self.error!r} at {self.error_at}; oracle={other.error!r} at {other.error_at}"
        return None


# -- our engine ------------------------------------------------------------------------------------

_OUR_KINDS = {"int": int, "double": float, "string": str, "bool": bool}


def _read_ours(bb, key: str, kind: str) -> Any:
    try:
        value = bb.get(key, _OUR_KINDS[kind])
    except Exception:
        return None
    return _double(value) if kind == "double" else value


def _double(value: float) -> float | str:
    """Rounded, and NaN as a string: NaN != NaN would make equal traces differ."""
    return "nan" if value != value else round(value, 9)


def run_ours(case: Case) -> Trace:
    factory = BehaviorTreeFactory()
    leaves = _Leaves(case.scripts)
    _register(factory, leaves, lambda s: NodeStatus[s])
    trace = Trace()
    try:
        tree_ = factory.create_tree_from_text(case.xml)
    except Exception as exc:  # noqa: BLE001 - the trace records where the engines diverge
        trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", "build"
        return trace
    bb = tree_.root_blackboard
    try:
        for key, value in case.setup.items():
            bb.set(key, value)
    except Exception as exc:  # noqa: BLE001
        trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", "setup"
        return trace
    for i in range(case.ticks):
        leaves.log = []
        try:
            for key, value in case.between.get(i, {}).items():
                bb.set(key, value)
            if case.halts_at(i):
                tree_.halt_tree()
                trace.statuses.append("HALT")
            else:
                status = tree_.tick_exactly_once() if case.mode_at(i) == "exactly_once" else tree_.tick_once()
                trace.statuses.append(status.name)
        except Exception as exc:  # noqa: BLE001
            trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", f"step {i + 1}"
            trace.logs.append(leaves.log)
            break
        trace.logs.append(leaves.log)
        trace.root_status.append(tree_.root_node.status.name)
        trace.values.append({k: _read_ours(bb, k, kind) for k, kind in case.keys.items()})
    return trace


# -- the oracle ------------------------------------------------------------------------------------

def _oracle_set(bb: Any, key: str, value: Any) -> None:
    if isinstance(value, bool):
        bb.set_bool(key, value)
    elif isinstance(value, int):
        bb.set_int(key, value)
    elif isinstance(value, float):
        bb.set_double(key, value)
    else:
        bb.set_string(key, str(value))


def run_oracle(case: Case) -> Trace:
    import behaviortreepy as bt

    factory = bt.BehaviorTreeFactory()
    leaves = _Leaves(case.scripts)
    _register(factory, leaves, lambda s: bt.NodeStatus.__members__[s])
    trace = Trace()
    try:
        tree_ = factory.create_tree_from_text(case.xml)
    except Exception as exc:  # noqa: BLE001
        trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", "build"
        return trace
    bb = tree_.root_blackboard()
    root = tree_.root_node()
    try:
        for key, value in case.setup.items():
            _oracle_set(bb, key, value)
    except Exception as exc:  # noqa: BLE001
        trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", "setup"
        _KEEP_ALIVE.append((factory, tree_))
        return trace
    getters = {"int": bb.get_int, "double": bb.get_double, "string": bb.get_string, "bool": bb.get_bool}
    for i in range(case.ticks):
        leaves.log = []
        try:
            for key, value in case.between.get(i, {}).items():
                _oracle_set(bb, key, value)
            if case.halts_at(i):
                tree_.halt_tree()
                trace.statuses.append("HALT")
            else:
                status = tree_.tick_exactly_once() if case.mode_at(i) == "exactly_once" else tree_.tick_once()
                trace.statuses.append(STATUS_NAMES[int(status)])
        except Exception as exc:  # noqa: BLE001
            trace.error, trace.error_at = f"{type(exc).__name__}: {exc}", f"step {i + 1}"
            trace.logs.append(leaves.log)
            break
        trace.logs.append(leaves.log)
        trace.root_status.append(STATUS_NAMES[int(root.status())])
        row = {}
        for key, kind in case.keys.items():
            try:
                v = getters[kind](key)
                row[key] = _double(v) if kind == "double" else v
            except Exception:
                row[key] = None
        trace.values.append(row)
    # BT.CPP's Tree destructor halts the tree; an _onHalted script that throws there aborts the
    # whole process (an exception escaping a destructor). Keep the trees alive instead.
    _KEEP_ALIVE.append((factory, tree_))
    return trace


_KEEP_ALIVE: list[Any] = []
