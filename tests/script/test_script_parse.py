"""Script language front end: tokens, literals, precedence and parse errors (spec 6.1, 6.2).

Covers upstream ``script_parser_test.cpp`` (AnyTypes, AnyTypes_Failing, TokenizerEdgeCases,
OperatorAssociativity_Issue1029, ChainedComparisons, OperatorPrecedence, ValidateScript
Issue923) in our own words, plus the exact 4.10 error texts.
"""

from __future__ import annotations

import math

import pytest

from bt_runtime.blackboard import Blackboard
from bt_runtime.errors import LogicError
from bt_runtime.ports import EMPTY
from bt_runtime.script import ScriptError, compile_script
from bt_runtime.script.lexer import END, ERROR, IDENT, INT, REAL, STR, tokenize
from bt_runtime.script.parser import MAX_DEPTH, Assign, Binary, Compare, Literal, Name, Ternary, Unary, parse


def run(text: str, bb: Blackboard | None = None, enums: dict | None = None):
    return compile_script(text).run(bb if bb is not None else Blackboard(), enums or {})


def parse_error(text: str) -> str:
    with pytest.raises(ScriptError) as info:
        compile_script(text)
    return info.value.message


def kinds(text: str) -> list[tuple[str, str]]:
    return [(t.kind, t.text) for t in tokenize(text)[:-1]]


# --- tokens ---------------------------------------------------------------------------------

def test_two_character_operators_win():
    assert [k for k, _ in kinds("a..b&&c||d==e!=f<=g>=h:=i+=j-=k*=l/=m")][1::2] == [
        "..", "&&", "||", "==", "!=", "<=", ">=", ":=", "+=", "-=", "*=", "/="]
    assert [k for k, _ in kinds("+ - * / & | ^ ~ ! < > = ? : ( ) ;")] == list("+-*/&|^~!<>=?:();")


def test_token_positions_and_end():
    toks = tokenize("  ab := 'x y' ")
    assert [(t.kind, t.text, t.pos) for t in toks] == [
        (IDENT, "ab", 2), (":=", ":=", 5), (STR, "x y", 8), (END, "", 14)]


def test_number_tokens():
    assert kinds("65..66") == [(INT, "65"), ("..", ".."), (INT, "66")]
    assert kinds("1.5e3 2E-2 7e+1 0x1F") == [(REAL, "1.5e3"), (REAL, "2E-2"), (REAL, "7e+1"), (INT, "0x1F")]
    # malformed numbers swallow what follows into one error token
    for bad in ("65.", "65.x", "65.e5", "0x", "0xG", "0x1.5", "0x1g", "3e", "3e+", "3foo", "65.43foo",
                "1_", "1a2"):
        assert kinds(bad) == [(ERROR, bad)], bad
    assert kinds("2@x") == [(ERROR, "2"), (IDENT, "@x")]  # '@' starts the error but is no ident char


def test_identifiers_are_ascii_with_optional_leading_at():
    assert kinds("@root_1 _x true false trueish") == [
        (IDENT, "@root_1"), (IDENT, "_x"), ("BOOL", "true"), ("BOOL", "false"), (IDENT, "trueish")]
    assert kinds("a@b") == [(IDENT, "a"), (IDENT, "@b")]
    assert kinds("é") == [(ERROR, "é")]


def test_strings_single_quotes_only_no_escapes():
    assert kinds(r"'a\nb' ''") == [(STR, r"a\nb"), (STR, "")]
    assert kinds("'open") == [(ERROR, "'open")]
    assert kinds('"dq"')[0] == (ERROR, '"')  # 4.8.2 also accepted "..." strings


# --- literals -------------------------------------------------------------------------------

@pytest.mark.parametrize("text, value", [
    ("628", 628), ("0x100", 256), ("0X100", 256), ("0xfF", 255), ("007", 7),
    ("9223372036854775807", 2**63 - 1),
    ("9223372036854775808", 0),            # int64 overflow parses as 0
    ("0x10000000000000000", 0),
])
def test_integer_literals_are_int64(text, value):
    result = run(text)
    assert type(result) is int and result == value


@pytest.mark.parametrize("text, value", [
    ("3.14", 3.14), ("3.14e2", 314.0), ("3.14e-2", 0.0314), ("3e2", 300.0), ("3e-2", 0.03),
    ("1E3", 1000.0), ("12.5E-1", 1.25), ("1e-320", 1e-320),
])
def test_real_literals_are_double(text, value):
    result = run(text)
    assert type(result) is float and result == value


