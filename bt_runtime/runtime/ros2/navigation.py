"""Ros2Navigation: Nav2's actions and services over DDS, behind the runtime's
``NavigationClient`` protocol (one ``Ros2NavHandle`` per goal), plus the costmap queries
answered from Nav2's global costmap topic."""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import structlog

from ..messages import ActionStatus, DockFeedback, NavErrorCode, NavFeedback, NavResult, Path, Pose2D
from . import dds, idl
from .convert import UNKNOWN_CODE, error_code_of, path_of, pose2d_of, pose_msg

if TYPE_CHECKING:
    from .driver import Ros2Driver

log = structlog.get_logger("bt_runtime.ros2")

E = NavErrorCode
S = idl.GoalStatus


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
        retries = int(getattr(result, "num_retries", 0))  # DockRobot
        if status == S.STATUS_SUCCEEDED:
            return NavResult(ActionStatus.SUCCEEDED, E.NONE, msg, num_retries=retries)
        if status == S.STATUS_CANCELED:
            return NavResult(ActionStatus.CANCELED, E.NONE, msg or "canceled", num_retries=retries)
        return NavResult(ActionStatus.ABORTED, error_code_of(self.kind, code) if code else unknown,
                         msg or f"goal ended with status {status}", num_retries=retries)

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
                 "wait": (cfg.wait, idl.Wait), "dock_robot": (cfg.dock_robot, idl.DockRobot),
                 "undock_robot": (cfg.undock_robot, idl.UndockRobot)}
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

    def dock_robot(self, *, use_dock_id: bool = True, dock_id: str = "", dock_pose: Pose2D | None = None,
                   dock_type: str = "", max_staging_time: float = 1000.0, navigate_to_staging_pose: bool = True,
                   feedback: Callable[[DockFeedback], None] | None = None) -> Ros2NavHandle:
        """opennav_docking's ``dock_robot`` (nav2_msgs/action/DockRobot)."""
        msg = idl.DockRobot.Goal(use_dock_id=use_dock_id, dock_id=dock_id,
                                 dock_pose=self._stamped(dock_pose if dock_pose is not None else Pose2D(0.0, 0.0)),
                                 dock_type=dock_type, max_staging_time=max_staging_time,
                                 navigate_to_staging_pose=navigate_to_staging_pose)
        return self._launch("dock_robot", msg, feedback,
                            lambda raw: DockFeedback(self._now(), int(raw.state), raw.docking_time.to_sec(),
                                                     int(raw.num_retries)))

    def undock_robot(self, *, dock_type: str = "", max_undocking_time: float = 30.0) -> Ros2NavHandle:
        """opennav_docking's ``undock_robot`` (nav2_msgs/action/UndockRobot)."""
        msg = idl.UndockRobot.Goal(dock_type=dock_type, max_undocking_time=max_undocking_time)
        return self._launch("undock_robot", msg, None, lambda raw: None)

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

    async def clear_obstacles(self) -> None:
        raise NotImplementedError("clear_obstacles is not available on real Nav2 (no add_obstacle either; "
                                  "see docs/ros2.md)")

    # -- costmap queries (from the global costmap topic) ------------------------------------------
    def _on_costmap(self, samples: list, _now: float) -> None:
        m = samples[-1]
        w, h = int(m.info.width), int(m.info.height)
        if w * h != len(m.data) or w == 0 or h == 0 or not m.info.resolution > 0:
            self.driver.count_drop("costmap", "size mismatch")
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

