"""Node base classes with BT.CPP's tick, halt and status semantics (spec 3 and 4.0).

A parent always calls ``child.execute_tick()``, never ``tick()``. ``execute_tick`` evaluates
pre-conditions, calls ``tick()``, runs post-conditions, and stores the status (SKIPPED is
returned but never stored). Nodes with no pre/post scripts and no hooks take a fast path: the
per-tick cost of the common case is one Python call per node plus a status store.

Hot state lives in a ``NodeCell`` per node (status and the callable a parent ticks), one
shared type whatever the node's class, so the attribute sites of the parents' loops stay
monomorphic (CPython 3.11 specializes them per type). An observed node's cell is an
``ObservedCell``, whose ``status`` setter notifies the subscribers: stores never need to
check for observers.

User node kinds: SyncActionNode, ConditionNode, StatefulActionNode (on_start / on_running /
on_halted), AsyncActionNode (``async def run(self)``: started on the first tick, polled each
tick, cancelled on halt), ControlNode, DecoratorNode. A tick never awaits.
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable, Iterable, Mapping
from types import MappingProxyType, MethodType
from typing import Any, ClassVar

from .blackboard import Blackboard
from .condition_tick import SharedConditions
from .condition_tick import conditions_tick as _conditions_tick
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
    """Everything a node gets at creation: blackboard, port remappings, identity, services.

    ``pre_conditions``, ``post_conditions`` and ``other_attributes`` are usually empty: they
    are created on first use (reading one returns a dict you may fill).
    """

    __slots__ = ("blackboard", "enums", "input_ports", "output_ports", "manifest", "uid", "_path", "_name",
                 "_pre", "_post", "_other", "context", "wake_up", "timers", "clock",
                 "registration_id", "_file", "_line", "_doc", "_elem")

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
        self._path = path
        self._name = None
        self._pre = self._post = self._other = None
        self.context = context
        self.wake_up: WakeUpSignal = wake_up
        self.timers: TimerQueue = timers
        self.clock: Callable[[], float] = clock or timers.clock
        self.registration_id = manifest.registration_id if manifest else ""
        self._file: str | None = None
        self._line: int | None = None
        self._doc = self._elem = None

    @classmethod
    def _for_node(cls, blackboard: Blackboard, enums: dict[str, int], manifest: TreeNodeManifest,
                  uid: int, path: str, name: str | None, context: Any, wake_up: WakeUpSignal,
                  timers: TimerQueue, clock: Callable[[], float], doc: Any, elem: Any) -> NodeConfig:
        """``NodeConfig(blackboard, enums=..., ...)`` for the builder: every service given,
        positional arguments (much cheaper than the keyword call, once per node).

        ``input_ports``/``output_ports`` start as one shared, read-only empty mapping; the
        builder gives a node with ports read-only mappings shared by every node of the build
        with the same type and attributes (two dicts fewer per node; see builder._ports).

        The source is kept as the element and its document (the document's plans hold the
        element anyway), resolved to the file and the line of the start tag only if someone
        asks (``source``): no per-node object, and the document check reads no line.

        With a ``name``, ``path`` is the prefix of the node's path: the full path (prefix, name,
        and ``::uid`` for a node named after its type) is joined when first read (``path``),
        which few nodes are; the join and the uid's formatting cost more than the rest of this."""
        self = _new_object(cls)
        self.blackboard = blackboard
        self.enums = enums
        self.input_ports = self.output_ports = _NO_PORTS
        self.manifest = manifest
        self.uid = uid
        self._path = path
        self._name = name
        self._pre = self._post = self._other = None
        self.context = context
        self.wake_up = wake_up
        self.timers = timers
        self.clock = clock
        self.registration_id = manifest.registration_id
        self._doc = doc  # (_file and _line are set by source when it resolves these)
        self._elem = elem
        return self

    @property
    def path(self) -> str:
        """The node's full path (``Main/sub/Sequence::3``), joined on first use (``_for_node``)."""
        name = self._name
        if name is None:
            return self._path
        path = self._path = (self._path + name + f"::{self.uid}" if name == self.registration_id
                             else self._path + name)
        self._name = None
        return path

    @path.setter
    def path(self, value: str) -> None:
        self._path = value
        self._name = None

    @property
    def source(self) -> tuple[str | None, int | None]:
        """(file, line) of the node's element, for messages. The builder gives the element:
        finding the start tag's line costs a text search, done only if someone asks."""
        doc = self._doc
        if doc is not None:
            self._file = doc.file
            self._line = doc.line_of(self._elem)
            self._doc = self._elem = None
        return (self._file, self._line)

    @source.setter
    def source(self, value: tuple[str | None, int | None]) -> None:
        self._file, self._line = value
        self._doc = self._elem = None

    @property
    def pre_conditions(self) -> dict[str, Any]:
        pre = self._pre
        if pre is None or type(pre) is SharedConditions:  # (the builder's, shared: a copy of our own)
            pre = self._pre = dict(pre or ())
        return pre

    @pre_conditions.setter
    def pre_conditions(self, value: dict[str, Any]) -> None:
        self._pre = value

    @property
    def post_conditions(self) -> dict[str, Any]:
        post = self._post
        if post is None or type(post) is SharedConditions:
            post = self._post = dict(post or ())
        return post

    @post_conditions.setter
    def post_conditions(self, value: dict[str, Any]) -> None:
        self._post = value

    @property
    def other_attributes(self) -> dict[str, str]:
        if self._other is None:
            self._other = {}
        return self._other

    @other_attributes.setter
    def other_attributes(self, value: dict[str, str]) -> None:
        self._other = value


