"""Property tests: no input makes the script engine fail with anything but its own errors.

Random text and random token soups must either compile or raise ``ScriptError``; whatever
compiles must run on a small blackboard (typed, untyped, empty, odd-typed entries, a subtree
view) and either return a script value or raise a ``BehaviorTreeException``. Derandomized so a
failure reproduces. Token soups are short, because ``a += a`` doubles a string each time.
"""

from __future__ import annotations

import contextlib

from hypothesis import given, settings
from hypothesis import strategies as st

from bt_runtime.blackboard import Blackboard
from bt_runtime.errors import BehaviorTreeException
from bt_runtime.ports import EMPTY, INT
from bt_runtime.script import ScriptError, compile_script, to_bool
from bt_runtime.status import NodeStatus

ENUMS = {"RED": 1, "BLUE": 3}

TOKENS = [
    # names (present, empty, odd types, missing, root, private, enum)
    "a", "b", "s", "e", "lst", "flag", "st", "big", "RED", "@a", "@new", "_p", "missing",
    # literals
    "0", "1", "2", "3.5", "0x10", "1e308", "9007199254740993", "9223372036854775807",
    "9223372036854775808", "'a'", "''", "'5'", "'true'", "'RED'", "'nan'", "true", "false",
    # operators and punctuation
    "+", "-", "*", "/", "..", "&", "|", "^", "~", "!", "&&", "||", "==", "!=", "<", ">", "<=",
    ">=", ":=", "=", "+=", "-=", "*=", "/=", "?", ":", "(", ")", ";",
    # junk
    "#", '"', "é", "65.", "3foo", "0x", "'open",
]


def make_blackboard() -> Blackboard:
    root = Blackboard()
    root.set("a", 3)
    root.set("b", 2.5)
    root.set("s", "text")
    root.create_entry("e", INT)
    root.set("lst", [1, 2])
    root.set("flag", True)
    root.set("st", NodeStatus.RUNNING)
    root.set("big", 2**64 - 1)
    child = Blackboard(root)
    child.enable_auto_remapping(True)
    return child


def check_run(text: str) -> None:
    try:
        prog = compile_script(text)
    except ScriptError:
        return
    bb = make_blackboard()
    try:
        value = prog.run(bb, ENUMS)
    except BehaviorTreeException:
        return
    assert value is EMPTY or type(value) in (int, float, str, list), repr(value)  # list: "lst"
    with contextlib.suppress(BehaviorTreeException):
        to_bool(value)


@settings(derandomize=True, max_examples=400, deadline=None)
@given(st.text(max_size=40))
def test_random_text_only_raises_script_error(text):
    check_run(text)


@settings(derandomize=True, max_examples=400, deadline=None)
@given(st.text(alphabet="0123456789abexXE.'+-*/&|^~!<>=?:();@_ \n", max_size=30))
def test_random_script_alphabet(text):
    check_run(text)


@settings(derandomize=True, max_examples=1000, deadline=None)
@given(st.lists(st.sampled_from(TOKENS), min_size=1, max_size=14), st.booleans())
def test_random_token_soups(tokens, spaced):
    check_run((" " if spaced else "").join(tokens))


# Well-formed scripts from the grammar (every sub-expression parenthesised, so they always
# parse): compiling must succeed and running may only fail with BT errors.
ATOMS = ["a", "b", "s", "e", "lst", "flag", "st", "big", "RED", "@a", "_p", "missing", "0", "1",
         "2", "3.5", "0x10", "1e308", "9007199254740993", "'a'", "''", "'5'", "'RED'", "true",
         "false"]
BINARY = ["+", "-", "*", "/", "..", "&", "|", "^", "&&", "||", "==", "!=", "<", ">", "<=", ">="]
TARGETS = ["a", "b", "e", "new", "@a", "_p", "flag", "st"]
ASSIGN = [":=", "=", "+=", "-=", "*=", "/="]


