"""The one-frame statement shortcuts (script/shortcuts.py) do exactly what the general closures
do: same result, same stored value and kind, same error, for every kind of entry they may meet,
and they never act on a remembered entry that a later change of structure replaced."""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest

from bt_runtime.blackboard import Blackboard
from bt_runtime.ports import DOUBLE, INT, STRING, UINT64
from bt_runtime.script import compiler
from bt_runtime.script.compiler import compile_script, forget_compiled
from bt_runtime.status import NodeStatus

STATEMENTS = ["x := 1", "x := 2.5", "x := 'text'", "x = 1", "x := y", "x = y", "x := y + 1",
              "x := y - 0.5", "x := y * 2", "x := y / 4", "x := x + 1", "x += 1", "x -= 2",
              "x *= 3", "x /= 2", "x += 0.25", "y := y + 1", "@x := 1", "@x += 1", "x := @y + 1", "x := y; x += 1",
              "!y", "x := !y", "!@y"]

# (name, how the entry is prepared on a fresh blackboard): the kinds a shortcut must either
# handle exactly or hand over.
STATES: dict[str, Callable[[Blackboard, str], None]] = {
    "missing": lambda bb, key: None,
    "double": lambda bb, key: bb.set(key, 3.0),
    "negative double": lambda bb, key: bb.set(key, -7.5),
    "int": lambda bb, key: bb.set(key, 4),
    "huge int": lambda bb, key: bb.set(key, 2**60 + 1),
    "uint64": lambda bb, key: bb.create_entry(key, UINT64).write(5),
    "typed empty double": lambda bb, key: bb.create_entry(key, DOUBLE),
    "typed empty int": lambda bb, key: bb.create_entry(key, INT),
    "untyped empty": lambda bb, key: bb.create_entry(key),
    "string": lambda bb, key: bb.set(key, "abc"),
    "numeric string": lambda bb, key: bb.create_entry(key, STRING).write("12"),
    "bool": lambda bb, key: bb.set(key, True),
}


@pytest.fixture
def general_only(monkeypatch: pytest.MonkeyPatch):
    """Compile without the shortcuts (the reference), then restore the normal compiler."""

    def compile_general(text: str):
        forget_compiled()
        with monkeypatch.context() as patch:
            patch.setattr(compiler, "shortcut_assign", lambda *args: None)
            unary = compiler._unary
            patch.setattr(compiler, "_unary", lambda op, f, operand=None: unary(op, f))
            return compile_script(text)

    yield compile_general
    forget_compiled()


@pytest.mark.parametrize("text", STATEMENTS)
def test_a_shortcut_does_what_the_general_closure_does(text: str, general_only) -> None:
    general = general_only(text)
    forget_compiled()
    fast = compile_script(text)
    assert fast._fn is not general._fn
    for (x_name, prep_x), (y_name, prep_y), enums in itertools.product(
            STATES.items(), STATES.items(), ({}, {"y": 9, "Z": 1})):
        expected = _outcome_with(general, prep_x, prep_y, enums)
        assert _outcome_with(fast, prep_x, prep_y, enums) == expected, (text, x_name, y_name, enums)


def _entries(bb: Blackboard) -> list:
    """Entries x and y as a tick left them: type, value, declared type, sequence id."""
    out = []
    for key in ("x", "y"):
        entry = bb.get_entry(key)
        out.append(None if entry is None else (key, type(entry.value), repr(entry.value), entry.type.name,
                                               entry.sequence_id))
    return out


def _outcome_with(script, prepare_x: Callable, prepare_y: Callable, enums: dict) -> list:
    bb = Blackboard()
    prepare_x(bb, "x")
    prepare_y(bb, "y")
    seen = []
    for _ in range(2):
        try:
            result = script.run(bb, enums)
            seen.append(("ok", type(result), repr(result)))
        except Exception as exc:  # noqa: BLE001  # the error itself is the outcome compared
            seen.append(("error", type(exc), str(exc)))
        seen.extend(_entries(bb))
    return seen


def test_the_shortcuts_are_what_runs() -> None:
    """The forms above compile to a shortcut (else the comparison would prove nothing)."""
    forget_compiled()
    assert compile_script("x := y + 1")._fn.__name__ == "assign_plus"
    assert compile_script("x += 1")._fn.__name__ == "add_constant"
    int_into_double = compile_script("x := 1")._fn  # the constant shortcut, with 1 stored as 1.0
    assert int_into_double.__name__ == "assign_constant"
    assert int_into_double.shape == ("constant", "x", float, 1.0)
    assert compile_script("x := y")._fn.__name__ == "copy"
    assert compile_script("!y")._fn.__name__ == "not_name"


