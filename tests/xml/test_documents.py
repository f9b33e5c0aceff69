"""Documents: includes (relative, confined to the top-level file's folder, cycles),
TreeNodesModel (subtree port defaults and mandatory ports, node placeholders), v3 files."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from bt_runtime import BehaviorTreeFactory, NodeExecutionError, NodeStatus, XMLLoadError
from bt_runtime.xml.v3 import BTFormatWarning
from tests.engine.helpers import doc
from tests.paths import REFERENCE

S, F = NodeStatus.SUCCESS, NodeStatus.FAILURE
NAV2 = REFERENCE / "nav2" / "trees"


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def tree_file(tree_id: str, body: str, includes: tuple[str, ...] = ()) -> str:
    inc = "".join(f'<include path="{p}"/>' for p in includes)
    return f'<root BTCPP_format="4">{inc}<BehaviorTree ID="{tree_id}">{body}</BehaviorTree></root>'


# -- includes ----------------------------------------------------------------------------------------

def test_includes_relative_to_the_including_file(tmp_path):
    write(tmp_path / "lib" / "deep" / "leaf.xml", tree_file("Leaf", '<Script code="@trail += \'leaf\'"/>'))
    write(tmp_path / "lib" / "mid.xml", tree_file("Mid", '<Sequence><Script code="@trail += \'mid,\'"/>'
                                                          '<SubTree ID="Leaf"/></Sequence>', ("deep/leaf.xml",)))
    main = write(tmp_path / "main.xml",
                 '<root BTCPP_format="4" main_tree_to_execute="Main"><include path="lib/mid.xml"/>'
                 '<BehaviorTree ID="Main"><Sequence><Script code="trail := \'\'"/><SubTree ID="Mid"/></Sequence>'
                 '</BehaviorTree></root>')
    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_file(main)
    assert tree.tick_once() is S
    assert tree.root_blackboard.get("trail") == "mid,leaf"
    assert sorted(factory.registered_behavior_trees()) == ["Leaf", "Main", "Mid"]


def test_include_from_text_is_relative_to_the_working_directory(tmp_path, monkeypatch):
    write(tmp_path / "sub.xml", tree_file("Sub", "<AlwaysFailure/>"))
    monkeypatch.chdir(tmp_path)
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4" main_tree_to_execute="M"><include path="sub.xml"/>'
        '<BehaviorTree ID="M"><SubTree ID="Sub"/></BehaviorTree></root>')
    assert tree.tick_once() is F


def test_include_outside_the_folder_is_refused(tmp_path):
    write(tmp_path / "secret.xml", tree_file("Secret", "<AlwaysSuccess/>"))
    write(tmp_path / "a" / "other.xml", tree_file("Other", "<AlwaysSuccess/>"))
    for target in ("../secret.xml", str(tmp_path / "secret.xml"), "../a/../secret.xml"):
        main = write(tmp_path / "a" / "main.xml", tree_file("M", "<AlwaysSuccess/>", (target,)))
        with pytest.raises(XMLLoadError, match="resolves outside the folder") as info:
            BehaviorTreeFactory().create_tree_from_file(main)
        assert info.value.element == "include" and info.value.file == str(main)
    # an absolute path inside the folder is fine
    main = write(tmp_path / "a" / "main.xml", tree_file("M", '<SubTree ID="Other"/>', (str(tmp_path / "a" / "other.xml"),)))
    assert BehaviorTreeFactory().create_tree_from_file(main).tick_once() is S


def test_included_file_may_climb_back_inside_the_top_level_folder(tmp_path):
    """sub/inner.xml includes ../top.xml: outside its own folder, inside main.xml's (as
    BT.CPP's own child_include_parent.xml does)."""
    write(tmp_path / "top.xml", tree_file("Top", "<AlwaysFailure/>"))
    write(tmp_path / "sub" / "inner.xml", tree_file("Inner", '<SubTree ID="Top"/>', ("../top.xml",)))
    write(tmp_path / "sub" / "deeper" / "leaf.xml", tree_file("Leaf", "<AlwaysSuccess/>", ("../../top.xml",)))
    main = write(tmp_path / "main.xml", tree_file("M", '<Sequence><SubTree ID="Leaf"/><SubTree ID="Inner"/></Sequence>',
                                                  ("sub/inner.xml", "sub/deeper/leaf.xml")))
    factory = BehaviorTreeFactory()
    assert factory.create_tree_from_file(main).tick_once() is F  # Leaf succeeds, Inner runs Top
    assert factory.registered_behavior_trees() == ["Inner", "Leaf", "M", "Top"]


