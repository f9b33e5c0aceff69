"""Pratt parser for the BT.CPP 4.10 script language (spec 6.2): tokens -> AST.

Binding powers (higher binds tighter): assignment 2, ternary 4, ``||`` 6, ``&&`` 8,
comparisons 10 (one chained node), ``| ^`` 12, ``&`` 14, ``+ - ..`` 16, ``* /`` 18,
prefix ``- ~ !`` 20. Assignment and ternary end the operator loop once parsed, exactly like
BT.CPP, so ``a ? b : c := 1`` leaves ``:= 1`` to fail as the next statement.

Parse errors raise ``ParseError`` with BT.CPP's message text; ``compile_script`` turns it into
a ``ScriptError``. A bad assignment target (``3 = 2``) is *not* a parse error in BT.CPP: it
fails when evaluated, so the AST keeps it.
"""

from __future__ import annotations

from .lexer import BOOL, END, ERROR, IDENT, INT, REAL, STR, Token, byte_offset, tokenize
from .values import from_chars_double

ASSIGN_BP = 2
TERNARY_BP = 4
COMPARE_BP = 10
PREFIX_BP = 20

LEFT_BP = {
    ":=": ASSIGN_BP, "=": ASSIGN_BP, "+=": ASSIGN_BP, "-=": ASSIGN_BP, "*=": ASSIGN_BP, "/=": ASSIGN_BP,
    "?": TERNARY_BP,
    "||": 6,
    "&&": 8,
    "==": COMPARE_BP, "!=": COMPARE_BP, "<": COMPARE_BP, ">": COMPARE_BP, "<=": COMPARE_BP,
    ">=": COMPARE_BP,
    "|": 12, "^": 12,
    "&": 14,
    "+": 16, "-": 16, "..": 16,
    "*": 18, "/": 18,
}
ASSIGN_OPS = frozenset({":=", "=", "+=", "-=", "*=", "/="})
COMPARE_OPS = frozenset({"==", "!=", "<", ">", "<=", ">="})
PREFIX_OPS = frozenset({"-", "~", "!"})

INT64_MAX = 2**63 - 1
# Python recurses once per AST level when compiling and evaluating, so nesting is bounded (BT.CPP
# has no limit but would overflow its own stack far deeper). Real scripts stay far below it.
MAX_DEPTH = 200


class ParseError(Exception):
    """A syntax error, with BT.CPP's message."""


# --- AST ------------------------------------------------------------------------------------

class Node:
    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and all(
            getattr(self, s) == getattr(other, s) for s in self.__slots__)

    def __repr__(self) -> str:
        args = ", ".join(repr(getattr(self, s)) for s in self.__slots__)
        return f"{type(self).__name__}({args})"


class Literal(Node):
    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value


class Name(Node):
    __slots__ = ("name",)

    def __init__(self, name: str):
        self.name = name


class Unary(Node):
    __slots__ = ("op", "operand")

    def __init__(self, op: str, operand: Node):
        self.op = op
        self.operand = operand


class Binary(Node):
    __slots__ = ("op", "left", "right")

    def __init__(self, op: str, left: Node, right: Node):
        self.op = op
        self.left = left
        self.right = right


class Compare(Node):
    """``operands[0] ops[0] operands[1] ops[1] ...``; evaluation stops at the first false link."""

    __slots__ = ("ops", "operands")

    def __init__(self, ops: list[str], operands: list[Node]):
        self.ops = ops
        self.operands = operands


class Ternary(Node):
    __slots__ = ("cond", "then", "other")

    def __init__(self, cond: Node, then: Node, other: Node):
        self.cond = cond
        self.then = then
        self.other = other


class Assign(Node):
    __slots__ = ("op", "target", "value")

    def __init__(self, op: str, target: Node, value: Node):
        self.op = op
        self.target = target
        self.value = value


# --- literals -------------------------------------------------------------------------------

def int_literal(text: str) -> int:
    """Decimal or 0x-hex int64; a value that overflows int64 is 0 (BT.CPP ignores the failure)."""
    value = int(text[2:], 16) if len(text) > 2 and text[1] in "xX" else int(text, 10)
    return value if value <= INT64_MAX else 0


def real_literal(text: str) -> float:
    """``digits.digits[e..]`` or ``digits e digits``; out of double range is a parse error."""
    value = from_chars_double(text)
    if value is None:
        raise ParseError(f"Can't convert string [{text}] to double")
    return value


# --- parser ---------------------------------------------------------------------------------