def test_a_shortcut_through_a_remapped_subtree_follows_a_recreated_entry() -> None:
    root = Blackboard.create()
    mid = Blackboard.create(root)
    mid.add_subtree_remapping("b", "a")
    leaf = Blackboard.create(mid)
    leaf.add_subtree_remapping("c", "b")
    root.set("a", 1.0)
    bump = compile_script("c += 1")
    assert bump.run(leaf) == 2.0
    old = root.get_entry("a")
    root.unset("a")
    root.set("a", 10.0)
    assert bump.run(leaf) == 11.0  # the new entry, not the remembered old one
    assert old.value == 2.0 and root.get("a") == 11.0


def test_a_local_entry_read_before_it_was_removed_is_not_written_again() -> None:
    bb = Blackboard.create()
    bb.set("x", 1.0)
    bump = compile_script("x := x + 1")
    bump.run(bb)
    old = bb.get_entry("x")
    bb.unset("x")
    with pytest.raises(Exception, match=r"left operand of the operator \[\+\] is not initialized"):
        bump.run(bb)  # ':=' made 'x' anew (empty), then reading it fails as BT.CPP does
    assert old.value == 2.0 and bb.get_entry("x") is not old


def test_an_autoremapped_key_after_cloning_resolves_to_the_clone() -> None:
    root = Blackboard.create()
    child = Blackboard.create(root)
    child.enable_auto_remapping()
    root.set("k", 1.0)
    bump = compile_script("k += 1")
    assert bump.run(child) == 2.0
    source = Blackboard.create()
    source.set("k", 100.0)
    source.clone_into(child)  # child now has its own 'k'
    assert bump.run(child) == 101.0
    assert root.get("k") == 2.0


def test_script_nodes_tick_through_their_scripts_one_call_tick() -> None:
    from bt_runtime import BehaviorTreeFactory

    bb = Blackboard.create()
    bb.set("n", 0.0)
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="n += 1"/><ScriptCondition code="n &gt; 1"/></Sequence></BehaviorTree></root>', bb)
    script_node, condition_node = tree.root_node.children
    assert script_node._cell.fast.__name__ == "add_tick"  # node_ticks: the statement is the tick
    assert condition_node._cell.fast.__name__ == "order_tick"
    assert tree.tick_exactly_once() is NodeStatus.FAILURE
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    assert bb.get("n") == 2.0


NODE_CODES = [("Script", t) for t in STATEMENTS + ["x += 1; x := y", "x := 'a'; y := x; x := 2", "x > 0", "y <= 2"]
              if not t.startswith("!")] + [
    ("ScriptCondition", t) for t in ("x > 0", "y < 2", "x >= -1", "@y <= 3", "x != 1", "y", "x == 3", "y == 9",
                                     "x != 4", "x == 0.5", "y == -7.5", "@x == 3")] + [("Script", "x == 3")]


def _two_ticks(tick, node, bb) -> list:
    """What two ticks of ``node`` by ``tick`` give, each with the entries x and y after it: the
    outcome the one-call and the general ticks compare."""
    seen = []
    for _ in range(2):
        try:
            seen.append(("ok", tick(node)))
        except Exception as exc:  # noqa: BLE001  # the error itself is the outcome compared
            seen.append(("error", type(exc), str(exc)))
        seen.extend(_entries(bb))
    return seen


@pytest.mark.parametrize(("tag", "code"), NODE_CODES)
def test_one_call_node_ticks_do_what_the_node_tick_does(tag: str, code: str) -> None:
    """node_ticks.py: ticking a Script/ScriptCondition through its one-call tick gives the
    status, error and blackboard that its general ``tick()`` gives, for every kind of entry."""
    from bt_runtime import BehaviorTreeFactory

    forget_compiled()
    tree = BehaviorTreeFactory().create_tree_from_text(
        f'<root BTCPP_format="4"><BehaviorTree ID="Main"><{tag} code="{code.replace(">", "&gt;").replace("<", "&lt;")}"/>'
        '</BehaviorTree></root>')
    node = tree.root_node
    fast = node._cell.fast
    assert fast is not type(node).tick  # the script's own tick (one call, or the general one)

    def outcome(tick, prep_x, prep_y, enums) -> list:
        bb = Blackboard()
        prep_x(bb, "x")
        prep_y(bb, "y")
        node.config.blackboard = bb
        node.config.enums = enums
        return _two_ticks(tick, node, bb)

    for (x_name, prep_x), (y_name, prep_y), enums in itertools.product(
            STATES.items(), STATES.items(), ({}, {"y": 9, "Z": 1})):
        expected = outcome(type(node).tick, prep_x, prep_y, enums)
        assert outcome(fast, prep_x, prep_y, enums) == expected, (code, x_name, y_name, enums)


