"""Typed ports and BT.CPP's string <-> value conversion rules.

A port has a direction, a ``PortType`` (the C++-style type name Groot2 shows, plus how to
convert a string into it), an optional default and a description. The conversion rules follow
BT.CPP's ``convertFromString`` and ``Any::cast`` exactly (spec sections 7.1 and 7.5), because
trees written for BT.CPP rely on them: ``num_cycles="2abc"`` is 2, ``then_skip="yes"`` is an
error, ``0.5`` is written back as ``0.500000``.
"""

from __future__ import annotations

import json
import math
import re
import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import Enum
from typing import Any

from .errors import BTRuntimeError, LogicError
from .status import STATUS_BY_NAME, NodeStatus, PortDirection

_INT_PREFIX = re.compile(r"-?[0-9]+")
_FLOAT_PREFIX = re.compile(
    r"-?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|inf(?:inity)?|nan)", re.IGNORECASE)
_BOOL_STRINGS = {"1": True, "true": True, "TRUE": True, "True": True,
                 "0": False, "false": False, "FALSE": False, "False": False}

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
UINT32_MAX = 2**32 - 1
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
UINT64_MAX = 2**64 - 1
MAX_SAFE_FLOAT_INT = 2**53 - 1


class _Empty:
    """The value of a blackboard entry that exists but was never written."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "EMPTY"

    def __bool__(self) -> bool:
        return False


EMPTY: Any = _Empty()


# ---------------------------------------------------------------------------------------------
# Scalar parsers (BT.CPP convertFromString)
# ---------------------------------------------------------------------------------------------

def parse_int(text: str, lo: int = INT64_MIN, hi: int = INT64_MAX) -> int:
    """Base-10 integer; trailing characters ignored, leading '+'/whitespace rejected."""
    m = _INT_PREFIX.match(text)
    if not m:
        raise BTRuntimeError(f"Can't convert string [{text}] to integer")
    value = int(m.group(0))
    if value < lo or value > hi:
        raise BTRuntimeError(f"Value out of bound when converting [{text}] to integer")
    return value


def parse_float(text: str, type_name: str = "double") -> float:
    """C ``from_chars`` general format: sign, decimals, exponent, inf/nan; trailing ignored.

    Like ``from_chars``, a finite number that overflows to infinity or underflows to zero in
    the target type (``result_out_of_range``) is an error, e.g. ``1e999`` or ``1e-400``.
    """
    m = _FLOAT_PREFIX.match(text)
    if not m:
        raise BTRuntimeError(f"Can't convert string [{text}] to {type_name}")
    number = m.group(0)
    value = float(number)
    if number.lstrip("-")[:1] in "iInN":  # inf / infinity / nan
        return value
    if type_name == "float":
        try:
            narrowed = struct.unpack("f", struct.pack("f", value))[0]
        except OverflowError:
            narrowed = math.inf
    else:
        narrowed = value
    mantissa = re.split("[eE]", number)[0]
    if math.isinf(narrowed) or (narrowed == 0.0 and mantissa.strip("-0.") != ""):
        raise BTRuntimeError(f"Can't convert string [{text}] to {type_name}")
    return value


def parse_bool(text: str) -> bool:
    try:
        return _BOOL_STRINGS[text]
    except KeyError:
        raise BTRuntimeError("convertFromString(): invalid bool conversion") from None


def parse_status(text: str) -> NodeStatus:
    try:
        return STATUS_BY_NAME[text]
    except KeyError:
        raise BTRuntimeError(f"Cannot convert this to NodeStatus: {text}") from None


def split_list(text: str) -> list[str]:
    """BT.CPP ``splitString(s, ';')``: a final empty part is not added; '' gives []."""
    if text == "":
        return []
    parts = text.split(";")
    if parts and parts[-1] == "":
        parts.pop()
    return parts


def format_double(value: float) -> str:
    """``std::to_string(double)``: %f with 6 decimals."""
    if math.isnan(value):
        return "-nan" if math.copysign(1.0, value) < 0 else "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:f}"


# ---------------------------------------------------------------------------------------------
# Port types
# ---------------------------------------------------------------------------------------------

class PortType:
    """A declared port/entry type: its C++-style name and how strings convert into it.

    ``kind`` groups types by storage behaviour: 'int', 'double', 'bool', 'string', 'status',
    'enum', 'list', 'any' (BT::Any), 'anytype' (untyped, BT::AnyTypeAllowed), 'custom'.
    """

    __slots__ = ("name", "kind", "py_type", "lo", "hi", "element", "enum_cls", "_from_string",
                 "_to_string")

    def __init__(self, name: str, kind: str, py_type: type | None = None, *, lo: int | None = None,
                 hi: int | None = None, element: PortType | None = None, enum_cls: type | None = None,
                 from_string: Callable[[str], Any] | None = None,
                 to_string: Callable[[Any], str] | None = None):
        self.name = name
        self.kind = kind
        self.py_type = py_type
        self.lo = lo
        self.hi = hi
        self.element = element
        self.enum_cls = enum_cls
        self._from_string = from_string
        self._to_string = to_string

    @property
    def strongly_typed(self) -> bool:
        return self.kind not in ("any", "anytype")

    @property
    def has_converter(self) -> bool:
        """Whether BT.CPP gives this type a string converter (``GetAnyFromStringFunctor``): not
        for untyped ports, nor for enums (NodeStatus included). Without it a literal is not
        checked when the tree is built, and a string written into such a blackboard entry is a
        type mismatch. A custom type always has one: without a ``from_string`` it is BT.CPP's
        generic ``convertFromString<T>``, which throws, so its literals are refused at build.
        A type known only by its name in a models file (no Python class) is not checked."""
        if self.kind == "custom":
            return self.py_type is not None or self._from_string is not None
        return self.kind not in ("enum", "status", "any", "anytype")

    def from_string(self, text: str, enums: dict[str, int] | None = None) -> Any:
        """Convert a string to this type (BT.CPP convertFromString<T>)."""
        kind = self.kind
        if kind == "string" or kind in ("any", "anytype"):
            return text
        if kind == "int":
            return parse_int(text, self.lo, self.hi)
        if kind == "double":
            return parse_float(text, self.name)
        if kind == "bool":
            return parse_bool(text)
        if kind == "status":
            return parse_status(text)
        if kind == "enum":
            return self._enum_from_string(text, enums)
        if kind == "list":
            if text.startswith("json:"):
                try:
                    items = json.loads(text[5:])
                except ValueError as exc:
                    raise BTRuntimeError(f"Can't parse JSON [{text[5:]}]: {exc}") from None
                return [self.element.coerce(v) for v in items]
            return [self.element.from_string(part, enums) for part in split_list(text)]
        if self._from_string is not None:
            return self._from_string(text)
        from_json = getattr(self.py_type, "from_json", None)
        if text.startswith("json:") and from_json is not None:  # BT.CPP's generic convertFromJSON
            try:
                data = json.loads(text[5:])
            except ValueError as exc:
                raise BTRuntimeError(f"Can't parse JSON [{text[5:]}]: {exc}") from None
            return from_json(data)
        raise LogicError("You didn't implement the template specialization of convertFromString "
                         f"for this type: {self.name}")

    def _enum_from_string(self, text: str, enums: dict[str, int] | None) -> Any:
        """BT.CPP ``TreeNode::parseString`` for enums: a scripting enum, then a number, then the
        type's own converter (``from_string``; NodeType and PortDirection have BT.CPP's), and
        only then, where there is none, a member's Python name."""
        cls = self.enum_cls
        if enums and text in enums:
            value = enums[text]
        elif re.fullmatch(r"-?[0-9]+", text):
            value = int(text)
        elif self._from_string is not None:
            return self._from_string(text)
        elif cls is not None and text in cls.__members__:
            return cls.__members__[text]
        else:
            raise BTRuntimeError(f"Can't convert string [{text}] to enum {self.name}")
        if cls is not None:
            try:
                return cls(value)
            except ValueError:
                raise BTRuntimeError(f"Value {value} is not a member of {self.name}") from None
        return value

    def to_string(self, value: Any) -> str:
        """BT.CPP ``toStr``: used for defaults in models and for string reads of typed values."""
        if self._to_string is not None:
            return self._to_string(value)
        return value_to_string(value)

    def coerce(self, value: Any, enums: dict[str, int] | None = None) -> Any:
        """Cast a stored value to this type following BT.CPP's Any::cast rules (spec 7.5)."""
        if isinstance(value, str) and self.kind not in ("string", "any", "anytype"):
            if self.kind == "bool":
                raise BTRuntimeError(
                    "[Any::convert]: no known safe conversion between [std::string] and [bool]")
            return self.from_string(value, enums)
        return cast_value(value, self)

    def __repr__(self) -> str:
        return f"PortType({self.name!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, PortType) and other.name == self.name and other.kind == self.kind

    def __hash__(self) -> int:
        return hash((self.name, self.kind))