_new_object = object.__new__
_NO_PORTS: Mapping[str, str] = MappingProxyType({})


def _unconverted_type(port: PortInfo | None) -> type | None:
    """The type of blackboard value that an input ``port`` returns unchanged (``_converted``):
    ``object`` for any value (an untyped port), None when every value goes through it."""
    if port is None or not port.type.strongly_typed:
        return object
    ptype = port.type
    if ptype.kind == "string":
        return str
    py_type = ptype.py_type
    if py_type is not None and not issubclass(py_type, str) and ptype.kind != "int":
        return py_type
    return None


class NodeCell:
    """The hot state of one node, shared with its parent: ``status``, and ``fast``, what a
    parent calls as ``fast(node)`` to tick it.

    ``fast`` is the bare ``tick`` when the node has no pre/post-condition scripts and no hooks
    (the parent then stores the result in ``status`` itself, see ``tick_cell``), otherwise the
    full ``execute_tick``: a plain function of the node, so that building a node does not make
    a bound method (fewer objects for the garbage collector). Every node has exactly one cell
    for its whole life; parents keep lists of their children's cells.
    """

    __slots__ = ("status", "fast", "node")
    # No __init__: TreeNode.__init__ fills the slots (a class without __init__ is the
    # cheapest object to make).


_status_slot = NodeCell.__dict__["status"]
_raw_get_status = _status_slot.__get__  # (cell) -> status, whatever the cell's class
_raw_set_status = _status_slot.__set__  # (cell, status): store without notifying


def _observed_set_status(cell: NodeCell, new: NodeStatus) -> None:
    prev = _raw_get_status(cell)
    if prev is not new:
        _raw_set_status(cell, new)
        cell.node._notify(prev, new)


class ObservedCell(NodeCell):
    """The cell of a node with status subscribers: a change of ``status`` notifies them
    synchronously (BT.CPP setStatus/resetStatus). Cells switch class in place, so parents'
    references stay valid."""

    __slots__ = ()
    status = property(_raw_get_status, _observed_set_status)  # type: ignore[assignment]


def _failure_observed_set_status(cell: NodeCell, new: NodeStatus) -> None:
    prev = _raw_get_status(cell)
    if prev is not new:
        _raw_set_status(cell, new)
        if new is FAILURE:
            cell.node._notify(prev, new)


class FailureObservedCell(NodeCell):
    """The cell of a node whose subscribers all want FAILURE only (e.g. the run summary's
    failure witness): the reactive nodes' many other changes per tick notify nobody."""

    __slots__ = ()
    status = property(_raw_get_status, _failure_observed_set_status)  # type: ignore[assignment]