def test_nested_include_cannot_leave_the_top_level_folder(tmp_path):
    write(tmp_path / "outside.xml", tree_file("Outside", "<AlwaysSuccess/>"))
    inner = write(tmp_path / "app" / "sub" / "inner.xml", tree_file("Inner", "<AlwaysSuccess/>", ("../../outside.xml",)))
    main = write(tmp_path / "app" / "main.xml", tree_file("M", '<SubTree ID="Inner"/>', ("sub/inner.xml",)))
    with pytest.raises(XMLLoadError, match="outside the folder of the top-level file") as info:
        BehaviorTreeFactory().create_tree_from_file(main)
    assert info.value.file == str(inner) and info.value.element == "include"


def test_include_search_path_widens_the_confinement(tmp_path):
    write(tmp_path / "shared" / "common.xml", tree_file("Common", "<AlwaysFailure/>"))
    main = write(tmp_path / "app" / "main.xml", tree_file("M", '<SubTree ID="Common"/>', ("../shared/common.xml",)))
    with pytest.raises(XMLLoadError, match="outside the folder"):
        BehaviorTreeFactory().create_tree_from_file(main)
    factory = BehaviorTreeFactory()
    factory.add_include_search_path(tmp_path / "shared")
    assert factory.create_tree_from_file(main).tick_once() is F


def test_include_cycles(tmp_path):
    write(tmp_path / "a.xml", tree_file("A", "<AlwaysSuccess/>", ("b.xml",)))
    write(tmp_path / "b.xml", tree_file("B", "<AlwaysSuccess/>", ("a.xml",)))
    with pytest.raises(XMLLoadError, match="include cycle"):
        BehaviorTreeFactory().create_tree_from_file(tmp_path / "a.xml")
    write(tmp_path / "self.xml", tree_file("Self", "<AlwaysSuccess/>", ("self.xml",)))
    with pytest.raises(XMLLoadError, match="include cycle"):
        BehaviorTreeFactory().create_tree_from_file(tmp_path / "self.xml")


def test_include_diamond_is_not_a_cycle(tmp_path):
    write(tmp_path / "common.xml", tree_file("Common", "<AlwaysSuccess/>"))
    write(tmp_path / "x.xml", tree_file("X", '<SubTree ID="Common"/>', ("common.xml",)))
    write(tmp_path / "y.xml", tree_file("Y", '<SubTree ID="Common"/>', ("common.xml",)))
    main = write(tmp_path / "main.xml",
                 '<root BTCPP_format="4" main_tree_to_execute="M"><include path="x.xml"/><include path="y.xml"/>'
                 '<BehaviorTree ID="M"><Sequence><SubTree ID="X"/><SubTree ID="Y"/></Sequence></BehaviorTree></root>')
    assert BehaviorTreeFactory().create_tree_from_file(main).tick_once() is S