def test_negative_literals_are_unary_minus_on_a_double():
    assert run("-628") == -628.0 and type(run("-628")) is float
    assert run("-3.14") == -3.14


def test_string_and_boolean_literals():
    assert run("'hello world '") == "hello world "
    assert run("''") == ""
    assert run("true") == 1.0 and type(run("true")) is float   # 4.10: double (4.8.2: int)
    assert run("false") == 0.0 and type(run("false")) is float
    assert run(" 'true' ") == "true"


def test_real_out_of_double_range_is_a_parse_error():
    assert parse_error("1e999") == "Can't convert string [1e999] to double"
    assert parse_error("x := 1e-400") == "Can't convert string [1e-400] to double"


@pytest.mark.parametrize("text, bad, pos", [
    ("0X100g", "0X100g", 0), ("0X100.", "0X100.", 0), ("3foo", "3foo", 0), ("65.", "65.", 0),
    ("65.43foo", "65.43foo", 0), ("x := 3foo", "3foo", 5), ("0x", "0x", 0), ("0xG", "0xG", 0),
    ("3e", "3e", 0), ("3e+", "3e+", 0), ("'hello", "'hello", 0), ("a # b", "#", 2),
    ("a := \"s\"", '"', 5),
])
def test_invalid_tokens(text, bad, pos):
    assert parse_error(text) == f"Invalid token '{bad}' at position {pos}"


def test_error_positions_are_utf8_byte_offsets():
    assert parse_error("a := 'é'; é") == "Invalid token 'é' at position 11"


def test_foo_parses_and_fails_only_when_run():
    prog = compile_script("foo")
    with pytest.raises(Exception, match="Variable not found: foo"):
        prog.run(Blackboard(), {})


# --- parse errors ---------------------------------------------------------------------------

@pytest.mark.parametrize("text", ["", "   ", "\t\n\r"])
def test_empty_script(text):
    assert parse_error(text) == "Empty Script"


@pytest.mark.parametrize("text, message", [
    ("(1 + 2", "Parse error at position 6: expected ')' (got '')"),
    ("(1 + 2 3", "Parse error at position 7: expected ')' (got '3')"),
    ("(1 'x'", "Parse error at position 3: expected ')' (got 'x')"),
    ("1 ? 2", "Parse error at position 5: expected ':' in ternary expression (got '')"),
    ("1 ? 2 3", "Parse error at position 6: expected ':' in ternary expression (got '3')"),
    ("1 +", "Expected operand at position 3 (got '')"),
    ("* 2", "Expected operand at position 0 (got '*')"),
    (";", "Expected operand at position 0 (got ';')"),
    ("a := 1 )", "Expected operand at position 7 (got ')')"),
    ("a ? b : c := 1", "Expected operand at position 10 (got ':=')"),
    ("+5", "Expected operand at position 0 (got '+')"),
])
def test_parse_error_messages(text, message):
    assert parse_error(text) == message


def test_script_error_is_a_logic_error_with_both_texts():
    with pytest.raises(LogicError) as info:
        compile_script("(1")
    err = info.value
    assert isinstance(err, ScriptError)
    assert str(err) == "Error in the script \"(1\"\nParse error at position 2: expected ')' (got '')"
    assert err.script == "(1" and err.message.startswith("Parse error")


def test_large_invalid_script_does_not_crash():
    # upstream Issue923: a long garbage script only has to fail cleanly
    chunk = ("+6e66>6666.6+66\r6>6;6e62=6+6e66>66666'; en';o';o'; en'; "
             "\x7fn\x7fr;6.6+66.H>6+6\x806\x1e;@e66")
    with pytest.raises(ScriptError):
        compile_script(chunk * 10)


def test_nesting_limit():
    ok = "(" * 50 + "1" + ")" * 50
    assert run(ok) == 1
    assert run("+".join(["1"] * 150)) == 150.0
    assert run("+".join(["1"] * MAX_DEPTH)) == MAX_DEPTH  # a chain as deep as allowed
    assert "nested too deeply" in parse_error("+".join(["1"] * (MAX_DEPTH + 1)))  # one deeper
    for deep in ("(" * (MAX_DEPTH + 5) + "1" + ")" * (MAX_DEPTH + 5), "-" * 1000 + "1",
                 "+".join(["1"] * (MAX_DEPTH + 5))):
        assert "nested too deeply" in parse_error(deep)


# --- grammar --------------------------------------------------------------------------------