INT = PortType("int", "int", int, lo=INT32_MIN, hi=INT32_MAX)
UINT = PortType("unsigned int", "int", int, lo=0, hi=UINT32_MAX)
INT64 = PortType("long", "int", int, lo=INT64_MIN, hi=INT64_MAX)
UINT64 = PortType("unsigned long", "int", int, lo=0, hi=UINT64_MAX)
DOUBLE = PortType("double", "double", float)
FLOAT = PortType("float", "double", float)
BOOL = PortType("bool", "bool", bool)
STRING = PortType("std::string", "string", str)
STATUS = PortType("BT::NodeStatus", "status", NodeStatus)
ANY = PortType("BT::Any", "any")
ANYTYPE = PortType("BT::AnyTypeAllowed", "anytype")
MILLISECONDS = PortType("std::chrono::milliseconds", "int", int, lo=INT64_MIN, hi=INT64_MAX)


def vector_of(element: PortType) -> PortType:
    cpp = element.name
    return PortType(f"std::vector<{cpp}, std::allocator<{cpp}> >", "list", list, element=element)


def deque_of(element: PortType) -> PortType:
    cpp = element.name
    return PortType(f"std::shared_ptr<std::deque<{cpp}, std::allocator<{cpp}> > >", "list", list,
                    element=element)


