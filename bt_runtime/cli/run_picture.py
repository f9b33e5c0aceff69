"""``run --png FILE``: draw the run: the map, the trajectory, the goals, collisions and faults,
and the obstacles the autonomy layer marked in the map.

In the simulator the trajectory is the ground truth (drawing a run is what the truth is for);
on a real robot it is the robot's own pose estimate, sampled at 10 Hz, drawn on ``--world``.
"""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import numpy as np

MARK = (200, 0, 160)


class MarkedObstacles:
    """A transparent proxy of the navigation client that remembers the obstacles marked in the map."""

    def __init__(self, inner: Any):
        self._inner = inner
        self.marks: list[tuple[float, float]] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    async def add_obstacle(self, x, y, radius=0.1):
        self.marks.append((float(x), float(y)))
        return await self._inner.add_obstacle(x, y, radius)


class RunPicture:
    def __init__(self, runtime: Any, world_name: str):
        self.runtime = runtime
        self.world_name = world_name
        self.sim = getattr(runtime.driver, "sim", None)
        self.samples: list[tuple[float, float, float]] = []
        self.nav: MarkedObstacles | None = None
        self._task: asyncio.Task | None = None

    @classmethod
    def attach(cls, runtime: Any, world_name: str) -> RunPicture:
        self = cls(runtime, world_name)
        driver = runtime.driver
        if getattr(driver, "navigation", None) is not None:
            self.nav = MarkedObstacles(driver.navigation)
            driver.navigation = self.nav
        if self.sim is None:
            self._task = runtime.loop.create_task(self._sample(), name="run-picture")
        return self

    async def _sample(self) -> None:
        while True:
            pose = self.runtime.backup.latest("pose")
            if pose is not None:
                self.samples.append((self.runtime.clock(), pose.pose.x, pose.pose.y))
            await asyncio.sleep(0.1)

    def write(self, path: str | Path, goals: list[Any], title: str) -> Path:
        from sim.render import render_png
        from sim.world import load_world

        if self._task is not None:
            self._task.cancel()
        if self.sim is not None:
            world, trajectory = self.sim.world, self.sim.trajectory()
            events, obstacles = self.sim.events, list(self.sim.dynamic_obstacles.values())
        else:
            world, trajectory = load_world(self.world_name), np.array(self.samples).reshape(-1, 3)
            events, obstacles = [], []
        marks = [(x, y, MARK, "obstacle marked by the layer") for x, y in (self.nav.marks if self.nav else [])]
        named = {f"goal {i}": (g.x, g.y) for i, g in enumerate(goals)}
        return render_png(path, world, trajectory=trajectory, events=events, obstacles=obstacles,
                          goals=named if goals else None, marks=marks, title=title, scale=50.0)
