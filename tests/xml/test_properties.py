"""Property-based robustness of the loader: random documents, random mutations of valid trees and
random bytes never make loading (or building, or ticking what was built) raise anything but a
``BehaviorTreeException`` subclass, and never hang."""

from __future__ import annotations

import contextlib
import os
import signal
import warnings
from xml.sax.saxutils import quoteattr

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_runtime import BehaviorTreeException, BehaviorTreeFactory, NodeStatus
from tests.paths import ROOT

TAGS = ["Sequence", "Fallback", "ReactiveSequence", "ReactiveFallback", "SequenceWithMemory", "Parallel",
        "ParallelAll", "IfThenElse", "WhileDoElse", "Switch2", "TryCatch", "Inverter", "Repeat",
        "RetryUntilSuccessful", "RunOnce", "Precondition", "LoopInt", "LoopString", "Timeout", "Delay",
        "SkipUnlessUpdated", "WaitValueUpdate", "KeepRunningUntilFailure", "ForceSuccess", "AlwaysSuccess",
        "AlwaysFailure", "Script", "ScriptCondition", "SetBlackboard", "UnsetBlackboard", "Sleep",
        "WasEntryUpdated", "SubTree", "Action", "Condition", "Control", "Decorator", "BehaviorTree", "root",
        "include", "TreeNodesModel", "input_port", "Leaf", "Unknown", "x"]
ATTRS = ["name", "ID", "num_cycles", "num_attempts", "msec", "delay_msec", "code", "if", "else", "queue",
         "value", "output_key", "key", "entry", "variable", "case_1", "case_2", "success_count",
         "failure_count", "max_failures", "then_skip", "catch_on_halt", "if_empty", "_autoremap", "_skipIf",
         "_while", "_successIf", "_failureIf", "_onHalted", "_post", "_onSuccess", "path", "main_tree_to_execute",
         "BTCPP_format", "default", "port", "bogus"]
VALUES = st.one_of(
    st.sampled_from(["", "1", "-1", "0", "3", "2.5", "abc", "true", "yes", "{x}", "{=}", "=", "{@x}", "{}",
                     "x := 1", "x += 1", "x == 1", "a &lt; b", "1 +", "'str'", "SUCCESS", "SKIPPED", "M", "L",
                     "1;2;3", "a;b", "Leaf", "Sequence", "4", "../x.xml", "nope.xml", "/etc/passwd"]),
    st.text(max_size=8),
)

LEAF_XML = '<root BTCPP_format="4"><BehaviorTree ID="L"><AlwaysSuccess/></BehaviorTree></root>'


ATTR_SETS = st.dictionaries(st.sampled_from(ATTRS), VALUES, max_size=4).map(
    lambda attrs: "".join(f" {k}={quoteattr(v)}" for k, v in attrs.items()))
ELEMENTS = st.recursive(
    st.builds(lambda tag, attrs: f"<{tag}{attrs}/>", st.sampled_from(TAGS), ATTR_SETS),
    lambda children: st.builds(lambda tag, attrs, kids: f"<{tag}{attrs}>{''.join(kids)}</{tag}>",
                               st.sampled_from(TAGS), ATTR_SETS, st.lists(children, min_size=1, max_size=3)),
    max_leaves=12)


@st.composite
def documents(draw) -> str:
    trees = draw(st.lists(st.tuples(st.sampled_from(["M", "L", "X", None]), ELEMENTS), min_size=1, max_size=3))
    body = "".join(f'<BehaviorTree{"" if i is None else f" ID={quoteattr(i)}"}>{e}</BehaviorTree>' for i, e in trees)
    extra = draw(st.sampled_from(["", '<include path="leaf.xml"/>', "<TreeNodesModel/>",
                                  '<TreeNodesModel><SubTree ID="L"><input_port name="p"/></SubTree></TreeNodesModel>']))
    main = draw(st.sampled_from(["", ' main_tree_to_execute="M"', ' main_tree_to_execute="Nope"']))
    fmt = draw(st.sampled_from([' BTCPP_format="4"', "", ' BTCPP_format="3"']))
    return f"<root{fmt}{main}>{extra}{body}</root>"


def _valid_sources() -> list[str]:
    sources = [(ROOT / "trees" / "demo.xml").read_text(encoding="utf-8")]
    from tests.differential.cases import CASES

    sources += [c.xml for c in CASES[::7]]
    return sources


SOURCES = _valid_sources()
NOISE = st.text(alphabet='<>/="\'&;{}@ \n\tabcSequenceID!-?[]', min_size=1, max_size=6)


@st.composite
def mutations(draw) -> str:
    text = draw(st.sampled_from(SOURCES))
    for _ in range(draw(st.integers(1, 4))):
        if not text:
            break
        i = draw(st.integers(0, len(text) - 1))
        j = draw(st.integers(i, min(len(text), i + 20)))
        kind = draw(st.sampled_from(["delete", "insert", "replace", "duplicate"]))
        if kind == "delete":
            text = text[:i] + text[j:]
        elif kind == "insert":
            text = text[:i] + draw(NOISE) + text[i:]
        elif kind == "replace":
            text = text[:i] + draw(NOISE) + text[j:]
        else:
            text = text[:j] + text[i:j] + text[j:]
    return text


@contextlib.contextmanager
def deadline(seconds: int):
    def fail(signum, frame):
        raise TimeoutError(f"the loader took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, fail)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module", autouse=True)
def in_scratch_folder(tmp_path_factory):
    """Random ``<include>`` paths resolve against the working directory: make it a scratch one."""
    folder = tmp_path_factory.mktemp("fuzz")
    (folder / "leaf.xml").write_text(LEAF_XML)
    old = os.getcwd()
    os.chdir(folder)
    yield
    os.chdir(old)


def check(text: str | bytes) -> None:
    factory = BehaviorTreeFactory()
    factory.register_simple_action("Leaf", lambda node: NodeStatus.SUCCESS)
    with deadline(10), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # v3 / missing-format warnings are expected here
        try:
            tree = factory.create_tree_from_text(text)
        except BehaviorTreeException:
            return
        try:
            for _ in range(3):
                tree.tick_exactly_once()
            tree.halt_tree()
        except BehaviorTreeException:
            pass


def SETTINGS(n: int) -> settings:  # noqa: N802
    return settings(max_examples=n, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much])


@SETTINGS(400)
@given(documents())
def test_random_documents(text):
    check(text)


@SETTINGS(400)
@given(mutations())
def test_mutated_valid_trees(text):
    check(text)


@SETTINGS(200)
@given(st.binary(max_size=300))
def test_random_bytes(data):
    try:
        check(data)
    except UnicodeDecodeError:
        pytest.fail("bytes that are not UTF-8 must give an XMLLoadError")


@SETTINGS(200)
@given(st.text(max_size=300))
def test_random_text(text):
    check(text)


@SETTINGS(200)
@given(st.text(alphabet="<>/=\"'& \nrootBehaviorTreeIDSequence!-[]?", max_size=200))
def test_markup_soup(text):
    check(text)
