"""Bad input: every load problem is an XMLLoadError naming file, line and element; a node
raising during a tick is a NodeExecutionError with the node's full path; dangerous XML is
refused; tinyxml2's leniency (raw ``<``/``&``, literal newlines in attributes) is kept."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_runtime import (
    BehaviorTreeException,
    BehaviorTreeFactory,
    NodeExecutionError,
    NodeStatus,
    XMLLoadError,
)
from bt_runtime.xml.reader import MAX_XML_BYTES
from tests.engine.helpers import doc


@pytest.fixture
def factory():
    f = BehaviorTreeFactory()
    f.register_simple_action("A", lambda n: NodeStatus.SUCCESS)
    return f


def _sub(body: str) -> str:
    return f'<BehaviorTree ID="S">{body}</BehaviorTree>'


LOAD_ERRORS = [
    ("not_root", '<tree><BehaviorTree ID="M"><A/></BehaviorTree></tree>', 1, "tree",
     "The XML must have a root node called <root>"),
    ("unknown_node", doc("<Sequence>\n<Sequense/></Sequence>"), 2, "Sequense",
     "Node not recognized: Sequense (did you mean: Sequence"),
    ("id_on_compact", doc('<Sequence ID="x"><A/></Sequence>'), 1, "Sequence", "Attribute [ID] is not allowed in <Sequence>"),
    ("explicit_without_id", doc('<Action name="x"/>'), 1, "Action", "The tag <Action> must have the attribute [ID]"),
    ("unknown_port", doc('<Sleep mse="1"/>'), 1, "Sleep",
     "a port with name [mse] is found in the XML (<Sleep>, line 1) but not in the providedPorts() of its "
     "registered node type. (did you mean: msec?)"),
    ("missing_code_port", doc("<Script/>"), 1, "Script", "Missing port [code] in Script"),
    ("missing_if_port", doc("<Precondition><A/></Precondition>"), 1, "Precondition", "Missing parameter [if] in Precondition"),
    ("missing_entry_port", doc("<WaitValueUpdate><A/></WaitValueUpdate>"), 1, "WaitValueUpdate", "Missing port 'entry'"),
    ("control_without_children", doc("<Sequence/>"), 1, "Sequence", "The node 'Sequence' must have 1 or more children"),
    ("decorator_two_children", doc("<Inverter><A/><A/></Inverter>"), 1, "Inverter",
     "The node 'Inverter' must have exactly 1 child"),
    ("decorator_no_child", doc("<Repeat num_cycles=\"2\"/>"), 1, "Repeat", "must have exactly 1 child"),
    ("leaf_with_child", doc("<A><A/></A>"), 1, "A", "The node 'A' must not have any child"),
    ("subtree_with_child", doc('<SubTree ID="S"><A/></SubTree>', _sub("<A/>")), 1, "SubTree",
     "<SubTree> with ID 'S' should not have any child"),
    ("tree_two_roots", '<root BTCPP_format="4"><BehaviorTree ID="M"><A/><A/></BehaviorTree></root>', 1,
     "BehaviorTree", "The tag <BehaviorTree> with ID 'M' must have exactly 1 child"),
    ("tree_without_id", '<root BTCPP_format="4"><BehaviorTree><A/></BehaviorTree><BehaviorTree ID="x"><A/>'
                        '</BehaviorTree></root>', 1, "BehaviorTree", "must have the attribute [ID]"),
    ("tree_id_is_node", '<root BTCPP_format="4"><BehaviorTree ID="Sequence"><A/></BehaviorTree></root>', 1,
     "BehaviorTree", "must not use the name of a registered Node"),
    ("subtree_id_is_node", doc('<SubTree ID="Sequence"/>'), 1, "SubTree", "must not use the name of a registered Node"),
    ("unknown_subtree", doc('<Sequence>\n<SubTree ID="Nope"/></Sequence>'), 2, "SubTree",
     "SubTree ID 'Nope' is not a registered BehaviorTree"),
    ("recursive_subtree", doc('<SubTree ID="Main"/>'), 1, "SubTree",
     "Recursive behavior tree cycle detected: tree 'Main' references itself (directly or indirectly)"),
    ("indirect_recursion", doc('<SubTree ID="X"/>', '<BehaviorTree ID="X">\n<SubTree ID="Main"/></BehaviorTree>'), 2,
     "SubTree", "Recursive behavior tree cycle detected: tree 'Main'"),
    ("duplicate_subtree_path", doc('<Sequence><SubTree ID="S" name="x"/>\n<SubTree ID="S" name="x"/></Sequence>',
                                   _sub("<A/>")), 2, "SubTree", "Duplicate SubTree path detected: 'x'"),
    ("bad_precondition_script", doc('<Sequence>\n<A _skipIf="a ="/></Sequence>'), 2, "A",
     '_skipIf: Error in the script "a ="'),
    ("bad_postcondition_script", doc('<A _onSuccess="x := (1"/>'), 1, "A", "_onSuccess: Error in the script"),
    ("bad_script_node", doc('<Script code="x := := 1"/>'), 1, "Script", "x := := 1"),
    ("bad_typed_literal", doc('<Sleep msec="soon"/>'), 1, "Sleep",
     'The port with name "msec" and value "soon" can not be converted to unsigned int'),
    ("bad_bool_literal", doc('<RunOnce then_skip="yes"><A/></RunOnce>'), 1, "RunOnce",
     'The port with name "then_skip" and value "yes" can not be converted to bool'),
    ("two_models", doc("<A/>", "<TreeNodesModel/>\n<TreeNodesModel/>"), 2, "TreeNodesModel",
     "Only a single node <TreeNodesModel> is supported"),
    ("subtree_model_without_id", doc("<A/>", "<TreeNodesModel><SubTree/></TreeNodesModel>"), 1, "SubTree",
     "Missing attribute 'ID' in SubTree element within TreeNodesModel"),
    ("mandatory_subtree_port", doc('<SubTree ID="S"/>', _sub("<A/>") + '<TreeNodesModel><SubTree ID="S">'
                                   '<input_port name="p"/></SubTree></TreeNodesModel>'), 1, "SubTree",
     'In the <TreeNodesModel> the <Subtree ID="S"> is defining a mandatory port called [p], but you are not remapping it'),
    ("bad_autoremap", doc('<SubTree ID="S" _autoremap="maybe"/>', _sub("<A/>")), 1, "SubTree", "_autoremap"),
    ("include_without_path", doc("<A/>", "<include/>"), 1, "include", "Invalid <include> tag: missing 'path' attribute"),
    ("reserved_tree_id", '<root BTCPP_format="4"><BehaviorTree ID="Root"><A/></BehaviorTree></root>', 1,
     "BehaviorTree", "'Root' is reserved"),
    ("forbidden_char_tree_id", '<root BTCPP_format="4"><BehaviorTree ID="a/b"><A/></BehaviorTree></root>', 1,
     "BehaviorTree", "forbidden character '/'"),
    ("reactive_explicit_child", doc('<ReactiveSequence>\n<Action ID="A"/></ReactiveSequence>'), 2, "Action",
     "Unknown node type: Action"),
    ("type_mismatch", doc('<Sequence><Repeat num_cycles="{n}"><A/></Repeat>\n<Sleep msec="{n}"/></Sequence>'), 2,
     "Sleep", "initially created with type [int] and, later type [unsigned int]"),
]


@pytest.mark.parametrize("name, xml, line, element, message", LOAD_ERRORS, ids=[c[0] for c in LOAD_ERRORS])
def test_load_errors_name_file_line_and_element(factory, tmp_path, name, xml, line, element, message):
    path = tmp_path / f"{name}.xml"
    path.write_text(xml, encoding="utf-8")
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_file(path)
    err = info.value
    assert (err.file, err.line, err.element) == (str(path), line, element)
    assert message in err.message
    assert str(err).startswith(f"{path}:{line}: <{element}>: ")
    assert err.to_dict() == {"file": str(path), "line": line, "element": element, "message": err.message}


@pytest.mark.parametrize("name, xml, line, element, message", LOAD_ERRORS[:6], ids=[c[0] for c in LOAD_ERRORS[:6]])
def test_load_errors_from_text(factory, name, xml, line, element, message):
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_text(xml)
    assert (info.value.file, info.value.line, info.value.element) == (None, line, element)
    assert str(info.value).startswith(f"line {line}: <{element}>: ")


def test_malformed_xml(factory, tmp_path):
    path = tmp_path / "broken.xml"
    path.write_text('<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n</BehaviorTree>\n</root>')
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_file(path)
    assert info.value.file == str(path) and info.value.line == 4
    assert info.value.message.startswith("Error parsing the XML: ")


@pytest.mark.parametrize("text", ["", "   \n", "<root", "<root></wrong>", "not xml at all", "<root/><root/>",
                                  "\x00\x01", '<root BTCPP_format="4"><BehaviorTree ID="M"><A/></BehaviorTree>'])
def test_garbage_is_an_xml_load_error(factory, text):
    with pytest.raises(XMLLoadError):
        factory.create_tree_from_text(text)


def test_unreadable_files(factory, tmp_path):
    with pytest.raises(XMLLoadError, match="Cannot read the file"):
        factory.create_tree_from_file(tmp_path / "missing.xml")
    bad = tmp_path / "latin1.xml"
    bad.write_bytes(b'<root BTCPP_format="4"><BehaviorTree ID="M"><A name="\xe9"/></BehaviorTree></root>')
    with pytest.raises(XMLLoadError, match="not valid UTF-8"):
        factory.create_tree_from_file(bad)
    with pytest.raises(XMLLoadError, match="not valid UTF-8"):
        factory.create_tree_from_text(bad.read_bytes())


def test_line_numbers_refer_to_the_original_file(factory, tmp_path):
    """Attributes with raw '<', '&' and newlines are rewritten before parsing; lines still match."""
    path = tmp_path / "lines.xml"
    path.write_text('<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n'
                    '<Script code="a := 1;\nb := 2;\nc := a &lt; 2 &amp;&amp; b > 1"/>\n'
                    '<ScriptCondition code="a<2 && b"/>\n\n<Nope/>\n</Sequence>\n</BehaviorTree>\n</root>\n')
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_file(path)
    assert (info.value.line, info.value.element) == (9, "Nope")


def test_line_of_a_multi_line_start_tag_is_its_first_line(factory, tmp_path):
    path = tmp_path / "multi.xml"
    path.write_text('<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n<Sleep\n   msec="1"\n'
                    '   bogus="2"/>\n</Sequence>\n</BehaviorTree>\n</root>\n')
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_file(path)
    assert (info.value.line, info.value.element) == (4, "Sleep")


def test_node_exception_has_full_path(factory):
    def explode(node):
        raise KeyError("no such sensor")

    factory.register_simple_action("Explode", explode)
    xml = doc('<Sequence><SubTree ID="S" name="outer"/></Sequence>',
              '<BehaviorTree ID="S"><Sequence><A/><Explode name="boom"/></Sequence></BehaviorTree>')
    tree = factory.create_tree_from_text(xml)
    with pytest.raises(NodeExecutionError) as info:
        tree.tick_once()
    err = info.value
    assert (err.node_path, err.registration_id) == ("outer/boom", "Explode")
    assert isinstance(err.original, KeyError)
    assert str(err) == "Exception in node 'outer/boom' [Explode]: 'no such sensor'"
    assert isinstance(err, BehaviorTreeException)


def test_script_error_at_tick_is_wrapped_once(factory):
    tree = factory.create_tree_from_text(doc('<Sequence><Inverter><Script name="s" code="y = 1"/></Inverter></Sequence>'))
    with pytest.raises(NodeExecutionError) as info:
        tree.tick_once()
    assert info.value.node_path == "s"
    assert not isinstance(info.value.original, NodeExecutionError)
    assert "The blackboard entry [y] doesn't exist, yet." in str(info.value)


def test_missing_required_port_is_a_tick_error(factory):
    tree = factory.create_tree_from_text(doc("<Sleep/>"))
    with pytest.raises(NodeExecutionError, match=r"Missing parameter \[msec\] in SleepNode"):
        tree.tick_once()


def test_explicit_syntax_and_category_not_checked(factory):
    xml = doc('<Sequence><Condition ID="A" name="x"/><Action ID="AlwaysSuccess"/><Control ID="Sequence">'
              '<A/></Control><Decorator ID="Inverter"><AlwaysFailure/></Decorator></Sequence>')
    assert factory.create_tree_from_text(xml).tick_once() is NodeStatus.SUCCESS


def test_nesting_depth(factory):
    ok = doc("<Inverter>" * 200 + "<A/>" + "</Inverter>" * 200)
    assert factory.create_tree_from_text(ok).tick_once() is NodeStatus.SUCCESS  # 200 inversions
    with pytest.raises(XMLLoadError, match="depth"):
        factory.create_tree_from_text(doc("<Inverter>" * 300 + "<A/>" + "</Inverter>" * 300))


# -- dangerous input -----------------------------------------------------------------------------------

BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol9 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<root BTCPP_format="4"><BehaviorTree ID="M"><Script code="x := '&lol9;'"/></BehaviorTree></root>"""

