"""IfThenElse, WhileDoElse, Switch2..6 and TryCatch (spec 4.2), quirks included.

Quirks kept on purpose because trees behave differently otherwise: IfThenElse does not reset
a FAILED condition when it has no else branch; WhileDoElse never resets its condition while a
branch runs; a skipped condition raises in both.
"""

from __future__ import annotations

import re

from ..errors import BehaviorTreeException, LogicError, NodeExecutionError
from ..node import ControlNode, NodeConfig, _is_execute_tick, _wrap_error
from ..ports import input_port, parse_float
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus

_FLT_EPSILON = 1.1920928955078125e-07
_FULL_INT = re.compile(r"-?[0-9]+")
_FULL_DOUBLE = re.compile(r"-?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|-?inf(?:inity)?|-?nan",
                          re.IGNORECASE)


class IfThenElseNode(ControlNode):
    """condition, then-branch, optional else-branch; the condition is not re-checked while
    a branch runs."""

    __slots__ = ("_child_idx",)  # (hot state in slots: no per-node __dict__ to touch)

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._child_idx = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        cells = self._cells  # the children's cells
        n = len(cells)
        if n != 2 and n != 3:
            raise LogicError("IfThenElseNode must have either 2 or 3 children")
        self._cell.status = RUNNING  # set_status(RUNNING)
        idx = self._child_idx
        if idx == 0:
            cell = cells[0]
            # -- cond = tick_cell(cell) (child.execute_tick()), inlined for speed ----------------
            fast = cell.fast
            try:
                cond = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                    raise
                raise _wrap_error(cell, exc) from exc
            if cond is not SKIPPED:
                if cond is IDLE:
                    cell.node.set_status(cond)  # raises, as BT.CPP's setStatus(IDLE) does
                cell.status = cond
            # ---------------------------------------------------------------------------------------
            if cond is RUNNING:
                return RUNNING
            if cond is SUCCESS:
                idx = self._child_idx = 1
            elif cond is FAILURE:
                if n == 3:
                    idx = self._child_idx = 2
                else:
                    return FAILURE
        if idx > 0:
            cell = cells[idx]
            # -- status = tick_cell(cell) (child.execute_tick()), inlined for speed ----------------
            fast = cell.fast
            try:
                status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                    raise
                raise _wrap_error(cell, exc) from exc
            if status is not SKIPPED:
                if status is IDLE:
                    cell.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
                cell.status = status
            # ---------------------------------------------------------------------------------------
            if status is RUNNING:
                return RUNNING
            for cell in cells:  # reset_children(), inlined for speed
                child_status = cell.status
                if child_status is not IDLE:
                    if child_status is RUNNING:
                        cell.node.halt_node()
                    cell.status = IDLE  # notifies if observed
            self._child_idx = 0
            return status
        raise LogicError("Something unexpected happened in IfThenElseNode")

    def halt(self) -> None:
        self._child_idx = 0
        ControlNode.halt(self)


