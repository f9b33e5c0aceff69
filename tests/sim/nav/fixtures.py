"""A small kinematic robot for testing ``sim.nav`` without the pymunk simulator.

A unicycle integrated at 100 Hz with acceleration limits, driven by ``nav_cmd_vel`` (with a
command timeout, like a real base), publishing ``pose`` (LocalizedPose) and ``odom`` at 20 Hz
and a 360-beam ``scan`` ray-cast against a world occupancy grid at 5 Hz. The world grid can
differ from the navigation map (e.g. obstacles the map does not know about). The robot does
not enter occupied cells: a step that would overlap one is refused (the robot stops).
"""

from __future__ import annotations

import asyncio
import contextlib
import math

import numpy as np

from bt_runtime.runtime.messages import LaserScan, LocalizedPose, Odometry, Pose2D, Twist
from sim.bus import Bus
from sim.nav.occupancy import OccupancyGrid
from tests.paths import REFERENCE as _SHARED_REFERENCE

REFERENCE = _SHARED_REFERENCE / "worlds"
HOUSE = REFERENCE / "turtlebot3_house_2d_rasterized.yaml"
TB3_WORLD = REFERENCE / "turtlebot3_world_2d_rasterized.yaml"


def small_world() -> OccupancyGrid:
    """An 8 x 6 m room split by a wall with a 1 m door, a pillar and a box (no ../shared needed).

    Outer walls on the border; the dividing wall at x = 4 runs the full height except the door
    at y in [2.5, 3.5].
    """
    segs = [
        (0.0, 0.0, 8.0, 0.0, 0.1), (8.0, 0.0, 8.0, 6.0, 0.1),
        (8.0, 6.0, 0.0, 6.0, 0.1), (0.0, 6.0, 0.0, 0.0, 0.1),
        (4.0, 0.0, 4.0, 2.5, 0.1), (4.0, 3.5, 4.0, 6.0, 0.1),
    ]
    circles = [(2.0, 4.5, 0.3)]
    polys = [np.array([[5.5, 1.0], [6.5, 1.0], [6.5, 1.8], [5.5, 1.8]])]
    return OccupancyGrid.from_shapes(polys, circles, segs, bounds=(-0.5, -0.5, 8.5, 6.5),
                                     resolution=0.05)


class KinematicRobot:
    def __init__(self, bus: Bus, world: OccupancyGrid, pose: Pose2D, *, radius: float = 0.1,
                 max_lin_acc: float = 2.5, max_ang_acc: float = 3.2, physics_rate: float = 100.0,
                 pose_rate: float = 20.0, scan_rate: float = 5.0, scan_range: float = 3.5,
                 cmd_timeout: float = 0.5, scan_noise: float = 0.0, seed: int = 0,
                 collide: bool = True):
        self.bus = bus
        self.world = world
        self.pose = pose
        self.odom_pose = pose
        self.v = 0.0
        self.w = 0.0
        self.radius = radius
        self.max_lin_acc = max_lin_acc
        self.max_ang_acc = max_ang_acc
        self.dt = 1.0 / physics_rate
        self.pose_every = max(int(round(physics_rate / pose_rate)), 1)
        self.scan_every = max(int(round(physics_rate / scan_rate)), 1)
        self.scan_range = scan_range
        self.cmd = Twist()
        self.cmd_time = -math.inf
        self.cmd_timeout = cmd_timeout
        self.scan_noise = scan_noise
        self.rng = np.random.default_rng(seed)
        self.collide = collide
        self.held = False  # wheels blocked (progress-checker tests)
        self.publish_pose = True  # False = localization silent (stale-pose tests)
        self.blocked_steps = 0
        self.commands: list[tuple[float, Twist]] = []
        self.angles = np.linspace(0.0, 2 * math.pi, 360, endpoint=False)
        occ = world.data >= 65
        self._occ = occ
        n = math.ceil(radius / world.resolution)
        dr, dc = np.mgrid[-n:n + 1, -n:n + 1]
        keep = (dr * dr + dc * dc) * world.resolution ** 2 <= radius * radius
        self._disc = (dr[keep], dc[keep])
        bus.subscribe("nav_cmd_vel", self._on_cmd)
        self._task: asyncio.Task | None = None

    def _on_cmd(self, twist: Twist) -> None:
        now = asyncio.get_running_loop().time()
        self.cmd = twist
        self.cmd_time = now
        self.commands.append((now, twist))

    def collides(self, x: float, y: float) -> bool:
        r, c = self.world.world_to_cell(x, y)
        rows, cols = r + self._disc[0], c + self._disc[1]
        inside = (rows >= 0) & (rows < self.world.height) & (cols >= 0) & (cols < self.world.width)
        return bool(self._occ[rows[inside], cols[inside]].any())

    def start(self) -> KinematicRobot:
        self._task = asyncio.get_running_loop().create_task(self._run(), name="kinematic_robot")
        return self

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task

    def _publish(self, now: float, scan: bool) -> None:
        if self.publish_pose:
            self.bus.publish("pose", LocalizedPose(now, self.pose, 0.0))
        self.bus.publish("odom", Odometry(now, self.odom_pose, Twist(self.v, self.w)))
        if scan:
            ranges = self.world.raycast(self.pose.x, self.pose.y, self.angles + self.pose.yaw,
                                        self.scan_range, step=self.world.resolution / 2)
            ranges = np.where(ranges < 0.12, np.inf, ranges)
            if self.scan_noise > 0:
                ranges = ranges + self.rng.normal(0.0, self.scan_noise, ranges.shape)
            self.bus.publish("scan", LaserScan(now, 0.0, 2 * math.pi / 360, 0.12, self.scan_range,
                                               ranges))

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        t = loop.time()
        k = 0
        self._publish(t, scan=True)
        while True:
            t += self.dt
            await asyncio.sleep(max(t - loop.time(), 0.0))
            now = loop.time()
            cmd = self.cmd if now - self.cmd_time <= self.cmd_timeout else Twist()
            if self.held:
                cmd = Twist()
            dv = max(min(cmd.linear - self.v, self.max_lin_acc * self.dt), -self.max_lin_acc * self.dt)
            dw = max(min(cmd.angular - self.w, self.max_ang_acc * self.dt), -self.max_ang_acc * self.dt)
            self.v += dv
            self.w += dw
            if self.held:
                self.v = self.w = 0.0
            p = self.pose
            yaw = p.yaw + self.w * self.dt
            nx = p.x + self.v * self.dt * math.cos(p.yaw + 0.5 * self.w * self.dt)
            ny = p.y + self.v * self.dt * math.sin(p.yaw + 0.5 * self.w * self.dt)
            if self.collide and self.collides(nx, ny) and not self.collides(p.x, p.y):
                self.blocked_steps += 1
                self.v = 0.0
                nx, ny = p.x, p.y
            yaw = math.atan2(math.sin(yaw), math.cos(yaw))
            o = self.odom_pose
            ddx, ddy = nx - p.x, ny - p.y
            self.pose = Pose2D(nx, ny, yaw)
            self.odom_pose = Pose2D(o.x + ddx, o.y + ddy, yaw)
            k += 1
            if k % self.pose_every == 0:
                self._publish(now, scan=(k % self.scan_every == 0))
