"""Compiled CDR (little endian) encoders of plain nested tuples, one generated function per type.

Why: the low-rate types of a recording (plan, diagnostics, battery, logs, tree log, map) went
through rosbags: a typestore message object built per (sub)message, then rosbags' generated
serializer with a sizing pass; a 50-pose ``nav_msgs/msg/Path`` cost ~350 us. Here a message is
a tuple of its fields in definition order (a nested message a tuple, a sequence of messages a
list of tuples, a primitive array or sequence a numpy array, bytes or a list of numbers), and
``encoder(typename)`` compiles the type's field definitions (rosbags' typestore, ``types.py``)
once into Python source: runs of fixed fields whose alignment is known where they start are
packed with one precompiled ``struct.Struct`` (padding included), strings and sequences between
them, nested messages inlined, sequences of messages a loop over the element type's function.

The bytes are rosbags' exactly (``tests/runtime/recording/test_cdr_encoder.py`` compares both
on random values of every recorded type). XCDR1 alignment: a field is aligned to its size (at
most 8) relative to the end of the 4-byte encapsulation header; a length is a uint32; a string
carries its terminating NUL; an empty primitive sequence adds no element padding.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np

from .types import typestore

HEADER = b"\x00\x01\x00\x00"  # CDR little endian, no options
# rosbags' primitive names -> struct code (rosbags packs byte as int8 and char as uint8)
CODES = {"bool": "?", "byte": "b", "char": "B", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
         "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q", "float32": "f", "float64": "d"}
ZEROS = tuple(bytes(n) for n in range(8))


def _array_bytes(value: Any, dtype: str, count: int, where: str) -> bytes:
    """A fixed primitive array as bytes (a numpy array, bytes or a list of numbers)."""
    data = value if type(value) is bytes else np.ascontiguousarray(value, dtype=dtype).tobytes()
    if len(data) != count * np.dtype(dtype).itemsize:
        raise ValueError(f"{where}: expected {count} elements")
    return data


def _seq_bytes(value: Any, dtype: str) -> bytes:
    """A primitive sequence as bytes."""
    if type(value) is bytes:
        return value
    return np.ascontiguousarray(value, dtype=dtype).tobytes()


class _Compiler:
    """Source of one type's ``enc_<n>(b, v)``: appends the encoding of tuple ``v`` to bytearray ``b``."""

    def __init__(self, store: Any, names: dict[str, str], env: dict[str, Any]):
        self.store = store
        self.names = names  # typename -> function name (made on demand, sequences of messages)
        self.env = env
        self.lines: list[str] = []
        self.run_fmt: list[str] = []
        self.run_args: list[str] = []
        self.r, self.m = 0, 1  # the offset is known to be r modulo m (m=1: unknown)

    # -- bookkeeping ------------------------------------------------------------------------------
    def _name(self, prefix: str) -> str:
        """A fresh name, unique across the functions of one compiled source (they share ``env``)."""
        n = self.env["_count"] = self.env["_count"] + 1
        return f"_{prefix}{n}"

    def _const(self, value: Any, prefix: str) -> str:
        name = self._name(prefix)
        self.env[name] = value
        return name

    def _flush(self, indent: str) -> None:
        if not self.run_fmt:
            return
        fmt = "<" + "".join(self.run_fmt)
        pack = self._const(struct.Struct(fmt).pack, "pack")
        self.lines.append(f"{indent}b += {pack}({', '.join(self.run_args)})")
        self.run_fmt, self.run_args = [], []

    def _align(self, align: int, indent: str) -> None:
        """Pad to ``align``: statically inside the run when the offset is known well enough."""
        if align <= 1:
            return
        if align <= self.m:
            pad = (-self.r) % align
            if pad:
                self.run_fmt.append(f"{pad}x")
            self.r = (self.r + pad) % self.m
            return
        self._flush(indent)
        self.lines.append(f"{indent}b += ZEROS[(4 - len(b)) % {align}]")
        self.r, self.m = 0, align

    def _advance(self, size: int) -> None:
        self.r = (self.r + size) % self.m

    # -- fields -----------------------------------------------------------------------------------
    def fields(self, typename: str, expr: str, indent: str) -> None:
        for i, (fname, desc) in enumerate(self.store.fielddefs[typename][1]):
            self.field(desc, f"{expr}[{i}]", indent, f"{typename}.{fname}")

    def field(self, desc: Any, expr: str, indent: str, where: str) -> None:
        kind = desc[0].name
        if kind == "NAME":
            self.fields(desc[1], expr, indent)
        elif kind == "BASE":
            name = desc[1][0]
            if name == "string":
                self.string(expr, indent)
            elif name in CODES:
                code = CODES[name]
                size = struct.calcsize(code)
                self._align(size, indent)
                self.run_fmt.append(code)
                self.run_args.append(expr)
                self._advance(size)
            else:
                raise ValueError(f"{where}: type {name} is not supported")
        elif kind == "ARRAY":
            sub, count = desc[1]
            if sub[0].name == "BASE" and sub[1][0] in CODES:
                code = CODES[sub[1][0]]
                size = struct.calcsize(code)
                self._align(size, indent)
                conv = self._const(_array_bytes, "arr")
                self.run_fmt.append(f"{size * count}s")
                self.run_args.append(f"{conv}({expr}, '<{code}', {count}, {where!r})")
                self._advance(size * count)
            else:
                item = self._name("e")
                self.lines.append(f"{indent}if len({expr}) != {count}:")
                self.lines.append(f"{indent}    raise ValueError({where + ': expected ' + str(count) + ' elements'!r})")
                self._elements(sub, expr, item, indent, where)
        elif kind == "SEQUENCE":
            sub = desc[1][0]
            if sub[0].name == "BASE" and sub[1][0] in CODES:
                code = CODES[sub[1][0]]
                size = struct.calcsize(code)
                data = self._name("s")
                conv = self._const(_seq_bytes, "seq")
                self.lines.append(f"{indent}{data} = {conv}({expr}, '<{code}')")
                self._align(4, indent)
                self.run_fmt.append("I")
                self.run_args.append(f"len({data}) // {size}" if size > 1 else f"len({data})")
                self._advance(4)
                self._flush(indent)
                if size > 4:
                    self.lines.append(f"{indent}if {data}:")
                    self.lines.append(f"{indent}    b += ZEROS[(4 - len(b)) % {size}]")
                    self.r, self.m = 0, 1
                self.lines.append(f"{indent}b += {data}")
                if size == 4 and self.m >= 4:  # whole elements: still aligned as after the length
                    self.r, self.m = self.r % 4, 4
                else:
                    self.r, self.m = 0, 1
            else:
                self._align(4, indent)
                self.run_fmt.append("I")
                self.run_args.append(f"len({expr})")
                self._advance(4)
                self._elements(sub, expr, self._name("e"), indent, where)
        else:
            raise ValueError(f"{where}: field kind {kind} is not supported")

    def string(self, expr: str, indent: str) -> None:
        data = self._name("t")
        self.lines.append(f"{indent}{data} = {expr}.encode()")
        self._align(4, indent)
        self.run_fmt.append("I")
        self.run_args.append(f"len({data}) + 1")
        self._flush(indent)
        self.lines.append(f"{indent}b += {data}")
        self.lines.append(f"{indent}b.append(0)")
        self.r, self.m = 0, 1

    def _elements(self, sub: Any, expr: str, item: str, indent: str, where: str) -> None:
        """A loop over a sequence or array of strings or messages."""
        self._flush(indent)
        self.lines.append(f"{indent}for {item} in {expr}:")
        inner = indent + "    "
        if sub[0].name == "BASE" and sub[1][0] == "string":
            self.r, self.m = 0, 1
            self.string(item, inner)
        elif sub[0].name == "NAME":
            self.lines.append(f"{inner}{function_name(sub[1], self.names)}(b, {item})")
        else:
            raise ValueError(f"{where}: element type {sub} is not supported")
        self.r, self.m = 0, 1  # after a loop: nothing is known of the offset