def _failures_only(callback: StatusCallback) -> StatusCallback:
    def on_failure(stamp: float, node: TreeNode, prev: NodeStatus, new: NodeStatus) -> None:
        if new is FAILURE:
            callback(stamp, node, prev, new)
    return on_failure


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

    def copy(self) -> TreeNodeManifest:
        """The same manifest with its own ``ports`` dict and ``metadata`` list (the PortInfos,
        frozen, are shared): what each factory gets of the built-in ones."""
        m = _new_object(TreeNodeManifest)
        m.registration_id = self.registration_id
        m.node_type = self.node_type
        m.ports = dict(self.ports)
        m.description = self.description
        m.metadata = list(self.metadata)
        m.builtin = self.builtin
        return m

    def __repr__(self) -> str:
        return f"TreeNodeManifest({self.registration_id!r}, {self.node_type.name}, ports={list(self.ports)})"


class TreeNode:
    """Base of every node. Subclasses implement ``tick()`` (and ``halt()`` when stateful).

    ``_cell`` holds the node's status and ``fast``, what a parent calls to tick this node:
    the bare ``tick`` when the node has no pre/post-condition scripts and no hooks (the parent
    then stores the status itself, saving a Python call per node), otherwise the full
    ``execute_tick``. Classes whose BT.CPP ``executeTick`` does extra work (decorators, sync
    actions) set ``_bare_tick_ok = False``. ``_status`` and ``_fast`` remain as properties
    over the cell; a raw ``_status`` store does not notify, as before.
    """

    __slots__ = ("name", "config", "_cell", "_input_cache", "__dict__", "__weakref__")

    node_type: ClassVar[NodeType] = NodeType.UNDEFINED
    description: ClassVar[str] = ""
    _bare_tick_ok: ClassVar[bool] = True
    # Rarely set: class-level defaults, an instance attribute once set (fewer stores per node).
    _subscribers: list[StatusCallback] | tuple[()] = ()  # a list once someone subscribes
    _wants_all: int = 0  # subscribers that want every change (the others: FAILURE only)
    _pre_hook: PreTickHook | None = None
    _post_hook: PostTickHook | None = None
    _monitor: Callable[[TreeNode, NodeStatus, float], None] | None = None
    # True while the node holds its execute_tick bound to itself in its __dict__ (a cycle that
    # Tree.__del__ breaks; _select_execute_tick keeps it)
    _bound_tick: bool = False
    # input port -> (blackboard key, port info, _unconverted_type), once read from the blackboard
    _input_pointers: dict[str, tuple[str, PortInfo | None, type]] | None = None
    # True when the class's MRO is a single-inheritance chain: then super().__init__ in any
    # __init__ of the chain is the direct base's __init__, which the hot constructors call
    # directly (super() costs about a microsecond in CPython 3.11, per node built).
    _linear_mro: ClassVar[bool] = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._linear_mro = all(len(c.__bases__) <= 1 for c in cls.__mro__)

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.name = name
        if config is None:
            config = NodeConfig()
        self.config = config
        self._cell = cell = NodeCell()
        cell.status = IDLE
        cell.node = self
        self._input_cache: dict[str, Any] | None = None  # literal inputs, converted once
        if config._pre or config._post:
            self._select_execute_tick()
        else:  # _select_execute_tick() without hooks, inlined: this runs once per node built
            fast = _fast_by_class.get(type(self))
            if fast is None:
                fast = _class_fast(self)
            cell.fast = fast if fast is not _PER_NODE else self._bare_tick()

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
        return self._cell.status

    @property
    def _status(self) -> NodeStatus:
        return self._cell.status

    @_status.setter
    def _status(self, value: NodeStatus) -> None:
        _raw_set_status(self._cell, value)  # raw: no notification (use set_status for that)

    @property
    def _fast(self) -> Callable[[], NodeStatus]:
        """What a parent calls to tick this node (``_cell.fast`` bound to the node)."""
        return MethodType(self._cell.fast, self)

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
        self._cell.status = new_status  # an ObservedCell notifies on change

    def reset_status(self) -> None:
        self._cell.status = IDLE

    def _notify(self, prev: NodeStatus, new: NodeStatus) -> None:
        stamp = self.config.clock()
        for callback in tuple(self._subscribers):
            callback(stamp, self, prev, new)

    def subscribe_to_status_change(self, callback: StatusCallback,
                                   failures_only: bool = False) -> Callable[[], None]:
        """Call ``callback(timestamp, node, previous, new)`` synchronously on every change, or
        with ``failures_only`` on every change to FAILURE (the others then cost nothing while
        no subscriber wants them)."""
        if not isinstance(self._subscribers, list):
            self._subscribers = list(self._subscribers)
        entry = _failures_only(callback) if failures_only else callback
        self._subscribers.append(entry)
        self._wants_all += not failures_only
        self._cell.__class__ = ObservedCell if self._wants_all else FailureObservedCell

        def unsubscribe() -> None:
            if entry in self._subscribers:
                self._subscribers.remove(entry)
                self._wants_all -= not failures_only
                self._cell.__class__ = (ObservedCell if self._wants_all else
                                        FailureObservedCell if self._subscribers else NodeCell)

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
        if self._pre_hook or self._post_hook or self._monitor:
            self.execute_tick = self._execute_tick_full  # type: ignore[method-assign]
            self._cell.fast = type(self)._execute_tick_full
            self._bound_tick = True
        elif (cfg._pre or cfg._post) and (after := _after_full_tick(type(self))) is not False:
            fast = _conditions_tick(self._unbound_tick(), cfg, after)
            self.execute_tick = fast.__get__(self)  # type: ignore[method-assign]
            self._cell.fast = fast
            self._bound_tick = True
        elif cfg._pre or cfg._post:  # a class with its own _execute_tick_full
            self.execute_tick = self._execute_tick_full  # type: ignore[method-assign]
            self._cell.fast = type(self)._execute_tick_full
            self._bound_tick = True
        else:
            self.__dict__.pop("execute_tick", None)
            self._bound_tick = False
            execute_tick = type(self).execute_tick
            bare = self._bare_tick_ok and execute_tick in _LIBRARY_EXECUTE_TICKS
            self._cell.fast = self._bare_tick() if bare else execute_tick

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        """The function ``f`` with ``f(self)`` equivalent to ``self.tick()``."""
        return type(self).tick

    def _unbound_tick(self) -> Callable[[TreeNode], NodeStatus]:
        """``f`` with ``f(self)`` equivalent to ``self.tick()``, for the pre/post-condition
        closure; unlike ``_bare_tick`` it never depends on the node's current children."""
        return type(self).tick

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
            raise NodeExecutionError(self.config.path, self.config.registration_id, exc, self.name) from exc
        if status is not SKIPPED:
            if status is IDLE:
                self.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
            self._cell.status = status  # an ObservedCell notifies on change
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
                    raise NodeExecutionError(self.config.path, self.config.registration_id, exc, self.name) from exc
                if monitor is not None:
                    monitor(self, status, (self.config.clock() - t0) * 1e6)
        if status is SUCCESS or status is FAILURE:
            self._run_post_conditions(status)
        post = self._post_hook
        if post is not None:
            hooked = post(self, status)
            if hooked is SUCCESS or hooked is FAILURE:
                status = hooked
        if status is not SKIPPED:
            if status is IDLE:
                self.set_status(status)  # raises
            self._cell.status = status
        return status

    def _check_pre_conditions(self) -> NodeStatus | None:
        pre = self.config._pre
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
        post = self.config._post
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
        post = self.config._post
        script = post.get("_onHalted") if post else None
        if script is not None:
            script.run(self.config.blackboard, self.config.enums)

    def emit_wake_up_signal(self) -> None:
        self.config.wake_up.emit()

    # -- ports ---------------------------------------------------------------------------------
    def get_input(self, name: str, default: Any = _MISSING) -> Any:
        """Read an input port (spec 7.3): literal converted to the port type, or a blackboard
        value (strings converted to typed ports). Raises BTRuntimeError unless ``default`` is
        given, which is then returned on failure."""
        cache = self._input_cache  # a literal already converted: no call (the usual case)
        if cache is not None:
            value = cache.get(name, _MISSING)
            if value is not _MISSING:
                return value
        pointers = self._input_pointers  # a blackboard port read before: its key is known
        if pointers is not None:
            pointer = pointers.get(name)
            if pointer is not None:
                key, _, same = pointer
                bb = self.config.blackboard
                entry = bb._resolved.get(key) or bb.get_entry(key)  # get_entry's first step inlined
                if entry is not None:
                    value = entry.value
                    # a value the port's type takes as it is (else _read_input converts or raises)
                    if value is not EMPTY and (same is object or type(value) is same):
                        return value
        try:
            return self._read_input(name)
        except BehaviorTreeException:
            if default is not _MISSING:
                return default
            raise

    def input_is_constant(self, name: str) -> bool:
        """Whether input port ``name`` holds a literal (or takes its default) rather than a
        blackboard pointer: its value can then never change, so a node may read it once."""
        try:
            raw, _ = self._raw_input(name)
        except BehaviorTreeException:
            return False
        return not (isinstance(raw, str) and blackboard_key(raw, name) is not None)

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
        if cache is not None:
            cached = cache.get(name, _MISSING)
            if cached is not _MISSING:
                return cached
        cfg = self.config
        pointers = self._input_pointers
        pointer = pointers.get(name) if pointers is not None else None
        if pointer is not None:  # a port already read from the blackboard: its key and port
            key, port, _ = pointer
            bb = cfg.blackboard
            entry = bb._resolved.get(key) or bb.get_entry(key)  # get_entry's first step inlined
            return self._converted(name, key, port, entry)
        raw, port = self._raw_input(name)
        if not isinstance(raw, str):
            return raw  # a non-string default is returned as is
        key = blackboard_key(raw, name)
        if key is None:
            if port is None or not port.type.strongly_typed:
                value = raw
            else:
                try:
                    value = port.type.from_string(raw, cfg.enums)
                except BehaviorTreeException as exc:
                    raise BTRuntimeError(f"getInput(): {exc}") from None
            if cache is None:
                cache = self._input_cache = {}
            cache[name] = value  # literals never change: convert once
            return value
        if pointers is None:
            pointers = self._input_pointers = {}
        pointers[name] = (key, port, _unconverted_type(port))  # the key never changes either
        return self._converted(name, key, port, cfg.blackboard.get_entry(key))

    def _converted(self, name: str, key: str, port: PortInfo | None, entry: Any) -> Any:
        """The value of input ``name`` from its blackboard ``entry`` (under ``key``), converted
        to the port's type."""
        cfg = self.config
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


