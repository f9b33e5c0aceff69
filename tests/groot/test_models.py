"""groot.models: TreeNodesModel export, in-place embedding, the models CLI, BT.CPP accepting it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode, input_port, output_port
from bt_runtime.cli import models as cli
from groot.models import XMLScanError, embed_models, embed_models_text, models_xml, scan_tags
from tests.paths import ROOT

S = NodeStatus


class Move(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("goal", str, description="where <to> go"), input_port("speed", float, default=0.5),
                output_port("result", int)]

    def tick(self):
        return S.SUCCESS


def register(factory: BehaviorTreeFactory) -> None:
    """Used by the CLI tests as --register tests.groot.test_models:register."""
    factory.register_node_type(Move)
    factory.register_simple_action("A", lambda n: S.SUCCESS)
    factory.register_simple_condition("C", lambda n: S.FAILURE)
    factory.register_simple_action("Unused", lambda n: S.SUCCESS)


def make_factory() -> BehaviorTreeFactory:
    f = BehaviorTreeFactory()
    register(f)
    return f


TREE = """\
<?xml version="1.0" encoding="UTF-8"?>
<!-- header comment: <TreeNodesModel> in a comment is not the section -->
<root BTCPP_format='4' main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence   name = "seq" >
      <Move goal="kitchen" speed='0.7'/>   <!-- trailing comment -->
      <A/>
      <Action ID="C" name="explicit"/>
      <SubTree ID="Sub" target="{t}"/>
      <Script code="x := 'a&amp;b' "/>
    </Sequence>
  </BehaviorTree>

  <BehaviorTree ID="Sub"><Nav2Thing goal="{target}"/></BehaviorTree>
</root>
"""


def test_models_xml_sorted_custom_only() -> None:
    xml = models_xml(make_factory())
    assert xml.splitlines()[:4] == ['<root BTCPP_format="4">', "    <TreeNodesModel>",
                                    '        <Action ID="A"/>', '        <Condition ID="C"/>']
    assert '<input_port name="goal" type="std::string">where &lt;to&gt; go</input_port>' in xml
    assert '<input_port name="speed" type="double" default="0.500000"/>' in xml
    assert "Sequence" not in xml
    assert '<Control ID="Sequence"/>' in models_xml(make_factory(), include_builtin=True)


def test_embed_adds_section_and_keeps_every_other_byte(tmp_path: Path) -> None:
    path = tmp_path / "tree.xml"
    path.write_text(TREE)
    result = embed_models(path, make_factory())
    text = path.read_text()
    assert result.changed and result.generated == ["Move", "A", "C"] and result.missing == ["Nav2Thing"]
    section = text[text.index("  <TreeNodesModel>"):text.index("</TreeNodesModel>") + len("</TreeNodesModel>\n")]
    assert text.replace(section, "") == TREE  # everything else byte for byte
    assert section == (
        "  <TreeNodesModel>\n"
        '    <Action ID="A"/>\n'
        '    <Condition ID="C"/>\n'
        '    <Action ID="Move">\n'
        '      <input_port name="goal" type="std::string">where &lt;to&gt; go</input_port>\n'
        '      <input_port name="speed" type="double" default="0.500000"/>\n'
        '      <output_port name="result" type="int"/>\n'
        "    </Action>\n"
        "  </TreeNodesModel>\n")
    # idempotent: the second run changes nothing, not even the file's mtime
    mtime = path.stat().st_mtime_ns
    again = embed_models(path, make_factory())
    assert not again.changed and path.stat().st_mtime_ns == mtime
    # the result still loads
    f = make_factory()
    f.register_models_from_text('<root BTCPP_format="4"><TreeNodesModel><Action ID="Nav2Thing">'
                                '<input_port name="goal"/></Action></TreeNodesModel></root>')
    f.create_tree_from_file(path)


def test_embed_refreshes_existing_section_and_keeps_foreign_entries() -> None:
    text = TREE.replace("</root>", """\
  <TreeNodesModel>
      <Action ID="Move"><input_port name="old"/></Action>
      <SubTree ID="Sub">
          <input_port name="target" default="{t}"/>
      </SubTree>
      <Action ID="Nav2Thing"><input_port name="goal"/></Action>
      <Action ID="Unused"/>
      <Action ID="Gone"/>
  </TreeNodesModel>