EXTERNAL_ENTITY = """<?xml version="1.0"?>
<!DOCTYPE root [<!ENTITY secret SYSTEM "file:///etc/passwd">]>
<root BTCPP_format="4"><BehaviorTree ID="M"><Script code="x := '&secret;'"/></BehaviorTree></root>"""


@pytest.mark.parametrize("text", [BILLION_LAUGHS, EXTERNAL_ENTITY,
                                  '<!DOCTYPE root SYSTEM "http://example.com/x.dtd"><root/>',
                                  '<root BTCPP_format="4"><!ENTITY x "y"></root>'])
def test_doctype_and_entities_refused(factory, text, tmp_path):
    with pytest.raises(XMLLoadError, match="DOCTYPE and ENTITY declarations are not allowed"):
        factory.create_tree_from_text(text)
    path = tmp_path / "evil.xml"
    path.write_text(text)
    with pytest.raises(XMLLoadError) as info:
        factory.create_tree_from_file(path)
    assert info.value.file == str(path) and info.value.line is not None


def test_huge_file_refused_without_reading(factory, tmp_path):
    path = tmp_path / "huge.xml"
    with open(path, "wb") as fh:
        fh.write(b'<root BTCPP_format="4"><!-- ')
        fh.seek(MAX_XML_BYTES + 10)
        fh.write(b" --></root>")
    with pytest.raises(XMLLoadError, match="too large"):
        factory.create_tree_from_file(path)
    with pytest.raises(XMLLoadError, match="too large"):
        factory.create_tree_from_text(" " * (MAX_XML_BYTES + 1))


