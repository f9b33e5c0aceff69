"""XML syntax corner cases against BT.CPP 4.8.2 (tinyxml2): what loads, what fails, what the
attribute values become. The few deliberate differences are pinned separately below."""

from __future__ import annotations

import pytest

from .harness import Case, run_oracle, run_ours

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle

B = '<root BTCPP_format="4"><BehaviorTree ID="M">{}</BehaviorTree></root>'

AGREE = {
    "raw_lt_gt_in_attribute": B.format('<Script code="a := 1; b := a<2; c := a>0"/>'),
    "duplicate_attribute": B.format('<Script code="a:=1" code="b:=2"/>'),
    "text_between_elements": B.format('<Sequence>hello<Script code="a:=1"/>world</Sequence>'),
    "cdata_between_elements": B.format('<Sequence><![CDATA[ x < y ]]><Script code="a:=1"/></Sequence>'),
    "whitespace_before_declaration": '  <?xml version="1.0"?>' + B.format('<Script code="a:=1"/>'),
    "unquoted_attribute": B.format("<Script code=a/>"),
    "empty_name": B.format('<Script name="" code="a:=1"/>'),
    "nul_character_reference": B.format("<Script code=\"a:='&#0;'\"/>"),
    "bad_character_reference": B.format("<Script code=\"a:='&#xZZ;'\"/>"),
    "namespaced_tag": B.format('<x:Script xmlns:x="u" code="a:=1"/>'),
    "tab_in_name": B.format('<Script name="a\tb" code="a:=1"/>'),
    "newline_in_name": B.format('<Script name="a\nb" code="a:=1"/>'),
    "comments_around": B.format("<!-- c --><Script code=\"a:=1\"/><!-- d -->"),
    "trailing_text": B.format('<Script code="a:=1"/>') + "junk",
    "gt_in_text": B.format('<Sequence> a > b <Script code="a:=1"/></Sequence>'),
    "upper_case_root": '<Root BTCPP_format="4"><BehaviorTree ID="M"><Script code="a:=1"/></BehaviorTree></Root>',
    "lt_in_single_quoted_attribute": "<root BTCPP_format='4'><BehaviorTree ID='M'><Script code='a := 1 < 2'/>"
                                     "</BehaviorTree></root>",
    "crlf_in_attribute": B.format("<Script\r\n code=\"a:='x\r\ny'\"/>"),
    "spaces_around_equals": B.format('<Script code = "a:=1" />'),
    "latin1_declaration": '<?xml version="1.0" encoding="ISO-8859-1"?>' + B.format('<Script code="a:=1"/>'),
    "entities": B.format("<Script code=\"a:='&lt;&gt;&amp;&quot;&#65;&#x42;'\"/>"),
}


@pytest.mark.parametrize("name", list(AGREE))
def test_xml_syntax_same_as_btcpp(name):
    case = Case(name, AGREE[name], ticks=1, keys={"a": "string"})
    diff = run_ours(case).first_difference(run_oracle(case))
    assert diff is None, diff


def _ours(xml: str) -> Case:
    return run_ours(Case("x", xml, ticks=1, keys={"a": "string"}))


def test_processing_instruction_inside_a_tree_is_ignored():
    """tinyxml2 rejects it (XML_ERROR_PARSING_DECLARATION); we drop it like a comment."""
    assert _ours(B.format('<?pi x?><Script code="a:=1"/>')).statuses == ["SUCCESS"]


def test_second_top_level_element_is_refused():
    """tinyxml2 loads the first element and ignores the rest; we refuse the document."""
    trace = _ours(B.format('<Script code="a:=1"/>') + "<root/>")
    assert trace.error_at == "build" and "Extra content" in trace.error


def test_any_doctype_is_refused():
    trace = _ours('<!DOCTYPE root>' + B.format('<Script code="a:=1"/>'))
    assert trace.error_at == "build" and "DOCTYPE" in trace.error


def test_raw_ampersand_after_an_entity_is_kept():
    """tinyxml2 replaces it by a stale character ('< t x'); we keep it."""
    assert _ours(B.format("<Script code=\"a:='&lt; & x'\"/>")).values == [{"a": "< & x"}]