_BY_PY_TYPE: dict[Any, PortType] = {
    int: INT, float: DOUBLE, str: STRING, bool: BOOL, NodeStatus: STATUS, None: ANYTYPE,
    Any: ANYTYPE, object: ANY,
}
_BY_NAME: dict[str, PortType] = {t.name: t for t in
                                 (INT, UINT, INT64, UINT64, DOUBLE, FLOAT, BOOL, STRING, STATUS, ANY,
                                  ANYTYPE, MILLISECONDS)}
_BY_NAME.update({"std::__cxx11::basic_string<char, std::char_traits<char>, std::allocator<char> >": STRING,
                 "AnyTypeAllowed": ANYTYPE, "string": STRING, "int64_t": INT64, "uint64_t": UINT64,
                 "unsigned": UINT, "size_t": UINT64})
_custom_cache: dict[type, PortType] = {}


def port_type(spec: Any) -> PortType:
    """Turn what a user writes in ``input_port(name, spec)`` into a PortType.

    Accepts a PortType, a Python type (int, float, str, bool, NodeStatus, an Enum subclass,
    ``list[int]`` and friends, or a class with a ``from_string`` classmethod), a C++ type name
    string (as found in TreeNodesModel files), or None for an untyped port.
    """
    if isinstance(spec, PortType):
        return spec
    if spec in _BY_PY_TYPE:
        return _BY_PY_TYPE[spec]
    if isinstance(spec, str):
        return type_from_name(spec)
    origin = getattr(spec, "__origin__", None)
    if origin is list:
        (arg,) = spec.__args__
        return vector_of(port_type(arg))
    if isinstance(spec, type):
        cached = _custom_cache.get(spec)
        if cached is not None:
            return cached
        name = getattr(spec, "bt_type_name", None) or spec.__name__
        from_string = getattr(spec, "from_string", None)
        to_string = getattr(spec, "to_string", None)
        if issubclass(spec, Enum):
            pt = PortType(name, "enum", spec, enum_cls=spec, from_string=from_string,
                          to_string=(lambda v: v.name if isinstance(v, Enum) else str(v)))
        else:
            to_str = (lambda v, _f=to_string: _f(v)) if to_string else None
            pt = PortType(name, "custom", spec, from_string=from_string, to_string=to_str)
        _custom_cache[spec] = pt
        return pt
    raise LogicError(f"Unsupported port type: {spec!r}")


def convert_from_string(spec: Any, text: str, enums: dict[str, int] | None = None) -> Any:
    """BT.CPP's ``convertFromString<T>(text)`` for a type as ``input_port`` accepts it (int,
    float, bool, str, NodeStatus, NodeType, PortDirection, list[...], a user class...)."""
    return port_type(spec).from_string(text, enums)