def test_prefix_binds_tighter_than_any_binary_operator():
    assert parse("-a*b") == [Binary("*", Unary("-", Name("a")), Name("b"))]
    assert parse("!a == b") == [Compare(["=="], [Unary("!", Name("a")), Name("b")])]
    assert parse("~-a") == [Unary("~", Unary("-", Name("a")))]


def test_precedence_levels():
    # || < && < comparison < | ^ < & < + - .. < * /
    arith = Binary("+", Name("f"), Binary("*", Name("g"), Name("h")))
    bits = Binary("|", Name("d"), Binary("&", Name("e"), arith))
    comparison = Compare(["=="], [Name("c"), bits])
    assert parse("a || b && c == d | e & f + g * h") == [
        Binary("||", Name("a"), Binary("&&", Name("b"), comparison))]


def test_binary_operators_are_left_associative():
    assert parse("a - b + c") == [Binary("+", Binary("-", Name("a"), Name("b")), Name("c"))]
    assert parse("a .. b + c") == [Binary("+", Binary("..", Name("a"), Name("b")), Name("c"))]
    assert parse("a | b ^ c") == [Binary("^", Binary("|", Name("a"), Name("b")), Name("c"))]


def test_comparisons_chain_into_one_node():
    assert parse("a < b <= c == d") == [Compare(["<", "<=", "=="], [Name("a"), Name("b"), Name("c"), Name("d")])]


def test_assignment_rhs_is_a_full_expression_and_nests_right():
    assert parse("a := b := 1 + 2") == [
        Assign(":=", Name("a"), Assign(":=", Name("b"), Binary("+", Literal(1), Literal(2))))]
    assert parse("a + b := 3") == [Assign(":=", Binary("+", Name("a"), Name("b")), Literal(3))]


def test_ternary_shapes():
    assert parse("a ? b : c ? d : e") == [
        Ternary(Name("a"), Name("b"), Ternary(Name("c"), Name("d"), Name("e")))]
    assert parse("a || b ? x := 1 : y + 2") == [
        Ternary(Binary("||", Name("a"), Name("b")), Assign(":=", Name("x"), Literal(1)),
                Binary("+", Name("y"), Literal(2)))]


def test_statements_and_semicolons():
    assert len(parse("a:=1;;; b:=2;;")) == 2
    assert len(parse("a:=1 b:=2")) == 2          # semicolons are optional (4.10)
    assert len(parse("A:=5;\nB:=6")) == 2
    assert parse("'it''s'") == [Literal("it"), Literal("s")]


@pytest.mark.parametrize("text, expected", [
    ("5 - 2 + 1", 4.0), ("10 - 3 - 2", 5.0), ("2 + 3 - 1", 4.0), ("12 / 3 / 2", 2.0),
    ("12 / 3 * 2", 8.0), ("2 + 3 * 4 - 1", 13.0), ("6 | 3 & 5", 7.0), ("true && (6 | 0)", 1.0),
    ("false || true && true", 1.0), ("false && true || true", 1.0), ("(2 + 3) * 4", 20.0),
    ("2 * (3 + 4)", 14.0), ("1 < 2 < 3", 1.0), ("3 > 2 > 1", 1.0), ("1 < 2 > 3", 0.0),
    ("5 == 5 == 5", 1.0), ("5 == 5 != 3", 1.0), ("1 <= 2 <= 3", 1.0), ("3 >= 2 >= 1", 1.0),
    ("1 + 2 * 3 == 7", 1.0), ("!true", 0.0), ("!false", 1.0), ("!!true", 1.0),
    ("-(3 + 2)", -5.0), ("10 + -3", 7.0), ("3 - -2", 5.0), ("- - 5", 5.0), ("~~5", 5.0),
    ("true ? 1 : 2", 1), ("false ? 1 : 2", 2), ("true ? 2 + 3 : 10", 5.0),
    ("false ? 10 : 2 + 3", 5.0), ("3 > 2 ? 'yes' : 'no'", "yes"), ("3 < 2 ? 'yes' : 'no'", "no"),
    ("0 ? 1 : 0 ? 2 : 3", 3), ("1 ? 2 : 0 ? 3 : 4", 2),
])
def test_evaluation_follows_the_grammar(text, expected):
    result = run(text)
    assert result == expected and type(result) is type(expected)


def test_complement_of_zero():
    assert run("~0") == -1.0


def test_concat_of_two_numbers_inside_a_chain():
    assert run("65..66") is EMPTY
    with pytest.raises(Exception, match=r"The left operand of the operator \[\+\] is not initialized"):
        run("1 .. 2 + 3")


def test_nan_literal_free_results():
    assert math.isnan(run("0/0"))