def _simple_builder(cls: type, fn: Callable[[TreeNode], NodeStatus]) -> Callable[[str, NodeConfig], Any]:
    """A builder of ``cls(name, config, fn)`` (a simple action or condition) without the type
    call and the ``__init__`` frames: one frame per node built."""
    def build(name: str, config: NodeConfig, cls: type = cls, fn: Callable = fn) -> Any:
        node = _new_object(cls)
        node._fn = fn
        _tree_node_init(node, name, config)
        return node
    return build


class SimpleActionNode(SyncActionNode):
    """``register_simple_action``: sets RUNNING first, then ``fn(node)`` (IDLE->RUNNING->result)."""

    __slots__ = ("_fn",)

    def __init__(self, name: str, config: NodeConfig, fn: Callable[[TreeNode], NodeStatus]):
        self._fn = fn
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            SyncActionNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    _bare_tick_ok = True  # tick() makes the RUNNING check itself

    @staticmethod
    def builder(fn: Callable[[TreeNode], NodeStatus]) -> Callable[[str, NodeConfig], SimpleActionNode]:
        """What ``register_simple_action`` registers: ``SimpleActionNode(n, c, fn)`` without
        the type call and the ``__init__`` frames (once per node built)."""
        return _simple_builder(SimpleActionNode, fn)

    def tick(self) -> NodeStatus:
        cell = self._cell
        if cell.status is IDLE:
            cell.status = RUNNING  # set_status(RUNNING); notifies if observed
        status = self._fn(self)
        if status is RUNNING:
            raise LogicError("SyncActionNode MUST never return RUNNING")
        return status


