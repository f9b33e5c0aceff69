"""Groot2 hooks: breakpoints and result replacement, without ever blocking the event loop.

BT.CPP blocks the ticking thread at a breakpoint until Groot2 unlocks it. Here the tree ticks
on the asyncio loop next to the supervisor, the decision gate and the monitor itself, so a
breakpoint **holds the node** instead: its pre-tick hook returns RUNNING, the node reports
RUNNING to its parent without being ticked, and everything else (the rest of the tree, every
other task, the Groot2 server) keeps running. On BREAKPOINT_UNLOCK the next tick of that node
uses the requested result (SUCCESS/FAILURE replaces ``tick()``; anything else ticks it for real).

Details that keep the held node honest:

* A node held while IDLE was never started. Before it really runs (unlock) or when the hook
  goes away, its status is reset to IDLE, so a stateful action starts with ``on_start``; and
  a halt while it is held only resets it (no ``on_halted`` for something that never started).
* A node held while RUNNING (breakpoint set on a running action) simply is not polled; a halt
  is a real halt.
* As in BT.CPP, a breakpoint fires every time the node's pre-tick hook runs (each tick while
  the node is not completed), a REPLACE hook publishes BREAKPOINT_REACHED each time it applies,
  a disabled hook does nothing, ``once``/``remove_when_done`` removes the hook after it fired.
* Position 1 (POST, BT.CPP 4.10): REPLACE hooks override the tick's result; a POST breakpoint
  cannot hold a result that was already computed, so it holds the node *before* the tick, like
  every hook in BT.CPP 4.8.2.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from bt_runtime.status import FAILURE, IDLE, RUNNING, SUCCESS, NodeStatus

if TYPE_CHECKING:
    from bt_runtime.node import TreeNode
    from bt_runtime.tree import Tree

BREAKPOINT, REPLACE = 0, 1
PRE, POST = 0, 1
_STATUS_NAMES = {s.name: s for s in NodeStatus}


class HookError(Exception):
    """A malformed hook request; its message is sent back as the error reply."""


class Hook:
    __slots__ = ("uid", "position", "mode", "enabled", "once", "desired", "waiting", "unlocked",
                 "held_from_idle")

    def __init__(self, uid: int, position: int):
        self.uid = uid
        self.position = position
        self.mode = BREAKPOINT
        self.enabled = True
        self.once = False
        self.desired = NodeStatus.SKIPPED
        self.waiting = False  # a breakpoint was reached and not yet unlocked
        self.unlocked: NodeStatus | None = None  # result chosen by BREAKPOINT_UNLOCK, not yet used
        self.held_from_idle = False

    def update(self, data: dict[str, Any]) -> None:
        """BT.CPP ``from_json``: every field is required."""
        try:
            enabled = data["enabled"]
            once = data["once"]
            mode = int(data["mode"])
            desired = data["desired_status"]
        except KeyError as exc:
            raise HookError(f"hook json: missing key {exc}") from None
        except (TypeError, ValueError) as exc:
            raise HookError(f"hook json: {exc}") from None
        if not isinstance(enabled, bool) or not isinstance(once, bool):
            raise HookError("hook json: 'enabled' and 'once' must be booleans")
        if mode not in (BREAKPOINT, REPLACE):
            raise HookError(f"hook json: invalid mode {mode}")
        if desired not in _STATUS_NAMES:
            raise HookError(f"Cannot convert this to NodeStatus: {desired}")
        self.enabled = enabled
        self.once = once
        self.mode = mode
        self.desired = _STATUS_NAMES[desired]

    def to_json(self) -> dict[str, Any]:
        return {"desired_status": self.desired.name, "enabled": self.enabled, "mode": self.mode,
                "once": self.once, "position": self.position, "uid": self.uid}


def _uid_and_position(data: Any) -> tuple[int, int]:
    if not isinstance(data, dict):
        raise HookError("hook json must be an object")
    try:
        uid = int(data["uid"])
        position = int(data["position"])
    except KeyError as exc:
        raise HookError(f"hook json: missing key {exc}") from None
    except (TypeError, ValueError) as exc:
        raise HookError(f"hook json: {exc}") from None
    if not 0 <= uid <= 0xFFFF:
        raise HookError(f"hook json: uid {uid} out of range")
    if position not in (PRE, POST):
        raise HookError(f"hook json: invalid position {position}")
    return uid, position


def parse_json(payload: bytes) -> Any:
    try:
        return json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise HookError(f"invalid json: {exc}") from None


class HookManager:
    """The hooks of one tree; ``notify(uid)`` publishes BREAKPOINT_REACHED."""

    def __init__(self, tree: Tree, notify: Callable[[int], None]):
        self._nodes: dict[int, TreeNode] = {n.uid: n for rec in tree.subtrees for n in rec.nodes}
        self._notify = notify
        self.hooks: dict[tuple[int, int], Hook] = {}  # (position, uid) -> hook
        self._with_pre: set[int] = set()  # uids whose pre/post-tick function is ours
        self._with_post: set[int] = set()

    # -- requests ----------------------------------------------------------------------------
    def insert(self, data: Any) -> None:
        """HOOK_INSERT: update the hook at (position, uid) or create one; unknown uids are ignored."""
        items = data if isinstance(data, list) else [data]
        for item in items:
            uid, position = _uid_and_position(item)
            hook = self.hooks.get((position, uid))
            if hook is not None:
                was_breakpoint = hook.mode == BREAKPOINT
                hook.update(item)
                if (was_breakpoint and hook.mode == REPLACE) or not hook.enabled:
                    self._release(hook)
                self._install(uid)
                continue
            node = self._nodes.get(uid)
            if node is None:
                continue  # BT.CPP: silently ignored, not listed by HOOKS_DUMP
            hook = Hook(uid, position)
            hook.update(item)
            self.hooks[(position, uid)] = hook
            self._install(uid)

    def remove(self, uid: int, position: int) -> bool:
        hook = self.hooks.pop((position, uid), None)
        if hook is None:
            return False
        self._release(hook)
        self._install(uid)
        return True

    def unlock(self, uid: int, position: int, status_name: str, remove: bool) -> bool:
        hook = self.hooks.get((position, uid))
        if hook is None or uid not in self._nodes:
            return False
        status = _STATUS_NAMES.get(status_name)
        if status is not SUCCESS and status is not FAILURE:
            status = NodeStatus.SKIPPED  # "anything else": run the node normally
        hook.desired = status
        hook.once = hook.once or remove
        if hook.mode == BREAKPOINT and hook.waiting:
            hook.waiting = False
            hook.unlocked = status
        return True

    def dump(self) -> list[dict[str, Any]]:
        pre = [h.to_json() for (pos, _), h in self.hooks.items() if pos == PRE]
        post = [h.to_json() for (pos, _), h in self.hooks.items() if pos == POST]
        return pre + post

    def remove_all(self) -> None:
        for key in list(self.hooks):
            hook = self.hooks.pop(key)
            self._release(hook)
            self._install(hook.uid)

    def enable_all(self, enabled: bool) -> None:
        for hook in self.hooks.values():
            hook.enabled = enabled
            if not enabled:
                self._release(hook)

    @property
    def held(self) -> list[int]:
        """Uids of the nodes currently held at a breakpoint."""
        return sorted({h.uid for h in self.hooks.values() if h.waiting})

    # -- installation --------------------------------------------------------------------------
    def _install(self, uid: int) -> None:
        node = self._nodes.get(uid)
        if node is None:
            return
        pre = self.hooks.get((PRE, uid))
        post = self.hooks.get((POST, uid))
        wants_pre = pre is not None or (post is not None and post.mode == BREAKPOINT)
        wants_post = post is not None and post.mode == REPLACE
        if wants_pre != (uid in self._with_pre):
            node.set_pre_tick_function(self._pre if wants_pre else None)
            (self._with_pre.add if wants_pre else self._with_pre.discard)(uid)
        if wants_post != (uid in self._with_post):
            node.set_post_tick_function(self._post if wants_post else None)
            (self._with_post.add if wants_post else self._with_post.discard)(uid)

    # -- the callbacks that run inside a tick ------------------------------------------------------
    def _pre(self, node: TreeNode) -> NodeStatus | None:
        uid = node.uid
        hook = self.hooks.get((PRE, uid))
        if hook is None:
            hook = self.hooks.get((POST, uid))
            if hook is None or hook.mode != BREAKPOINT:
                return None
        if not hook.enabled:
            return None
        if hook.mode == REPLACE:
            self._notify(uid)
            status = hook.desired
            if hook.once:
                self._drop(hook)
            return status if status is SUCCESS or status is FAILURE else None
        if hook.waiting:
            if node.status is IDLE:  # halted while held: hold it again, from IDLE
                self._begin_hold(hook, node)
            return RUNNING
        if hook.unlocked is not None:
            status = hook.unlocked
            hook.unlocked = None
            self._end_hold(hook, node)
            if hook.once:
                self._drop(hook)
            return status if status is SUCCESS or status is FAILURE else None
        # the breakpoint is reached
        self._notify(uid)
        hook.waiting = True
        self._begin_hold(hook, node)
        return RUNNING

    def _post(self, node: TreeNode, status: NodeStatus) -> NodeStatus | None:
        hook = self.hooks.get((POST, node.uid))
        if hook is None or hook.mode != REPLACE or not hook.enabled:
            return None
        self._notify(node.uid)
        desired = hook.desired
        if hook.once:
            self._drop(hook)
        return desired if desired is SUCCESS or desired is FAILURE else None

    def _drop(self, hook: Hook) -> None:
        """Remove a one-shot hook from inside a tick (the node's hook slots are updated)."""
        if self.hooks.get((hook.position, hook.uid)) is hook:
            del self.hooks[(hook.position, hook.uid)]
            self._install(hook.uid)

    # -- holding -----------------------------------------------------------------------------------
    def _begin_hold(self, hook: Hook, node: TreeNode) -> None:
        if node.status is IDLE:
            hook.held_from_idle = True

            def quiet_halt() -> None:
                node.reset_status()

            node.__dict__["halt"] = quiet_halt  # it never started: no on_halted()

    def _end_hold(self, hook: Hook, node: TreeNode) -> None:
        """Before a held node really runs again: restore halt() and, if it was held from IDLE,
        its IDLE status (so it starts fresh, e.g. a StatefulActionNode gets on_start)."""
        if hook.held_from_idle:
            hook.held_from_idle = False
            node.__dict__.pop("halt", None)
            if node.status is RUNNING:
                node.reset_status()

    def _release(self, hook: Hook) -> None:
        """The hook stops holding (disabled, removed, switched to REPLACE, server stopped)."""
        hook.unlocked = None
        if hook.waiting:
            hook.waiting = False
            node = self._nodes.get(hook.uid)
            if node is not None:
                self._end_hold(hook, node)
