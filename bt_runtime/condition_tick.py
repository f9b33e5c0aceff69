"""The tick of a node with pre/post-condition scripts and no hooks: ``TreeNode._execute_tick_full``
(BT.CPP executeTick, spec 3.1) specialised to the scripts the node has.

A node usually carries one pre-condition and a post-condition or two, so the common closure
holds at most one IDLE check and one script per outcome in its cells and calls the compiled
scripts directly (their errors reported as ``Script.run`` reports them): no dictionary look-ups,
no loops, no absent scripts on the tick path. Other combinations take the general closure.

The closures read the blackboard and identity from ``node.config`` when they run, so they
depend only on the node's tick and scripts: while a tree is built (``shared_during_build``) the
nodes with the same tick and the same conditions share one closure (a tree repeats a few
condition combinations on many nodes; each closure is about fifteen objects). The tree builder
gives the elements with the same condition attributes the same ``SharedConditions``, so the
closure is found by the attributes' text, without a key made from the scripts.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .errors import BTRuntimeError, NodeExecutionError
from .script import CastError, ScriptRuntimeError, to_bool
from .status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus

Tick = Callable[[Any], NodeStatus]
After = Callable[[Any, NodeStatus], None]

_NONE: dict = {}  # (never changed)

# (attribute, the status it gives, whether the script's value is negated), in BT.CPP's order
_IDLE_CHECKS = (("_failureIf", FAILURE, False), ("_successIf", SUCCESS, False), ("_skipIf", SKIPPED, False),
                ("_while", SKIPPED, True))


class SharedConditions(dict):
    """The pre- or post-condition scripts (attribute -> Script) the tree builder gives every
    node of a build whose element has the same condition attributes, ``key`` those attributes
    ((name, text), ... in BT.CPP's order). Read-only: ``NodeConfig.pre_conditions`` and
    ``post_conditions`` hand a node its own copy before anyone may change it."""

    __slots__ = ("key",)


# (tick, after, pre items, post items) or (tick, after, attributes) -> closure, while the tree builder builds a tree (None
# otherwise: nothing outlives a build, so a closure never keeps a node or a script alive)
_build_memo: dict[tuple, Tick] | None = None


class shared_during_build:
    """``with shared_during_build():`` nodes built meanwhile share equal condition closures."""

    __slots__ = ("_previous",)

    def __enter__(self) -> None:
        global _build_memo
        self._previous = _build_memo
        _build_memo = {}

    def __exit__(self, *exc: object) -> None:
        global _build_memo
        _build_memo = self._previous


def conditions_tick(tick: Tick, cfg: Any, after: After | None) -> Tick:
    """``_execute_tick_full`` for a node with pre/post-conditions and no hooks. ``tick`` is
    ``f(node) -> status``; ``after`` is the library subclass's own step (SyncActionNode's
    RUNNING check, DecoratorNode's child reset).

    The scripts are taken from the config now; code that changes a node's conditions later
    calls ``refresh_conditions()``, as it must for the fast paths too."""
    pre = cfg._pre or _NONE
    post = cfg._post or _NONE
    memo = _build_memo
    if memo is not None:
        given = pre or post
        if type(given) is SharedConditions and (post is _NONE or type(post) is SharedConditions):
            key = (tick, after, given.key)  # (both from the same element's attributes)
        else:
            key = (tick, after, tuple(pre.items()), tuple(post.items()))
        shared = memo.get(key)
        if shared is not None:
            return shared
    idle_checks = tuple((script, result, negate) for key, result, negate in _IDLE_CHECKS
                        if (script := pre.get(key)) is not None)
    on_success = tuple(s for k in ("_onSuccess", "_post") if (s := post.get(k)) is not None)
    on_failure = tuple(s for k in ("_onFailure", "_post") if (s := post.get(k)) is not None)
    if len(idle_checks) <= 1 and len(on_success) <= 1 and len(on_failure) <= 1:
        execute = _one_each(tick, after, idle_checks, pre.get("_while"), on_success, on_failure)
    else:
        execute = _general(tick, after, idle_checks, pre.get("_while"), on_success, on_failure)
    execute.wraps_tick_errors = True  # type: ignore[attr-defined]  # see node._is_execute_tick
    if memo is not None:
        memo[key] = execute
    return execute


def _one_each(tick: Tick, after: After | None, idle_checks: tuple, while_script: Any,
              on_success: tuple, on_failure: tuple) -> Tick:
    """At most one IDLE check and one script per outcome: everything in closure cells."""
    check, check_text, result, negate = None, "", None, False
    if idle_checks:
        script, result, negate = idle_checks[0]
        check, check_text = script._fn, script.text
    running_while = while_script.run_bool if while_script is not None else None
    success_fn, success_text = (on_success[0]._fn, on_success[0].text) if on_success else (None, "")
    failure_fn, failure_text = (on_failure[0]._fn, on_failure[0].text) if on_failure else (None, "")

    def execute(node: Any) -> NodeStatus:
        cfg = node.config
        cell = node._cell
        current = cell.status
        status = None
        if current is IDLE:
            if check is not None:
                try:
                    value = check(cfg.blackboard, cfg.enums)
                except CastError:
                    raise
                except BTRuntimeError as exc:  # as Script.run_bool reports it
                    raise ScriptRuntimeError(f"Error in script [{check_text}]\n{exc}") from exc
                if (value != 0.0 if type(value) is float and value >= 0.0 else to_bool(value)) is not negate:
                    status = result
        elif current is RUNNING and running_while is not None and not running_while(cfg.blackboard, cfg.enums):
            node.halt_node()
            return SKIPPED
        if status is None:
            try:
                status = tick(node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise NodeExecutionError(cfg.path, cfg.registration_id, exc) from exc
        if status is SUCCESS:
            if success_fn is not None:
                try:
                    success_fn(cfg.blackboard, cfg.enums)
                except CastError:
                    raise
                except BTRuntimeError as exc:  # as Script.run reports it
                    raise ScriptRuntimeError(f"Error in script [{success_text}]\n{exc}") from exc
            cell.status = status
        elif status is FAILURE:
            if failure_fn is not None:
                try:
                    failure_fn(cfg.blackboard, cfg.enums)
                except CastError:
                    raise
                except BTRuntimeError as exc:
                    raise ScriptRuntimeError(f"Error in script [{failure_text}]\n{exc}") from exc
            cell.status = status
        elif status is not SKIPPED:
            if status is IDLE:
                node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
            cell.status = status
        if after is not None:
            after(node, status)
        return status

    return execute


def _general(tick: Tick, after: After | None, idle_checks: tuple, while_script: Any,
             on_success: tuple, on_failure: tuple) -> Tick:
    """Any number of checks and post-conditions."""
    # (the script's closure, its Script for errors, the result, negate): Script.run_bool inlined
    checks = tuple((script._fn, script, result, negate) for script, result, negate in idle_checks)
    running_while = while_script.run_bool if while_script is not None else None
    success_runs = tuple(s.run for s in on_success)
    failure_runs = tuple(s.run for s in on_failure)

    def execute(node: Any) -> NodeStatus:
        cfg = node.config
        bb = cfg.blackboard
        enums = cfg.enums
        cell = node._cell
        current = cell.status
        status = None
        if current is IDLE:
            for fn, script, result, negate in checks:
                try:
                    value = fn(bb, enums)
                except CastError:
                    raise
                except BTRuntimeError as exc:  # as Script.run_bool reports it
                    raise ScriptRuntimeError(f"Error in script [{script.text}]\n{exc}") from exc
                if (value != 0.0 if type(value) is float and value >= 0.0 else to_bool(value)) is not negate:
                    status = result
                    break
        elif current is RUNNING and running_while is not None and not running_while(bb, enums):
            node.halt_node()
            return SKIPPED
        if status is None:
            try:
                status = tick(node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise NodeExecutionError(cfg.path, cfg.registration_id, exc) from exc
        if status is SUCCESS:
            for run in success_runs:
                run(bb, enums)
        elif status is FAILURE:
            for run in failure_runs:
                run(bb, enums)
        if status is not SKIPPED:
            if status is IDLE:
                node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
            cell.status = status
        if after is not None:
            after(node, status)
        return status

    return execute
