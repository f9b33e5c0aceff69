"""Fakes shared by the Nav2 node tests (no tests here): a context with a scripted clock, a
data backup fed by the test and a navigation client whose actions the test finishes."""

from __future__ import annotations

import asyncio
from collections import defaultdict
from types import SimpleNamespace
from typing import Any

from bt_runtime.factory import BehaviorTreeFactory
from bt_runtime.runtime.messages import (
    ActionStatus,
    BatteryState,
    LocalizedPose,
    NavErrorCode,
    NavResult,
    Odometry,
    Pose2D,
    Twist,
)
from bt_runtime.status import NodeStatus
from nodes.nav2 import register_nav2_nodes


class FakeClock:
    def __init__(self, t: float = 0.0):
        self.t = t

    def __call__(self) -> float:
        return self.t

    def advance(self, dt: float) -> None:
        self.t += dt


class FakeBackup:
    """The DataBackup queries the nodes use, over lists the test appends to."""

    def __init__(self, clock: FakeClock):
        self.clock = clock
        self.streams: dict[str, list[tuple[float, Any]]] = defaultdict(list)

    def record(self, stream: str, message: Any, stamp: float | None = None) -> None:
        self.streams[stream].append((self.clock() if stamp is None else stamp, message))

    def pose(self, x: float, y: float, yaw: float = 0.0) -> None:
        self.record("pose", LocalizedPose(self.clock(), Pose2D(x, y, yaw)))

    def odom(self, v: float, stamp: float | None = None) -> None:
        t = self.clock() if stamp is None else stamp
        self.record("odom", Odometry(t, Pose2D(0, 0), Twist(v, 0.0)), stamp=t)

    def battery(self, percentage: float, voltage: float = 11.0, current: float = 1.0) -> None:
        self.record("battery", BatteryState(self.clock(), voltage, percentage, current))

    def latest(self, stream: str) -> Any:
        items = self.streams.get(stream)
        return items[-1][1] if items else None

    def age(self, stream: str) -> float | None:
        items = self.streams.get(stream)
        return self.clock() - items[-1][0] if items else None

    def last_n(self, stream: str, n: int) -> list[Any]:
        return [m for _, m in self.streams.get(stream, [])[-n:]]

    def since(self, stream: str, t: float) -> list[Any]:
        return [m for s, m in self.streams.get(stream, []) if s >= t]


class FakeHandle:
    """A navigation action the test finishes with ``finish(status, code)``."""

    def __init__(self, kind: str, args: tuple, kwargs: dict):
        self.kind, self.args, self.kwargs = kind, args, kwargs
        self._result: NavResult | None = None
        self.cancelled = False
        self.updates: list[Any] = []
        self.feedback = None

    def done(self) -> bool:
        return self._result is not None

    def result(self) -> NavResult:
        assert self._result is not None
        return self._result

    def finish(self, status: ActionStatus = ActionStatus.SUCCEEDED, code: int = 0, msg: str = "",
               path: Any = None) -> None:
        self._result = NavResult(status, NavErrorCode(code) if code in NavErrorCode._value2member_map_
                                 else code, msg, path)

    def cancel(self) -> None:
        if self._result is None:
            self.cancelled = True
            self._result = NavResult(ActionStatus.CANCELED, NavErrorCode.NONE, "canceled")

    def __await__(self):
        async def wait():
            while self._result is None:
                await asyncio.sleep(0.001)
            return self._result
        return wait().__await__()

    def update_path(self, path: Any) -> bool:
        if self._result is not None:
            return False
        self.updates.append(path)
        return True


class FakeNav:
    """Records every call; actions return FakeHandles; coroutines wait for the test."""

    def __init__(self):
        self.calls: list[tuple[str, tuple, dict]] = []
        self.handles: list[FakeHandle] = []
        self.valid = True
        self.plan_results: list[NavResult] = []
        self.clears: list[str] = []
        self.service_delay = 0.0

    def _action(self, kind: str, *args: Any, **kwargs: Any) -> FakeHandle:
        self.calls.append((kind, args, kwargs))
        h = FakeHandle(kind, args, kwargs)
        self.handles.append(h)
        return h

    def follow_path(self, path, **kw):
        return self._action("follow_path", path, **kw)

    def spin(self, yaw, **kw):
        return self._action("spin", yaw, **kw)

    def back_up(self, dist, speed=0.025, **kw):
        return self._action("backup", dist, speed, **kw)

    def drive_on_heading(self, dist, speed=0.025, **kw):
        return self._action("drive_on_heading", dist, speed, **kw)

    def wait(self, duration):
        return self._action("wait", duration)

    def navigate_to_pose(self, goal, **kw):
        return self._action("navigate_to_pose", goal, **kw)

    def dock_robot(self, **kw):
        return self._action("dock_robot", **kw)

    def undock_robot(self, **kw):
        return self._action("undock_robot", **kw)

    async def compute_path_to_pose(self, goal, *, start=None, planner_id="", use_start=False):
        self.calls.append(("compute_path_to_pose", (goal,), {"start": start, "planner_id": planner_id,
                                                              "use_start": use_start}))
        await asyncio.sleep(0)
        return self.plan_results.pop(0)

    async def clear_costmaps(self, which="both"):
        self.clears.append(which)
        if self.service_delay:
            await asyncio.sleep(self.service_delay)

    def is_path_valid(self, path, max_cost=253):
        self.calls.append(("is_path_valid", (path,), {"max_cost": max_cost}))
        return self.valid

    def cancel_all(self):
        for h in self.handles:
            h.cancel()


def fake_context(t: float = 0.0) -> SimpleNamespace:
    clock = FakeClock(t)
    return SimpleNamespace(clock=clock, backup=FakeBackup(clock), navigation=FakeNav(), extras={})


class Counter:
    """``Count`` leaves: each returns the status the test set for it and counts its ticks."""

    def __init__(self):
        self.ticks: dict[str, int] = defaultdict(int)
        self.status: dict[str, NodeStatus] = defaultdict(lambda: NodeStatus.SUCCESS)

    def register(self, factory: BehaviorTreeFactory) -> None:
        def tick(node):
            self.ticks[node.name] += 1
            return self.status[node.name]
        factory.register_simple_action("Count", tick)

    def register_running(self, factory: BehaviorTreeFactory) -> None:
        """``Busy`` leaves may return RUNNING (stateful)."""
        def step(node):
            self.ticks[node.name] += 1
            return self.status[node.name]
        factory.register_simple_stateful_action("Busy", step, step)


def build(xml_body: str, ctx: Any = None, *, tree_id: str = "T", bb_init: dict | None = None,
          register: tuple = ()):
    """A tree of Nav2 nodes on a fake context; the tree runs on the context's clock."""
    ctx = ctx if ctx is not None else fake_context()
    factory = BehaviorTreeFactory(context=ctx)
    register_nav2_nodes(factory)
    for reg in register:
        reg(factory)
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="{tree_id}">{xml_body}</BehaviorTree></root>'
    tree = factory.create_tree_from_text(xml)
    tree.set_clock(ctx.clock)
    for key, value in (bb_init or {}).items():
        tree.root_blackboard.set(key, value)
    return tree, ctx


def node_named(tree, name: str):
    return next(n for n in tree.nodes() if n.name == name)
