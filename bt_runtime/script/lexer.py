"""Tokenizer for the BT.CPP 4.10 script language (spec 6.1).

Hand-written, one pass, ASCII-only classes (C locale ``isalpha``/``isdigit``), so that the
token boundaries, the malformed-number rules (``65.``, ``3foo``, ``0x``, ``3e+``) and the
error tokens match the C++ tokenizer: a bad number does not fail here, it becomes an
``ERROR`` token that the parser reports as ``Invalid token '<text>' at position P``.
Positions are character offsets; ``byte_offset`` turns one into the byte offset the C++
messages use.
"""

from __future__ import annotations

from typing import NamedTuple

# Token kinds that are not operators. Operators use their own text as kind ('+', ':=', ...).
INT = "INT"
REAL = "REAL"
STR = "STR"
BOOL = "BOOL"
IDENT = "IDENT"
ERROR = "ERROR"
END = "END"

_DIGITS = frozenset("0123456789")
_HEX = frozenset("0123456789abcdefABCDEF")
_ALPHA = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ")
_IDENT_START = _ALPHA | {"_", "@"}
_IDENT_CHAR = _ALPHA | _DIGITS | {"_"}
_GARBAGE = _IDENT_CHAR | {"."}
_SPACE = frozenset(" \t\n\r")
TWO_CHAR_OPS = frozenset({"..", "&&", "||", "==", "!=", "<=", ">=", ":=", "+=", "-=", "*=", "/="})
ONE_CHAR_OPS = frozenset("+-*/&|^~!<>=?:();")


class Token(NamedTuple):
    kind: str
    text: str  # for STR: the content without quotes
    pos: int   # character offset of the first character


def _scan_hex(src: str, n: int, i: int) -> tuple[int, bool]:
    """Scan '0x...' starting at ``i``; returns (end, has_error)."""
    i += 2
    error = False
    if i >= n or src[i] not in _HEX:
        error = True
    else:
        while i < n and src[i] in _HEX:
            i += 1
    if i < n and (src[i] == "." or src[i] in _IDENT_CHAR):
        error = True
        while i < n and src[i] in _GARBAGE:
            i += 1
    return i, error


def _scan_decimal(src: str, n: int, i: int) -> tuple[int, bool, bool]:
    """Scan a decimal integer or real at ``i``; returns (end, is_real, has_error)."""
    is_real = error = False
    while i < n and src[i] in _DIGITS:
        i += 1
    if i < n and src[i] == ".":
        nxt = src[i + 1] if i + 1 < n else ""
        if nxt == ".":
            pass  # '65..' is Integer 65 followed by the '..' operator
        elif nxt and nxt in _DIGITS:
            is_real = True
            i += 1
            while i < n and src[i] in _DIGITS:
                i += 1
        else:  # '65.' or '65.x': an incomplete real, swallow what follows
            error = True
            i += 1
            while i < n and src[i] in _GARBAGE:
                i += 1
    if not error and i < n and src[i] in "eE":
        is_real = True
        i += 1
        if i < n and src[i] in "+-":
            i += 1
        if i >= n or src[i] not in _DIGITS:
            error = True
        else:
            while i < n and src[i] in _DIGITS:
                i += 1
    if not error and i < n and src[i] in _IDENT_START:  # '3foo', '65.43foo', '1_', '2@'
        error = True
        while i < n and src[i] in _IDENT_CHAR:
            i += 1
    return i, is_real, error


_new_tuple = tuple.__new__  # Token(kind, text, pos) without the namedtuple's Python __new__ frame


def tokenize(src: str) -> list[Token]:
    """Split ``src`` into tokens, always ending with an END token."""
    tokens: list[Token] = []
    append = tokens.append
    n = len(src)
    i = 0
    while i < n:
        c = src[i]
        if c in _SPACE:
            i += 1
            continue
        start = i
        if c == "'":
            end = src.find("'", i + 1)
            if end < 0:
                append(_new_tuple(Token, (ERROR, src[start:], start)))
                i = n
            else:
                append(_new_tuple(Token, (STR, src[start + 1:end], start)))
                i = end + 1
            continue
        if c in _DIGITS:
            if c == "0" and i + 1 < n and src[i + 1] in "xX":
                i, error = _scan_hex(src, n, i)
                is_real = False
            else:
                i, is_real, error = _scan_decimal(src, n, i)
            kind = ERROR if error else (REAL if is_real else INT)
            append(_new_tuple(Token, (kind, src[start:i], start)))
            continue
        if c in _IDENT_START:
            i += 1
            while i < n and src[i] in _IDENT_CHAR:
                i += 1
            text = src[start:i]
            append(_new_tuple(Token, (BOOL if text in ("true", "false") else IDENT, text, start)))
            continue
        two = src[i:i + 2]
        if two in TWO_CHAR_OPS:
            append(_new_tuple(Token, (two, two, start)))
            i += 2
            continue
        append(_new_tuple(Token, (c if c in ONE_CHAR_OPS else ERROR, c, start)))
        i += 1
    append(_new_tuple(Token, (END, "", n)))
    return tokens


def byte_offset(src: str, pos: int) -> int:
    """The UTF-8 byte offset of character ``pos`` (what BT.CPP prints in parse errors)."""
    if src.isascii():
        return pos
    return len(src[:pos].encode("utf-8", "surrogatepass"))