def function_name(typename: str, names: dict[str, str]) -> str:
    found = names.get(typename)
    if found is None:
        found = names[typename] = f"enc_{len(names)}"
    return found


def _source(typename: str, store: Any, names: dict[str, str], env: dict[str, Any]) -> str:
    comp = _Compiler(store, names, env)
    comp.fields(typename, "v", "    ")
    comp._flush("    ")
    body = comp.lines or ["    pass"]
    return f"def {function_name(typename, names)}(b, v):\n" + "\n".join(body) + "\n"


@cache
def encoder(typename: str) -> Callable[[tuple], bytes]:
    """``encode(values) -> bytes`` (CDR with its encapsulation header) for ``typename``."""
    store = typestore()
    names: dict[str, str] = {}
    env: dict[str, Any] = {"ZEROS": ZEROS, "_count": 0}
    sources: list[str] = []
    done: set[str] = set()
    function_name(typename, names)
    while len(done) < len(names):  # element types of sequences get their own function
        for name in [n for n in names if n not in done]:
            done.add(name)
            sources.append(_source(name, store, names, env))
    top = names[typename]
    sources.append(f"def encode(v):\n    b = bytearray(HEADER)\n    {top}(b, v)\n    return bytes(b)\n")
    env["HEADER"] = HEADER
    exec(compile("\n".join(sources), f"<cdr encoder {typename}>", "exec"), env)  # noqa: S102 - our own source
    return env["encode"]


def encode(values: tuple, typename: str) -> bytes:
    return encoder(typename)(values)