class SimpleConditionNode(ConditionNode):
    """``register_simple_condition``: ``fn(node)`` each tick."""

    __slots__ = ("_fn",)

    def __init__(self, name: str, config: NodeConfig, fn: Callable[[TreeNode], NodeStatus]):
        self._fn = fn
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            ConditionNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    @staticmethod
    def builder(fn: Callable[[TreeNode], NodeStatus]) -> Callable[[str, NodeConfig], SimpleConditionNode]:
        """What ``register_simple_condition`` registers: ``SimpleConditionNode(n, c, fn)``
        without the type call and the ``__init__`` frame (once per node built)."""
        return _simple_builder(SimpleConditionNode, fn)

    def tick(self) -> NodeStatus:
        return self._fn(self)

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        return self._fn  # fn(node) is tick(): one Python frame per tick instead of two

    _unbound_tick = _bare_tick


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
        status = self._cell.status
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
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            StatefulActionNode.__init__(self, name, config)
        else:
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

class ChildList(list):
    """``ControlNode.children``: a list of nodes that keeps ``cells``, the parent's list of the
    children's cells (what the hot loops read), in step however it is modified."""

    __slots__ = ("cells",)

    def __init__(self, items: Iterable[TreeNode] = (), cells: list[NodeCell] | None = None):
        list.__init__(self, items)
        self.cells = cells if cells is not None else []
        self._sync()

    def _sync(self) -> None:
        try:
            cells = self.cells
        except AttributeError:  # a copy made without __init__ (copy.copy, pickle)
            cells = self.cells = []
        cells[:] = [child._cell for child in self]

    def append(self, child: TreeNode) -> None:
        list.append(self, child)
        try:
            self.cells.append(child._cell)
        except AttributeError:
            self._sync()


