"""Parallel (success/failure thresholds, early exit) and ParallelAll (spec 4.2)."""

from __future__ import annotations

from ..errors import BTRuntimeError, LogicError
from ..node import ControlNode, NodeConfig, tick_cell
from ..ports import input_port
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _effective(threshold: int, n: int) -> int:
    return max(n + threshold + 1, 0) if threshold < 0 else threshold


class ParallelNode(ControlNode):
    """Tick all children each tick; SUCCESS when ``success_count`` succeeded, FAILURE when
    ``failure_count`` failed (negative values count from the number of children)."""

    description = "Tick every child; succeed/fail by thresholds"

    @classmethod
    def provided_ports(cls):
        return [input_port("success_count", int, -1,
                           "number of children that need to succeed to trigger a SUCCESS"),
                input_port("failure_count", int, 1,
                           "number of children that need to fail to trigger a FAILURE")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._completed: set[int] = set()
        self._successes = 0
        self._failures = 0
        super().__init__(name, config)

    def _clear(self) -> None:
        self._completed.clear()
        self._successes = 0
        self._failures = 0

    def tick(self) -> NodeStatus:
        try:
            s_raw = int(self.get_input("success_count"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [success_count] in ParallelNode") from None
        try:
            f_raw = int(self.get_input("failure_count"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [failure_count] in ParallelNode") from None
        cells = self._cells
        n = len(cells)
        s_eff = _effective(s_raw, n)
        f_eff = _effective(f_raw, n)
        if n < s_eff:
            raise LogicError("Number of children is less than threshold. Can never succeed.")
        if n < f_eff:
            raise LogicError("Number of children is less than threshold. Can never fail.")
        self._cell.status = RUNNING  # set_status(RUNNING)
        skipped = 0
        completed = self._completed
        for i, child in enumerate(cells):
            if i not in completed:
                status = tick_cell(child)  # child.execute_tick()
                if status is SKIPPED:
                    skipped += 1
                elif status is SUCCESS:
                    completed.add(i)
                    self._successes += 1
                elif status is FAILURE:
                    completed.add(i)
                    self._failures += 1
                elif status is IDLE:
                    raise LogicError(f"[{self.name}]: A children should not return IDLE")
            if self._successes >= s_eff or (s_raw < 0 and self._successes + skipped >= s_eff):
                self._clear()
                self.reset_children()
                return SUCCESS
            if (n - self._failures) < s_eff or self._failures == f_eff:
                self._clear()
                self.reset_children()
                return FAILURE
        return SKIPPED if skipped == n else RUNNING

    def halt(self) -> None:
        self._clear()
        ControlNode.halt(self)


class ParallelAllNode(ControlNode):
    """Run every child to completion; FAILURE if at least ``max_failures`` failed."""

    description = "Tick every child until all complete"

    @classmethod
    def provided_ports(cls):
        return [input_port("max_failures", int, 1,
                           "If the number of children returning FAILURE exceeds this value, "
                           "ParallelAll returns FAILURE")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._completed: set[int] = set()
        self._failures = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        try:
            max_failures = int(self.get_input("max_failures"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [max_failures] in ParallelNode") from None
        cells = self._cells
        n = len(cells)
        threshold = _effective(max_failures, n)
        if n < threshold:
            raise LogicError("Number of children is less than threshold. Can never fail.")
        self._cell.status = RUNNING  # set_status(RUNNING)
        skipped = 0
        completed = self._completed
        for i, child in enumerate(cells):
            if i in completed:
                continue
            status = tick_cell(child)  # child.execute_tick()
            if status is SUCCESS:
                completed.add(i)
            elif status is FAILURE:
                completed.add(i)
                self._failures += 1
            elif status is SKIPPED:
                skipped += 1
            elif status is IDLE:
                raise LogicError(f"[{self.name}]: A children should not return IDLE")
        if skipped == n:
            return SKIPPED
        if skipped + len(completed) >= n:
            self.reset_children()
            completed.clear()
            result = FAILURE if self._failures >= threshold else SUCCESS
            self._failures = 0
            return result
        return RUNNING

    def halt(self) -> None:
        self._completed.clear()
        self._failures = 0
        ControlNode.halt(self)
