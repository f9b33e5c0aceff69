"""Stateless-ish decorators: Inverter, ForceSuccess/Failure, KeepRunningUntilFailure, Repeat,
RetryUntilSuccessful, RunOnce, Precondition, SubTree (spec 4.3, 4.4)."""

from __future__ import annotations

from ..errors import BTRuntimeError, LogicError, NodeExecutionError
from ..node import DecoratorNode, NodeConfig, _is_execute_tick, _wrap_error, tick_cell
from ..ports import BOOL, PortInfo, blackboard_key, input_port
from ..script import compile_node_script
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus, NodeType, PortDirection


def _idle(node: DecoratorNode) -> LogicError:
    return LogicError(f"[{node.name}]: A children should not return IDLE")


class InverterNode(DecoratorNode):
    _bare_tick_ok = True  # tick() resets a completed child itself

    def tick(self) -> NodeStatus:
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        # -- status = tick_cell(child), inlined for speed ------------------------------------
        fast = child.fast
        try:
            status = fast(child.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                raise
            raise _wrap_error(child, exc) from exc
        if status is not SKIPPED:
            if status is IDLE:
                child.node.set_status(status)  # raises
            child.status = status
        # -------------------------------------------------------------------------------------
        if status is SUCCESS or status is FAILURE:
            if child.status is RUNNING:  # reset_child(), inlined
                child.node.halt_node()
            child.status = IDLE
            return FAILURE if status is SUCCESS else SUCCESS
        if status is RUNNING or status is SKIPPED:
            return status
        raise _idle(self)


class ForceSuccessNode(DecoratorNode):
    _bare_tick_ok = True  # tick() resets a completed child itself

    def tick(self) -> NodeStatus:
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        # -- status = tick_cell(child), inlined for speed ------------------------------------
        fast = child.fast
        try:
            status = fast(child.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                raise
            raise _wrap_error(child, exc) from exc
        # -------------------------------------------------------------------------------------
        if status is SUCCESS or status is FAILURE:
            child.status = status
            child.status = IDLE  # reset_child(): a completed child is not RUNNING
            return SUCCESS
        if status is not SKIPPED:
            if status is IDLE:
                child.node.set_status(status)  # raises
            child.status = status
        return status


class ForceFailureNode(DecoratorNode):
    _bare_tick_ok = True  # tick() resets a completed child itself

    def tick(self) -> NodeStatus:
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        # -- status = tick_cell(child), inlined for speed ------------------------------------
        fast = child.fast
        try:
            status = fast(child.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                raise
            raise _wrap_error(child, exc) from exc
        # -------------------------------------------------------------------------------------
        if status is SUCCESS or status is FAILURE:
            child.status = status
            child.status = IDLE  # reset_child(): a completed child is not RUNNING
            return FAILURE
        if status is not SKIPPED:
            if status is IDLE:
                child.node.set_status(status)  # raises
            child.status = status
        return status


class KeepRunningUntilFailureNode(DecoratorNode):
    _bare_tick_ok = True  # tick() resets a completed child itself

    def tick(self) -> NodeStatus:
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        # -- status = tick_cell(child), inlined for speed ------------------------------------
        fast = child.fast
        try:
            status = fast(child.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                raise
            raise _wrap_error(child, exc) from exc
        if status is not SKIPPED:
            if status is IDLE:
                child.node.set_status(status)  # raises
            child.status = status
        # -------------------------------------------------------------------------------------
        if status is FAILURE:
            child.status = IDLE  # reset_child(): a completed child is not RUNNING
            return FAILURE
        if status is SUCCESS:
            child.status = IDLE
            return RUNNING
        if status is RUNNING:
            return RUNNING
        return self._cell.status


class _CountingDecorator(DecoratorNode):
    """Repeat and RetryUntilSuccessful: a decorator with an int port read every tick, unless
    it is a literal (or its default), which cannot change: then it is read once."""

    __slots__ = ("_limit",)  # the port's value, once known to be constant (else None)
    _bare_tick_ok = True  # tick() resets a completed child itself
    _port = ""
    _missing = ""

    def _read_limit(self) -> int:
        try:
            n = self.get_input(self._port)
        except BTRuntimeError:
            raise BTRuntimeError(self._missing) from None
        if self.input_is_constant(self._port):
            self._limit = n
        return n


class RepeatNode(_CountingDecorator):
    """Repeat a successful child ``num_cycles`` times (-1: forever)."""

    __slots__ = ("_count",)
    _port = "num_cycles"
    _missing = "Missing parameter [num_cycles] in RepeatNode"

    @classmethod
    def provided_ports(cls):
        return [input_port("num_cycles", int, description="Repeat a successful child up to N times. "
                                                            "Use -1 to create an infinite loop.")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._count = 0
        self._limit = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        n = self._limit
        if n is None:
            n = self._read_limit()
        loop = self._count < n or n == -1
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        while loop:
            prev = child.status
            # -- status = tick_cell(child), inlined for speed --------------------------------
            fast = child.fast
            try:
                status = fast(child.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                    raise
                raise _wrap_error(child, exc) from exc
            # ---------------------------------------------------------------------------------
            if status is SUCCESS:
                child.status = status
                self._count += 1
                loop = self._count < n or n == -1
                child.status = IDLE  # reset_child(): a completed child is not RUNNING
                if prev is IDLE and loop:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is FAILURE:
                child.status = status
                self._count = 0
                child.status = IDLE
                return FAILURE
            elif status is RUNNING:
                child.status = status
                return RUNNING
            elif status is SKIPPED:
                self.reset_child()
                return SKIPPED
            else:
                if status is IDLE:
                    child.node.set_status(status)  # raises
                child.status = status
                raise _idle(self)
        self._count = 0
        return SUCCESS

    def halt(self) -> None:
        self._count = 0
        DecoratorNode.halt(self)


class RetryNode(_CountingDecorator):
    """Retry a failing child up to ``num_attempts`` times (-1: forever)."""

    __slots__ = ("_tries",)
    _port = "num_attempts"
    _missing = "Missing parameter [num_attempts] in RetryNode"

    @classmethod
    def provided_ports(cls):
        return [input_port("num_attempts", int, description="Execute again a failing child up to N times. "
                                                              "Use -1 to create an infinite loop.")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._tries = 0
        self._limit = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        n = self._limit
        if n is None:
            n = self._read_limit()
        loop = self._tries < n or n == -1
        self._cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        while loop:
            prev = child.status
            # -- status = tick_cell(child), inlined for speed --------------------------------
            fast = child.fast
            try:
                status = fast(child.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                    raise
                raise _wrap_error(child, exc) from exc
            # ---------------------------------------------------------------------------------
            if status is SUCCESS:
                child.status = status
                self._tries = 0
                child.status = IDLE  # reset_child(): a completed child is not RUNNING
                return SUCCESS
            if status is FAILURE:
                child.status = status
                self._tries += 1
                if self._limit is None:  # a blackboard entry: re-read (BT.CPP re-reads it here)
                    n = self.get_input("num_attempts", n)
                loop = self._tries < n or n == -1
                child.status = IDLE
                if prev is IDLE and loop:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is RUNNING:
                child.status = status
                return RUNNING
            elif status is SKIPPED:
                self.reset_child()
                return SKIPPED
            else:
                if status is IDLE:
                    child.node.set_status(status)  # raises
                child.status = status
                raise _idle(self)
        self._tries = 0
        return FAILURE

    def halt(self) -> None:
        self._tries = 0
        DecoratorNode.halt(self)


class RunOnceNode(DecoratorNode):
    """Run the child to completion once for the life of the node; then skip (or repeat the
    remembered status when ``then_skip`` is false)."""

    _bare_tick_ok = True  # tick() resets a completed child itself

    @classmethod
    def provided_ports(cls):
        return [input_port("then_skip", bool, True,
                           "If true, skip after the first execution, otherwise return the same "
                           "NodeStatus returned once by the child.")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._done = False
        self._returned = IDLE
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        skip = self.get_input("then_skip", True)
        if self._done:
            return SKIPPED if skip else self._returned
        self._cell.status = RUNNING  # set_status(RUNNING)
        status = tick_cell(self._child_cell)
        if status is SUCCESS or status is FAILURE:
            self._done = True
            self._returned = status
            self.reset_child()
        return status


class PreconditionNode(DecoratorNode):
    """Tick the child only if the ``if`` script is true, else return ``else``; the script is
    not re-checked while the child runs (and, as in BT.CPP, not after a halt either)."""

    _bare_tick_ok = True  # tick() resets a completed child itself

    @classmethod
    def provided_ports(cls):
        return [input_port("if", str),
                input_port("else", NodeStatus, FAILURE, "Return status if condition is false")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._script_text: str | None = None
        self._script = None
        self._children_running = False
        super().__init__(name, config)
        raw = self.config.input_ports.get("if")
        # a literal script cannot change: compile it once (only {key} scripts are re-read)
        self._if_from_blackboard = isinstance(raw, str) and blackboard_key(raw, "if") is not None
        self._load()

    def _load(self) -> None:
        try:
            text = self.get_input("if")
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [if] in Precondition") from None
        if text != self._script_text:
            self._script = compile_node_script(text)
            self._script_text = text

    def tick(self) -> NodeStatus:
        if self._if_from_blackboard:
            self._load()
        try:
            else_status = self.get_input("else")
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [else] in Precondition") from None
        cfg = self.config
        if not self._children_running:
            self._children_running = self._script.run_bool(cfg.blackboard, cfg.enums)
        if not self._children_running:
            return else_status
        status = tick_cell(self._child_cell)
        if status is SUCCESS or status is FAILURE:
            self.reset_child()
            self._children_running = False
        return status


class SubTreeNode(DecoratorNode):
    """The node standing for an expanded <SubTree>; its child is the subtree's root, its
    ``subtree_id`` the ID of the tree it expands."""

    __slots__ = ("subtree_id",)
    _bare_tick_ok = True  # tick() resets a completed child itself

    node_type = NodeType.SUBTREE

    def __init__(self, name: str, config: NodeConfig | None = None, subtree_id: str = ""):
        self.subtree_id = subtree_id
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            DecoratorNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    @staticmethod
    def _built(name: str, config: NodeConfig, subtree_id: str) -> SubTreeNode:
        """``SubTreeNode(name, config, subtree_id)`` without the type call and the first
        ``__init__`` frame: what the tree builder calls, once per SubTree expanded."""
        node = _new_node(SubTreeNode)
        node.subtree_id = subtree_id
        _decorator_init(node, name, config)
        return node

    @classmethod
    def provided_ports(cls):
        # '_autoremap' is reserved for users; BT.CPP declares it for SubTree only.
        return [PortInfo("_autoremap", PortDirection.INPUT, BOOL, False,
                         "If true, all the ports with the same name will be remapped")]

    def tick(self) -> NodeStatus:
        cell = self._cell
        if cell.status is IDLE:
            cell.status = RUNNING  # set_status(RUNNING)
        child = self._child_cell
        # -- status = tick_cell(child), inlined: every level of a SubTree chain pays it ----------
        fast = child.fast
        try:
            status = fast(child.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            if _is_execute_tick(fast, child.node):  # not the bare tick: execute_tick's own error
                raise
            raise _wrap_error(child, exc) from exc
        if status is not SKIPPED:
            if status is IDLE:
                child.node.set_status(status)  # raises
            child.status = status
        # -------------------------------------------------------------------------------------
        if status is SUCCESS or status is FAILURE:
            if child.status is RUNNING:  # reset_child(), inlined
                child.node.halt_node()
            child.status = IDLE
        return status


_new_node = object.__new__
_decorator_init = DecoratorNode.__init__
