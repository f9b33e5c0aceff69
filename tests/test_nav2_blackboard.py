"""Writes through a SubTree remapping into a typed parent entry (what the Nav2 nodes need when
Nav2's tree runs as a SubTree, as in trees/navigation.xml)."""

from __future__ import annotations

import numpy as np
import pytest

from bt_runtime.blackboard import Blackboard
from bt_runtime.errors import LogicError
from bt_runtime.ports import INT, PortType
from bt_runtime.runtime.messages import Path

UINT16 = PortType("unsigned short", "int", int, lo=0, hi=65535)
PATH = PortType("nav_msgs::msg::Path", "custom", Path)


def child_of(parent: Blackboard, autoremap: bool = True, **remap: str) -> Blackboard:
    child = Blackboard(parent)
    child.enable_auto_remapping(autoremap)
    for internal, external in remap.items():
        child.add_subtree_remapping(internal, external)
    return child


@pytest.mark.parametrize("autoremap", [True, False])
def test_remapped_typed_entries_take_the_values_a_local_entry_takes(autoremap):
    parent = Blackboard()
    parent.create_entry("code", UINT16)
    parent.create_entry("path", PATH)
    child = child_of(parent, autoremap) if autoremap else child_of(parent, False, code="code", path="path")
    child.set("code", 105)  # an int into an unsigned short entry: exact conversion
    path = Path(1.0, np.zeros((2, 3)))
    child.set("path", path)  # a Path into a nav_msgs::msg::Path entry
    assert parent.get("code") == 105 and parent.get_entry("code").type is UINT16
    assert parent.get("path") is path
    assert child.keys() == []  # written in the parent, nothing local


def test_remapped_entries_still_refuse_other_types():
    parent = Blackboard()
    parent.create_entry("code", UINT16)
    parent.create_entry("n", INT)
    child = child_of(parent)
    with pytest.raises(LogicError, match="once declared"):
        child.set("code", Path(0.0, np.zeros((0, 3))))
    with pytest.raises(LogicError, match="once declared"):
        child.set("n", 2.5)  # not an exact conversion
    with pytest.raises(LogicError, match="once declared"):
        child.set("code", -1)  # out of an unsigned short's range