def type_from_name(name: str) -> PortType:
    """Resolve a C++ type name found in a models file; unknown names become opaque types."""
    name = name.strip()
    known = _BY_NAME.get(name)
    if known is not None:
        return known
    m = re.fullmatch(r"std::vector<(.+?)(?:, ?std::allocator<.+>\s*)?>", name)
    if m:
        return vector_of(type_from_name(m.group(1)))
    if not name:
        return ANYTYPE
    return PortType(name, "custom")


# ---------------------------------------------------------------------------------------------
# Values: naming, casting and text form
# ---------------------------------------------------------------------------------------------

def type_of_value(value: Any) -> PortType:
    """The type an entry gets when a value of this Python type is first written."""
    cls = type(value)
    if cls is bool:
        return BOOL
    if cls is int:
        return INT if INT32_MIN <= value <= INT32_MAX else INT64
    if cls is float:
        return DOUBLE
    if cls is str:
        return STRING
    if cls is NodeStatus:
        return STATUS
    if cls is list:
        return vector_of(type_of_value(value[0]) if value else ANYTYPE)
    return port_type(cls)


def value_to_string(value: Any) -> str:
    """BT.CPP text form of a value: bool true/false, double %f, NodeStatus by name, lists ';'."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, NodeStatus):
        return value.name
    if isinstance(value, Enum):
        return value.name
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return format_double(value)
    if isinstance(value, (list, tuple)):
        return ";".join(value_to_string(v) for v in value)
    if value is EMPTY or value is None:
        return ""
    to_string = getattr(value, "to_string", None)
    if callable(to_string):
        return to_string()
    return str(value)


def cast_value(value: Any, target: PortType) -> Any:
    """Cast a non-string stored value to ``target`` (BT.CPP Any::cast number rules)."""
    kind = target.kind
    if kind in ("any", "anytype"):
        return value
    if kind == "string":
        # BT.CPP stores bool and enums (NodeStatus too) as int64: they read back as "1", "2"...
        if isinstance(value, bool):
            return "1" if value else "0"
        if isinstance(value, Enum) and isinstance(value.value, int):
            return str(int(value.value))
        return value_to_string(value)
    if isinstance(value, bool):
        if kind == "bool":
            return value
        value = int(value)
    if isinstance(value, NodeStatus) and kind != "status":
        value = int(value)
    if isinstance(value, int):
        if kind == "int":
            if target.lo is not None and value < target.lo:
                if value < 0 and target.lo == 0:
                    raise BTRuntimeError("Value is negative and can't be converted to unsigned")
                raise BTRuntimeError("Value outside the max numerical limit.")
            if target.hi is not None and value > target.hi:
                raise BTRuntimeError("Value outside the max numerical limit.")
            return value
        if kind == "double":
            if abs(value) > MAX_SAFE_FLOAT_INT:
                raise BTRuntimeError("Loss of precision when converting a large integer number to "
                                     f"floating point:{value}")
            return float(value)
        if kind == "bool":
            if value in (0, 1):
                return bool(value)
            if value < 0:  # bool is unsigned for BT.CPP's convertNumber
                raise BTRuntimeError("Value is negative and can't be converted to unsigned")
            raise BTRuntimeError("Implicit casting to bool is not allowed")
        if kind == "status":
            return NodeStatus(value)
        if kind == "enum":
            return target.enum_cls(value) if target.enum_cls is not None else value
    elif isinstance(value, float):
        if kind == "double":
            return value
        if kind == "int":
            if not math.isfinite(value) or value != int(value):
                raise BTRuntimeError("Invalid floating point to integer conversion")
            return cast_value(int(value), target)
        if kind == "bool":
            if value < 0.0:
                raise BTRuntimeError("Value is negative and can't be converted to unsigned")
            return value != 0.0
        if kind == "enum" or kind == "status":
            return cast_value(cast_value(value, INT64), target)
    if kind == "status" and isinstance(value, NodeStatus):
        return value
    if kind == "enum" and target.enum_cls is not None and isinstance(value, target.enum_cls):
        return value
    if kind == "list" and isinstance(value, (list, tuple)):
        return list(value)
    if target.py_type is not None and isinstance(value, target.py_type):
        return value
    raise BTRuntimeError(f"[Any::convert]: no known safe conversion between "
                         f"[{type_of_value(value).name}] and [{target.name}]")


def polymorphic(stored: PortType, wanted: PortType) -> bool:
    """Whether an entry of user class ``stored`` may feed an input port of user class
    ``wanted``: one derives from the other (BT.CPP 4.10's polymorphic ports, which need a
    registered cast; a Python class carries its hierarchy). An upcast always succeeds; a
    downcast is checked on each read (``isinstance``), as BT.CPP's dynamic_pointer_cast."""
    a, b = stored.py_type, wanted.py_type
    return (stored.kind == wanted.kind == "custom" and isinstance(a, type) and isinstance(b, type)
            and (issubclass(a, b) or issubclass(b, a)))