def test_unknown_entity_reference(factory):
    tree = factory.create_tree_from_text(doc('<Script code="x := \'a &unknown; b\'"/>'))
    tree.tick_once()
    assert tree.root_blackboard.get("x") == "a &unknown; b"  # left as text, like tinyxml2


# -- tinyxml2 leniency ----------------------------------------------------------------------------------

def test_raw_lt_and_amp_in_attributes(factory):
    xml = doc('<Sequence><Script code="a := 1; b := 1"/><ScriptCondition code="a<2 && b == 1"/>'
              '<Script code="msg := \'x<y & z\'" _skipIf="a>5 && b<0"/></Sequence>')
    tree = factory.create_tree_from_text(xml)
    assert tree.tick_once() is NodeStatus.SUCCESS
    assert tree.root_blackboard.get("msg") == "x<y & z"


def test_entities_decoded(factory):
    tree = factory.create_tree_from_text(doc('<Script code="m := \'&lt;&gt;&amp;&quot;&#65;&#x42;\' + &apos;!&apos;"/>'))
    tree.tick_once()
    assert tree.root_blackboard.get("m") == '<>&"AB!'


def test_literal_newlines_and_tabs_kept(factory):
    tree = factory.create_tree_from_text(doc("<Script code=\"m := 'x\ny\tz'\r\nn := 'a\r\nb\rc'\"/>"))
    tree.tick_once()
    assert tree.root_blackboard.get("m") == "x\ny\tz"
    assert tree.root_blackboard.get("n") == "a\nb\nc"


def test_single_quoted_attributes_and_comments(factory):
    xml = ("<root BTCPP_format='4'><!-- a comment --><BehaviorTree ID='M'><Sequence><!-- <Nope/> -->"
           "<Script code='x := \"no\" ; y := 1 &lt; 2'/></Sequence></BehaviorTree></root>")
    with pytest.raises(XMLLoadError):  # "..." strings are not 4.10 script syntax
        factory.create_tree_from_text(xml)
    xml = xml.replace('x := \"no\" ; ', "")
    tree = factory.create_tree_from_text(xml)
    assert tree.tick_once() is NodeStatus.SUCCESS


def test_xml_declaration_and_bom(factory, tmp_path):
    path = Path(tmp_path / "bom.xml")
    path.write_bytes("\ufeff<?xml version='1.0' encoding='UTF-8'?>\n".encode() + doc("<A/>").encode())
    assert factory.create_tree_from_file(path).tick_once() is NodeStatus.SUCCESS
