"""Leaf nodes BT.CPP registers by default: AlwaysSuccess/Failure, Script, ScriptCondition,
SetBlackboard, UnsetBlackboard (spec 4.5). Sleep and WasEntryUpdated live with their kin."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from itertools import repeat

from ..errors import BTRuntimeError, LogicError
from ..node import _LIBRARY_EXECUTE_TICKS, ConditionNode, NodeCell, NodeConfig, SyncActionNode, TreeNode
from ..ports import ANY, ANYTYPE, EMPTY, STRING, bidirectional_port, blackboard_key, input_port, type_of_value
from ..script import Script, ScriptError, compile_node_script, compile_script
from ..status import FAILURE, IDLE, SUCCESS, NodeStatus


class AlwaysSuccessNode(SyncActionNode):
    _bare_tick_ok = True  # never RUNNING: parents may call the bare tick
    _bare_tick_per_class = True  # (_bare_tick() is the same for every node: see node._class_fast)

    def tick(self) -> NodeStatus:
        return SUCCESS

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        return _returns_success


class AlwaysFailureNode(SyncActionNode):
    _bare_tick_ok = True
    _bare_tick_per_class = True

    def tick(self) -> NodeStatus:
        return FAILURE

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        return _returns_failure


# f(node) -> the status, without a Python frame: next() of an endless repeat, whose second
# argument (the node) would only be the default of an exhausted iterator. What parents call.
_returns_success = partial(next, repeat(SUCCESS))
_returns_failure = partial(next, repeat(FAILURE))


class _ScriptHolder:
    """Compile the ``code`` port once; recompile only if its text changes.

    A literal ``code`` (the usual case) cannot change, so it is compiled as it stands in the
    XML (what reading the port would return: the text, a string port or an untyped one) and
    never read again; only code taken from a blackboard entry is re-read on every tick."""

    __slots__ = ()  # the nodes hold _code_text, _script, _code_from_blackboard in slots
    _kind = "Script"

    def __init__(self, name: str, config: NodeConfig):
        if type(self) in _PLAIN_INIT:  # super().__init__ is TreeNode's: called without super()'s cost
            if self._literal_script(config):  # (then TreeNode.__init__ picks the script's tick)
                TreeNode.__init__(self, name, config)
                return
            TreeNode.__init__(self, name, config)
        else:
            self._script = None  # see _bare_tick
            super().__init__(name, config)
        self._init_script()
        self._use_script_tick()

    def _literal_script(self, config: NodeConfig | None) -> bool:
        """Compile a literal ``code`` before the node is initialised (True), so that
        ``TreeNode.__init__`` picks the script's own tick at once; otherwise (no config, no
        ``code``, code from the blackboard: False) ``_init_script`` does it after."""
        raw = config.input_ports.get("code") if config is not None else None
        # (a pointer is '{key}' or '='; '{' not in the text settles most without the call)
        if type(raw) is str and (("{" not in raw and raw != "=") or blackboard_key(raw, "code") is None):
            self._code_from_blackboard = False
            self._script = compile_node_script(raw)
            self._code_text = raw
            return True
        self._script = None  # see _bare_tick
        return False

    def _init_script(self) -> None:
        raw = self.config.input_ports.get("code")
        if raw is None:
            raise BTRuntimeError(f"Missing port [code] in {self._kind}")
        if type(raw) is str and blackboard_key(raw, "code") is None:
            self._code_from_blackboard = False
            self._script = compile_node_script(raw)
            self._code_text = raw
            return
        self._code_text = None
        self._script = None
        self._code_from_blackboard = isinstance(raw, str)
        self._load()

    def _use_script_tick(self) -> None:
        """Once the script is known, let parents call its one-call tick (``_bare_tick``)."""
        if self._code_from_blackboard:
            return
        cfg = self.config
        if cfg._pre or cfg._post:
            self._select_execute_tick()
        elif self._cell.fast is type(self).tick:
            self._cell.fast = self._script_tick(self._script)

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        """The script's own tick for literal code (``tick()`` while the node is being built,
        or when the code comes from the blackboard)."""
        script = self._script  # None while TreeNode.__init__ runs (before the script is compiled)
        if script is None or self._code_from_blackboard:
            return type(self).tick
        return self._script_tick(script)

    @classmethod
    def builder(cls) -> Callable[[str, NodeConfig], TreeNode]:
        """What the factory registers: ``cls(name, config)``, for literal ``code`` (the usual
        case) in one frame without the type call and ``__init__`` frames (once per node)."""
        plain = cls in _PLAIN_INIT
        # the fast tick TreeNode.__init__ picks for a node of cls without conditions is _bare_tick()
        assert cls._bare_tick_ok and cls.execute_tick in _LIBRARY_EXECUTE_TICKS, cls
        script_tick = cls._tick_of  # Script.action_tick or .condition_tick

        def build(name: str, config: NodeConfig) -> TreeNode:
            raw = config.input_ports.get("code")
            # (a pointer is '{key}' or '='; '{' not in the text settles most without the call)
            if plain and type(raw) is str and (("{" not in raw and raw != "=") or blackboard_key(raw, "code") is None):
                try:
                    script = compile_script(raw)  # compile_node_script(raw), inlined
                except ScriptError as exc:
                    raise BTRuntimeError(str(exc)) from None
                node = _new_object(cls)
                node._code_from_blackboard = False
                node._script = script
                node._code_text = raw
                if config._pre or config._post:
                    _tree_node_init(node, name, config)  # (which picks the conditions' tick)
                    return node
                # TreeNode.__init__(node, name, config), inlined: the node's fast tick is its
                # script's one-call tick (what _bare_tick gives; the class's execute_tick is the
                # library's and the bare tick is allowed: checked below, once)
                node.name = name
                node.config = config
                node._cell = cell = _new_cell()
                cell.status = IDLE
                cell.node = node
                node._input_cache = None
                cell.fast = script_tick(script)
                return node
            return cls(name, config)
        build.node_class = cls  # type: ignore[attr-defined]
        return build

    _unbound_tick = _bare_tick

    def _load(self) -> None:
        try:
            text = self.get_input("code")
        except BTRuntimeError:
            raise BTRuntimeError(f"Missing port [code] in {self._kind}") from None
        if not isinstance(text, str):
            raise BTRuntimeError(f"The port [code] of {self._kind} must contain a string")
        if text != self._code_text:
            self._script = compile_node_script(text)
            self._code_text = text


class ScriptNode(_ScriptHolder, SyncActionNode):
    """Run a script (assignments, expressions); always SUCCESS."""

    __slots__ = ("_code_text", "_script", "_code_from_blackboard")
    _kind = "Script"
    _bare_tick_ok = True  # tick() always returns SUCCESS: no RUNNING check needed

    @classmethod
    def provided_ports(cls):
        return [input_port("code", str, description="Piece of code that can be parsed")]

    def tick(self) -> NodeStatus:
        if self._code_from_blackboard:
            self._load()
        self._script.run(self.config.blackboard, self.config.enums)
        return SUCCESS

    def _script_tick(self, script: Script) -> Callable[[TreeNode], NodeStatus]:
        return script._action_tick or script.action_tick()

    _tick_of = staticmethod(Script.action_tick)

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        """``_ScriptHolder._bare_tick`` in one frame (once per node built)."""
        script = self._script  # None while TreeNode.__init__ runs (before the script is compiled)
        if script is None or self._code_from_blackboard:
            return type(self).tick
        return script._action_tick or script.action_tick()

    _unbound_tick = _bare_tick


class ScriptConditionNode(_ScriptHolder, ConditionNode):
    """SUCCESS if the script's last value is true, else FAILURE."""

    __slots__ = ("_code_text", "_script", "_code_from_blackboard")
    _kind = "ScriptCondition"

    @classmethod
    def provided_ports(cls):
        return [input_port("code", ANYTYPE,
                           description="Piece of code that can be parsed. Must return false or true")]

    def tick(self) -> NodeStatus:
        if self._code_from_blackboard:
            self._load()
        cfg = self.config
        return SUCCESS if self._script.run_bool(cfg.blackboard, cfg.enums) else FAILURE

    def _script_tick(self, script: Script) -> Callable[[TreeNode], NodeStatus]:
        return script._condition_tick or script.condition_tick()

    _tick_of = staticmethod(Script.condition_tick)

    def _bare_tick(self) -> Callable[[TreeNode], NodeStatus]:
        """``_ScriptHolder._bare_tick`` in one frame (once per node built)."""
        script = self._script
        if script is None or self._code_from_blackboard:
            return type(self).tick
        return script._condition_tick or script.condition_tick()

    _unbound_tick = _bare_tick


