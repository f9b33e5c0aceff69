"""Ports: typed literal conversion (spec 7.1), defaults, ``{=}``, ``@key``, outputs, type checks
when the tree is built and when it runs, string as the universal donor (spec 2.7, 7.2-7.4)."""

from __future__ import annotations

import enum

import pytest

from bt_runtime import (
    BehaviorTreeFactory,
    BTRuntimeError,
    LogicError,
    NodeExecutionError,
    NodeStatus,
    SyncActionNode,
    XMLLoadError,
    bidirectional_port,
    input_port,
    output_port,
)
from tests.engine.helpers import doc

S = NodeStatus.SUCCESS


class Color(enum.Enum):
    RED = 1
    GREEN = 2


class Read(SyncActionNode):
    """Reads every input port into ``Read.seen[name]`` (or the error text)."""

    seen: dict = {}

    @classmethod
    def provided_ports(cls):
        return [input_port("i", int), input_port("u", "unsigned int"), input_port("d", float),
                input_port("b", bool), input_port("s", str), input_port("st", NodeStatus),
                input_port("c", Color), input_port("any"), input_port("v", list[int]),
                input_port("dflt", int, 7), input_port("dflt_s", str, "hi"),
                input_port("dflt_key", int, "{from_bb}")]

    def tick(self) -> NodeStatus:
        for name in self.config.input_ports.keys() | {"dflt", "dflt_s", "dflt_key"}:
            try:
                Read.seen[name] = self.get_input(name)
            except BTRuntimeError as exc:
                Read.seen[name] = f"error: {exc}"
        return S