class WhileDoElseNode(ControlNode):
    """Reactive if/else: the condition is ticked every tick and switches branches."""

    def tick(self) -> NodeStatus:
        cells = self._cells  # the children's cells
        n = len(cells)
        if n != 2 and n != 3:
            raise LogicError("WhileDoElseNode must have either 2 or 3 children")
        self._cell.status = RUNNING  # set_status(RUNNING)
        cell = cells[0]
        # -- cond = tick_cell(cell) (child.execute_tick()), inlined for speed ----------------
        fast = cell.fast
        try:
            cond = fast(cell.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                raise
            raise _wrap_error(cell, exc) from exc
        if cond is not SKIPPED:
            if cond is IDLE:
                cell.node.set_status(cond)  # raises, as BT.CPP's setStatus(IDLE) does
            cell.status = cond
        # ---------------------------------------------------------------------------------------
        if cond is RUNNING:
            return RUNNING
        status = IDLE
        take = 0  # the branch to tick: 1 (then) on SUCCESS, 2 (else, if any) on FAILURE
        if cond is SUCCESS:
            take = 1
        elif cond is FAILURE:
            if n == 3:
                take = 2
            else:
                status = FAILURE
        if take:
            if n == 3:
                cell = cells[3 - take]  # halt_child(the other branch), inlined
                if cell.status is RUNNING:
                    cell.node.halt_node()
                cell.status = IDLE
            cell = cells[take]
            # -- status = tick_cell(cell) (child.execute_tick()), inlined for speed ----------------
            fast = cell.fast
            try:
                status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                    raise
                raise _wrap_error(cell, exc) from exc
            if status is not SKIPPED:
                if status is IDLE:
                    cell.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
                cell.status = status
            # ---------------------------------------------------------------------------------------
        if status is RUNNING:
            return RUNNING
        for cell in cells:  # reset_children(), inlined for speed
            child_status = cell.status
            if child_status is not IDLE:
                if child_status is RUNNING:
                    cell.node.halt_node()
                cell.status = IDLE  # notifies if observed
        return status


def _to_int(text: str, enums: dict[str, int]) -> int | None:
    if text in enums:
        return enums[text]
    if _FULL_INT.fullmatch(text):
        value = int(text)
        if -(2**31) <= value < 2**31:
            return value
    return None


def _to_real(text: str, enums: dict[str, int]) -> float | None:
    if text in enums:
        return float(enums[text])
    if _FULL_DOUBLE.fullmatch(text):
        try:
            return parse_float(text)
        except BehaviorTreeException:
            return None
    return None


def switch_case_matches(a: str, b: str, enums: dict[str, int]) -> bool:
    """BT.CPP CheckStringEquality: identical, or equal as ints, or as doubles within FLT_EPSILON."""
    if a == b:
        return True
    ia, ib = _to_int(a, enums), _to_int(b, enums)
    if ia is not None and ib is not None and ia == ib:
        return True
    ra, rb = _to_real(a, enums), _to_real(b, enums)
    return ra is not None and rb is not None and abs(ra - rb) <= _FLT_EPSILON


class SwitchNode(ControlNode):
    """Tick the child whose ``case_i`` equals ``variable``; the last child is the default."""

    __slots__ = ("_running_child", "_cases")
    num_cases = 2

    @classmethod
    def provided_ports(cls):
        ports = [input_port("variable", str)]
        ports += [input_port(f"case_{i}", str) for i in range(1, cls.num_cases + 1)]
        return ports

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._running_child = -1
        self._cases: tuple[str | None, ...] | None = None  # the case values, once known to be literals
        super().__init__(name, config)

    def _case_values(self) -> tuple[str | None, ...] | None:
        """The ``case_i`` values, if every one is a literal (they then never change), else None."""
        names = [f"case_{i + 1}" for i in range(self.num_cases)]
        if not all(self.input_is_constant(name) for name in names):
            return None
        cases = self._cases = tuple(self.get_input(name, None) for name in names)
        return cases

    def tick(self) -> NodeStatus:
        k = self.num_cases
        cells = self._cells
        if len(cells) != k + 1:
            raise LogicError("Wrong number of children in SwitchNode; must be (num_cases + default)")
        match = k
        variable = self.get_input("variable", None)
        if variable is not None:
            enums = self.config.enums
            cases = self._cases
            if cases is None and (cases := self._case_values()) is None:
                for i in range(k):  # cases taken from the blackboard: read them every tick
                    value = self.get_input(f"case_{i + 1}", None)
                    if value is not None and switch_case_matches(variable, value, enums):
                        match = i
                        break
            else:
                for i, value in enumerate(cases):
                    if value is not None and (variable == value or switch_case_matches(variable, value, enums)):
                        match = i
                        break
        running = self._running_child
        if running != -1 and running != match:
            self.halt_child(running)
        cell = cells[match]
        # -- status = tick_cell(cell) (child.execute_tick()), inlined for speed -----------------
        fast = cell.fast
        try:
            status = fast(cell.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                raise
            raise _wrap_error(cell, exc) from exc
        if status is SKIPPED:
            self._running_child = -1
            return SKIPPED
        if status is IDLE:
            cell.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
        cell.status = status
        # ----------------------------------------------------------------------------------------
        if status is RUNNING:
            self._running_child = match
        else:
            for cell in cells:  # reset_children(), inlined for speed
                child_status = cell.status
                if child_status is not IDLE:
                    if child_status is RUNNING:
                        cell.node.halt_node()
                    cell.status = IDLE  # notifies if observed
            self._running_child = -1
        return status

    def halt(self) -> None:
        self._running_child = -1
        ControlNode.halt(self)


def switch_class(k: int) -> type[SwitchNode]:
    return type(f"Switch{k}Node", (SwitchNode,), {"num_cases": k, "__doc__": SwitchNode.__doc__})


class TryCatchNode(ControlNode):
    """Run children 0..N-2 like a Sequence; on a failure run the last (catch) child, then
    FAILURE. ``catch_on_halt`` also runs the catch child when halted mid-try (BT.CPP 4.9+)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("catch_on_halt", bool, False,
                           "If true, the catch child is also executed when the node is halted")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        self._in_catch = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        children = self.children
        n = len(children)
        if n < 2:
            raise LogicError(f"[{self.name}]: TryCatch requires at least 2 children")
        if self._cell.status is IDLE:
            self._skipped = 0
            self._in_catch = False
        self.set_status(RUNNING)
        try_count = n - 1
        if self._in_catch:
            status = children[-1].execute_tick()
            if status is RUNNING:
                return RUNNING
            self.reset_children()
            self._idx = 0
            self._in_catch = False
            return FAILURE
        while self._idx < try_count:
            status = children[self._idx].execute_tick()
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                self.reset_children()
                self._idx = 0
                self._in_catch = True
                return self.tick()
            if status is SUCCESS:
                self._idx += 1
            elif status is SKIPPED:
                self._idx += 1
                self._skipped += 1
            else:
                raise LogicError(f"[{self.name}]: A child should not return IDLE")
        all_skipped = self._skipped == try_count
        self.reset_children()
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        catch_on_halt = bool(self.get_input("catch_on_halt", False))
        children = self.children
        if (catch_on_halt and not self._in_catch and self._cell.status is not IDLE and len(children) >= 2):
            for i in range(len(children) - 1):
                self.halt_child(i)
            if children[-1].execute_tick() is RUNNING:
                self.halt_child(len(children) - 1)
        self._idx = 0
        self._skipped = 0
        self._in_catch = False
        ControlNode.halt(self)
