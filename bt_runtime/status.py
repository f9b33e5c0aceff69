"""Status, node-type and port-direction enumerations, with BT.CPP's integer values and names.

The integer values are used on the wire (Groot2, .btlog), so they must not change.
Hot paths compare with the module constants (``status is RUNNING``), which is faster than
attribute lookups on the enum class.
"""

from __future__ import annotations

from enum import IntEnum


class NodeStatus(IntEnum):
    IDLE = 0
    RUNNING = 1
    SUCCESS = 2
    FAILURE = 3
    SKIPPED = 4

    def is_active(self) -> bool:
        return self is not NodeStatus.IDLE and self is not NodeStatus.SKIPPED

    def is_completed(self) -> bool:
        return self is NodeStatus.SUCCESS or self is NodeStatus.FAILURE

    def __str__(self) -> str:
        return self.name


class NodeType(IntEnum):
    UNDEFINED = 0
    ACTION = 1
    CONDITION = 2
    CONTROL = 3
    DECORATOR = 4
    SUBTREE = 5

    @property
    def xml_name(self) -> str:
        """The element name BT.CPP uses for this type in TreeNodesModel ('Action', ...)."""
        return _NODE_TYPE_NAMES.get(self, "Undefined")

    @classmethod
    def from_xml_name(cls, text: str) -> NodeType:
        for value, name in _NODE_TYPE_NAMES.items():
            if name == text:
                return value
        return cls.UNDEFINED

    @classmethod
    def from_string(cls, text: str) -> NodeType:
        """BT.CPP's ``convertFromString<NodeType>``: "Action", "Condition", ...; anything else
        is UNDEFINED (never an error)."""
        return cls.from_xml_name(text)


_NODE_TYPE_NAMES = {
    NodeType.ACTION: "Action",
    NodeType.CONDITION: "Condition",
    NodeType.CONTROL: "Control",
    NodeType.DECORATOR: "Decorator",
    NodeType.SUBTREE: "SubTree",
}


class PortDirection(IntEnum):
    INPUT = 0
    OUTPUT = 1
    INOUT = 2

    @property
    def xml_tag(self) -> str:
        return ("input_port", "output_port", "inout_port")[self]

    @property
    def display_name(self) -> str:
        """BT.CPP's ``toStr(PortDirection)``: "Input", "Output", "InOut"."""
        return ("Input", "Output", "InOut")[self]

    @classmethod
    def from_string(cls, text: str) -> PortDirection:
        """BT.CPP's ``convertFromString<PortDirection>``: "Input"/"INPUT", "Output"/"OUTPUT",
        "InOut"/"INOUT"; anything else raises BTRuntimeError."""
        direction = _DIRECTION_NAMES.get(text)
        if direction is None:
            from .errors import BTRuntimeError

            raise BTRuntimeError(f"Cannot convert this to PortDirection: {text}")
        return direction


_DIRECTION_NAMES = {"Input": PortDirection.INPUT, "INPUT": PortDirection.INPUT,
                    "Output": PortDirection.OUTPUT, "OUTPUT": PortDirection.OUTPUT,
                    "InOut": PortDirection.INOUT, "INOUT": PortDirection.INOUT}

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE
SKIPPED = NodeStatus.SKIPPED

STATUS_BY_NAME = {s.name: s for s in NodeStatus}