class Write(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [output_port("out_i", int), output_port("out_s", str), bidirectional_port("io", float),
                output_port("out_any"), output_port("out_dflt", int, "{default_out}")]

    def tick(self) -> NodeStatus:
        for name in self.config.output_ports:
            value = {"out_i": 5, "out_s": "text", "io": 1.5, "out_any": [1, 2], "out_dflt": 9}[name]
            self.set_output(name, value)
        return S


@pytest.fixture
def factory():
    Read.seen = {}
    f = BehaviorTreeFactory()
    f.register_node_type(Read)
    f.register_node_type(Write)
    return f


def read(factory, attrs: str, setup: dict | None = None) -> dict:
    tree = factory.create_tree_from_text(doc(f"<Read {attrs}/>"))
    for key, value in (setup or {}).items():
        tree.root_blackboard.set(key, value)
    tree.tick_once()
    return dict(Read.seen)


@pytest.mark.parametrize("attr, expected", [
    ('i="42"', 42), ('i="-7"', -7), ('i="2abc"', 2), ('i="2.7"', 2), ('i="0x10"', 0),
    ('u="4000000000"', 4000000000), ('d="1e3"', 1000.0), ('d="-0.5x"', -0.5), ('d="inf"', float("inf")),
    ('b="true"', True), ('b="0"', False), ('b="TRUE"', True), ('b="False"', False),
    ('s="  spaced "', "  spaced "), ('st="RUNNING"', NodeStatus.RUNNING), ('c="GREEN"', Color.GREEN),
    ('c="1"', Color.RED), ('any="raw text"', "raw text"), ('v="1;2;3"', [1, 2, 3]), ('v=""', []),
])
def test_literal_conversion(factory, attr, expected):
    name = attr.split("=")[0]
    assert read(factory, attr)[name] == expected


@pytest.mark.parametrize("attr, type_name", [
    ('i="+2"', "int"), ('i=" 2"', "int"), ('i="abc"', "int"), ('u="-5"', "unsigned int"),
    ('i="3000000000"', "int"), ('d="abc"', "double"), ('b="yes"', "bool"), ('i=" {m} "', "int"),
])
def test_bad_literal_rejected_when_built(factory, attr, type_name):
    name, value = attr.split("=", 1)
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_text(doc(f"<Read {attr}/>"))
    assert f'The port with name "{name}" and value {value} can not be converted to {type_name}' in str(info.value)
    assert info.value.line == 1 and info.value.element == "Read"


@pytest.mark.parametrize("attr", ['st="DONE"', 'c="PURPLE"'])
def test_enum_literals_are_checked_when_read(factory, attr):
    """BT.CPP gives enum types (NodeStatus too) no string converter, so their literals are not
    checked when the tree is built: the tree loads and the read fails."""
    name = attr.split("=")[0]
    seen = read(factory, attr)
    assert isinstance(seen[name], str) and seen[name].startswith("error: getInput(): ")


def test_defaults(factory):
    seen = read(factory, "", {"from_bb": "11"})
    assert seen["dflt"] == 7 and seen["dflt_s"] == "hi" and seen["dflt_key"] == 11


def test_empty_string_overrides_default(factory):
    assert read(factory, 'dflt_s=""')["dflt_s"] == ""


def test_default_pointing_to_missing_key(factory):
    assert read(factory, "")["dflt_key"].startswith("error: getInput() failed because it was unable to find "
                                                    "the key [dflt_key] remapped to [from_bb]")


def test_blackboard_pointer_forms(factory):
    seen = read(factory, 'i="{x}" s="{=}" d="=" any=" {flag} "', {"x": 3, "s": "str", "d": 2.5, "flag": True})
    assert (seen["i"], seen["s"], seen["d"], seen["any"]) == (3, "str", 2.5, True)


def test_string_blackboard_values_feed_typed_ports(factory):
    seen = read(factory, 'i="{x}" d="{y}" b="{z}"', {"x": "12", "y": "0.25", "z": "true"})
    assert (seen["i"], seen["d"], seen["b"]) == (12, 0.25, True)


def test_strings_into_enum_entries_are_refused(factory):
    """Enum-typed entries (NodeStatus too) have no string converter in BT.CPP."""
    tree = factory.create_tree_from_text(doc('<Read st="{z}" c="{w}"/>'))
    for key, text in (("z", "FAILURE"), ("w", "RED")):
        with pytest.raises(LogicError, match="once declared, the type of a port shall not change"):
            tree.root_blackboard.set(key, text)
    tree.root_blackboard.set("z", NodeStatus.FAILURE)
    tree.root_blackboard.set("w", Color.RED)
    tree.tick_once()
    assert (Read.seen["st"], Read.seen["c"]) == (NodeStatus.FAILURE, Color.RED)



def read_after(factory, attrs: str, code: str) -> dict:
    """Values written by a script keep their own kind in the port-typed entries."""
    tree = factory.create_tree_from_text(doc(f'<Sequence><Script code="{code}"/><Read {attrs}/></Sequence>'))
    tree.tick_once()
    return dict(Read.seen)


def test_numeric_blackboard_values_are_cast(factory):
    seen = read_after(factory, 'i="{x}" d="{y}" s="{z}" b="{w}"', "x := 4.0; y := 3; z := 2.5; w := 1")
    assert (seen["i"], seen["d"], seen["s"], seen["b"]) == (4, 3.0, "2.500000", True)
    assert type(seen["i"]) is int and type(seen["d"]) is float


@pytest.mark.parametrize("attr, code, message", [
    ('i="{x}"', "x := 2.5", "Invalid floating point to integer conversion"),
    ('u="{x}"', "x := -1", "Value is negative and can't be converted to unsigned"),
    ('b="{x}"', "x := 2", "Implicit casting to bool is not allowed"),
    ('b="{x}"', "x := -1.5", "Value is negative and can't be converted to unsigned"),
    ('b="{x}"', "x := -1", "Value is negative and can't be converted to unsigned"),
    ('i="{x}"', "x := 3000000000", "Value outside the max numerical limit."),
])
def test_bad_blackboard_values(factory, attr, code, message):
    name = attr.split("=")[0]
    seen = read_after(factory, attr, code)
    assert isinstance(seen[name], str) and message in seen[name]


def test_string_to_bool_port_uses_the_converter(factory):
    assert read(factory, 'b="{x}"', {"x": "true"})["b"] is True


def test_missing_entry(factory):
    seen = read(factory, 'i="{nothing}"')
    assert seen["i"] == "error: getInput() failed because it was unable to find the key [i] remapped to [nothing]"


def test_root_keys_with_at(factory):
    xml = doc('<SubTree ID="S"/>', '<BehaviorTree ID="S"><Sequence><Read i="{@top}"/>'
                                    '<Write out_i="{@made}"/></Sequence></BehaviorTree>')
    tree = factory.create_tree_from_text(xml)
    tree.root_blackboard.set("top", 8)
    tree.tick_once()
    assert Read.seen["i"] == 8
    assert tree.root_blackboard.get("made") == 5
    assert "made" not in tree.subtrees[1].blackboard.local_entries()


def test_get_input_with_default_and_unknown_port(factory):
    tree = factory.create_tree_from_text(doc('<Read i="{nope}"/>'))
    node = tree.root_node
    assert node.get_input("i", -1) == -1
    with pytest.raises(BTRuntimeError, match="manifest doesn't contain the key: \\[zzz\\]"):
        node.get_input("zzz")
    with pytest.raises(BTRuntimeError, match="nor the manifest or the XML contain the key: \\[s\\]"):
        node.get_input("s")


def test_outputs(factory):
    tree = factory.create_tree_from_text(doc('<Write out_i="{a}" out_s="{=}" io="{c}" out_any="{d}"/>'))
    tree.root_blackboard.set("c", 0.5)
    tree.tick_once()
    bb = tree.root_blackboard
    assert (bb.get("a"), bb.get("out_s"), bb.get("c"), bb.get("d"), bb.get("default_out")) == (5, "text", 1.5, [1, 2], 9)


def test_output_needs_a_blackboard_pointer(factory):
    tree = factory.create_tree_from_text(doc('<Write out_i="literal"/>'))
    with pytest.raises(NodeExecutionError, match="setOutput requires a blackboard pointer"):
        tree.tick_once()


def test_set_output_of_undeclared_port(factory):
    tree = factory.create_tree_from_text(doc('<Write/>'))
    with pytest.raises(LogicError, match="does not contain the key: \\[nope\\]"):
        tree.root_node.set_output("nope", 1)


def test_ports_create_typed_empty_entries_when_built(factory):
    tree = factory.create_tree_from_text(doc('<Sequence><Read i="{n}"/><Write out_s="{txt}"/></Sequence>'))
    bb = tree.root_blackboard
    assert bb.get_entry("n").type.name == "int" and bb.get_entry("n").is_empty
    assert bb.get_entry("txt").type.name == "std::string"
    with pytest.raises(BTRuntimeError, match="hasn't been initialized"):
        bb.get("n")


def test_type_mismatch_between_ports_when_built(factory):
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_text(doc('<Sequence><Read i="{k}"/><Read u="{k}"/></Sequence>'))
    assert ("The creation of the tree failed because the port [u] was initially created with type [int] "
            "and, later type [unsigned int] was used somewhere else.") in str(info.value)


def test_string_is_a_universal_donor_when_built(factory):
    factory.create_tree_from_text(doc('<Sequence><Read s="{k}"/><Read i="{k}"/><Read d="{k}"/></Sequence>'))
    with pytest.raises(XMLLoadError, match="initially created with type \\[int\\]"):
        factory.create_tree_from_text(doc('<Sequence><Read i="{k}"/><Read s="{k}"/></Sequence>'))


def test_untyped_ports_do_not_lock(factory):
    factory.create_tree_from_text(doc('<Sequence><Read any="{k}"/><Read i="{k}"/><Read d="{j}"/>'
                                      '<Read any="{j}"/></Sequence>'))


def test_type_lock_at_run_time(factory):
    tree = factory.create_tree_from_text(doc('<Read i="{n}"/>'))
    bb = tree.root_blackboard
    bb.set("n", "42")  # a string converted by the entry's type
    assert bb.get("n") == 42
    bb.set("n", 3.0)  # an exact conversion is accepted
    assert bb.get("n") == 3 and type(bb.get("n")) is int
    with pytest.raises(LogicError, match="once declared, the type of a port shall not change"):
        bb.set("n", 2.5)
    with pytest.raises(BTRuntimeError, match="Can't convert string \\[abc\\] to integer"):
        bb.set("n", "abc")


def test_scripting_enums_in_enum_ports(factory):
    factory.register_scripting_enum("VERDE", 2)
    assert read(factory, 'c="VERDE"')["c"] is Color.GREEN
    with pytest.raises(XMLLoadError, match="can not be converted to int"):
        factory.create_tree_from_text(doc('<Read i="VERDE"/>'))  # only enum-typed ports use the table


@pytest.mark.parametrize("default", ["5", "", 5, "{x"])
def test_output_port_default_must_name_an_entry(default):
    """BT.CPP's OutputPort(name, default, description) refuses a default that is not {key}."""
    from bt_runtime import LogicError, output_port

    with pytest.raises(LogicError, match="Output port can only refer to blackboard entries"):
        output_port("out", int, default=default)
    assert output_port("out", int, default="{x}").default == "{x}"


def test_blackboard_ports_read_again_see_new_values_converted(factory):
    """A port read from the blackboard once is read through its remembered key afterwards:
    every later read still sees the entry's current value, converted as the first one was."""
    tree = factory.create_tree_from_text(doc('<Read i="{x}" d="{y}" s="{z}" any="{w}"/>'))
    bb = tree.root_blackboard
    steps = [({"x": "12", "y": 0.5, "z": "a", "w": "text"}, (12, 0.5, "a", "text")),
             ({"x": "13", "y": "0.25", "z": "b", "w": "other"}, (13, 0.25, "b", "other")),
             ({"x": 14, "y": 2.0, "z": "c", "w": ""}, (14, 2.0, "c", ""))]
    for values, expected in steps:
        for key, value in values.items():
            bb.set(key, value)
        tree.tick_once()
        assert tuple(Read.seen[name] for name in ("i", "d", "s", "any")) == expected
        assert type(Read.seen["i"]) is int and type(Read.seen["d"]) is float
    bb.unset("x")
    tree.tick_once()
    assert Read.seen["i"].startswith("error: getInput() failed because it was unable to find the key [i]")