def _synced(name: str) -> Callable[..., Any]:
    method = getattr(list, name)

    @functools.wraps(method)
    def wrapper(self: ChildList, *args: Any, **kwargs: Any) -> Any:
        result = method(self, *args, **kwargs)
        self._sync()
        return result

    return wrapper


for _name in ("extend", "insert", "remove", "pop", "clear", "sort", "reverse", "__setitem__",
              "__delitem__", "__iadd__", "__imul__"):
    setattr(ChildList, _name, _synced(_name))
del _name


class ControlNode(TreeNode):
    """A node with an ordered list of children (``children``; ``_cells`` are their cells).

    The ``children`` list is made on first use: the hot loops and the builder need only
    ``_cells`` (each cell knows its node), so most trees never build it.
    """

    __slots__ = ("_children", "_cells")
    node_type = NodeType.CONTROL

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._cells: list[NodeCell] = []
        self._children: ChildList | None = None
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            TreeNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    @property
    def children(self) -> list[TreeNode]:
        children = self._children
        if children is None:
            children = self._children = ChildList([cell.node for cell in self._cells], self._cells)
        return children

    @children.setter
    def children(self, nodes: Iterable[TreeNode]) -> None:
        self._cells = []
        self._children = ChildList(nodes, self._cells)

    def add_child(self, child: TreeNode) -> None:
        if self._children is not None:
            list.append(self._children, child)  # self.children.append(child), one call less
        self._cells.append(child._cell)

    def children_nodes(self) -> list[TreeNode]:
        return self.children

    def reset_children(self) -> None:
        """Halt RUNNING children, then set every child IDLE (BT.CPP resetChildren)."""
        for cell in self._cells:
            status = cell.status
            if status is not IDLE:
                if status is RUNNING:
                    cell.node.halt_node()
                cell.status = IDLE  # notifies if observed

    def halt_child(self, index: int) -> None:
        cell = self._cells[index]
        if cell.status is RUNNING:
            cell.node.halt_node()
        cell.status = IDLE

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()