</root>""")
    result = embed_models_text(text, make_factory())
    assert result.kept == ["Sub", "Nav2Thing", "Unused", "Gone"] and result.missing == []
    new = result.text
    assert new[:new.rindex("<TreeNodesModel>")] == text[:text.rindex("<TreeNodesModel>")]
    assert new.endswith("</TreeNodesModel>\n</root>\n")
    assert '<input_port name="old"/>' not in new  # regenerated from the factory
    assert '      <SubTree ID="Sub">\n          <input_port name="target" default="{t}"/>\n      </SubTree>' in new
    ids = [t.attrs["ID"] for t in scan_tags(new[new.rindex("<TreeNodesModel>"):])
           if t.kind in ("start", "empty") and "ID" in t.attrs]
    assert ids == sorted(ids)  # one sorted list: generated and kept entries together
    pruned = embed_models_text(text, make_factory(), prune=True)
    assert pruned.kept == ["Sub", "Nav2Thing"]  # Unused/Gone are not used by the file
    assert embed_models_text(result.text, make_factory()).changed is False


def test_embed_crlf_tabs_and_empty_section() -> None:
    text = ('<root BTCPP_format="4">\r\n\t<BehaviorTree ID="M">\r\n\t\t<A/>\r\n\t</BehaviorTree>\r\n'
            "\t<TreeNodesModel/>\r\n</root>")
    result = embed_models_text(text, make_factory())
    assert result.text == ('<root BTCPP_format="4">\r\n\t<BehaviorTree ID="M">\r\n\t\t<A/>\r\n\t</BehaviorTree>\r\n'
                           '\t<TreeNodesModel>\r\n\t\t<Action ID="A"/>\r\n\t</TreeNodesModel>\r\n</root>')
    # nothing to describe: an empty section, and a one-line document keeps its single line
    only_builtins = '<root BTCPP_format="4"><BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>'
    out = embed_models_text(only_builtins, make_factory()).text
    assert out.startswith(only_builtins[:-len("</root>")]) and "<TreeNodesModel/>" in out
    assert '<Action ID="AlwaysSuccess"/>' in embed_models_text(only_builtins, make_factory(),
                                                               include_builtin=True).text


@pytest.mark.parametrize("bad", ["<root><BehaviorTree ID='x'>", "<notroot/>", "<root a=b></root>",
                                 "<root><!-- x </root>"])
def test_embed_refuses_malformed(bad: str) -> None:
    with pytest.raises(XMLScanError):
        embed_models_text(bad, make_factory())


def test_cli_print_embed_check(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    args = ["--no-nodes", "--register", "tests.groot.test_models:register"]
    out = tmp_path / "models.xml"
    assert cli.main([*args, "--out", str(out)]) == 0
    assert out.read_text() == models_xml(make_factory())
    tree = tmp_path / "t.xml"
    tree.write_text(TREE)
    assert cli.main([*args, "--embed", str(tree), "--check"]) == 1  # missing: would change
    assert tree.read_text() == TREE
    assert cli.main([*args, "--embed", str(tree)]) == 0
    assert cli.main([*args, "--embed", str(tree), "--check"]) == 0
    err = capsys.readouterr().err
    assert "Nav2Thing" in err and "updated" in err
    bad = tmp_path / "bad.xml"
    bad.write_text("<root>")
    assert cli.main([*args, "--embed", str(bad)]) == 2


def test_cli_includes_the_project_nodes_by_default(tmp_path: Path) -> None:
    nodes = pytest.importorskip("nodes")
    register_all = getattr(nodes, "register_all", None)
    if register_all is None:
        pytest.skip("the nodes package has no register_all yet")
    f = BehaviorTreeFactory()
    register_all(f)
    out = tmp_path / "models.xml"
    assert cli.main(["--out", str(out)]) == 0
    assert out.read_text() == models_xml(f)
    assert out.read_text().count(" ID=") > 3


def test_cli_parser_and_module_entry(tmp_path: Path) -> None:
    import argparse

    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    cli.add_parser(sub)
    args = parser.parse_args(["models", "--builtin", "--no-nodes"])
    assert args.func is cli.run and args.builtin
    proc = subprocess.run([sys.executable, "-m", "bt_runtime.cli.models", "--builtin"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and '<Decorator ID="RunOnce">' in proc.stdout


@pytest.mark.oracle
def test_btcpp_loads_a_file_with_our_models(tmp_path: Path) -> None:
    bt = pytest.importorskip("behaviortreepy")
    # behaviortreepy's Python nodes have no ports: use them without port attributes (their
    # models still declare ports); keep a SubTree model, which BT.CPP does read.
    text = TREE.replace("<Nav2Thing goal=\"{target}\"/>", "<Sequence><A/><Script code=\"y := target\"/></Sequence>")
    text = text.replace("<Script code=\"x := 'a&amp;b' \"/>", "<Script code=\"x := 1\"/>")
    text = text.replace("<Move goal=\"kitchen\" speed='0.7'/>", "<Move/>")
    text = text.replace('<SubTree ID="Sub" target="{t}"/>', '<Script code="t := 5"/><SubTree ID="Sub"/>')
    text = text.replace("</root>", '  <TreeNodesModel>\n    <SubTree ID="Sub"><input_port name="target" '
                                   'default="{t}"/></SubTree>\n  </TreeNodesModel>\n</root>')
    path = tmp_path / "tree.xml"
    path.write_text(text)
    f = make_factory()
    embed_models(path, f, include_builtin=True)  # builtins too: the richest section we write
    embedded = path.read_text()
    assert "<TreeNodesModel>" in embedded and '<Action ID="Move">' in embedded
    ref = bt.BehaviorTreeFactory()
    for name in ("Move", "A", "C"):
        ref.register_simple_action(name, lambda n: bt.NodeStatus.SUCCESS)
    tree = ref.create_tree_from_file(str(path))
    assert tree.tick_once() == bt.NodeStatus.SUCCESS
    ours = make_factory().create_tree_from_file(path)
    assert ours.tick_once() == S.FAILURE  # our C is a condition that fails


@pytest.mark.parametrize("tree", sorted((ROOT / "trees").glob("*.xml")), ids=lambda p: p.name)
def test_every_shipped_tree_carries_current_models(tree):
    """Groot2 shows a shipped tree's nodes from its embedded TreeNodesModel: a port added to a
    node (e.g. BatteryCanReach's dock) must reach the model, or Groot2 drops it on save."""
    assert cli.main(["--embed", str(tree), "--check"]) == 0, f"run: python -m bt_runtime models --embed trees/{tree.name}"
