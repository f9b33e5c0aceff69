"""Why a run went wrong, in words: the last failing node of the tree and the navigation stack's
last error (Nav2 error code and message), so a summary can say why a goal was not reached.

    why = FailureWitness.attach(runtime)      # after load_tree, before start
    ...
    why.reason(since=t_goal_sent)              # 'navigation: GOAL_OUTSIDE_MAP (204) ...'

It watches from the outside: a status observer on the tree and a transparent proxy around the
driver's navigation client. Nothing in the tree changes behaviour because it is watched.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
from dataclasses import dataclass
from typing import Any

from ..status import NodeStatus
from .messages import ActionStatus, NavErrorCode, NavResult

_KEEP = 50


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
        self._leaf_failures: collections.deque[tuple[float, str, str]] = collections.deque(maxlen=20)
        self._nav: WatchedNavigation | None = None
        self._task: asyncio.Task | None = None

    @classmethod
    def attach(cls, runtime: Any) -> FailureWitness:
        """Watch ``runtime`` (its tree must be loaded; call before ``runtime.start()``)."""
        self = cls(runtime)
        runtime.tree.add_status_observer(self._on_status, failures_only=True)  # all it reads
        driver = runtime.driver
        if getattr(driver, "navigation", None) is not None:
            self._nav = WatchedNavigation(driver.navigation, runtime.clock, self.nav_errors)
            driver.navigation = self._nav
        self._task = runtime.loop.create_task(self._poll(), name="failure-witness")
        return self

    def detach(self) -> None:
        if self._task is not None:
            self._task.cancel()

    async def _poll(self) -> None:
        while True:
            await asyncio.sleep(0.1)
            if self._nav is not None:
                self._nav.poll()

    def _on_status(self, _stamp: float, node: Any, _previous: NodeStatus, new: NodeStatus) -> None:
        """A leaf's FAILURE counts once it fails its parent too (an inverted condition failing
        is business as usual); as it climbs, the same leaf stays the cause."""
        if new is not NodeStatus.FAILURE:
            return
        path = node.full_path
        if not list(node.children_nodes()):
            self._leaf_failures.append((self.runtime.clock(), path, node.registration_name))
            return
        prefix = path + "/"
        for t, leaf_path, leaf_type in reversed(self._leaf_failures):
            if leaf_path.startswith(prefix):
                last = self.node_failures[-1] if self.node_failures else None
                if last is None or (last.path, last.t) != (leaf_path, t):
                    self.node_failures.append(NodeFailure(t, leaf_path, leaf_type))
                return

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
