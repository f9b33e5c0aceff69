"""Nodes that react to blackboard writes through the entries' sequence ids (spec 4.3, 4.5):
SkipUnlessUpdated, WaitValueUpdate (decorators) and WasEntryUpdated (action)."""

from __future__ import annotations

from ..errors import LogicError
from ..node import DecoratorNode, NodeConfig, SyncActionNode, tick_cell
from ..ports import ANY, blackboard_key, input_port
from ..status import FAILURE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _entry_key(config: NodeConfig, name: str) -> str:
    raw = config.input_ports.get("entry")
    if not raw:
        raise LogicError(f"Missing port 'entry' in {name}")
    key = blackboard_key(raw, "entry")
    return key if key is not None else raw


class EntryUpdatedDecorator(DecoratorNode):
    """Tick the child only when ``entry`` was written since the last check."""

    if_not_updated: NodeStatus = SKIPPED

    @classmethod
    def provided_ports(cls):
        return [input_port("entry", ANY, description="Entry to check")]

    def __init__(self, name: str, config: NodeConfig):
        self._key = _entry_key(config, name)
        self._sequence_id = 0
        self._still_running = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self._still_running:
            status = tick_cell(self._child_cell)
            self._still_running = status is RUNNING
            return status
        entry = self.config.blackboard.get_entry(self._key)
        if entry is None:
            return self.if_not_updated
        previous, self._sequence_id = self._sequence_id, entry.sequence_id
        if previous == entry.sequence_id:
            return self.if_not_updated
        status = tick_cell(self._child_cell)
        self._still_running = status is RUNNING
        return status

    def halt(self) -> None:
        self._still_running = False
        DecoratorNode.halt(self)


class SkipUnlessUpdatedNode(EntryUpdatedDecorator):
    if_not_updated = SKIPPED


class WaitValueUpdateNode(EntryUpdatedDecorator):
    if_not_updated = RUNNING


class WasEntryUpdatedNode(SyncActionNode):
    """SUCCESS if ``entry`` was written since this node last looked, else FAILURE."""

    @classmethod
    def provided_ports(cls):
        return [input_port("entry", ANY, description="Entry to check")]

    def __init__(self, name: str, config: NodeConfig):
        self._key = _entry_key(config, name)
        self._sequence_id = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        entry = self.config.blackboard.get_entry(self._key)
        if entry is None:
            return FAILURE
        previous, self._sequence_id = self._sequence_id, entry.sequence_id
        return SUCCESS if previous != entry.sequence_id else FAILURE
