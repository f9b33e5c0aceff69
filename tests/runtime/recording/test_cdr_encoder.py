"""The compiled CDR encoder writes rosbags' bytes exactly, for every type a recording uses."""

from __future__ import annotations

import random
import string

import numpy as np
import pytest

from bt_runtime.runtime.recording.cdr_encoder import CODES, encode, encoder
from bt_runtime.runtime.recording.msgdefs import DEFINITIONS
from bt_runtime.runtime.recording.types import NAV2_MSGS, serialize, typestore

TYPES = sorted({*DEFINITIONS, *NAV2_MSGS})
INTS = {"int8": 8, "int16": 16, "int32": 32, "int64": 64}
DTYPES = {"float32": "<f4", "float64": "<f8", "uint8": "u1", "int8": "i1", "byte": "i1", "char": "u1",
          "int16": "<i2", "uint16": "<u2", "int32": "<i4", "uint32": "<u4", "int64": "<i8", "uint64": "<u8",
          "bool": "?"}


def _primitive(rng: random.Random, name: str):
    if name == "bool":
        return rng.random() < 0.5
    if name in ("float32", "float64"):
        value = rng.uniform(-1e6, 1e6)
        return float(np.float32(value)) if name == "float32" else value
    if name in INTS:
        bits = INTS[name]
        return rng.randrange(-(2 ** (bits - 1)), 2 ** (bits - 1))
    if name == "byte":
        return rng.randrange(-128, 128)
    bits = {"uint8": 8, "char": 8, "uint16": 16, "uint32": 32, "uint64": 64}[name]
    return rng.randrange(0, 2 ** bits)


def _text(rng: random.Random) -> str:
    return "".join(rng.choice(string.ascii_letters + "/_ é") for _ in range(rng.randrange(0, 12)))


def _primitives(rng: random.Random, name: str, n: int) -> np.ndarray:
    return np.array([_primitive(rng, name) for _ in range(n)], dtype=DTYPES[name])


def random_message(rng: random.Random, typename: str):
    """(rosbags message, the same values as the encoder's tuple)"""
    store = typestore()
    objs, tups = [], []
    for _name, desc in store.fielddefs[typename][1]:
        obj, tup = _random_field(rng, desc)
        objs.append(obj)
        tups.append(tup)
    return store.types[typename](*objs), tuple(tups)


def _random_field(rng: random.Random, desc):
    kind = desc[0].name
    if kind == "NAME":
        return random_message(rng, desc[1])
    if kind == "BASE":
        if desc[1][0] == "string":
            text = _text(rng)
            return text, text
        value = _primitive(rng, desc[1][0])
        return value, value
    sub, count = desc[1]
    n = count if kind == "ARRAY" else rng.choice([0, 0, 1, 2, 3, 7])
    if sub[0].name == "BASE" and sub[1][0] in CODES:
        arr = _primitives(rng, sub[1][0], n)
        as_list = rng.random() < 0.3 and sub[1][0] != "bool"
        return arr, (arr.tolist() if as_list else arr)
    pairs = [_random_field(rng, sub) for _ in range(n)]
    return [p[0] for p in pairs], [p[1] for p in pairs]


@pytest.mark.parametrize("typename", TYPES)
def test_random_values_encode_as_rosbags_does(typename):
    rng = random.Random(1700 + TYPES.index(typename))
    for _ in range(60):
        msg, values = random_message(rng, typename)
        assert encode(values, typename) == serialize(msg, typename)


def test_a_wrong_fixed_array_length_is_refused():
    _msg, values = random_message(random.Random(5), "geometry_msgs/msg/PoseWithCovariance")
    with pytest.raises(ValueError, match="covariance: expected 36 elements"):
        encoder("geometry_msgs/msg/PoseWithCovariance")((values[0], np.zeros(35)))
