"""A scripted waypoint follower: drives the base through waypoints on a pose source.

For tests and benchmarks while no planner/controller runs. By default it steers on ground
truth (``sim.pose``); pass ``pose_source`` (e.g. the localization's latest ``pose``) and
``send`` (e.g. a decision gate's input) to put it in a more realistic loop. The Nav2 stand-in's
controller replaces it by implementing the same two calls: ``compute(pose) -> (v, w)`` at
``control_hz`` and ``done``.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable, Sequence

from bt_runtime.runtime.messages import Pose2D

from .geometry import wrap_angle
from .simulator import Simulator


class WaypointFollower:
    def __init__(self, sim: Simulator, waypoints: Sequence[tuple[float, float]], *,
                 speed: float | None = None, tolerance: float = 0.1, control_hz: float = 10.0,
                 pose_source: Callable[[], Pose2D] | None = None,
                 send: Callable[[float, float], object] | None = None) -> None:
        self.sim = sim
        self.waypoints = [tuple(map(float, w)) for w in waypoints]
        self.speed = speed if speed is not None else sim.profile.max_linear
        self.tolerance = tolerance
        self.period = 1.0 / control_hz
        self.pose_source = pose_source or (lambda: sim.pose)
        self.send = send or sim.command
        self.index = 0
        self.max_angular = min(sim.profile.max_angular, 1.5)

    @property
    def done(self) -> bool:
        return self.index >= len(self.waypoints)

    def compute(self, pose: Pose2D) -> tuple[float, float]:
        while not self.done:
            tx, ty = self.waypoints[self.index]
            if math.hypot(tx - pose.x, ty - pose.y) > self.tolerance:
                break
            self.index += 1
        if self.done:
            return 0.0, 0.0
        tx, ty = self.waypoints[self.index]
        err = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.yaw)
        w = max(-self.max_angular, min(self.max_angular, 2.0 * err))
        if abs(err) > 0.6:  # turn towards the waypoint first
            return 0.0, w
        dist = math.hypot(tx - pose.x, ty - pose.y)
        last = self.index == len(self.waypoints) - 1
        v = self.speed * math.cos(err)
        if last:
            v = min(v, max(0.05, dist))  # slow down on the final approach
        return v, w

    async def run(self, timeout: float | None = None) -> bool:
        """Drive until the last waypoint is reached (True) or ``timeout`` passes (False)."""
        loop = asyncio.get_running_loop()
        end = math.inf if timeout is None else loop.time() + timeout
        while not self.done and loop.time() < end:
            v, w = self.compute(self.pose_source())
            self.send(v, w)
            await asyncio.sleep(self.period)
        self.send(0.0, 0.0)
        return self.done