def _extend(sub):
    return st.one_of(
        st.tuples(sub, st.sampled_from(BINARY), sub).map(lambda t: f"({t[0]}) {t[1]} ({t[2]})"),
        st.tuples(sub, st.sampled_from(["<", "=="]), sub, sub).map(
            lambda t: f"({t[0]}) {t[1]} ({t[2]}) < ({t[3]})"),
        st.tuples(st.sampled_from(["-", "!", "~"]), sub).map(lambda t: f"{t[0]}({t[1]})"),
        st.tuples(sub, sub, sub).map(lambda t: f"({t[0]}) ? ({t[1]}) : ({t[2]})"),
        st.tuples(st.sampled_from(TARGETS), st.sampled_from(ASSIGN), sub).map(
            lambda t: f"{t[0]} {t[1]} ({t[2]})"),
    )


EXPRS = st.recursive(st.sampled_from(ATOMS), _extend, max_leaves=8)


@settings(derandomize=True, max_examples=800, deadline=None)
@given(st.lists(EXPRS, min_size=1, max_size=3))
def test_well_formed_scripts_compile_and_run(statements):
    text = "; ".join(statements)
    prog = compile_script(text)
    try:
        value = prog.run(make_blackboard(), ENUMS)
    except BehaviorTreeException:
        return
    assert value is EMPTY or type(value) in (int, float, str, list)


def _outcome(compile_one, text: str):
    """What compiling and running ``text`` gives: the error message or the value and the
    blackboard's values afterwards."""
    try:
        prog = compile_one(text)
    except ScriptError as exc:
        return ("compile", str(exc))
    bb = make_blackboard()
    try:
        value = prog.run(bb, ENUMS)
    except BehaviorTreeException as exc:
        return ("run", type(exc).__name__, str(exc))
    values = {key: bb.get_entry(key).value for key in ("a", "b", "e", "new", "_p", "flag", "x1", "y")
              if bb.get_entry(key) is not None}
    return ("ok", repr(value), repr(values))


def _plain(text: str):
    """The compiler without the shared templates (a parse of this very text)."""
    from bt_runtime.script import compiler

    try:
        return compiler.Script(text, compiler._sequence([compiler.compile_node(s) for s in compiler.parse(text)]))
    except compiler.ParseError as exc:
        raise ScriptError(text, str(exc)) from None
    except RecursionError:
        raise ScriptError(text, "Parse error at position 0: expression nested too deeply") from None


SHARED = ["a := a + 1", "b := b + 1", "x1 := x1 * 2; y := x1 > 3", "new := 0x1f + 1e2", "a > 1 ? b : a",
          "3foo + a", "a..b", "65.x", "a := 'b'", "_p += 1", "flag && a", "true + a", "trueish := 1",
          "1.e5 + a", "a.b", "a := b.5", ".5x + a", "a@b", "1e5x + a", "0x1fz", "_a1 := 1.5e-3 * _a1", "a := @b",
          "x1:=x1+1", "a := 1.5.x"]


@settings(derandomize=True, max_examples=600, deadline=None)
@given(st.one_of(st.lists(EXPRS, min_size=1, max_size=3).map("; ".join),
                 st.lists(st.sampled_from(TOKENS + ["x1", "y", "1e5", "0x1f"]), min_size=1, max_size=10)
                 .map(" ".join), st.sampled_from(SHARED)))
def test_scripts_sharing_a_template_compile_as_their_own_text(text):
    """Scripts that differ only in variable names share one parse (the template): each still
    behaves exactly as its own text compiled alone, errors (with their positions) included."""
    assert _outcome(compile_script, text) == _outcome(_plain, text)


@settings(derandomize=True, max_examples=400, deadline=None)
@given(st.lists(EXPRS, min_size=1, max_size=3))
def test_a_script_is_no_deeper_than_it_has_tokens(statements):
    # parse() walks a tree for its depth only when the script has more tokens than MAX_DEPTH
    from bt_runtime.script.lexer import tokenize
    from bt_runtime.script.parser import ast_depth, parse

    text = "; ".join(statements)
    tokens = len(tokenize(text)) - 1  # (END)
    assert all(ast_depth(stmt) <= tokens for stmt in parse(text)), text
