"""Parallel (success/failure thresholds, early exit) and ParallelAll (spec 4.2).

Their ports are read every tick, as BT.CPP reads them, unless they are literals (or take their
defaults), which cannot change: then the thresholds are worked out once per number of children.
The children are ticked through their cells (``tick_cell`` inlined: one frame per child); the
children already completed are a bit mask in a slot (bit i: child i), not a set per node.
"""

from __future__ import annotations

from ..errors import BTRuntimeError, LogicError, NodeExecutionError
from ..node import ControlNode, NodeConfig, _is_execute_tick, _wrap_error
from ..ports import input_port
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _effective(threshold: int, n: int) -> int:
    return max(n + threshold + 1, 0) if threshold < 0 else threshold


class ParallelNode(ControlNode):
    """Tick all children each tick; SUCCESS when ``success_count`` succeeded, FAILURE when
    ``failure_count`` failed (negative values count from the number of children)."""

    __slots__ = ("_completed", "_successes", "_failures", "_limits")  # no per-node __dict__
    description = "Tick every child; succeed/fail by thresholds"

    @classmethod
    def provided_ports(cls):
        return [input_port("success_count", int, -1,
                           "number of children that need to succeed to trigger a SUCCESS"),
                input_port("failure_count", int, 1,
                           "number of children that need to fail to trigger a FAILURE")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._completed = 0  # bit mask of the children that completed
        self._successes = 0
        self._failures = 0
        # (number of children, success_count, effective success, effective failure) once both
        # ports are known to be constant and the thresholds were checked for that many children
        self._limits: tuple[int, int, int, int] | None = None
        super().__init__(name, config)

    def _clear(self) -> None:
        self._completed = 0
        self._successes = 0
        self._failures = 0

    def _read_limits(self, n: int) -> tuple[int, int, int, int]:
        try:
            s_raw = int(self.get_input("success_count"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [success_count] in ParallelNode") from None
        try:
            f_raw = int(self.get_input("failure_count"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [failure_count] in ParallelNode") from None
        s_eff = _effective(s_raw, n)
        f_eff = _effective(f_raw, n)
        if n < s_eff:
            raise LogicError("Number of children is less than threshold. Can never succeed.")
        if n < f_eff:
            raise LogicError("Number of children is less than threshold. Can never fail.")
        limits = (n, s_raw, s_eff, f_eff)
        if self.input_is_constant("success_count") and self.input_is_constant("failure_count"):
            self._limits = limits
        return limits

    def tick(self) -> NodeStatus:
        cells = self._cells
        n = len(cells)
        limits = self._limits
        if limits is None or limits[0] != n:
            limits = self._read_limits(n)
        _, s_raw, s_eff, f_eff = limits
        self._cell.status = RUNNING  # set_status(RUNNING)
        skipped = 0
        completed = self._completed
        successes = self._successes
        failures = self._failures
        bit = 1
        for child in cells:
            if not completed & bit:
                # -- status = tick_cell(child) (child.execute_tick()), inlined for speed ----------
                fast = child.fast
                try:
                    status = fast(child.node)
                except NodeExecutionError:
                    raise
                except Exception as exc:
                    if _is_execute_tick(fast, child.node):  # execute_tick's own error
                        raise
                    raise _wrap_error(child, exc) from exc
                # ---------------------------------------------------------------------------------
                # (the state is stored as it changes: a later child's error leaves it as BT.CPP does)
                if status is SUCCESS:
                    child.status = status
                    self._completed = completed = completed | bit
                    self._successes = successes = successes + 1
                elif status is FAILURE:
                    child.status = status
                    self._completed = completed = completed | bit
                    self._failures = failures = failures + 1
                elif status is SKIPPED:
                    skipped += 1
                else:
                    if status is IDLE:
                        child.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
                    child.status = status
            if successes >= s_eff or (s_raw < 0 and successes + skipped >= s_eff):
                result = SUCCESS
                break
            if (n - failures) < s_eff or failures == f_eff:
                result = FAILURE
                break
            bit <<= 1
        else:
            return SKIPPED if skipped == n else RUNNING
        self._completed = 0  # _clear(), inlined
        self._successes = 0
        self._failures = 0
        for cell in cells:  # reset_children(), inlined for speed
            status = cell.status
            if status is not IDLE:
                if status is RUNNING:
                    cell.node.halt_node()
                cell.status = IDLE  # notifies if observed
        return result

    def halt(self) -> None:
        self._clear()
        ControlNode.halt(self)


class ParallelAllNode(ControlNode):
    """Run every child to completion; FAILURE if at least ``max_failures`` failed."""

    __slots__ = ("_completed", "_failures", "_limits")
    description = "Tick every child until all complete"

    @classmethod
    def provided_ports(cls):
        return [input_port("max_failures", int, 1,
                           "If the number of children returning FAILURE exceeds this value, "
                           "ParallelAll returns FAILURE")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._completed = 0  # bit mask of the children that completed
        self._failures = 0
        self._limits: tuple[int, int] | None = None  # (children, effective threshold) if constant
        super().__init__(name, config)

    def _read_limits(self, n: int) -> tuple[int, int]:
        try:
            max_failures = int(self.get_input("max_failures"))
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [max_failures] in ParallelNode") from None
        threshold = _effective(max_failures, n)
        if n < threshold:
            raise LogicError("Number of children is less than threshold. Can never fail.")
        limits = (n, threshold)
        if self.input_is_constant("max_failures"):
            self._limits = limits
        return limits

    def tick(self) -> NodeStatus:
        cells = self._cells
        n = len(cells)
        limits = self._limits
        if limits is None or limits[0] != n:
            limits = self._read_limits(n)
        threshold = limits[1]
        self._cell.status = RUNNING  # set_status(RUNNING)
        skipped = 0
        completed = self._completed
        bit = 1
        for child in cells:
            if completed & bit:
                bit <<= 1
                continue
            # -- status = tick_cell(child) (child.execute_tick()), inlined for speed --------------
            fast = child.fast
            try:
                status = fast(child.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, child.node):  # execute_tick's own error
                    raise
                raise _wrap_error(child, exc) from exc
            # -------------------------------------------------------------------------------------
            if status is SUCCESS:
                child.status = status
                self._completed = completed = completed | bit
            elif status is FAILURE:
                child.status = status
                self._completed = completed = completed | bit
                self._failures += 1
            elif status is SKIPPED:
                skipped += 1
            else:
                if status is IDLE:
                    child.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
                child.status = status
            bit <<= 1
        if skipped == n:
            return SKIPPED
        if skipped + completed.bit_count() >= n:
            for cell in cells:  # reset_children(), inlined for speed
                status = cell.status
                if status is not IDLE:
                    if status is RUNNING:
                        cell.node.halt_node()
                    cell.status = IDLE  # notifies if observed
            self._completed = 0
            result = FAILURE if self._failures >= threshold else SUCCESS
            self._failures = 0
            return result
        return RUNNING

    def halt(self) -> None:
        self._completed = 0
        self._failures = 0
        ControlNode.halt(self)
