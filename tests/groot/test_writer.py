"""bt_runtime.xml.writer: the editable round trip, the FULLTREE form (vs BT.CPP), the printer."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode, input_port, output_port
from bt_runtime.ports import bidirectional_port
from bt_runtime.xml.writer import (
    escape_attribute,
    write_tree,
    write_tree_nodes_model_xml,
    write_tree_to_xml,
)
from groot.testing import GrootClient, free_port_pair
from tests.paths import ROOT

S = NodeStatus


class Move(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("goal", str, description="where to go"),
                input_port("speed", float, default=0.5, description="m/s"),
                output_port("result", int),
                bidirectional_port("state", str, default="{state}")]

    @classmethod
    def metadata(cls):
        return [("color", "blue")]

    def tick(self):
        return S.SUCCESS


def factory() -> BehaviorTreeFactory:
    f = BehaviorTreeFactory()
    f.register_simple_action("A", lambda n: S.SUCCESS)
    f.register_simple_condition("C", lambda n: S.FAILURE)
    f.register_node_type(Move)
    return f


TREES = {
    "subtrees_and_conditions": """
<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="root_seq">
      <Script code="a:=1; msg:='hello'"/>
      <SubTree ID="Sub" name="first" in="{a}" out="{res}" lit="3.5"/>
      <A/>
      <Fallback _skipIf="a == 2" _onSuccess="b := 3" _while="true" _post="c:=1" _failureIf="false">
        <C name="cc" _onHalted="h := 1" _successIf="a &gt; 5" _onFailure="f := 1"/>
        <A name="a &amp; &quot;b&quot; &apos;c&apos;"/>
      </Fallback>
      <SubTree ID="Sub" in="{a}" out="{res2}" lit="hi" _autoremap="true"/>
      <SubTree ID="Leaf" name="Leaf" _skipIf="a == 7"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Sub">
    <Sequence>
      <Script code="out := in; loc := 5"/>
      <SubTree ID="Leaf"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Leaf"><A name="leafA"/></BehaviorTree>
</root>""",
    "builtins_and_ports": """
<root BTCPP_format="4">
  <BehaviorTree ID="B">
    <Sequence>
      <Action ID="C" name="explicit_form"/>
      <Parallel success_count="2" failure_count="2">
        <Move goal="kitchen" result="{r}"/>
        <Move goal="{g}" speed="0.5" state="{=}"/>
        <Move name="m3" goal="x" speed="1.25" state="{@global}"/>
      </Parallel>
      <Switch3 variable="{v}" case_1="1" case_2="two" case_3="3">
        <A/><A/><A/><C/>
      </Switch3>
      <RetryUntilSuccessful num_attempts="3"><Timeout msec="100"><Delay delay_msec="5"><A/></Delay></Timeout></RetryUntilSuccessful>
      <RunOnce then_skip="false"><KeepRunningUntilFailure><C/></KeepRunningUntilFailure></RunOnce>
      <Precondition if="v &lt; 2 &amp;&amp; v != 0" else="SUCCESS"><A/></Precondition>
      <IfThenElse><C/><A/><A/></IfThenElse>
      <WhileDoElse><C/><A/><A/></WhileDoElse>
      <TryCatch catch_on_halt="true"><A/><A/></TryCatch>
      <LoopInt queue="1;2;3" value="{i}"><A/></LoopInt>
      <Repeat num_cycles="-1"><Inverter><ForceFailure><AlwaysSuccess/></ForceFailure></Inverter></Repeat>
      <SetBlackboard output_key="k" value="multi&#10;line"/>
      <Script code="x := 'a'
y := 2"/>
    </Sequence>
  </BehaviorTree>
</root>""",
    "subtree_models": """
<root BTCPP_format="4" main_tree_to_execute="M">
  <BehaviorTree ID="M">
    <Sequence>
      <SubTree ID="Nav" goal="{g}"/>
      <SubTree ID="Nav" name="second" goal="home" tries="{t}" _autoremap="false"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Nav"><Move goal="{goal}" result="{tries}"/></BehaviorTree>
  <TreeNodesModel>
    <SubTree ID="Nav">
      <input_port name="goal"/>
      <input_port name="tries" default="2"/>
    </SubTree>
  </TreeNodesModel>