class DecoratorNode(TreeNode):
    """A node with exactly one child (``child``; ``_child_cell`` is its cell); a completed
    child is reset after the tick."""

    __slots__ = ("_child", "_child_cell")
    node_type = NodeType.DECORATOR
    # execute_tick resets a completed child afterwards; subclasses whose tick() always does
    # that itself may set _bare_tick_ok = True.
    _bare_tick_ok = False

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._child: TreeNode | None = None
        self._child_cell: NodeCell | None = None
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            TreeNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    @property
    def child(self) -> TreeNode | None:
        return self._child

    @child.setter
    def child(self, child: TreeNode | None) -> None:
        self._child = child
        self._child_cell = child._cell if child is not None else None

    def set_child(self, child: TreeNode) -> None:
        if self._child is not None:
            raise BehaviorTreeException("Decorator already has a child")
        self.child = child

    add_child = set_child

    def children_nodes(self) -> list[TreeNode]:
        return [self._child] if self._child is not None else []

    def reset_child(self) -> None:
        cell = self._child_cell
        if cell is None:
            return
        if cell.status is RUNNING:
            cell.node.halt_node()
        cell.status = IDLE

    halt_child = reset_child

    def halt(self) -> None:
        self.reset_child()
        self.reset_status()

    def execute_tick(self) -> NodeStatus:
        status = TreeNode.execute_tick(self)
        cell = self._child_cell
        if cell is not None:
            cs = cell.status
            if cs is SUCCESS or cs is FAILURE:
                cell.status = IDLE
        return status

    def _execute_tick_full(self) -> NodeStatus:
        status = TreeNode._execute_tick_full(self)
        cell = self._child_cell
        if cell is not None:
            cs = cell.status
            if cs is SUCCESS or cs is FAILURE:
                cell.status = IDLE
        return status


_tree_node_init = TreeNode.__init__

# A class that overrides execute_tick (as BT.CPP allows: it is virtual) is always ticked
# through it; the library's own overrides are known to be equivalent to the bare tick where
# the class sets _bare_tick_ok.
_LIBRARY_EXECUTE_TICKS = (TreeNode.execute_tick, SyncActionNode.execute_tick, DecoratorNode.execute_tick)
# class -> what TreeNode.__init__ makes the cell's ``fast`` of its nodes without conditions or
# hooks: the class's execute_tick, its bare tick, or _PER_NODE (ask the node's _bare_tick())
_fast_by_class: dict[type, Callable[[TreeNode], NodeStatus]] = {}
_PER_NODE: Any = object()


def _class_fast(node: TreeNode) -> Callable[[TreeNode], NodeStatus]:
    """``_fast_by_class`` of the node's class, worked out from its first node (both choices
    depend on class attributes only; the bare tick is the same for every node when the class
    that defines ``_bare_tick`` is TreeNode or says so with ``_bare_tick_per_class``)."""
    cls = type(node)
    if not (cls._bare_tick_ok and cls.execute_tick in _LIBRARY_EXECUTE_TICKS):
        fast = cls.execute_tick
    else:
        owner = next(c for c in cls.__mro__ if "_bare_tick" in c.__dict__)
        per_class = owner is TreeNode or owner.__dict__.get("_bare_tick_per_class", False)
        fast = node._bare_tick() if per_class else _PER_NODE
    _fast_by_class[cls] = fast
    return fast


class SimpleDecoratorNode(DecoratorNode):
    """``register_simple_decorator``: returns ``fn(child_status, node)``."""

    __slots__ = ("_fn",)

    def __init__(self, name: str, config: NodeConfig,
                 fn: Callable[[NodeStatus, TreeNode], NodeStatus]):
        self._fn = fn
        super().__init__(name, config)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "tick" in cls.__dict__ and "execute_tick" not in cls.__dict__:
            cls.execute_tick = DecoratorNode.execute_tick  # the one-frame path below inlines tick()

    def tick(self) -> NodeStatus:
        return self._fn(self.child.execute_tick(), self)

    def execute_tick(self) -> NodeStatus:
        """``DecoratorNode.execute_tick`` (tick, store the status, then reset a completed child,
        as BT.CPP's executeTick does in that order) in one frame, ``tick()`` inlined: what a
        parent calls. The child is ticked through its cell; errors are wrapped as the nested
        execute_tick calls wrap them (the child's tick with its path, the rest with ours)."""
        cell = self._child_cell
        try:
            fast = cell.fast
            try:
                child_status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, cell.node):  # the child's execute_tick's own error
                    raise
                raise _wrap_error(cell, exc) from exc
            if child_status is not SKIPPED:
                if child_status is IDLE:
                    cell.node.set_status(child_status)  # raises, as BT.CPP's setStatus(IDLE) does
                cell.status = child_status
            status = self._fn(child_status, self)
        except NodeExecutionError:
            raise
        except Exception as exc:
            raise NodeExecutionError(self.config.path, self.config.registration_id, exc, self.name) from exc
        if status is not SKIPPED:
            if status is IDLE:
                self.set_status(status)  # raises
            self._cell.status = status
        cs = cell.status
        if cs is SUCCESS or cs is FAILURE:
            cell.status = IDLE
        return status


