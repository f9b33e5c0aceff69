"""Why a run went wrong, in words: the last failing node of the tree and the navigation stack's
last error (Nav2 error code and message), so a summary can say why a goal was not reached.

    why = FailureWitness.attach(runtime)      # after load_tree, before start
    ...
    why.reason(since=t_goal_sent)              # 'navigation: GOAL_OUTSIDE_MAP (204) ...'

It watches from the outside: a status observer on some of the tree's nodes and a transparent
proxy around the driver's navigation client. Nothing in the tree changes behaviour because it is
watched.

A leaf's FAILURE is reported once the SubTree holding it fails too (an inverted condition failing
is business as usual; a planning failure that fails the PathPlanning subtree is a cause): more
exactly, when a node whose path is a prefix of leaf paths (``mission/path_planning`` of
``mission/path_planning/ComputePathToPose::77``, a SubTree node) fails, the latest of the last
20 leaf failures under it is the failing node. Only those nodes and the leaves under them are
observed, and only for FAILURE: an observed node's status stores and reads cost more on every
tick, and the other nodes' failures could never be reported.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
from dataclasses import dataclass
from typing import Any

from ..status import FAILURE, NodeStatus
from .messages import ActionStatus, NavErrorCode, NavResult

_KEEP = 50
_LEAF_WINDOW = 20  # a leaf failure older than the last 20 explains no later failure


@dataclass(frozen=True, slots=True)
class NodeFailure:
    t: float
    path: str  # the node's full path in the tree, e.g. Mission/handle_goal/plan_and_go/NavigateToPose
    node_type: str


@dataclass(frozen=True, slots=True)
class NavError:
    t: float
    action: str  # navigate_to_pose, compute_path_to_pose, follow_path, ...
    status: str  # ABORTED, CANCELED, ...
    code: int
    code_name: str
    message: str

    def describe(self) -> str:
        text = f"{self.action} {self.status}: {self.code_name} ({self.code})"
        return f"{text}: {self.message}" if self.message else text


def code_name(code: int) -> str:
    try:
        return NavErrorCode(int(code)).name
    except ValueError:
        return "UNKNOWN_CODE"


class WatchedNavigation:
    """A transparent proxy of a NavigationClient that remembers each failed result."""

    _HANDLE_METHODS = ("navigate_to_pose", "follow_path", "spin", "back_up", "drive_on_heading", "wait")

    def __init__(self, inner: Any, clock, errors: collections.deque):
        self._inner = inner
        self._clock = clock
        self._errors = errors
        self._open: list[tuple[str, Any]] = []  # handles not yet finished

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._inner, name)
        if name in self._HANDLE_METHODS and callable(attr):
            def start(*args: Any, **kw: Any) -> Any:
                handle = attr(*args, **kw)
                self._open.append((name, handle))
                return handle
            return start
        return attr

    async def compute_path_to_pose(self, goal, **kw):
        result = await self._inner.compute_path_to_pose(goal, **kw)
        self._note("compute_path_to_pose", result)
        return result

    def poll(self) -> None:
        """Collect the results of the handles that finished since the last poll."""
        still = []
        for name, handle in self._open:
            try:
                done = handle.done()
            except Exception:
                continue
            if not done:
                still.append((name, handle))
                continue
            with contextlib.suppress(Exception):  # a cancelled or broken handle has nothing to explain
                self._note(name, handle.result())
        self._open = still

    def _note(self, action: str, result: NavResult) -> None:
        status = getattr(result, "status", None)
        if status is None or status is ActionStatus.SUCCEEDED:
            return
        code = int(getattr(result, "error_code", 0) or 0)
        self._errors.append(NavError(self._clock(), action, getattr(status, "name", str(status)), code,
                                     code_name(code), str(getattr(result, "error_msg", "") or "")))


class FailureWitness:
    """Remembers the last failing leaf nodes and navigation errors of a runtime."""

    def __init__(self, runtime: Any):
        self.runtime = runtime
        self.node_failures: collections.deque[NodeFailure] = collections.deque(maxlen=_KEEP)
        self.nav_errors: collections.deque[NavError] = collections.deque(maxlen=_KEEP)
        # leaf -> (path, type, paths of the nodes holding it); holding node -> its path
        self._leaves: dict[Any, tuple[str, str, list[str]]] = {}
        self._holders: dict[Any, str] = {}
        self._leaf_count = 0  # leaf failures seen; only the last _LEAF_WINDOW of them are causes
        self._latest: dict[str, tuple[int, float, str, str]] = {}  # holder path -> its latest leaf failure
        self._nav: WatchedNavigation | None = None
        self._task: asyncio.Task | None = None
        self._unobserve = None

    @classmethod
    def attach(cls, runtime: Any) -> FailureWitness:
        """Watch ``runtime`` (its tree must be loaded; call before ``runtime.start()``)."""
        self = cls(runtime)
        tree = runtime.tree
        self._index(tree.nodes())
        self._unobserve = tree.add_status_observer(self._on_status, failures_only=True,
                                                   nodes=[*self._leaves, *self._holders])
        driver = runtime.driver
        if getattr(driver, "navigation", None) is not None:
            self._nav = WatchedNavigation(driver.navigation, runtime.clock, self.nav_errors)
            driver.navigation = self._nav
        self._task = runtime.loop.create_task(self._poll(), name="failure-witness")
        return self

    def _index(self, nodes) -> None:
        """Find the holding nodes (paths that prefix a leaf's path) and the leaves under them."""
        nodes = list(nodes)
        by_path: dict[str, list[Any]] = {}
        for node in nodes:
            if node.children_nodes():
                by_path.setdefault(node.full_path, []).append(node)
        for node in nodes:
            if node.children_nodes():
                continue
            path = node.full_path
            holders = [path[:i] for i, c in enumerate(path) if c == "/" and path[:i] in by_path]
            if holders:
                self._leaves[node] = (path, node.registration_name, holders)
                for holder in holders:
                    for held in by_path[holder]:
                        self._holders[held] = holder

    def detach(self) -> None:
        if self._task is not None:
            self._task.cancel()
        if self._unobserve is not None:
            self._unobserve()  # the tree's cells go back to plain stores
            self._unobserve = None

    async def _poll(self) -> None:
        while True:
            await asyncio.sleep(0.1)
            if self._nav is not None:
                self._nav.poll()

    def _on_status(self, _stamp: float, node: Any, _previous: NodeStatus, new: NodeStatus) -> None:
        """A leaf's FAILURE is remembered under each node holding it; it counts once one of
        them fails too, and as it climbs, the same leaf stays the cause."""
        if new is not FAILURE:
            return
        leaf = self._leaves.get(node)
        if leaf is not None:
            self._leaf_count += 1
            seen = (self._leaf_count, self.runtime.clock(), leaf[0], leaf[1])
            latest = self._latest
            for holder in leaf[2]:
                latest[holder] = seen
            return
        seen = self._latest.get(self._holders[node])
        if seen is None or seen[0] <= self._leaf_count - _LEAF_WINDOW:
            return
        _, t, leaf_path, leaf_type = seen
        last = self.node_failures[-1] if self.node_failures else None
        if last is None or (last.path, last.t) != (leaf_path, t):
            self.node_failures.append(NodeFailure(t, leaf_path, leaf_type))

    # -- queries ---------------------------------------------------------------------------------
    def last_node_failure(self, since: float = float("-inf")) -> NodeFailure | None:
        return next((f for f in reversed(self.node_failures) if f.t >= since), None)

    def last_nav_error(self, since: float = float("-inf")) -> NavError | None:
        if self._nav is not None:
            self._nav.poll()
        return next((e for e in reversed(self.nav_errors) if e.t >= since and e.status != "CANCELED"), None)

    def reason(self, since: float = float("-inf")) -> str:
        """The best explanation of a failure since ``since``: the navigation error, then the
        failing node (a condition such as BatteryCanReach says more than a navigation code)."""
        parts = []
        nav = self.last_nav_error(since)
        if nav is not None:
            parts.append(nav.describe())
        node = self.last_node_failure(since)
        if node is not None:
            parts.append(f"last failing node {node.path} [{node.node_type}]")
        return "; ".join(parts) or "no node failed and the navigation stack reported no error"

    def to_dict(self, since: float = float("-inf")) -> dict[str, Any]:
        nav, node = self.last_nav_error(since), self.last_node_failure(since)
        return {"failing_node": None if node is None else {"path": node.path, "type": node.node_type,
                                                           "t": round(node.t, 3)},
                "navigation_error": None if nav is None else {
                    "action": nav.action, "status": nav.status, "code": nav.code, "code_name": nav.code_name,
                    "message": nav.message, "t": round(nav.t, 3)}}
