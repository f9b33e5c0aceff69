"""Ros2Driver: a ROS 2 robot behind the runtime's driver interface, over DDS (no ROS install).

Sensor topics are read by Cyclone DDS listeners on Cyclone's threads; each sample is stamped
there with the loop clock (its receive time) and handed to the event loop with
``call_soon_threadsafe`` (see ``dds.py``). On the loop it is checked, converted to the
runtime's message dataclasses and passed to the stream's subscribers. Malformed or absurd
messages are dropped and counted per stream (``dropped``); the header stamp of the last good
message of each stream is kept in ``header_stamps`` (ROS time, seconds).

Only the decision gate calls ``send_velocity``; it writes the robot's ``cmd_vel``. Nav2's
controller must therefore publish elsewhere (``cmd_vel_nav`` by default), which this driver
reads as the ``nav_cmd_vel`` stream. See docs/ros2.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import os
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np
import structlog

from ..messages import (
    ActionStatus,
    BatteryState,
    ComponentInfo,
    ComponentState,
    Contact,
    Imu,
    LaserScan,
    LocalizedPose,
    NavErrorCode,
    NavFeedback,
    NavResult,
    Odometry,
    Path,
    Pose2D,
    RobotInfo,
    Twist,
)
from . import dds, idl
from .config import Qos, Ros2Config

log = structlog.get_logger("bt_runtime.ros2")

E = NavErrorCode
S = idl.GoalStatus


# ---------------------------------------------------------------------------------------------
# conversions
# ---------------------------------------------------------------------------------------------

def yaw_of(q: idl.Quaternion) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def quaternion_of(yaw: float) -> idl.Quaternion:
    return idl.Quaternion(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def pose2d_of(pose: idl.Pose) -> Pose2D:
    return Pose2D(pose.position.x, pose.position.y, yaw_of(pose.orientation))


def pose_msg(p: Pose2D) -> idl.Pose:
    return idl.Pose(position=idl.Point(p.x, p.y, 0.0), orientation=quaternion_of(p.yaw))


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def _qos(q: Qos) -> dds.QosProfile:
    return dds.QosProfile(reliable=q.reliability == "reliable", transient_local=q.durability == "transient_local",
                          depth=q.depth)


class Drop(Exception):  # noqa: N818 - a verdict, not an error
    """A message that fails validation."""


class Converter:
    """ROS messages -> runtime messages, with the validation limits of the config."""

    def __init__(self, config: Ros2Config):
        self.v = config.validation

    def scan(self, m: idl.LaserScan, now: float) -> LaserScan:
        v = self.v
        n = len(m.ranges)
        if n == 0 or n > v.max_scan_beams:
            raise Drop(f"{n} beams")
        if not _finite(m.angle_min, m.angle_max, m.angle_increment, m.range_min, m.range_max):
            raise Drop("non-finite scan geometry")
        if m.angle_increment == 0 or not (0 <= m.range_min < m.range_max <= v.max_range):
            raise Drop("absurd scan geometry")
        expected = (m.angle_max - m.angle_min) / m.angle_increment + 1
        if abs(expected - n) > 1.5:
            raise Drop(f"{n} ranges for {expected:.0f} beams")
        if m.intensities and len(m.intensities) != n:
            raise Drop("intensities and ranges differ in size")
        ranges = np.asarray(m.ranges, dtype=np.float32)
        nan = np.isnan(ranges)
        if nan.mean() > v.max_nan_fraction:
            raise Drop(f"{int(nan.sum())} of {n} ranges NaN")
        finite = ranges[np.isfinite(ranges)]
        if finite.size and (finite.min() < 0 or finite.max() > 10 * m.range_max):
            raise Drop("ranges out of bounds")
        return LaserScan(now, float(m.angle_min), float(m.angle_increment), float(m.range_min),
                         float(m.range_max), ranges)

    def imu(self, m: idl.Imu, now: float) -> Imu:
        v = self.v
        w, a, q = m.angular_velocity, m.linear_acceleration, m.orientation
        if not _finite(w.x, w.y, w.z, a.x, a.y, a.z, q.x, q.y, q.z, q.w):
            raise Drop("non-finite imu")
        if abs(w.z) > v.max_yaw_rate or max(abs(a.x), abs(a.y), abs(a.z)) > v.max_accel:
            raise Drop("absurd imu")
        norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
        known = m.orientation_covariance[0] != -1.0 and norm > 0
        if known and abs(norm - 1.0) > 0.1:
            raise Drop("orientation is not a unit quaternion")
        return Imu(now, float(w.z), float(a.x), float(a.y), yaw_of(q) if known else 0.0)

    def odom(self, m: idl.Odometry, now: float) -> Odometry:
        v = self.v
        p, q, t = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist
        if not _finite(p.x, p.y, q.x, q.y, q.z, q.w, t.linear.x, t.angular.z):
            raise Drop("non-finite odometry")
        if max(abs(p.x), abs(p.y)) > v.max_position or abs(t.linear.x) > v.max_speed \
                or abs(t.angular.z) > v.max_yaw_rate:
            raise Drop("absurd odometry")
        if q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w < 1e-6:
            raise Drop("zero quaternion")
        return Odometry(now, Pose2D(p.x, p.y, yaw_of(q)), Twist(float(t.linear.x), float(t.angular.z)))

    def pose(self, m: idl.PoseWithCovarianceStamped, now: float) -> LocalizedPose:
        p, q = m.pose.pose.position, m.pose.pose.orientation
        cov = m.pose.covariance
        if not _finite(p.x, p.y, q.x, q.y, q.z, q.w, cov[0], cov[7], cov[35]):
            raise Drop("non-finite pose")
        if max(abs(p.x), abs(p.y)) > self.v.max_position:
            raise Drop("absurd pose")
        if q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w < 1e-6:
            raise Drop("zero quaternion")
        sigma = math.sqrt(max(0.0, (cov[0] + cov[7]) / 2.0))
        return LocalizedPose(now, Pose2D(p.x, p.y, yaw_of(q)), sigma)

    def battery(self, m: idl.BatteryState, now: float) -> BatteryState:
        if not _finite(m.voltage, m.percentage) or not (0 <= m.voltage <= self.v.max_voltage):
            raise Drop("bad voltage or percentage")
        if not (-0.001 <= m.percentage <= 1.001):
            raise Drop("percentage outside 0..1")
        current = float(m.current) if math.isfinite(m.current) else 0.0
        capacity = float(m.capacity) if math.isfinite(m.capacity) else 0.0
        # ROS: current is negative while discharging; ours is positive when discharging
        return BatteryState(now, float(m.voltage), float(m.percentage) * 100.0, -current,
                            float(m.voltage) * -current, capacity)

    def bumper_bool(self, m: idl.Bool, now: float) -> Contact:
        return Contact(now, bool(m.data))

    def bumper_vector(self, m: idl.Vector3Stamped, now: float) -> Contact:
        x, y, z = m.vector.x, m.vector.y, m.vector.z
        if not _finite(x, y, z):
            raise Drop("non-finite contact")
        if x == 0.0 and y == 0.0:
            return Contact(now, False)
        return Contact(now, True, math.atan2(y, x), None, float(z))

    def twist(self, m: idl.Twist, now: float) -> Twist:
        v, w = m.linear.x, m.angular.z
        if not _finite(v, w) or abs(v) > self.v.max_speed or abs(w) > self.v.max_yaw_rate:
            raise Drop("bad velocity command")
        return Twist(float(v), float(w))


# ---------------------------------------------------------------------------------------------
# navigation (Nav2 over DDS)
# ---------------------------------------------------------------------------------------------

UNKNOWN_CODE = {"navigate_to_pose": E.NAVIGATE_UNKNOWN, "compute_path_to_pose": E.PLANNER_UNKNOWN,
                "follow_path": E.CONTROLLER_UNKNOWN, "spin": E.BEHAVIOR_UNKNOWN, "backup": E.BEHAVIOR_UNKNOWN,
                "drive_on_heading": E.BEHAVIOR_UNKNOWN, "wait": E.BEHAVIOR_UNKNOWN}
# Jazzy gives BackUp 710.., DriveOnHeading 720.., Wait 740..; the runtime uses Spin's 700..
BEHAVIOR_CODES = {710: E.BEHAVIOR_UNKNOWN, 711: E.BEHAVIOR_TIMEOUT, 712: E.BEHAVIOR_TF_ERROR,
                  713: E.INVALID_INPUT, 714: E.COLLISION_AHEAD, 720: E.BEHAVIOR_UNKNOWN,
                  721: E.BEHAVIOR_TIMEOUT, 722: E.BEHAVIOR_TF_ERROR, 723: E.COLLISION_AHEAD,
                  724: E.INVALID_INPUT, 740: E.BEHAVIOR_UNKNOWN, 741: E.BEHAVIOR_TIMEOUT}


def error_code_of(kind: str, value: int) -> NavErrorCode:
    if value in BEHAVIOR_CODES:
        return BEHAVIOR_CODES[value]
    try:
        return NavErrorCode(value)
    except ValueError:
        return UNKNOWN_CODE[kind]


def path_of(msg: idl.Path, stamp: float) -> Path:
    pts = np.array([[p.pose.position.x, p.pose.position.y, yaw_of(p.pose.orientation)] for p in msg.poses],
                   dtype=float).reshape(-1, 3)
    return Path(stamp, pts)


class Ros2NavHandle:
    """A goal on a Nav2 action server; implements ``NavigationHandle``."""

    def __init__(self, nav: Ros2Navigation, kind: str, client: dds.ActionClient | None, goal: Any,
                 feedback_cb: Callable[[NavFeedback], None] | None, to_feedback: Callable[[Any], NavFeedback]):
        self.nav = nav
        self.kind = kind
        self.client = client
        self.goal_id: bytes | None = None
        self.cancel_requested = False
        self._feedback: NavFeedback | None = None
        self._feedback_cb = feedback_cb
        self._to_feedback = to_feedback
        self.raw_result: Any = None
        self._task = nav.loop.create_task(self._run(goal), name=f"ros2.{kind}")

    async def _run(self, goal: Any) -> NavResult:
        cfg = self.nav.config
        unknown = UNKNOWN_CODE[self.kind]
        if self.client is None:
            return NavResult(ActionStatus.ABORTED, unknown, "navigation is disabled in the ROS 2 config")
        try:
            goal_id, accepted = await self.client.send_goal(goal, feedback=self._on_feedback,
                                                            timeout=cfg.server_timeout)
        except dds.ServiceError as exc:
            return NavResult(ActionStatus.ABORTED, unknown, str(exc))
        if not accepted:
            return NavResult(ActionStatus.ABORTED, unknown, "goal rejected")
        self.goal_id = goal_id
        if self.cancel_requested:
            self._send_cancel()
        status, result = await self.client.get_result(goal_id, gone_after=cfg.server_gone_after)
        self.raw_result = result
        if result is None:
            return NavResult(ActionStatus.ABORTED, unknown, f"action server {self.client.name} is gone")
        code = int(getattr(result, "error_code", 0))
        msg = str(getattr(result, "error_msg", ""))
        if status == S.STATUS_SUCCEEDED:
            return NavResult(ActionStatus.SUCCEEDED, E.NONE, msg)
        if status == S.STATUS_CANCELED:
            return NavResult(ActionStatus.CANCELED, E.NONE, msg or "canceled")
        return NavResult(ActionStatus.ABORTED, error_code_of(self.kind, code) if code else unknown,
                         msg or f"goal ended with status {status}")

    def _on_feedback(self, raw: Any) -> None:
        try:
            fb = self._to_feedback(raw)
        except Exception:
            return
        self._feedback = fb
        if self._feedback_cb is not None:
            try:
                self._feedback_cb(fb)
            except Exception:
                log.exception("nav_feedback_callback_failed", action=self.kind)

    def _send_cancel(self) -> None:
        async def cancel() -> None:
            with contextlib.suppress(dds.ServiceError):
                await self.client.cancel(self.goal_id, timeout=self.nav.config.service_timeout)
            # no CANCELED result within the service timeout (server gone): end here
            await asyncio.sleep(self.nav.config.service_timeout)
            if not self._task.done():
                self._task.cancel()

        self.nav._spawn(cancel())

    # -- NavigationHandle ------------------------------------------------------------------------
    def done(self) -> bool:
        return self._task.done()

    def result(self) -> NavResult:
        if not self._task.done():
            raise asyncio.InvalidStateError(f"{self.kind} is still running")
        if self._task.cancelled():
            return NavResult(ActionStatus.CANCELED, E.NONE, "canceled (no answer from the server)")
        exc = self._task.exception()
        if exc is not None:
            return NavResult(ActionStatus.ABORTED, UNKNOWN_CODE[self.kind], f"internal error: {exc!r}")
        return self._task.result()

    def cancel(self) -> None:
        if self._task.done() or self.cancel_requested:
            return
        self.cancel_requested = True
        if self.goal_id is not None:
            self._send_cancel()

    def __await__(self):
        return self._wait().__await__()

    async def _wait(self) -> NavResult:
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.shield(self._task)
        if not self._task.done():
            raise asyncio.CancelledError
        return self.result()

    @property
    def feedback(self) -> NavFeedback | None:
        return self._feedback


class Ros2Navigation:
    """Nav2's actions and services over DDS; implements ``NavigationClient``."""

    def __init__(self, driver: Ros2Driver):
        self.driver = driver
        self.config = driver.config.navigation
        self.node: dds.DdsNode | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.clients: dict[str, dds.ActionClient] = {}
        self.handles: set[Ros2NavHandle] = set()
        self._tasks: set[asyncio.Task] = set()
        self._clear: dict[str, dds.ServiceClient] = {}
        self._costmap: tuple[np.ndarray, float, float, float] | None = None
        self._lethal_distance: np.ndarray | None = None
        self._speed_limit_writer: Any = None

    def attach(self, node: dds.DdsNode) -> None:
        self.node = node
        self.loop = node.loop
        cfg = self.config
        if not cfg.enabled:
            return
        names = {"navigate_to_pose": (cfg.navigate_to_pose, idl.NavigateToPose),
                 "compute_path_to_pose": (cfg.compute_path_to_pose, idl.ComputePathToPose),
                 "follow_path": (cfg.follow_path, idl.FollowPath), "spin": (cfg.spin, idl.Spin),
                 "backup": (cfg.back_up, idl.BackUp), "drive_on_heading": (cfg.drive_on_heading, idl.DriveOnHeading),
                 "wait": (cfg.wait, idl.Wait)}
        for kind, (name, types) in names.items():
            self.clients[kind] = dds.ActionClient(node, name, types)
        self._clear = {
            "global": dds.ServiceClient(node, cfg.clear_global_costmap, idl.ClearEntireCostmap_Request,
                                        idl.ClearEntireCostmap_Response),
            "local": dds.ServiceClient(node, cfg.clear_local_costmap, idl.ClearEntireCostmap_Request,
                                       idl.ClearEntireCostmap_Response)}
        if cfg.speed_limit:
            self._speed_limit_writer = node.publisher(cfg.speed_limit, idl.SpeedLimit, dds.DEFAULT)
        if cfg.global_costmap:
            node.subscription(cfg.global_costmap, idl.OccupancyGrid, dds.QosProfile(True, True, 1), self._on_costmap)

    def _spawn(self, coro) -> asyncio.Task:
        task = self.loop.create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    def _launch(self, kind: str, goal: Any, feedback: Callable[[NavFeedback], None] | None,
                to_feedback: Callable[[Any], NavFeedback]) -> Ros2NavHandle:
        if self.loop is None:
            raise RuntimeError("start the driver before navigating")
        handle = Ros2NavHandle(self, kind, self.clients.get(kind), goal, feedback, to_feedback)
        self.handles.add(handle)
        handle._task.add_done_callback(lambda _t: self.handles.discard(handle))
        return handle

    def _stamped(self, pose: Pose2D) -> idl.PoseStamped:
        return idl.PoseStamped(header=idl.Header(stamp=idl.Time(), frame_id=self.config.map_frame), pose=pose_msg(pose))

    def _now(self) -> float:
        return self.loop.time()

    def _nav_feedback(self, raw: Any) -> NavFeedback:
        return NavFeedback(self._now(), pose2d_of(raw.current_pose.pose), float(raw.distance_remaining),
                           raw.navigation_time.to_sec(), int(raw.number_of_recoveries))

    def _pose_feedback(self, **kw: float) -> NavFeedback:
        latest = self.driver.latest.get("pose")
        pose = latest.pose if latest is not None else Pose2D(math.nan, math.nan, math.nan)
        return NavFeedback(self._now(), pose, **kw)

    # -- NavigationClient ------------------------------------------------------------------------
    def navigate_to_pose(self, goal: Pose2D, *, behavior_tree: str = "",
                         feedback: Callable[[NavFeedback], None] | None = None) -> Ros2NavHandle:
        msg = idl.NavigateToPose.Goal(pose=self._stamped(goal), behavior_tree=behavior_tree)
        return self._launch("navigate_to_pose", msg, feedback, self._nav_feedback)

    async def compute_path_to_pose(self, goal: Pose2D, *, start: Pose2D | None = None,
                                   planner_id: str = "", use_start: bool = False) -> NavResult:
        msg = idl.ComputePathToPose.Goal(goal=self._stamped(goal), start=self._stamped(start or Pose2D(0, 0)),
                                         planner_id=planner_id, use_start=bool(use_start and start is not None))
        handle = self._launch("compute_path_to_pose", msg, None, lambda raw: None)
        result = await handle
        if result.succeeded and handle.raw_result is not None:
            result.path = path_of(handle.raw_result.path, self._now())
        return result

    def follow_path(self, path: Path, *, controller_id: str = "", goal_checker_id: str = "",
                    progress_checker_id: str = "",
                    feedback: Callable[[NavFeedback], None] | None = None) -> Ros2NavHandle:
        pts = np.asarray(path.points, dtype=float)
        poses, yaw = [], 0.0
        for i, p in enumerate(pts):
            if pts.shape[1] > 2:
                yaw = float(p[2])
            elif i + 1 < len(pts):
                yaw = math.atan2(pts[i + 1, 1] - p[1], pts[i + 1, 0] - p[0])
            poses.append(self._stamped(Pose2D(float(p[0]), float(p[1]), yaw)))
        msg = idl.FollowPath.Goal(path=idl.Path(header=idl.Header(frame_id=self.config.map_frame), poses=poses),
                                  controller_id=controller_id, goal_checker_id=goal_checker_id,
                                  progress_checker_id=progress_checker_id)
        return self._launch("follow_path", msg, feedback,
                            lambda raw: self._pose_feedback(distance_remaining=float(raw.distance_to_goal),
                                                            speed=float(raw.speed)))

    def spin(self, target_yaw: float, *, time_allowance: float = 10.0) -> Ros2NavHandle:
        msg = idl.Spin.Goal(target_yaw=target_yaw, time_allowance=idl.Duration.from_sec(time_allowance))
        return self._launch("spin", msg, None, lambda raw: self._pose_feedback())

    def back_up(self, distance: float, speed: float = 0.025, *, time_allowance: float = 10.0) -> Ros2NavHandle:
        msg = idl.BackUp.Goal(target=idl.Point(abs(distance), 0.0, 0.0), speed=abs(speed),
                              time_allowance=idl.Duration.from_sec(time_allowance))
        return self._launch("backup", msg, None,
                            lambda raw: self._pose_feedback(distance_remaining=abs(distance) - raw.distance_traveled))

    def drive_on_heading(self, distance: float, speed: float = 0.025, *,
                         time_allowance: float = 10.0) -> Ros2NavHandle:
        msg = idl.DriveOnHeading.Goal(target=idl.Point(distance, 0.0, 0.0), speed=speed,
                                      time_allowance=idl.Duration.from_sec(time_allowance))
        return self._launch("drive_on_heading", msg, None,
                            lambda raw: self._pose_feedback(distance_remaining=abs(distance) - raw.distance_traveled))

    def wait(self, duration: float) -> Ros2NavHandle:
        msg = idl.Wait.Goal(time=idl.Duration.from_sec(duration))
        return self._launch("wait", msg, None, lambda raw: self._pose_feedback())

    def cancel_all(self) -> None:
        for handle in list(self.handles):
            handle.cancel()

    def set_speed_limit(self, limit: float | None, percentage: bool = False) -> None:
        """Nav2's SpeedLimit (m/s, or percent of the maximum); None or <= 0 lifts it."""
        writer = self._speed_limit_writer
        if writer is None or self.node is None or self.node.closed:
            return
        value = 0.0 if limit is None or not math.isfinite(limit) or limit <= 0 else float(limit)
        writer.write(idl.SpeedLimit(header=idl.Header(frame_id=""), percentage=percentage, speed_limit=value))

    async def clear_costmaps(self, which: str = "both") -> None:
        if which not in ("local", "global", "both"):
            raise ValueError(f"which must be 'local', 'global' or 'both', got {which!r}")
        if not self._clear:
            raise dds.ServiceError("navigation is disabled in the ROS 2 config")
        for name in (("global", "local") if which == "both" else (which,)):
            await self._clear[name].call(idl.ClearEntireCostmap_Request(), self.config.service_timeout)

    async def add_obstacle(self, x: float, y: float, radius: float = 0.1) -> None:
        raise NotImplementedError(
            "add_obstacle is not available on real Nav2: Nav2 has no service that marks an obstacle. "
            "Options: an extra observation source of the obstacle layer fed with a PointCloud2, a "
            "keepout filter mask, or an updated map from map_server (see docs/ros2.md)")

    # -- costmap queries (from the global costmap topic) ------------------------------------------
    def _on_costmap(self, samples: list, _now: float) -> None:
        m = samples[-1]
        w, h = int(m.info.width), int(m.info.height)
        if w * h != len(m.data) or w == 0 or h == 0 or not m.info.resolution > 0:
            self.driver._count_drop("costmap", "size mismatch")
            return
        grid = np.frombuffer(bytes(np.asarray(m.data, dtype=np.int8).tobytes()), dtype=np.int8).reshape(h, w)
        self._costmap = (grid, float(m.info.resolution), m.info.origin.position.x, m.info.origin.position.y)
        self._lethal_distance = None

    @staticmethod
    def _cost(occ: np.ndarray) -> np.ndarray:
        """OccupancyGrid values back to Nav2 costs (100 lethal, 99 inscribed, -1 unknown)."""
        cost = np.round(occ.astype(float) * 252.0 / 98.0)
        cost = np.where(occ >= 100, 254, np.where(occ == 99, 253, cost))
        return np.where(occ < 0, 255, cost)

    def _cells(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        grid, res, ox, oy = self._costmap
        cols = np.floor((pts[:, 0] - ox) / res).astype(int)
        rows = np.floor((pts[:, 1] - oy) / res).astype(int)
        inside = (rows >= 0) & (rows < grid.shape[0]) & (cols >= 0) & (cols < grid.shape[1])
        return rows, cols, inside

    def is_path_valid(self, path: Path, max_cost: int = 253) -> bool:
        """False if a pose of the path lies on a cell of at least ``max_cost`` in the last global
        costmap received (unknown counts as free). True when no costmap has been received."""
        pts = np.asarray(path.points if isinstance(path, Path) else path, dtype=float)
        if len(pts) == 0:
            return False
        if self._costmap is None:
            return True
        rows, cols, inside = self._cells(pts)
        cost = self._cost(self._costmap[0][rows[inside], cols[inside]])
        return not bool(np.any((cost >= max_cost) & (cost != 255)))

    def path_clearance(self, path: Path) -> float:
        pts = np.asarray(path.points if isinstance(path, Path) else path, dtype=float)
        if self._costmap is None or len(pts) == 0:
            return math.inf
        grid, res, _, _ = self._costmap
        if self._lethal_distance is None:
            from scipy.ndimage import distance_transform_edt

            free = grid < 100
            self._lethal_distance = (distance_transform_edt(free) * res if not free.all()
                                     else np.full(grid.shape, np.inf))
        rows, cols, inside = self._cells(pts)
        if not inside.any():
            return math.inf
        return float(self._lethal_distance[rows[inside], cols[inside]].min())

    async def close(self) -> None:
        for handle in list(self.handles):
            handle.cancel()
        for task in list(self._tasks):
            task.cancel()


# ---------------------------------------------------------------------------------------------
# the driver
# ---------------------------------------------------------------------------------------------

STATE_IDS = {idl.State.PRIMARY_STATE_UNCONFIGURED: "unconfigured", idl.State.PRIMARY_STATE_INACTIVE: "inactive",
             idl.State.PRIMARY_STATE_ACTIVE: "active", idl.State.PRIMARY_STATE_FINALIZED: "finalized"}
T = idl.Transition
RESTART_SEQUENCE = {  # from the current primary state back to active
    idl.State.PRIMARY_STATE_ACTIVE: (T.TRANSITION_DEACTIVATE, T.TRANSITION_CLEANUP, T.TRANSITION_CONFIGURE,
                                     T.TRANSITION_ACTIVATE),
    idl.State.PRIMARY_STATE_INACTIVE: (T.TRANSITION_CLEANUP, T.TRANSITION_CONFIGURE, T.TRANSITION_ACTIVATE),
    idl.State.PRIMARY_STATE_UNCONFIGURED: (T.TRANSITION_CONFIGURE, T.TRANSITION_ACTIVATE),
}
TRANSITION_LABELS = {T.TRANSITION_CONFIGURE: "configure", T.TRANSITION_CLEANUP: "cleanup",
                     T.TRANSITION_ACTIVATE: "activate", T.TRANSITION_DEACTIVATE: "deactivate"}


class Ros2Driver:
    """A ROS 2 robot over DDS; implements ``RobotDriver``."""

    name = "ros2"

    def __init__(self, config: Ros2Config | None = None):
        self.config = config or Ros2Config()
        self.conv = Converter(self.config)
        self.navigation = Ros2Navigation(self)
        self.node: dds.DdsNode | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self._subscribers: dict[str, list[Callable[[Any], None]]] = defaultdict(list)
        self.received: dict[str, int] = defaultdict(int)
        self.dropped: dict[str, int] = defaultdict(int)
        self.drop_reasons: dict[str, str] = {}
        self.header_stamps: dict[str, float] = {}
        self.latest: dict[str, Any] = {}
        self.last_seen: dict[str, float] = {}
        self._readers: dict[str, dds.Reader] = {}
        self._cmd_writer: Any = None
        self._cmd_type: type | None = None
        self._lifecycle: dict[str, tuple[dds.ServiceClient, dds.ServiceClient]] = {}
        self.lifecycle_states: dict[str, int] = {}
        self._restarting: set[str] = set()
        self._poller: asyncio.Task | None = None
        self.sent = 0
        self.send_errors = 0

    @classmethod
    def from_args(cls, args: Any) -> Ros2Driver:
        """For ``python -m bt_runtime run --driver ros2 [--ros2-config FILE]``."""
        path = getattr(args, "ros2_config", None)
        try:
            config = Ros2Config.load(path) if path else Ros2Config()
        except ValueError as exc:  # reported by the CLI as a usage error, without a traceback
            from ...cli.run import UsageError

            raise UsageError(str(exc)) from None
        if "domain_id" not in config.model_fields_set and os.environ.get("ROS_DOMAIN_ID", "").isdigit():
            config.domain_id = int(os.environ["ROS_DOMAIN_ID"])
        return cls(config)

    # -- lifecycle -------------------------------------------------------------------------------
    async def start(self) -> None:
        if self.node is not None:
            return
        cfg = self.config
        self.loop = asyncio.get_running_loop()
        uri = cfg.cyclonedds_uri or (dds.loopback_config() if cfg.loopback_only and
                                     not os.environ.get("CYCLONEDDS_URI") else None)
        self.node = node = dds.DdsNode(cfg.domain_id, loop=self.loop, namespace=cfg.namespace, cyclonedds_uri=uri)
        t = cfg.topics
        conv = self.conv
        specs: list[tuple[str, Any, type, Callable]] = [
            ("scan", t.scan, idl.LaserScan, conv.scan), ("imu", t.imu, idl.Imu, conv.imu),
            ("odom", t.odom, idl.Odometry, conv.odom), ("pose", t.pose, idl.PoseWithCovarianceStamped, conv.pose),
            ("battery", t.battery, idl.BatteryState, conv.battery)]
        if t.bumper is not None:
            specs.append(("bumper", t.bumper, idl.Bool if t.bumper.type == "bool" else idl.Vector3Stamped,
                          conv.bumper_bool if t.bumper.type == "bool" else conv.bumper_vector))
        if t.nav_cmd_vel is not None:
            nav_stamped = t.nav_cmd_vel.stamped
            specs.append(("nav_cmd_vel", t.nav_cmd_vel, idl.TwistStamped if nav_stamped else idl.Twist,
                          (lambda m, now: conv.twist(m.twist, now)) if nav_stamped else conv.twist))
        for stream, topic, msg_type, convert in specs:
            if topic is None:
                continue
            self._readers[stream] = node.subscription(topic.name, msg_type, _qos(topic.qos),
                                                      self._stream_handler(stream, convert))
        cmd = t.cmd_vel
        self._cmd_type = idl.TwistStamped if cmd.stamped else idl.Twist
        self._cmd_writer = node.publisher(cmd.name, self._cmd_type, _qos(cmd.qos))
        for name, comp in cfg.components.items():
            if comp.lifecycle_node:
                self._lifecycle[name] = (
                    dds.ServiceClient(node, comp.lifecycle_node.rstrip("/") + "/get_state",
                                      idl.GetState_Request, idl.GetState_Response),
                    dds.ServiceClient(node, comp.lifecycle_node.rstrip("/") + "/change_state",
                                      idl.ChangeState_Request, idl.ChangeState_Response))
        self.navigation.attach(node)
        polled = [n for n, c in cfg.components.items() if c.heartbeat == "lifecycle"]
        if polled:
            self._poller = self.loop.create_task(self._poll_lifecycles(polled), name="ros2.lifecycle_poll")
        log.info("ros2_driver_started", domain_id=cfg.domain_id, namespace=cfg.namespace or "/",
                 streams=sorted(self._readers), cmd_vel=node.fq(cmd.name), stamped=cmd.stamped)

    async def stop(self) -> None:
        if self.node is None:
            return
        await self.navigation.close()
        if self._poller is not None:
            self._poller.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._poller
            self._poller = None
        node, self.node = self.node, None
        self._cmd_writer = None
        node.close()
        log.info("ros2_driver_stopped", received=dict(self.received), dropped=self.dropped_counts())

    # -- streams ---------------------------------------------------------------------------------
    def _stream_handler(self, stream: str, convert: Callable[[Any, float], Any]) -> Callable[[list, float], None]:
        subscribers = self._subscribers

        def on_samples(samples: list, now: float) -> None:
            for raw in samples:
                self.received[stream] += 1
                try:
                    msg = convert(raw, now)
                except Drop as why:
                    self._count_drop(stream, str(why))
                    continue
                except Exception as exc:  # anything odd in a message is the message's fault
                    self._count_drop(stream, repr(exc))
                    continue
                header = getattr(raw, "header", None)
                if header is not None:
                    self.header_stamps[stream] = header.stamp.to_sec()
                self.latest[stream] = msg
                self.last_seen[stream] = now
                for callback in tuple(subscribers.get(stream, ())):
                    callback(msg)

        return on_samples

    async def _poll_lifecycles(self, names: list[str]) -> None:
        """Heartbeats of servers without a data stream (Nav2's): their lifecycle node answers
        get_state with 'active' -> a ``ComponentState.ACTIVE`` message on ``lifecycle/<name>``."""
        period = 1.0 / self.config.lifecycle.poll_hz
        timeout = min(self.config.lifecycle.transition_timeout, 0.9 * period)
        loop = self.loop
        start = loop.time()
        k = 0

        async def poll(name: str) -> None:
            state = await self.get_lifecycle_state(name, timeout=timeout)
            if state == idl.State.PRIMARY_STATE_ACTIVE:
                stream = f"lifecycle/{name}"
                self.last_seen[stream] = loop.time()
                for callback in tuple(self._subscribers.get(stream, ())):
                    callback(ComponentState.ACTIVE)

        while True:
            await asyncio.gather(*(poll(n) for n in names), return_exceptions=True)
            k += 1
            await asyncio.sleep(max(0.0, start + k * period - loop.time()))

    def _count_drop(self, stream: str, reason: str) -> None:
        self.dropped[stream] += 1
        if self.drop_reasons.get(stream) != reason:
            log.warning("ros2_message_dropped", stream=stream, reason=reason, count=self.dropped[stream])
        self.drop_reasons[stream] = reason

    def dropped_counts(self) -> dict[str, int]:
        """Dropped messages per stream: failed validation + failed deserialisation."""
        counts = dict(self.dropped)
        for stream, reader in self._readers.items():
            if reader.malformed:
                counts[stream] = counts.get(stream, 0) + reader.malformed
        return counts

    def subscribe(self, stream: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        self._subscribers[stream].append(callback)

        def unsubscribe() -> None:
            with contextlib.suppress(ValueError):
                self._subscribers[stream].remove(callback)

        return unsubscribe

    def send_velocity(self, linear: float, angular: float) -> None:
        writer = self._cmd_writer
        if writer is None:
            return
        twist = idl.Twist(linear=idl.Vector3(float(linear), 0.0, 0.0), angular=idl.Vector3(0.0, 0.0, float(angular)))
        try:
            if self._cmd_type is idl.TwistStamped:
                writer.write(idl.TwistStamped(header=idl.Header(stamp=idl.Time.now(),
                                                                frame_id=self.config.topics.cmd_vel.frame_id),
                                              twist=twist))
            else:
                writer.write(twist)
            self.sent += 1
        except Exception as exc:
            self.send_errors += 1
            if self.send_errors == 1 or self.send_errors % 1000 == 0:
                log.error("ros2_cmd_vel_failed", error=repr(exc), errors=self.send_errors)
            return
        for callback in tuple(self._subscribers.get("cmd_vel_out", ())):
            callback(Twist(float(linear), float(angular)))

    # -- components ------------------------------------------------------------------------------
    def _timeout(self, name: str) -> float:
        rate = self.config.components[name].rate_hz
        return max(1.0, 2.5 / rate) if rate > 0 else 1.0

    def components(self) -> list[ComponentInfo]:
        infos = []
        for name, comp in self.config.components.items():
            streams = tuple(s for s in comp.streams
                            if s in self._readers or s.startswith("lifecycle/") or self.node is None)
            infos.append(ComponentInfo(name=name, kind=comp.kind, streams=streams,
                                       restartable=comp.lifecycle_node is not None,
                                       expected_rate_hz=comp.rate_hz, state=self.component_state(name),
                                       extra={"lifecycle_node": comp.lifecycle_node,
                                              "depends_on": tuple(comp.depends_on)}))
        return infos

    def robot_info(self) -> RobotInfo:
        """The robot's size, limits and power model, from the config's ``robot`` section."""
        robot = self.config.robot
        return RobotInfo(**robot.model_dump()) if robot is not None else RobotInfo()

    def component_state(self, name: str) -> ComponentState:
        comp = self.config.components.get(name)
        if comp is None:
            return ComponentState.UNKNOWN
        if name in self._restarting:
            return ComponentState.STARTING
        seen = [self.last_seen[s] for s in comp.streams if s in self.last_seen]
        if not seen:
            return ComponentState.UNKNOWN
        now = self.loop.time() if self.loop is not None else 0.0
        return ComponentState.ACTIVE if now - max(seen) <= self._timeout(name) else ComponentState.INACTIVE

    async def get_lifecycle_state(self, name: str, timeout: float | None = None) -> int | None:
        """The component's lifecycle state id (None: no answer or no lifecycle node)."""
        clients = self._lifecycle.get(name)
        if clients is None:
            return None
        try:
            response = await clients[0].call(idl.GetState_Request(), timeout or self.config.lifecycle.transition_timeout)
        except dds.ServiceError:
            return None
        self.lifecycle_states[name] = int(response.current_state.id)
        return self.lifecycle_states[name]

    async def restart(self, name: str) -> bool:
        """deactivate -> cleanup -> configure -> activate (from whatever primary state it is
        in) through the component's lifecycle services; False without lifecycle node, if a
        service does not answer or a transition fails."""
        if name not in self._lifecycle:
            log.warning("ros2_restart_unsupported", component=name, reason="no lifecycle node configured")
            return False
        self._restarting.add(name)
        try:
            state = await self.get_lifecycle_state(name)
            sequence = RESTART_SEQUENCE.get(state) if state is not None else None
            if sequence is None:
                log.warning("ros2_restart_failed", component=name, reason=f"lifecycle state {state}")
                return False
            change = self._lifecycle[name][1]
            for transition in sequence:
                label = TRANSITION_LABELS[transition]
                try:
                    response = await change.call(idl.ChangeState_Request(transition=T(transition, label)),
                                                 self.config.lifecycle.transition_timeout)
                except dds.ServiceError as exc:
                    log.warning("ros2_restart_failed", component=name, transition=label, reason=str(exc))
                    return False
                if not response.success:
                    log.warning("ros2_restart_failed", component=name, transition=label, reason="refused")
                    return False
            self.lifecycle_states[name] = idl.State.PRIMARY_STATE_ACTIVE
            log.info("ros2_component_restarted", component=name)
            return True
        finally:
            self._restarting.discard(name)
