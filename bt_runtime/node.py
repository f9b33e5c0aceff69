"""Node base classes with BT.CPP's tick, halt and status semantics (spec 3 and 4.0).

A parent always calls ``child.execute_tick()``, never ``tick()``. ``execute_tick`` evaluates
pre-conditions, calls ``tick()``, runs post-conditions, and stores the status (SKIPPED is
returned but never stored). Nodes with no pre/post scripts and no hooks take a fast path: the
per-tick cost of the common case is one Python call per node plus a status store.

User node kinds: SyncActionNode, ConditionNode, StatefulActionNode (on_start / on_running /
on_halted), AsyncActionNode (``async def run(self)``: started on the first tick, polled each
tick, cancelled on halt), ControlNode, DecoratorNode. A tick never awaits.
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable, Iterable
from typing import Any, ClassVar

from .blackboard import Blackboard
from .errors import BehaviorTreeException, BTRuntimeError, LogicError, NodeExecutionError
from .ports import EMPTY, PortInfo, blackboard_key, ports_dict
from .status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus, NodeType
from .timers import TimerQueue, WakeUpSignal

StatusCallback = Callable[[float, "TreeNode", NodeStatus, NodeStatus], None]
# A pre-tick hook returns SUCCESS/FAILURE to replace tick(), RUNNING to hold the node (it reports
# RUNNING without ticking, e.g. at a Groot2 breakpoint), anything else to tick normally.
PreTickHook = Callable[["TreeNode"], NodeStatus | None]
PostTickHook = Callable[["TreeNode", NodeStatus], NodeStatus | None]

_MISSING: Any = object()


class NodeConfig:
    """Everything a node gets at creation: blackboard, port remappings, identity, services."""

    __slots__ = ("blackboard", "enums", "input_ports", "output_ports", "manifest", "uid", "path",
                 "pre_conditions", "post_conditions", "other_attributes", "context", "wake_up",
                 "timers", "clock", "registration_id", "source")

    def __init__(self, blackboard: Blackboard | None = None, *, input_ports: dict[str, str] | None = None,
                 output_ports: dict[str, str] | None = None, enums: dict[str, int] | None = None,
                 manifest: TreeNodeManifest | None = None, uid: int = 0, path: str = "",
                 context: Any = None, wake_up: WakeUpSignal | None = None,
                 timers: TimerQueue | None = None, clock: Callable[[], float] | None = None):
        if blackboard is None:
            blackboard = Blackboard()
        if wake_up is None:
            wake_up = WakeUpSignal()
        if timers is None:
            timers = TimerQueue()
        self.blackboard = blackboard
        self.enums = enums if enums is not None else {}
        self.input_ports = input_ports if input_ports is not None else {}
        self.output_ports = output_ports if output_ports is not None else {}
        self.manifest = manifest
        self.uid = uid
        self.path = path
        self.pre_conditions: dict[str, Any] = {}
        self.post_conditions: dict[str, Any] = {}
        self.other_attributes: dict[str, str] = {}
        self.context = context
        self.wake_up: WakeUpSignal = wake_up
        self.timers: TimerQueue = timers
        self.clock: Callable[[], float] = clock or timers.clock
        self.registration_id = manifest.registration_id if manifest else ""
        self.source: tuple[str | None, int | None] = (None, None)  # (file, line) for messages


class TreeNodeManifest:
    """What the factory knows about a registered node type (ports, type, description)."""

    __slots__ = ("registration_id", "node_type", "ports", "description", "metadata", "builtin")

    def __init__(self, registration_id: str, node_type: NodeType, ports: dict[str, PortInfo],
                 description: str = "", metadata: list[tuple[str, str]] | None = None,
                 builtin: bool = False):
        self.registration_id = registration_id
        self.node_type = node_type
        self.ports = ports
        self.description = description
        self.metadata = metadata or []
        self.builtin = builtin

    def __repr__(self) -> str:
        return f"TreeNodeManifest({self.registration_id!r}, {self.node_type.name}, ports={list(self.ports)})"


class TreeNode:
    """Base of every node. Subclasses implement ``tick()`` (and ``halt()`` when stateful).

    ``_fast`` is what a parent calls to tick this node: the bare ``tick`` when the node has
    no pre/post-condition scripts and no hooks (the parent then stores the status itself,
    saving a Python call per node), otherwise the full ``execute_tick``. Classes whose BT.CPP
    ``executeTick`` does extra work (decorators, sync actions) set ``_bare_tick_ok = False``.
    """

    __slots__ = ("name", "config", "_status", "_subscribers", "_pre_hook", "_post_hook", "_monitor",
                 "_input_cache", "_fast", "__dict__", "__weakref__")

    node_type: ClassVar[NodeType] = NodeType.UNDEFINED
    description: ClassVar[str] = ""
    _bare_tick_ok: ClassVar[bool] = True

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.name = name
        self.config = config if config is not None else NodeConfig()
        self._status = IDLE
        self._subscribers: list[StatusCallback] = []
        self._pre_hook: PreTickHook | None = None
        self._post_hook: PostTickHook | None = None
        self._monitor: Callable[[TreeNode, NodeStatus, float], None] | None = None
        self._input_cache: dict[str, Any] = {}
        self._select_execute_tick()

    # -- declaration ---------------------------------------------------------------------------
    @classmethod
    def provided_ports(cls) -> Iterable[PortInfo] | dict[str, PortInfo]:
        return ()

    @classmethod
    def metadata(cls) -> list[tuple[str, str]]:
        return []

    # -- identity ------------------------------------------------------------------------------
    @property
    def status(self) -> NodeStatus:
        return self._status

    @property
    def uid(self) -> int:
        return self.config.uid

    @property
    def full_path(self) -> str:
        return self.config.path

    @property
    def registration_name(self) -> str:
        return self.config.registration_id

    registration_id = registration_name

    @property
    def type(self) -> NodeType:
        return self.node_type

    @property
    def blackboard(self) -> Blackboard:
        return self.config.blackboard

    @property
    def context(self) -> Any:
        """The runtime context given to the factory (supervisor, backup, gate, driver)."""
        return self.config.context

    def children_nodes(self) -> list[TreeNode]:
        return []

    # -- status --------------------------------------------------------------------------------
    def set_status(self, new_status: NodeStatus) -> None:
        if new_status is IDLE:
            raise LogicError(f"Node [{self.name}]: you are not allowed to set manually the status to "
                             "IDLE. If you know what you are doing (?) use resetStatus() instead.")
        prev = self._status
        if prev is not new_status:
            self._status = new_status
            if self._subscribers:
                self._notify(prev, new_status)

    def reset_status(self) -> None:
        prev = self._status
        if prev is not IDLE:
            self._status = IDLE
            if self._subscribers:
                self._notify(prev, IDLE)

    def _notify(self, prev: NodeStatus, new: NodeStatus) -> None:
        stamp = self.config.clock()
        for callback in tuple(self._subscribers):
            callback(stamp, self, prev, new)

    def subscribe_to_status_change(self, callback: StatusCallback) -> Callable[[], None]:
        """Call ``callback(timestamp, node, previous, new)`` synchronously on every change."""
        self._subscribers.append(callback)

        def unsubscribe() -> None:
            if callback in self._subscribers:
                self._subscribers.remove(callback)

        return unsubscribe

    # -- hooks (Groot2 breakpoints, tests) -------------------------------------------------------
    def set_pre_tick_function(self, fn: PreTickHook | None) -> None:
        self._pre_hook = fn
        self._select_execute_tick()

    def set_post_tick_function(self, fn: PostTickHook | None) -> None:
        self._post_hook = fn
        self._select_execute_tick()

    def set_tick_monitor_callback(self, fn: Callable[[TreeNode, NodeStatus, float], None] | None) -> None:
        self._monitor = fn
        self._select_execute_tick()

    def _select_execute_tick(self) -> None:
        """Choose the fast path when there is nothing but ``tick()`` to run."""
        cfg = self.config
        if (cfg.pre_conditions or cfg.post_conditions or self._pre_hook or self._post_hook
                or self._monitor):
            self.execute_tick = self._execute_tick_full  # type: ignore[method-assign]
            self._fast = self._execute_tick_full
        else:
            self.__dict__.pop("execute_tick", None)
            self._fast = self._bare_tick() if self._bare_tick_ok else self.execute_tick

    def _bare_tick(self) -> Callable[[], NodeStatus]:
        return self.tick

    def refresh_conditions(self) -> None:
        """Re-select the tick path after pre/post-conditions were set on the config."""
        self._select_execute_tick()

    # -- ticking -------------------------------------------------------------------------------
    def tick(self) -> NodeStatus:
        raise NotImplementedError(f"{type(self).__name__}.tick() is not implemented")

    def halt(self) -> None:
        self.reset_status()

    def execute_tick(self) -> NodeStatus:
        """Fast path: no pre/post-conditions, no hooks."""
        try:
            status = self.tick()
        except NodeExecutionError:
            raise
        except Exception as exc:
            raise NodeExecutionError(self.config.path, self.config.registration_id, exc) from exc
        if status is not self._status:
            if status is not SKIPPED:
                self.set_status(status)
        elif status is IDLE:
            self.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
        return status

    def _execute_tick_full(self) -> NodeStatus:
        """BT.CPP executeTick: pre-conditions, hooks, tick, post-conditions, store (spec 3.1)."""
        status = self._check_pre_conditions()
        if status is None:
            pre = self._pre_hook
            if pre is not None and self._status is not SUCCESS and self._status is not FAILURE:
                hooked = pre(self)
                if hooked is SUCCESS or hooked is FAILURE:
                    status = hooked
                elif hooked is RUNNING:
                    # Held by the hook (a Groot2 breakpoint that must not block the event
                    # loop): report RUNNING without calling tick() or the post-conditions.
                    self.__dict__["_held"] = True
                    if self._status is not RUNNING:
                        self.set_status(RUNNING)
                    return RUNNING
            if status is None:
                monitor = self._monitor
                t0 = self.config.clock() if monitor is not None else 0.0
                try:
                    status = self.tick()
                except NodeExecutionError:
                    raise
                except Exception as exc:
                    raise NodeExecutionError(self.config.path, self.config.registration_id, exc) from exc
                if monitor is not None:
                    monitor(self, status, (self.config.clock() - t0) * 1e6)
        if status is SUCCESS or status is FAILURE:
            self._run_post_conditions(status)
        post = self._post_hook
        if post is not None:
            hooked = post(self, status)
            if hooked is SUCCESS or hooked is FAILURE:
                status = hooked
        if status is not self._status:
            if status is not SKIPPED:
                self.set_status(status)
        elif status is IDLE:
            self.set_status(status)
        return status

    def _check_pre_conditions(self) -> NodeStatus | None:
        pre = self.config.pre_conditions
        if not pre:
            return None
        bb = self.config.blackboard
        enums = self.config.enums
        current = self._status
        if current is IDLE:
            script = pre.get("_failureIf")
            if script is not None and script.run_bool(bb, enums):
                return FAILURE
            script = pre.get("_successIf")
            if script is not None and script.run_bool(bb, enums):
                return SUCCESS
            script = pre.get("_skipIf")
            if script is not None and script.run_bool(bb, enums):
                return SKIPPED
            script = pre.get("_while")
            if script is not None and not script.run_bool(bb, enums):
                return SKIPPED
        elif current is RUNNING:
            script = pre.get("_while")
            if script is not None and not script.run_bool(bb, enums):
                self.halt_node()
                return SKIPPED
        return None

    def _run_post_conditions(self, status: NodeStatus) -> None:
        post = self.config.post_conditions
        if not post:
            return
        bb = self.config.blackboard
        enums = self.config.enums
        script = post.get("_onSuccess" if status is SUCCESS else "_onFailure")
        if script is not None:
            script.run(bb, enums)
        script = post.get("_post")
        if script is not None:
            script.run(bb, enums)

    def halt_node(self) -> None:
        """BT.CPP haltNode(): ``halt()`` then the ``_onHalted`` script."""
        self.halt()
        script = self.config.post_conditions.get("_onHalted") if self.config.post_conditions else None
        if script is not None:
            script.run(self.config.blackboard, self.config.enums)

    def emit_wake_up_signal(self) -> None:
        self.config.wake_up.emit()

    # -- ports ---------------------------------------------------------------------------------
    def get_input(self, name: str, default: Any = _MISSING) -> Any:
        """Read an input port (spec 7.3): literal converted to the port type, or a blackboard
        value (strings converted to typed ports). Raises BTRuntimeError unless ``default`` is
        given, which is then returned on failure."""
        try:
            return self._read_input(name)
        except BehaviorTreeException:
            if default is not _MISSING:
                return default
            raise

    def get_input_stamped(self, name: str) -> tuple[Any, int, int]:
        """(value, sequence_id, timestamp_ns) of an input; (value, 0, 0) for a literal."""
        raw, port = self._raw_input(name)
        key = blackboard_key(raw, name) if isinstance(raw, str) else None
        if key is None:
            return self._read_input(name), 0, 0
        entry = self.config.blackboard.get_entry(key)
        value = self._read_input(name)
        return value, entry.sequence_id, entry.stamp

    def _raw_input(self, name: str) -> tuple[Any, PortInfo | None]:
        cfg = self.config
        manifest = cfg.manifest
        port = manifest.ports.get(name) if manifest is not None else None
        raw = cfg.input_ports.get(name, _MISSING)
        if raw is _MISSING:
            if port is None:
                raise BTRuntimeError(f"getInput() of node '{cfg.path}' failed because the manifest "
                                     f"doesn't contain the key: [{name}]")
            if not port.has_default:
                raise BTRuntimeError(f"getInput() of node '{cfg.path}' failed because nor the manifest "
                                     f"or the XML contain the key: [{name}]")
            raw = port.default
        return raw, port

    def _read_input(self, name: str) -> Any:
        cache = self._input_cache
        cached = cache.get(name, _MISSING)
        if cached is not _MISSING:
            return cached
        raw, port = self._raw_input(name)
        if not isinstance(raw, str):
            return raw  # a non-string default is returned as is
        cfg = self.config
        key = blackboard_key(raw, name)
        if key is None:
            if port is None or not port.type.strongly_typed:
                value = raw
            else:
                try:
                    value = port.type.from_string(raw, cfg.enums)
                except BehaviorTreeException as exc:
                    raise BTRuntimeError(f"getInput(): {exc}") from None
            cache[name] = value  # literals never change: convert once
            return value
        entry = cfg.blackboard.get_entry(key)
        if entry is None or entry.value is EMPTY:
            raise BTRuntimeError(f"getInput() failed because it was unable to find the key [{name}] "
                                 f"remapped to [{key}]")
        value = entry.value
        if port is None or not port.type.strongly_typed:
            return value
        ptype = port.type
        if isinstance(value, str):
            if ptype.kind == "string":
                return value
            return ptype.from_string(value, cfg.enums)
        if ptype.py_type is not None and type(value) is ptype.py_type and ptype.kind != "int":
            return value
        return ptype.coerce(value, cfg.enums)

    def set_output(self, name: str, value: Any) -> None:
        """Write an output port to the blackboard entry it is remapped to (spec 7.4)."""
        cfg = self.config
        raw = cfg.output_ports.get(name, _MISSING)
        if raw is _MISSING:
            raise LogicError(f"setOutput() failed: NodeConfig::output_ports does not contain the key: [{name}]")
        key = blackboard_key(raw, name)
        if key is None:
            raise LogicError("setOutput requires a blackboard pointer. Use {}")
        port = cfg.manifest.ports.get(name) if cfg.manifest is not None else None
        ptype = port.type if port is not None else None
        if ptype is None or not ptype.strongly_typed or ptype.kind == "string":
            cfg.blackboard.set(key, value)
            return
        # The port's declared type is the value's static type (C++ setOutput<T>); check it.
        py_type = ptype.py_type
        if py_type is not None and not isinstance(value, py_type) and not (
                ptype.kind in ("int", "double") and isinstance(value, (int, float))):
            raise LogicError(f"setOutput() of node '{cfg.path}': port [{name}] is declared "
                             f"[{ptype.name}] but got a value of type [{type(value).__name__}]")
        cfg.blackboard.set(key, value, ptype)

    def get_raw_port_value(self, name: str) -> str | None:
        raw = self.config.input_ports.get(name)
        if raw is None:
            raw = self.config.output_ports.get(name)
        return raw

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.config.path or self.name} {self._status.name}>"


# ---------------------------------------------------------------------------------------------
# Leaves
# ---------------------------------------------------------------------------------------------

class LeafNode(TreeNode):
    pass


class ActionNodeBase(LeafNode):
    node_type = NodeType.ACTION


class ConditionNode(LeafNode):
    """A condition: returns SUCCESS or FAILURE (RUNNING is not checked, as in BT.CPP)."""

    node_type = NodeType.CONDITION


class SyncActionNode(ActionNodeBase):
    """An action that completes within one tick; returning RUNNING is a LogicError."""

    _bare_tick_ok = False  # the RUNNING check lives in execute_tick

    def execute_tick(self) -> NodeStatus:
        status = TreeNode.execute_tick(self)
        if status is RUNNING:
            raise LogicError("SyncActionNode MUST never return RUNNING")
        return status

    def _execute_tick_full(self) -> NodeStatus:
        status = TreeNode._execute_tick_full(self)
        if status is RUNNING and not self.__dict__.pop("_held", False):
            raise LogicError("SyncActionNode MUST never return RUNNING")
        return status


class SimpleActionNode(SyncActionNode):
    """``register_simple_action``: sets RUNNING first, then ``fn(node)`` (IDLE->RUNNING->result)."""

    def __init__(self, name: str, config: NodeConfig, fn: Callable[[TreeNode], NodeStatus]):
        self._fn = fn
        super().__init__(name, config)

    _bare_tick_ok = True  # tick() makes the RUNNING check itself

    def tick(self) -> NodeStatus:
        if self._status is IDLE:
            self.set_status(RUNNING)
        status = self._fn(self)
        if status is RUNNING:
            raise LogicError("SyncActionNode MUST never return RUNNING")
        return status


class SimpleConditionNode(ConditionNode):
    """``register_simple_condition``: ``fn(node)`` each tick."""

    def __init__(self, name: str, config: NodeConfig, fn: Callable[[TreeNode], NodeStatus]):
        self._fn = fn
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        return self._fn(self)

    def _bare_tick(self) -> Callable[[], NodeStatus]:
        return functools.partial(self._fn, self)  # one Python frame per tick instead of two


class StatefulActionNode(ActionNodeBase):
    """An action with ``on_start`` / ``on_running`` / ``on_halted`` (spec 4.0)."""

    _halt_requested = False

    def on_start(self) -> NodeStatus:
        raise NotImplementedError

    def on_running(self) -> NodeStatus:
        raise NotImplementedError

    def on_halted(self) -> None:
        pass

    def is_halt_requested(self) -> bool:
        return self._halt_requested

    def tick(self) -> NodeStatus:
        status = self._status
        if status is IDLE:
            result = self.on_start()
            if result is IDLE:
                raise LogicError("StatefulActionNode::onStart() must not return IDLE")
            return result
        if status is RUNNING:
            result = self.on_running()
            if result is IDLE:
                raise LogicError("StatefulActionNode::onRunning() must not return IDLE")
            return result
        return status

    def halt(self) -> None:
        self._halt_requested = True
        if self._status is RUNNING:
            self.on_halted()
        self.reset_status()


class SimpleStatefulActionNode(StatefulActionNode):
    """``register_simple_stateful_action``: the three callbacks take the node."""

    def __init__(self, name: str, config: NodeConfig, on_start: Callable[[TreeNode], NodeStatus],
                 on_running: Callable[[TreeNode], NodeStatus],
                 on_halted: Callable[[TreeNode], None] | None = None):
        self._on_start_fn = on_start
        self._on_running_fn = on_running
        self._on_halted_fn = on_halted
        super().__init__(name, config)

    def on_start(self) -> NodeStatus:
        return self._on_start_fn(self)

    def on_running(self) -> NodeStatus:
        return self._on_running_fn(self)

    def on_halted(self) -> None:
        if self._on_halted_fn is not None:
            self._on_halted_fn(self)


class AsyncActionNode(ActionNodeBase):
    """An action whose work is ``async def run(self) -> NodeStatus``.

    The first tick starts ``run()`` as an asyncio task on the running loop and returns RUNNING;
    each later tick polls it (never awaits). When the task finishes its result is returned
    (an exception it raised is raised from the tick). ``halt()`` cancels the task.
    """

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._task: asyncio.Task | None = None
        super().__init__(name, config)

    async def run(self) -> NodeStatus:
        raise NotImplementedError

    def on_halted(self) -> None:
        """Called (synchronously) when the node is halted while running."""

    def tick(self) -> NodeStatus:
        task = self._task
        if task is None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                raise LogicError(f"AsyncActionNode '{self.name}' needs a running asyncio event loop "
                                 "(use tick_while_running_async or the runtime)") from None
            self.set_status(RUNNING)
            self._task = task = loop.create_task(self.run(), name=f"bt:{self.config.path}")
            task.add_done_callback(self._on_done)
            if not task.done():
                return RUNNING
        if not task.done():
            return RUNNING
        self._task = None
        if task.cancelled():
            raise BTRuntimeError(f"AsyncActionNode '{self.name}': run() was cancelled")
        exc = task.exception()
        if exc is not None:
            raise exc
        result = task.result()
        if result is None or result is IDLE or result is RUNNING:
            raise LogicError(f"AsyncActionNode '{self.name}': run() must return SUCCESS or FAILURE, "
                             f"got {result!r}")
        return result

    def _on_done(self, task: asyncio.Task) -> None:
        if task is self._task:
            self.config.wake_up.emit()

    def halt(self) -> None:
        task = self._task
        self._task = None
        if task is not None and not task.done():
            task.cancel()
        if self._status is RUNNING:
            self.on_halted()
        self.reset_status()


# ---------------------------------------------------------------------------------------------
# Control nodes and decorators
# ---------------------------------------------------------------------------------------------

class ControlNode(TreeNode):
    """A node with an ordered list of children."""

    __slots__ = ("children",)
    node_type = NodeType.CONTROL

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.children: list[TreeNode] = []
        super().__init__(name, config)

    def add_child(self, child: TreeNode) -> None:
        self.children.append(child)

    def children_nodes(self) -> list[TreeNode]:
        return self.children

    def reset_children(self) -> None:
        """Halt RUNNING children, then set every child IDLE (BT.CPP resetChildren)."""
        for child in self.children:
            status = child._status
            if status is not IDLE:
                if status is RUNNING:
                    child.halt_node()
                if child._subscribers:
                    child.reset_status()
                else:
                    child._status = IDLE

    def halt_child(self, index: int) -> None:
        child = self.children[index]
        if child._status is RUNNING:
            child.halt_node()
        child.reset_status()

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()


class DecoratorNode(TreeNode):
    """A node with exactly one child; a completed child is reset after the tick."""

    __slots__ = ("child",)
    node_type = NodeType.DECORATOR
    # execute_tick resets a completed child afterwards; subclasses whose tick() always does
    # that itself may set _bare_tick_ok = True.
    _bare_tick_ok = False

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.child: TreeNode | None = None
        super().__init__(name, config)

    def set_child(self, child: TreeNode) -> None:
        if self.child is not None:
            raise BehaviorTreeException("Decorator already has a child")
        self.child = child

    add_child = set_child

    def children_nodes(self) -> list[TreeNode]:
        return [self.child] if self.child is not None else []

    def reset_child(self) -> None:
        child = self.child
        if child is None:
            return
        if child._status is RUNNING:
            child.halt_node()
        child.reset_status()

    halt_child = reset_child

    def halt(self) -> None:
        self.reset_child()
        self.reset_status()

    def execute_tick(self) -> NodeStatus:
        status = TreeNode.execute_tick(self)
        child = self.child
        if child is not None:
            cs = child._status
            if cs is SUCCESS or cs is FAILURE:
                child.reset_status()
        return status

    def _execute_tick_full(self) -> NodeStatus:
        status = TreeNode._execute_tick_full(self)
        child = self.child
        if child is not None:
            cs = child._status
            if cs is SUCCESS or cs is FAILURE:
                child.reset_status()
        return status


class SimpleDecoratorNode(DecoratorNode):
    """``register_simple_decorator``: returns ``fn(child_status, node)``."""

    def __init__(self, name: str, config: NodeConfig,
                 fn: Callable[[NodeStatus, TreeNode], NodeStatus]):
        self._fn = fn
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        return self._fn(self.child.execute_tick(), self)


def store_child_status(child: TreeNode, status: NodeStatus) -> None:
    """What a parent does after calling ``child._fast()``: store the result like executeTick.

    The hot control loops inline this (see sequences.py, reactive.py); keep them in sync.
    """
    if status is not child._status:
        if status is not SKIPPED:
            if status is IDLE or child._subscribers:
                child.set_status(status)
            else:
                child._status = status
    elif status is IDLE:
        child.set_status(status)


def tick_child(child: TreeNode) -> NodeStatus:
    """Tick ``child`` through its fast path, wrapping errors with its path like executeTick."""
    try:
        status = child._fast()
    except NodeExecutionError:
        raise
    except Exception as exc:
        raise NodeExecutionError(child.config.path, child.config.registration_id, exc) from exc
    store_child_status(child, status)
    return status


def manifest_for(cls: type[TreeNode], registration_id: str, ports: Any = None,
                 builtin: bool = False) -> TreeNodeManifest:
    """Build a manifest from a node class (its provided_ports/metadata) or explicit ports."""
    declared = ports_dict(cls.provided_ports() if ports is None else ports)
    return TreeNodeManifest(registration_id, cls.node_type, declared,
                            description=getattr(cls, "description", "") or "",
                            metadata=list(cls.metadata()), builtin=builtin)