def _wrap(value: int, bits: int, signed: bool) -> int:
    """``static_cast`` of an integer to a ``bits``-wide (un)signed integer: two's complement."""
    value &= (1 << bits) - 1
    if signed and value >= 1 << (bits - 1):
        value -= 1 << bits
    return value


def _int_width(target: PortType) -> tuple[int, bool]:
    signed = target.lo is not None and target.lo < 0
    span = (target.hi or 0) - (target.lo or 0)
    return (32 if span <= UINT32_MAX else 64), signed


def casting_safe(value: Any, target: PortType) -> bool:
    """BT.CPP ``isCastingSafe(target, value)``: may a number of another type be written into an
    entry declared ``target`` (``Blackboard::set``)? Its ``ValidCast`` quirks are kept: the
    target's limits are first cast to the *source* type, so a C++ ``int`` (a Python int that
    fits 32 bits) is never accepted by an unsigned entry, and ``false`` is refused by a signed
    integer entry."""
    kind = target.kind
    if isinstance(value, bool):
        src_bits, src_signed = 1, False
    elif isinstance(value, int):
        src_bits, src_signed = (32, True) if INT32_MIN <= value <= INT32_MAX else (64, True)
    elif isinstance(value, float):
        src_bits, src_signed = 0, True
    else:
        return False
    if kind == "double":
        if target.name == "float" and isinstance(value, float):
            return struct.unpack("f", struct.pack("f", value))[0] == value if math.isfinite(value) else True
        return isinstance(value, float) or float(value) == value
    if kind != "int" or target.lo is None or target.hi is None:
        return False  # bool, string, enum, status... entries take no other type
    bits, signed = _int_width(target)
    if isinstance(value, float):
        if not math.isfinite(value):
            return False
        over = value >= float(target.hi) if bits > 53 else value > float(target.hi)
        if over or value < float(target.lo):
            return False
        return float(int(value)) == value
    if src_bits == 1:  # bool: both limits become bool
        max_limit, low_limit = bool(target.hi), bool(target.lo)
        return not (value > max_limit or value < low_limit)
    max_limit = _wrap(target.hi, src_bits, src_signed)
    low_limit = _wrap(target.lo, src_bits, src_signed)
    if value > max_limit or value < low_limit:
        return False
    return _wrap(_wrap(value, bits, signed), src_bits, src_signed) == value


def convert_exact(value: Any, target: PortType) -> tuple[bool, Any]:
    """Blackboard.set's numeric acceptance rule: does ``value`` convert *exactly* to target?

    An int into a double entry, 2.0 into an int entry, a bool into an int entry: yes.
    2.5 into an int entry, any int into a bool entry: no.
    """
    kind = target.kind
    if kind == "bool":
        if isinstance(value, bool):
            return True, value
        return False, None
    if value is False and kind == "int" and target.lo is not None and target.lo < 0:
        # BT.CPP's isCastingSafe<bool> into a signed integer compares false < bool(INT_MIN),
        # which is true, so writing `false` into an int entry is refused (`true` is accepted).
        return False, None
    if isinstance(value, (bool, int, float)) and kind in ("int", "double"):
        try:
            return True, cast_value(value, target)
        except BTRuntimeError:
            return False, None
    if kind == "status" and isinstance(value, NodeStatus):
        return True, value
    if kind == "enum" and isinstance(value, int) and not isinstance(value, bool):
        try:
            return True, cast_value(value, target)
        except (BTRuntimeError, ValueError):
            return False, None
    return False, None


# ---------------------------------------------------------------------------------------------
# Port declarations
# ---------------------------------------------------------------------------------------------

_NO_DEFAULT: Any = object()


@dataclass(frozen=True, slots=True)
class PortInfo:
    """One declared port: ``input_port('msec', int, default=10, description='...')``."""

    name: str
    direction: PortDirection
    type: PortType
    default: Any = _NO_DEFAULT
    description: str = ""

    @property
    def has_default(self) -> bool:
        return self.default is not _NO_DEFAULT

    def default_string(self) -> str:
        """The default's string form, as BT.CPP stores it in a node's configuration."""
        if not self.has_default:
            return ""
        if isinstance(self.default, str):
            return self.default
        return self.type.to_string(self.default)


