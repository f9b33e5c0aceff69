"""LoopInt / LoopBool / LoopDouble / LoopString: tick the child once per queue element.

The queue is a literal ``a;b;c`` (parsed once at construction, copied per activation) or a
blackboard entry. A ``collections.deque`` in the blackboard is a *shared* queue, consumed in
place (BT.CPP's SharedQueue); a list or a string is copied once per activation (4.10's vector
and string support). Returns RUNNING after every element, SUCCESS (``if_empty``) after the
last: ``queue="1;2;3"`` gives RUNNING, RUNNING, RUNNING, SUCCESS.
"""

from __future__ import annotations

from collections import deque

from ..errors import BTRuntimeError
from ..node import DecoratorNode, NodeConfig, tick_cell
from ..ports import (
    BOOL,
    DOUBLE,
    EMPTY,
    INT,
    STRING,
    PortType,
    bidirectional_port,
    blackboard_key,
    input_port,
    output_port,
    split_list,
)
from ..status import FAILURE, IDLE, RUNNING, SUCCESS, NodeStatus


class LoopNode(DecoratorNode):
    _bare_tick_ok = True  # tick() resets a completed child itself

    element: PortType = INT

    @classmethod
    def provided_ports(cls):
        return [bidirectional_port("queue"),
                input_port("if_empty", NodeStatus, SUCCESS,
                           "Status to return if queue is empty: SUCCESS, FAILURE, SKIPPED"),
                output_port("value", cls.element)]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._child_running = False
        self._current: deque | None = None
        super().__init__(name, config)
        raw = self.get_raw_port_value("queue") or ""
        self._queue_key = blackboard_key(raw, "queue")
        self._static = None if self._queue_key is not None else self._parse(raw)

    def _parse(self, text: str) -> list:
        return [self.element.from_string(part) for part in split_list(text)]

    def _load_from_blackboard(self) -> None:
        entry = self.config.blackboard.get_entry(self._queue_key)
        value = EMPTY if entry is None else entry.value
        if isinstance(value, deque):
            self._current = value
        elif self._current is None:
            if isinstance(value, (list, tuple)):
                self._current = deque(self.element.coerce(v) for v in value)
            elif isinstance(value, str):
                self._current = deque(self._parse(value))
            else:
                raise BTRuntimeError("LoopNode: port 'queue' must contain either SharedQueue<T>, "
                                     "std::vector<T>, or a string")

    def tick(self) -> NodeStatus:
        popped = False
        if self._cell.status is IDLE:
            self._child_running = False
            self._current = deque(self._static) if self._static is not None else None
        if not self._child_running:
            if self._static is None:
                self._load_from_blackboard()
            if self._current:
                self.set_output("value", self._current.popleft())
                popped = True
        if not popped and not self._child_running:
            return self.get_input("if_empty")
        if self._cell.status is IDLE:
            self.set_status(RUNNING)
        status = tick_cell(self._child_cell)
        self._child_running = status is RUNNING
        if status is SUCCESS or status is FAILURE:
            self.reset_child()
        if status is FAILURE:
            return FAILURE
        return RUNNING


def loop_class(name: str, element: PortType) -> type[LoopNode]:
    return type(name, (LoopNode,), {"element": element, "__doc__": LoopNode.__doc__})


LoopIntNode = loop_class("LoopIntNode", INT)
LoopBoolNode = loop_class("LoopBoolNode", BOOL)
LoopDoubleNode = loop_class("LoopDoubleNode", DOUBLE)
LoopStringNode = loop_class("LoopStringNode", STRING)