@pytest.mark.parametrize(("tag", "code"), NODE_CODES)
def test_a_fresh_scripts_one_call_tick_does_what_the_node_tick_does(tag: str, code: str) -> None:
    """The same, each combination on a script compiled anew, so its first tick is the first
    use of the script: a one-statement script made without its closure (compiler.Script)
    finds its entries on that tick, or compiles the closure when the one-call tick hands over."""
    from bt_runtime import BehaviorTreeFactory

    forget_compiled()
    tree = BehaviorTreeFactory().create_tree_from_text(
        f'<root BTCPP_format="4"><BehaviorTree ID="Main"><{tag} code="{code.replace(">", "&gt;").replace("<", "&lt;")}"/>'
        '</BehaviorTree></root>')
    node = tree.root_node
    general = type(node).tick

    def outcome(fresh: bool, prep_x, prep_y, enums) -> list:
        bb = Blackboard()
        prep_x(bb, "x")
        prep_y(bb, "y")
        node.config.blackboard = bb
        node.config.enums = enums
        forget_compiled()
        script = node._script = compiler.compile_script(code)
        tick = (script.action_tick() if tag == "Script" else script.condition_tick()) if fresh else general
        return _two_ticks(tick, node, bb)

    for (x_name, prep_x), (y_name, prep_y), enums in itertools.product(
            STATES.items(), STATES.items(), ({}, {"y": 9, "Z": 1})):
        expected = outcome(False, prep_x, prep_y, enums)
        assert outcome(True, prep_x, prep_y, enums) == expected, (code, x_name, y_name, enums)


def test_a_one_statement_script_node_ticks_without_compiling_its_closure() -> None:
    """Loading makes no closure for 'x := x + 1' or 'x > 0' on a Script/ScriptCondition node
    (the node's one-call tick is the statement), and ticking on entries of the usual kind
    never needs one; a statement that meets another kind compiles it then."""
    from bt_runtime import BehaviorTreeFactory

    forget_compiled()
    bb = Blackboard.create()
    bb.set("n", 0.0)
    bb.set("k", 1)
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="n := n + 1"/><ScriptCondition code="n &gt; 1"/><Script code="k += 1"/>'
        '</Sequence></BehaviorTree></root>', bb)
    plus, above, int_counter = (node._script for node in tree.root_node.children)
    assert tree.tick_exactly_once() is NodeStatus.FAILURE
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    assert bb.get("n") == 2.0 and bb.get("k") == 2
    assert plus._compiled is None and above._compiled is None  # never needed
    assert int_counter._compiled is not None  # an int entry: the general rules ran


@pytest.mark.parametrize("cls_name", ["ScriptNode", "ScriptConditionNode"])
@pytest.mark.parametrize("code", ["x := x + 1", "x > 0", "x := 1; y := x", "{code}", "=", "a +"])
@pytest.mark.parametrize("conditions", [False, True])
def test_script_node_builders_make_what_the_constructor_makes(cls_name: str, code: str, conditions: bool) -> None:
    """The builder the factory registers for Script/ScriptCondition makes the node the class
    makes (literal code in one frame, anything else through the class), errors included."""
    from bt_runtime.builtins import actions
    from bt_runtime.node import NodeConfig

    cls = getattr(actions, cls_name)

    def config() -> NodeConfig:
        cfg = NodeConfig(input_ports={"code": code})
        if conditions:
            cfg.pre_conditions["_skipIf"] = compile_script("x > 1")
        return cfg

    def state_or_error(make):
        cfg = config()
        try:
            node = make("n", cfg)
        except Exception as exc:  # noqa: BLE001  # the error itself is the outcome compared
            return ("error", type(exc), str(exc))
        assert type(node) is cls
        state = {}  # every slot and instance attribute, the cell by its contents
        for klass in cls.__mro__:
            for slot in klass.__dict__.get("__slots__", ()):
                if slot not in ("__dict__", "__weakref__") and hasattr(node, slot):
                    state[slot] = getattr(node, slot)
        cell = state.pop("_cell")
        assert state.pop("config") is cfg
        fast = cell.fast
        state["cell"] = (type(cell), cell.status, cell.node is node,
                         fast.__name__ if hasattr(fast, "__name__") else type(fast))
        state["__dict__"] = sorted(node.__dict__)
        state["pre"] = node.config.pre_conditions.keys()
        return state

    assert state_or_error(cls.builder()) == state_or_error(cls)