class _Parser:
    def __init__(self, src: str):
        self.src = src
        self.tokens = tokenize(src)
        self.i = 0
        self.depth = 0

    def _pos(self, tok: Token) -> int:
        return byte_offset(self.src, tok.pos)

    def peek(self) -> Token:
        return self.tokens[self.i]

    def advance(self) -> Token:
        tok = self.tokens[self.i]
        if tok.kind != END:
            self.i += 1
        return tok

    def expect(self, kind: str, msg: str) -> Token:
        tok = self.peek()
        if tok.kind != kind:
            raise ParseError(f"Parse error at position {self._pos(tok)}: {msg} (got '{tok.text}')")
        return self.advance()

    def parse_all(self) -> list[Node]:
        stmts = []
        while self.peek().kind != END:
            stmts.append(self.parse_expr(0))
            while self.peek().kind == ";":
                self.advance()
        return stmts

    def parse_prefix(self) -> Node:
        tok = self.peek()
        kind = tok.kind
        if kind in PREFIX_OPS:
            self.advance()
            return Unary(kind, self.parse_expr(PREFIX_BP))
        if kind == "(":
            self.advance()
            expr = self.parse_expr(0)
            self.expect(")", "expected ')'")
            return expr
        if kind == BOOL:
            self.advance()
            return Literal(1.0 if tok.text == "true" else 0.0)
        if kind == INT:
            self.advance()
            return Literal(int_literal(tok.text))
        if kind == REAL:
            self.advance()
            return Literal(real_literal(tok.text))
        if kind == STR:
            self.advance()
            return Literal(tok.text)
        if kind == IDENT:
            self.advance()
            return Name(tok.text)
        if kind == ERROR:
            raise ParseError(f"Invalid token '{tok.text}' at position {self._pos(tok)}")
        raise ParseError(f"Expected operand at position {self._pos(tok)} (got '{tok.text}')")

    def parse_expr(self, min_bp: int) -> Node:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.too_deep(self.peek())
        try:
            return self._parse_expr(min_bp)
        finally:
            self.depth -= 1

    def too_deep(self, tok: Token) -> ParseError:
        return ParseError(f"Parse error at position {self._pos(tok)}: expression nested too deeply")

    def _parse_expr(self, min_bp: int) -> Node:
        left = self.parse_prefix()
        while True:
            kind = self.peek().kind
            lbp = LEFT_BP.get(kind, -1)
            if lbp < 0 or lbp < min_bp:
                break
            if kind in ASSIGN_OPS:
                self.advance()
                left = Assign(kind, left, self.parse_expr(0))
                break
            if kind == "?":
                self.advance()
                then = self.parse_expr(0)
                self.expect(":", "expected ':' in ternary expression")
                left = Ternary(left, then, self.parse_expr(TERNARY_BP))
                break
            if kind in COMPARE_OPS:
                ops, operands = [], [left]
                while self.peek().kind in COMPARE_OPS:
                    ops.append(self.advance().kind)
                    operands.append(self.parse_expr(COMPARE_BP + 1))
                left = Compare(ops, operands)
                continue
            self.advance()
            left = Binary(kind, left, self.parse_expr(lbp + 1))
        return left


def ast_depth(node: Node) -> int:
    """Depth of the tree below ``node`` (iterative, so a long ``a+b+c+...`` chain is safe)."""
    deepest = 0
    stack = [(node, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        if isinstance(node, Unary):
            children = (node.operand,)
        elif isinstance(node, (Binary, Assign)):
            children = (node.left, node.right) if isinstance(node, Binary) else (node.target, node.value)
        elif isinstance(node, Compare):
            children = node.operands
        elif isinstance(node, Ternary):
            children = (node.cond, node.then, node.other)
        else:
            children = ()
        stack.extend((child, depth + 1) for child in children)
    return deepest


def parse(src: str) -> list[Node]:
    """Parse a whole script into its statements. Raises ParseError (also for 'Empty Script')."""
    parser = _Parser(src)
    stmts = parser.parse_all()
    if not stmts:
        raise ParseError("Empty Script")
    # Every node of a tree has a token of its own (its operand, operator or '?'), so a tree is
    # no deeper than the script has tokens: most scripts need no walk (END is not a node's).
    if len(parser.tokens) - 1 > MAX_DEPTH:
        for stmt in stmts:
            if ast_depth(stmt) > MAX_DEPTH:
                raise ParseError("Parse error at position 0: expression nested too deeply")
    return stmts