def tick_cell(cell: NodeCell) -> NodeStatus:
    """``cell.node.execute_tick()``, through the cell: tick the node and store the result
    (SKIPPED is not stored, IDLE raises; spec 3.1). An error raised by ``tick()`` is wrapped
    with the node's path (spec 3.7); one raised by execute_tick's own checks (IDLE, a sync
    action returning RUNNING, scripts, hooks) is not, exactly as from execute_tick.

    This is the canonical child tick; decorators.py inlines it where it is hot. (The loops of
    sequences.py and reactive.py also wrap errors from the checks of a non-bare child.)
    """
    fast = cell.fast
    try:
        status = fast(cell.node)
    except NodeExecutionError:
        raise
    except Exception as exc:
        if _is_execute_tick(fast, cell.node):  # not the bare tick: execute_tick's own error
            raise
        raise _wrap_error(cell, exc) from exc
    if status is not SKIPPED:
        if status is IDLE:
            cell.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
        cell.status = status
    return status


def _is_execute_tick(fast: Callable[[TreeNode], NodeStatus], node: TreeNode) -> bool:
    """Is ``fast`` the node's execute_tick (which wraps tick()'s errors itself)?"""
    cls = type(node)
    return fast is cls.execute_tick or fast is cls._execute_tick_full or getattr(fast, "wraps_tick_errors", False)


def _wrap_error(cell: NodeCell, exc: Exception) -> NodeExecutionError:
    config = cell.node.config
    return NodeExecutionError(config.path, config.registration_id, exc, cell.node.name)


def store_child_status(child: TreeNode, status: NodeStatus) -> None:
    """What a parent does after calling ``child._fast()``: store the result like executeTick
    (``tick_cell`` does both)."""
    if status is not SKIPPED:
        if status is IDLE:
            child.set_status(status)  # raises
        child._cell.status = status


def tick_child(child: TreeNode) -> NodeStatus:
    """Tick ``child`` through its fast path, wrapping errors with its path like executeTick."""
    return tick_cell(child._cell)


def manifest_for(cls: type[TreeNode], registration_id: str, ports: Any = None,
                 builtin: bool = False) -> TreeNodeManifest:
    """Build a manifest from a node class (its provided_ports/metadata) or explicit ports."""
    declared = ports_dict(cls.provided_ports() if ports is None else ports)
    return TreeNodeManifest(registration_id, cls.node_type, declared,
                            description=getattr(cls, "description", "") or "",
                            metadata=list(cls.metadata()), builtin=builtin)


def _after_sync_tick(node: TreeNode, status: NodeStatus) -> None:
    if status is RUNNING:
        raise LogicError("SyncActionNode MUST never return RUNNING")


def _after_decorator_tick(node: TreeNode, status: NodeStatus) -> None:
    cell = node._child_cell
    if cell is not None:
        cs = cell.status
        if cs is SUCCESS or cs is FAILURE:
            cell.status = IDLE


def _after_full_tick(cls: type) -> Callable[[TreeNode, NodeStatus], None] | None | bool:
    """What the class's ``_execute_tick_full`` does after TreeNode's (None: nothing), or False
    when the class has an override of its own that a specialised closure cannot reproduce."""
    full = cls._execute_tick_full
    if full is TreeNode._execute_tick_full:
        return None
    if full is SyncActionNode._execute_tick_full:
        return _after_sync_tick
    if full is DecoratorNode._execute_tick_full:
        return _after_decorator_tick
    return False