def test_include_errors(tmp_path):
    main = write(tmp_path / "main.xml", tree_file("M", "<AlwaysSuccess/>", ("missing.xml",)))
    with pytest.raises(XMLLoadError, match="included file not found"):
        BehaviorTreeFactory().create_tree_from_file(main)
    main = write(tmp_path / "main.xml", '<root BTCPP_format="4"><include ros_pkg="nav2" path="x.xml"/>'
                                        '<BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>')
    with pytest.raises(XMLLoadError, match="ros_pkg"):
        BehaviorTreeFactory().create_tree_from_file(main)
    write(tmp_path / "bad.xml", '<root BTCPP_format="4">\n<BehaviorTree ID="Bad">\n<Nope/></BehaviorTree></root>')
    main = write(tmp_path / "main.xml", tree_file("M", "<AlwaysSuccess/>", ("bad.xml",)))
    with pytest.raises(XMLLoadError) as info:
        BehaviorTreeFactory().create_tree_from_file(main)
    assert (Path(info.value.file).name, info.value.line, info.value.element) == ("bad.xml", 3, "Nope")


# -- TreeNodesModel ------------------------------------------------------------------------------------

SUB = ('<BehaviorTree ID="Sub"><Script code="out := msg .. \'/\' .. num"/></BehaviorTree>'
       '<TreeNodesModel><SubTree ID="Sub"><input_port name="msg" default="hello"/>'
       '<input_port name="num" default="{n}"/><output_port name="out"/></SubTree>'
       '<Action ID="Ignored"><input_port name="x"/></Action></TreeNodesModel>')


def test_subtree_model_defaults():
    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_text(doc(
        '<Sequence><Script code="n := 7"/><SubTree ID="Sub" out="{a}"/><SubTree ID="Sub" msg="bye" num="1" out="{b}"/>'
        '</Sequence>', SUB))
    tree.tick_once()
    assert tree.root_blackboard.get("a") == "hello/7"
    assert tree.root_blackboard.get("b") == "bye/1"
    assert "Ignored" not in factory.manifests  # only SubTree models are used by the runtime


def test_subtree_model_mandatory_port_and_autoremap():
    factory = BehaviorTreeFactory()
    with pytest.raises(XMLLoadError, match=r"mandatory port called \[out\]"):
        factory.create_tree_from_text(doc('<SubTree ID="Sub"/>', SUB))
    # with _autoremap the model's defaults are not applied: keys come from the parent instead
    tree = factory.create_tree_from_text(doc('<Sequence><Script code="msg := \'m\'; num := 2"/>'
                                             '<SubTree ID="Sub" _autoremap="true"/></Sequence>', SUB))
    tree.tick_once()
    assert tree.root_blackboard.get("out") == "m/2"


def test_subtree_literal_remapping_and_equals():
    tree = BehaviorTreeFactory().create_tree_from_text(doc(
        '<Sequence><Script code="num := 3"/><SubTree ID="Sub" msg="lit" num="{=}" out="{=}"/></Sequence>', SUB))
    tree.tick_once()
    assert tree.root_blackboard.get("out") == "lit/3"


def test_register_models_creates_placeholders():
    factory = BehaviorTreeFactory()
    added = factory.register_models_from_text(
        '<root BTCPP_format="4"><TreeNodesModel><Action ID="Move"><input_port name="goal" type="double"/>'
        '<output_port name="done" type="bool"/></Action><Condition ID="Ready"/>'
        '<Decorator ID="Guard"/><Control ID="Pick"/></TreeNodesModel></root>')
    assert sorted(added) == ["Guard", "Move", "Pick", "Ready"]
    tree = factory.create_tree_from_text(doc('<Pick><Guard><Sequence><Ready/><Move goal="1.5" done="{d}"/>'
                                             '</Sequence></Guard></Pick>'))
    assert factory.manifests["Move"].ports["goal"].type.name == "double"
    with pytest.raises(XMLLoadError, match="can not be converted to double"):
        factory.create_tree_from_text(doc('<Move goal="far"/>'))
    with pytest.raises(NodeExecutionError):
        tree.tick_once()  # placeholders cannot run


# -- v3 files --------------------------------------------------------------------------------------------