</root>""",
}


def describe(tree) -> list:
    """Everything the round trip must keep, per subtree record and node."""
    out = []
    for rec in tree.subtrees:
        nodes = []
        for node in rec.nodes:
            cfg = node.config
            nodes.append({
                "uid": node.uid, "id": node.registration_name, "name": node.name, "path": node.full_path,
                "in": dict(cfg.input_ports), "out": dict(cfg.output_ports),
                "pre": {k: v.text for k, v in cfg.pre_conditions.items()},
                "post": {k: v.text for k, v in cfg.post_conditions.items()},
                "other": dict(cfg.other_attributes),
                "subtree": getattr(node, "subtree_id", None),
                "children": [c.uid for c in node.children_nodes()],
                "remap": node.blackboard.remappings,
            })
        out.append({"id": rec.tree_id, "instance": rec.instance_name, "nodes": nodes,
                    "remap": rec.blackboard.remappings, "autoremap": rec.blackboard.autoremap,
                    "local": {k: e.value for k, e in rec.blackboard.local_entries().items()}})
    return out


@pytest.mark.parametrize("name", sorted(TREES))
def test_round_trip(name: str) -> None:
    tree = factory().create_tree_from_text(TREES[name])
    text = write_tree(tree)
    again = factory().create_tree_from_text(text)
    assert describe(again) == describe(tree)
    assert write_tree(again) == text  # stable
    # With every default written out, the nodes are the same; a default "{key}" port that is
    # now given explicitly makes the loader create its (empty) blackboard entry up front.
    text_all = write_tree(tree, include_defaults=True, models=False)
    strip = [{k: v for k, v in rec.items() if k != "local"} for rec in describe(tree)]
    assert [{k: v for k, v in rec.items() if k != "local"}
            for rec in describe(factory().create_tree_from_text(text_all))] == strip


def test_editable_form_details() -> None:
    tree = factory().create_tree_from_text(TREES["subtrees_and_conditions"])
    text = write_tree(tree)
    assert text.startswith('<root BTCPP_format="4" main_tree_to_execute="Main">\n    <BehaviorTree ID="Main">\n')
    assert text.endswith("</root>\n")
    assert text.count('<BehaviorTree ID="Sub">') == 1  # one definition per tree ID
    assert '<SubTree ID="Sub" name="first" in="{a}" out="{res}" lit="3.5"/>' in text
    assert '<SubTree ID="Sub" in="{a}" out="{res2}" lit="hi" _autoremap="true"/>' in text
    assert '<SubTree ID="Leaf" name="Leaf" _skipIf="a == 7"/>' in text  # explicit name == ID kept
    assert "<Parallel" not in text or 'success_count="-1"' not in text  # defaults left out
    assert '_failureIf="false" _skipIf="a == 2" _while="true" _onSuccess="b := 3" _post="c:=1"' in text
    assert "<TreeNodesModel>\n        <Action ID=\"A\"/>\n        <Condition ID=\"C\"/>\n    </TreeNodesModel>" in text


def test_fulltree_form() -> None:
    tree = factory().create_tree_from_text(TREES["subtrees_and_conditions"])
    xml = write_tree_to_xml(tree)
    root = ET.fromstring(xml)
    blocks = root.findall("BehaviorTree")
    assert [(b.get("ID"), b.get("_fullpath")) for b in blocks] == [
        ("Main", ""), ("Sub", "first"), ("Leaf", "first/Leaf::6"), ("Sub", "Sub::12"),
        ("Leaf", "Sub::12/Leaf::15"), ("Leaf", "Leaf")]
    uids = [int(e.get("_uid")) for b in blocks for e in b.iter() if e is not b]
    assert sorted(uids) == list(range(1, 19))
    subtree_elems = [e for e in root.iter("SubTree") if e.get("_uid")]
    assert all(e.get("name") is None and len(e) == 0 for e in subtree_elems)
    assert '<Script name="Script" _uid="2" code="a:=1; msg:=&apos;hello&apos;"/>' in xml
    models = root.find("TreeNodesModel")
    ids = [m.get("ID") for m in models]
    assert ids == sorted(ids) and "Sequence" in ids and "Move" in ids  # builtins included
    assert root.find("TreeNodesModel").tail is None or root.find("TreeNodesModel").tail.strip() == ""
    assert xml.endswith("    </TreeNodesModel>\n</root>\n")
    assert "_uid" not in write_tree_to_xml(tree, add_metadata=False, add_builtin_models=False)


def test_models_writer_format() -> None:
    text = write_tree_nodes_model_xml(factory().manifests)
    assert text == (
        '<root BTCPP_format="4">\n'
        "    <TreeNodesModel>\n"
        '        <Action ID="A"/>\n'
        '        <Condition ID="C"/>\n'
        '        <Action ID="Move">\n'
        '            <input_port name="goal" type="std::string">where to go</input_port>\n'
        '            <input_port name="speed" type="double" default="0.500000">m/s</input_port>\n'
        '            <output_port name="result" type="int"/>\n'
        '            <inout_port name="state" type="std::string" default="{state}"/>\n'
        "            <MetadataFields>\n"
        '                <Metadata color="blue"/>\n'
        "            </MetadataFields>\n"
        "        </Action>\n"
        "    </TreeNodesModel>\n"
        "</root>\n")
    with_builtins = write_tree_nodes_model_xml(factory().manifests, include_builtin=True)
    assert '<SubTree ID="SubTree">\n            <input_port name="_autoremap" type="bool" default="false">' \
           "If true, all the ports with the same name will be remapped</input_port>" in with_builtins
    assert '<Decorator ID="RunOnce">' in with_builtins


def test_escaping_like_tinyxml2() -> None:
    assert escape_attribute("a<b>&\"c'\n") == "a&lt;b&gt;&amp;&quot;c&apos;\n"


# ---------------------------------------------------------------------------------------------
# Against BT.CPP (behaviortreepy's Groot2Publisher FULLTREE reply)
# ---------------------------------------------------------------------------------------------

# (A SubTree named like its ID is left out on purpose: BT.CPP then writes the SubTree element
# with _fullpath "ID::uid" but its block with "ID", an inconsistency we do not copy.)
ORACLE_XML = TREES["subtrees_and_conditions"].replace(
    '<SubTree ID="Leaf" name="Leaf" _skipIf="a == 7"/>',
    '<Parallel><A/></Parallel><RunOnce><C/></RunOnce><SubTree ID="Leaf" name="leaf_x" _skipIf="a == 7"/>')


def _elements(xml: str) -> list[tuple]:
    root = ET.fromstring(xml)
    out = []
    for block in root.findall("BehaviorTree"):
        out.append(("BehaviorTree", dict(block.attrib)))
        for e in block.iter():
            if e is not block:
                out.append((e.tag, dict(e.attrib), len(e)))
    return out


@pytest.mark.oracle
def test_fulltree_matches_btcpp() -> None:
    bt = pytest.importorskip("behaviortreepy")
    f = bt.BehaviorTreeFactory()
    f.register_simple_action("A", lambda n: bt.NodeStatus.SUCCESS)
    f.register_simple_condition("C", lambda n: bt.NodeStatus.FAILURE)
    ref_tree = f.create_tree_from_text(ORACLE_XML)
    port = free_port_pair()
    publisher = bt.Groot2Publisher(ref_tree, port)
    try:
        with GrootClient(port) as client:
            ref_xml = client.fulltree()
    finally:
        del publisher
    ours = write_tree_to_xml(factory().create_tree_from_text(ORACLE_XML))
    # Same blocks, node order, uids, full paths, names and attributes (port order may differ).
    assert _elements(ours) == _elements(ref_xml)
    # The same printer layout: one line per element in the tree part.
    assert ours.split("<TreeNodesModel>")[0].count("\n") == ref_xml.split("<TreeNodesModel>")[0].count("\n")
    ours_models = {m.get("ID"): m.tag for m in ET.fromstring(ours).find("TreeNodesModel")}
    ref_models = {m.get("ID"): m.tag for m in ET.fromstring(ref_xml).find("TreeNodesModel")}
    # BT.CPP 4.10 added TryCatch; otherwise the same node types with the same kinds.
    assert {k: v for k, v in ours_models.items() if k not in ("TryCatch", "Move")} == ref_models


PROJECT_TREES = sorted((ROOT / "trees").glob("*.xml"))


@pytest.mark.parametrize("path", PROJECT_TREES, ids=[p.name for p in PROJECT_TREES])
def test_round_trip_project_trees(path: Path) -> None:
    """The project's own trees (with the project's node library) survive write -> load."""
    nodes = pytest.importorskip("nodes")
    if not hasattr(nodes, "register_all"):
        pytest.skip("nodes.register_all is not available")

    def project_factory() -> BehaviorTreeFactory:
        f = BehaviorTreeFactory()
        nodes.register_all(f)
        return f

    tree = project_factory().create_tree_from_file(path)
    text = write_tree(tree)
    assert describe(project_factory().create_tree_from_text(text)) == describe(tree)