def _next_init(cls: type) -> object:
    """The constructor ``super().__init__`` reaches from ``_ScriptHolder.__init__``."""
    mro = cls.__mro__
    return next(k.__dict__["__init__"] for k in mro[mro.index(_ScriptHolder) + 1:] if "__init__" in k.__dict__)


# The script node classes whose super().__init__ is TreeNode.__init__ (checked, not assumed:
# a base that gains a constructor is then called through super() again).
_PLAIN_INIT = frozenset(cls for cls in (ScriptNode, ScriptConditionNode) if _next_init(cls) is TreeNode.__init__)


_new_object = object.__new__
_new_cell = NodeCell
_tree_node_init = TreeNode.__init__


class SetBlackboardNode(SyncActionNode):
    """Write ``value`` (a literal string or ``{other_key}``) into the entry named by ``output_key``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("value", ANYTYPE, description="Value to be written into the output_key"),
                bidirectional_port("output_key", ANYTYPE,
                                   description="Name of the blackboard entry where the value should be written")]

    def tick(self) -> NodeStatus:
        try:
            output_key = self.get_input("output_key")
        except BTRuntimeError:
            raise BTRuntimeError("missing port [output_key]") from None
        output_key = str(output_key)
        cfg = self.config
        bb = cfg.blackboard
        value_str = cfg.input_ports.get("value")
        if value_str is None:
            raise BTRuntimeError("missing port [value]")
        dst = bb.get_entry(output_key)
        src_key = blackboard_key(value_str, "value")
        if src_key is not None:
            src = bb.get_entry(src_key)
            if src is None:
                raise BTRuntimeError("Can't find the port referred by [value]")
            if dst is None:
                bb.create_entry(output_key, src.type)
                dst = bb.get_entry(output_key)
            out = src.value
            out_type = src.type if src.type.strongly_typed else None
        else:
            out, out_type = value_str, STRING
        if out is EMPTY:
            return FAILURE
        if dst is not None and dst.type.name != STRING.name and isinstance(out, str):
            if dst.type.kind == "anytype":
                # BT.CPP quirk: an untyped entry has no converter, the conversion yields an empty
                # BT::Any, so the entry becomes "not initialized". A local entry is typed BT::Any
                # from then on; one reached through a remapping keeps its type (BT.CPP's set()
                # takes its create-entry branch for keys it does not store itself).
                dst.write(EMPTY)
                if output_key[:1] == "@" or bb.local_entries().get(output_key) is dst:
                    dst.type = ANY
                return SUCCESS
            if dst.type.kind == "any":
                raise LogicError(f"Can't convert string [{out}] to type [BT::Any]: You didn't implement "
                                 "the template specialization of convertFromString for this type: BT::Any")
            if not dst.type.has_converter:
                # e.g. a NodeStatus entry: BT.CPP's parseString gives an empty value, which set() refuses
                raise LogicError(f"Blackboard::set({output_key}): once declared, the type of a port shall not "
                                 f"change. Previously declared type [{dst.type.name}], current type [BT::Any]")
            try:
                out = dst.type.from_string(out, cfg.enums)
            except Exception as exc:
                raise LogicError(f"Can't convert string [{out}] to type [{dst.type.name}]: {exc}") from None
            out_type = dst.type
        bb.set_any(output_key, out, out_type or type_of_value(out))
        return SUCCESS


class UnsetBlackboardNode(SyncActionNode):
    """Remove ``key`` from the node's own (local) blackboard."""

    @classmethod
    def provided_ports(cls):
        return [input_port("key", str, description="Key of the entry to remove")]

    def tick(self) -> NodeStatus:
        try:
            key = self.get_input("key")
        except BTRuntimeError:
            raise BTRuntimeError("missing input port [key]") from None
        self.config.blackboard.unset(key)
        return SUCCESS