RESERVED_ATTRIBUTES = frozenset({"name", "ID", "_autoremap", "_failureIf", "_successIf", "_skipIf",
                                 "_while", "_onHalted", "_onFailure", "_onSuccess", "_post"})
FORBIDDEN_NAME_CHARS = frozenset(" \t\n\r<>&\"'/\\:*?|.")


_FORBIDDEN_NAME_RE = re.compile("[" + re.escape("".join(sorted(FORBIDDEN_NAME_CHARS))) + "\x00-\x1f\x7f]")


def find_forbidden_char(name: str) -> str | None:
    """The first character of ``name`` BT.CPP forbids in a name (one regex scan: this runs
    for every port of every node type a factory registers)."""
    m = _FORBIDDEN_NAME_RE.search(name)
    return m.group(0) if m is not None else None


def is_allowed_port_name(name: str) -> bool:
    """BT.CPP IsAllowedPortName: starts with a letter, no forbidden character, not reserved."""
    if not name or not name[0].isascii() or not name[0].isalpha():
        return False
    if name in RESERVED_ATTRIBUTES:
        return False
    return find_forbidden_char(name) is None


def _make_port(direction: PortDirection, name: str, type_: Any, default: Any,
               description: str) -> PortInfo:
    # BT.CPP's CreatePort throws RuntimeError for any name IsAllowedPortName refuses
    if not name or not name[0].isascii() or not name[0].isalpha() or name in RESERVED_ATTRIBUTES:
        raise BTRuntimeError("The name of a port must not be 'name' or 'ID' and must start with an "
                             f"alphabetic character. Underscore is reserved. (got '{name}')")
    bad = find_forbidden_char(name)
    if bad is not None:
        raise BTRuntimeError(f"The port name '{name}' contains the forbidden character {bad!r}")
    return PortInfo(name, direction, port_type(type_), default, description)


def input_port(name: str, type: Any = None, default: Any = _NO_DEFAULT,  # noqa: A002
               description: str = "") -> PortInfo:
    return _make_port(PortDirection.INPUT, name, type, default, description)


def output_port(name: str, type: Any = None, default: Any = _NO_DEFAULT,  # noqa: A002
                description: str = "") -> PortInfo:
    """An output port; its default, if any, must name a blackboard entry (``"{key}"``)."""
    if default is not _NO_DEFAULT and not (isinstance(default, str) and len(default) >= 2
                                           and default[0] == "{" and default[-1] == "}"):
        raise LogicError("Output port can only refer to blackboard entries, i.e. use the syntax "
                         f"'{{port_name}}' (port '{name}', default {default!r})")
    return _make_port(PortDirection.OUTPUT, name, type, default, description)


def bidirectional_port(name: str, type: Any = None, default: Any = _NO_DEFAULT,  # noqa: A002
                       description: str = "") -> PortInfo:
    return _make_port(PortDirection.INOUT, name, type, default, description)


inout_port = bidirectional_port


def ports_dict(ports: Iterable[PortInfo] | dict[str, PortInfo] | None) -> dict[str, PortInfo]:
    """Normalise a ports declaration (list/tuple or dict) into name -> PortInfo."""
    if not ports:
        return {}
    if isinstance(ports, dict):
        return dict(ports)
    result: dict[str, PortInfo] = {}
    for p in ports:
        if not isinstance(p, PortInfo):
            raise LogicError(f"Ports must be declared with input_port()/output_port(), got {p!r}")
        result[p.name] = p
    return result


# ---------------------------------------------------------------------------------------------
# Remapping strings
# ---------------------------------------------------------------------------------------------

def blackboard_key(raw: str, port_name: str) -> str | None:
    """If ``raw`` points to a blackboard entry, return its key; else None (a literal).

    ``{key}`` (spaces around the braces trimmed) -> key; ``{=}`` or ``=`` -> the port name.
    """
    if raw == "=" or raw == "{=}":
        return port_name
    s = raw.strip(" ")
    if len(s) >= 3 and s[0] == "{" and s[-1] == "}":
        inner = s[1:-1]
        return port_name if inner == "=" else inner
    return None


def is_strict_blackboard_pointer(raw: str) -> bool:
    """The load-time test (no trimming): first char '{', last '}', length >= 3."""
    return len(raw) >= 3 and raw[0] == "{" and raw[-1] == "}"
