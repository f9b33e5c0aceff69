"""What a scenario run leaves behind, for judging and reports.

Success is judged from these records (ground truth trajectory, supervisor events, navigation
requests, map updates, the simulator's fault and component log), never from what the tree
believes. The navigation client is wrapped so every request is recorded with its time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_runtime.runtime.messages import Pose2D


@dataclass
class NavRequest:
    t: float
    method: str
    goal: Pose2D | None = None
    args: dict[str, Any] = field(default_factory=dict)


class RecordingNavigation:
    """A transparent proxy of a NavigationClient that logs requests."""

    def __init__(self, inner: Any, clock):
        self._inner = inner
        self._clock = clock
        self.requests: list[NavRequest] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def _log(self, method: str, goal: Pose2D | None = None, **args: Any) -> None:
        self.requests.append(NavRequest(self._clock(), method, goal, args))

    def navigate_to_pose(self, goal, **kw):
        self._log("navigate_to_pose", goal)
        return self._inner.navigate_to_pose(goal, **kw)

    async def compute_path_to_pose(self, goal, **kw):
        self._log("compute_path_to_pose", goal)
        return await self._inner.compute_path_to_pose(goal, **kw)

    def follow_path(self, path, **kw):
        end = path.points[-1] if len(path) else None
        goal = Pose2D(float(end[0]), float(end[1]), float(end[2]) if len(end) > 2 else 0.0) if end is not None else None
        self._log("follow_path", goal)
        return self._inner.follow_path(path, **kw)

    async def add_obstacle(self, x, y, radius=0.1):
        self._log("add_obstacle", Pose2D(x, y), radius=radius)
        return await self._inner.add_obstacle(x, y, radius)

    async def clear_costmaps(self, which="both"):
        self._log("clear_costmaps", which=which)
        return await self._inner.clear_costmaps(which)

    def cancel_all(self):
        self._log("cancel_all")
        return self._inner.cancel_all()

    def of(self, method: str) -> list[NavRequest]:
        return [r for r in self.requests if r.method == method]


@dataclass
class GoalRecord:
    index: int
    pose: Pose2D
    sent: float
    finished: float | None = None
    outcome: str = ""  # what the tree/navigator reported (for sequencing, not judging)


@dataclass
class RunRecord:
    """Everything a run recorded."""

    scenario: str
    mode: str
    seed: int
    duration: float
    trajectory: np.ndarray  # columns t, x, y, yaw, v, w, contact (ground truth, 10 Hz)
    goals: list[GoalRecord]
    supervisor_events: list[Any]
    final_health: dict[str, str]
    component_states: dict[str, str]
    nav_requests: list[NavRequest]
    fault_log: list[Any]
    sim_events: list[Any]
    obstacles: dict[str, Any]  # name -> obstacle shape added at run time
    gate_switches: list[Any]
    tick_errors: int = 0
    tick_cost_mean_us: float = 0.0
    wall_time: float = 0.0
    start: Pose2D | None = None
    map_grid: Any = None
    component_log: list[Any] = field(default_factory=list)  # the simulator's (sim.component_log)