def test_missing_format_warns():
    with pytest.warns(BTFormatWarning, match="BTCPP_format"):
        BehaviorTreeFactory().create_tree_from_text('<root><BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>')


def test_v3_names_translated():
    xml = ('<root main_tree_to_execute="M"><BehaviorTree ID="M"><SequenceStar><Action ID="AlwaysSuccess"/>'
           '<SubTreePlus ID="S" __autoremap="true"/><SubTree ID="S2" __shared_blackboard="true"/>'
           '<RetryUntilSuccesful num_attempts="2"><AlwaysSuccess/></RetryUntilSuccesful></SequenceStar></BehaviorTree>'
           '<BehaviorTree ID="S"><Script code="a := 1"/></BehaviorTree>'
           '<BehaviorTree ID="S2"><Script code="b := 2"/></BehaviorTree></root>')
    with pytest.warns(BTFormatWarning, match="v3 file translated to v4") as record:
        tree = BehaviorTreeFactory().create_tree_from_text(xml)
    text = " ".join(str(w.message) for w in record)
    for change in ("SequenceStar -> SequenceWithMemory", "SubTreePlus -> SubTree",
                   "RetryUntilSuccesful -> RetryUntilSuccessful", "__shared_blackboard -> _autoremap"):
        assert change in text
    assert tree.tick_while_running(0) is S
    assert tree.root_blackboard.get("a") == 1 and tree.root_blackboard.get("b") == 2


def test_v4_file_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        BehaviorTreeFactory().create_tree_from_text(doc("<AlwaysSuccess/>"))


@pytest.mark.skipif(not NAV2.is_dir(), reason="the shared Nav2 reference trees are not available")
@pytest.mark.parametrize("path", sorted(p.name for p in (NAV2 / "humble").glob("*.xml"))
                         if NAV2.is_dir() else [])
def test_nav2_humble_v3_trees_load_with_placeholders(path):
    if path in ("nav2_tree_nodes.xml", "odometry_calibration.xml"):
        pytest.skip("the models file itself / uses a port Humble's models file does not declare")
    factory = BehaviorTreeFactory()
    with pytest.warns(BTFormatWarning):
        factory.register_models_from_file(NAV2 / "humble" / "nav2_tree_nodes.xml")
    with pytest.warns(BTFormatWarning):
        tree = factory.create_tree_from_file(NAV2 / "humble" / path)
    assert tree.root_node.uid == 1


@pytest.mark.skipif(not NAV2.is_dir(), reason="the shared Nav2 reference trees are not available")
def test_nav2_jazzy_tree_loads_without_warning():
    factory = BehaviorTreeFactory()
    factory.register_models_from_file(NAV2 / "jazzy" / "nav2_tree_nodes.xml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tree = factory.create_tree_from_file(NAV2 / "jazzy" / "navigate_to_pose_w_replanning_and_recovery.xml")
    assert len(list(tree.nodes())) > 20


def test_a_node_knows_the_file_and_line_of_its_start_tag(tmp_path: Path) -> None:
    """``node.config.source`` (what validate reports): the line where the start tag begins,
    even when the tag spans lines or a script attribute had to be escaped."""
    path = write(tmp_path / "t.xml", '<root BTCPP_format="4">\n<BehaviorTree ID="Main">\n<Sequence>\n'
                 '  <Script code="a := 1"/>\n  <Script\n     code="b := a < 2"\n     name="two"/>\n'
                 '  <Action ID="AlwaysSuccess"\n   name="three"/>\n</Sequence>\n</BehaviorTree>\n</root>\n')
    tree = BehaviorTreeFactory().create_tree_from_file(path)
    by_name = {node.name: node.config.source for node in tree.nodes()}
    assert by_name["Sequence"] == (str(path), 3)
    assert by_name["Script"] == (str(path), 4)
    assert by_name["two"] == (str(path), 5)
    assert by_name["three"] == (str(path), 8)
