"""``NavStack``: the Nav2 stand-in behind ``bt_runtime.runtime.driver.NavigationClient``.

It listens on the bus (``pose`` LocalizedPose in the map frame, ``odom`` Odometry, ``scan``
LaserScan), plans on a global costmap, follows paths with Regulated Pure Pursuit on a local
costmap, runs Spin / BackUp / DriveOnHeading / Wait, and publishes velocity on ``nav_cmd_vel``
(never to the wheels: the autonomy layer's decision gate multiplexes it) and plans on ``plan``.

Everything runs as asyncio tasks on the running loop and takes time from ``loop.time()``.
Actions return ``NavHandle`` objects (awaitable; ``done()``, ``result()``, ``cancel()``,
``feedback``). One motion action runs at a time: a new one preempts the running one, which
ends ABORTED with "preempted" (as Nav2's simple action server does). ``navigate_to_pose`` plans,
follows, replans at 1 Hz and ends within the goal tolerance; it runs no recoveries (that is the
behavior tree's job) and aborts with the planner's or controller's Nav2 error code.

Components that can fail (``planner_server``, ``controller_server``, ``behavior_server``) each
publish ``heartbeat/<name>`` (a ``Heartbeat``) at ~10 Hz while alive, and can be crashed
(actions abort, nothing more is published), hung (requests are accepted and never answered,
heartbeats stop), set to fail every request until restarted, and restarted (STARTING for
``restart_delay`` seconds, then ACTIVE; whatever was running on it is aborted).
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import structlog

from bt_runtime.runtime.messages import (
    ZERO_TWIST,
    ActionStatus,
    ComponentInfo,
    ComponentState,
    LaserScan,
    LocalizedPose,
    NavErrorCode,
    NavFeedback,
    NavResult,
    Odometry,
    Path,
    Pose2D,
    Twist,
)

from .behaviors import BackUp, Behavior, DriveOnHeading, Spin
from .controller import GoalChecker, NoValidControl, ProgressChecker, RegulatedPurePursuit
from .costmap import GlobalCostmap, LocalCostmap
from .docking import DockingServer
from .occupancy import OccupancyGrid
from .params import NavParams, RobotParams
from .planner import GridPlanner, PlanResult

log = structlog.get_logger("sim.nav")

E = NavErrorCode
PLANNER, CONTROLLER, BEHAVIOR = "planner_server", "controller_server", "behavior_server"
COMPONENTS = (PLANNER, CONTROLLER, BEHAVIOR)
_UNKNOWN_CODE = {PLANNER: E.PLANNER_UNKNOWN, CONTROLLER: E.CONTROLLER_UNKNOWN,
                 BEHAVIOR: E.BEHAVIOR_UNKNOWN}


@dataclass(slots=True, frozen=True)
class Heartbeat:
    """Published on ``heartbeat/<name>`` while a component is alive."""

    stamp: float
    name: str
    seq: int


class NavServiceError(RuntimeError):
    """A costmap service could not be served (component down, or no answer in time)."""


class _ComponentDown(Exception):
    def __init__(self, comp: NavComponent, why: str):
        super().__init__(f"{comp.name} {why}")
        self.comp = comp


class _Finish(Exception):  # noqa: N818 - control flow, not an error
    def __init__(self, result: NavResult):
        super().__init__(result.error_msg)
        self.result = result


class NavComponent:
    """A navigation server as a process that can crash, hang, fail and be restarted."""

    def __init__(self, name: str):
        self.name = name
        self.state = ComponentState.ACTIVE
        self.hung = False
        self.failing = False
        self.generation = 0  # bumps on crash and restart: in-flight work is lost
        self.seq = 0
        self.announce = False  # log the next heartbeat (the first after a restart)
        self._waiters: list[asyncio.Future] = []

    @property
    def available(self) -> bool:
        return self.state is ComponentState.ACTIVE

    @property
    def alive(self) -> bool:
        """Heartbeating: running and not hung."""
        return self.state is ComponentState.ACTIVE and not self.hung

    def changed(self) -> None:
        for fut in self._waiters:
            if not fut.done():
                fut.set_result(None)
        self._waiters.clear()

    async def wait_change(self) -> None:
        fut = asyncio.get_running_loop().create_future()
        self._waiters.append(fut)
        try:
            await fut
        finally:
            if fut in self._waiters:
                self._waiters.remove(fut)


class NavHandle:
    """A running action. Awaiting it gives the ``NavResult`` (cancelling the awaiter does not
    cancel the action; use ``cancel()``)."""

    def __init__(self, kind: str, feedback_cb: Callable[[NavFeedback], None] | None = None):
        self.kind = kind
        self._task: asyncio.Task | None = None
        self._feedback: NavFeedback | None = None
        self._feedback_cb = feedback_cb
        self.preempted = False
        self.cancel_requested = False
        self.start_time = 0.0
        self._path_update: np.ndarray | None = None

    def done(self) -> bool:
        return self._task is not None and self._task.done()

    def result(self) -> NavResult:
        if self._task is None or not self._task.done():
            raise asyncio.InvalidStateError(f"{self.kind} is still running")
        if self._task.cancelled():
            return NavResult(ActionStatus.CANCELED, E.NONE, "canceled before it started")
        exc = self._task.exception()
        if exc is not None:
            return NavResult(ActionStatus.ABORTED, E.NAVIGATE_UNKNOWN, f"internal error: {exc!r}")
        return self._task.result()

    def cancel(self) -> None:
        if self._task is not None and not self._task.done():
            self.cancel_requested = True
            self._task.cancel()

    def update_path(self, path: Path | np.ndarray) -> bool:
        """Give a running ``follow_path`` a new path without restarting it (Nav2's controller
        server accepting a preempting FollowPath goal: ``updateGlobalPath`` resets the goal
        checker, not the progress checker). Applied at the next control cycle. False if this
        is not a running follow_path or the path is empty (the caller may send a new goal)."""
        if self.kind != "follow_path" or self._task is None or self._task.done():
            return False
        pts = path.points if isinstance(path, Path) else np.asarray(path)
        if pts is None or len(pts) == 0:
            return False
        self._path_update = np.asarray(pts, dtype=float)
        return True

    def _preempt(self) -> None:
        if self._task is not None and not self._task.done():
            self.preempted = True
            self._task.cancel()

    def __await__(self):
        return self._wait().__await__()

    async def _wait(self) -> NavResult:
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.shield(self._task)
        if not self._task.done():  # our awaiter was cancelled, not the action
            raise asyncio.CancelledError
        return self.result()

    @property
    def feedback(self) -> NavFeedback | None:
        return self._feedback

    def _set_feedback(self, fb: NavFeedback) -> None:
        self._feedback = fb
        if self._feedback_cb is not None:
            try:
                self._feedback_cb(fb)
            except Exception:  # a bad callback must not kill the action
                log.exception("nav_feedback_callback_failed", action=self.kind)


def _ok() -> NavResult:
    return NavResult(ActionStatus.SUCCEEDED)


def _abort(code: NavErrorCode, msg: str) -> NavResult:
    return NavResult(ActionStatus.ABORTED, code, msg)


class NavStack:
    """Nav2-like navigation on the simulator bus; implements ``NavigationClient``."""

    def __init__(self, bus: Any, grid: OccupancyGrid, robot: RobotParams | dict | None = None,
                 params: NavParams | dict | None = None, docks: dict[str, Pose2D] | None = None):
        self.bus = bus
        self.grid = grid
        self.robot = robot if isinstance(robot, RobotParams) else RobotParams.model_validate(robot or {})
        self.params = params if isinstance(params, NavParams) else NavParams.model_validate(params or {})
        p = self.params
        self.global_costmap = GlobalCostmap(grid, self.robot.radius, p.global_costmap,
                                            self.robot.laser_offset)
        self.local_costmap = LocalCostmap(self.global_costmap, self.robot.radius, p.local_costmap,
                                          self.robot.laser_offset)
        self.planner = GridPlanner(self.global_costmap, p.planner)
        self.controller = RegulatedPurePursuit(p.controller, self.robot, self.local_costmap)
        c = p.controller
        self.goal_checker = GoalChecker(c.xy_goal_tolerance, c.yaw_goal_tolerance,
                                        c.stateful_goal_checker, c.path_length_tolerance)
        self.progress_checker = ProgressChecker(c.required_movement_radius, c.movement_time_allowance)
        self.components: dict[str, NavComponent] = {n: NavComponent(n) for n in COMPONENTS}
        # called with (component, event) for the simulator's component log (see SimDriver)
        self.on_component_event: Callable[[str, str], None] | None = None
        # latest inputs
        self._pose: Pose2D | None = None
        self._pose_time = -math.inf
        self._odom: Odometry | None = None
        self._odom_time = -math.inf
        self._scan: LaserScan | None = None
        self._scan_pose: Pose2D | None = None
        self._scan_seq = 0
        self._local_seq = 0
        self._global_seq = 0
        self._last_cmd = ZERO_TWIST
        # actions
        self._motion: NavHandle | None = None
        self._handles: set[NavHandle] = set()
        self._heartbeat_task: asyncio.Task | None = None
        self._restart_tasks: dict[str, asyncio.Task] = {}
        self._unsubs: list[Callable[[], None]] = []
        self._subscribe()
        self.current_plan: Path | None = None
        self.docking = DockingServer(self, docks)  # opennav_docking's dock_robot / undock_robot

    # ------------------------------------------------------------------------------------
    # lifecycle
    # ------------------------------------------------------------------------------------
    def _subscribe(self) -> None:
        if not self._unsubs:
            self._unsubs = [self.bus.subscribe("pose", self._on_pose),
                            self.bus.subscribe("odom", self._on_odom),
                            self.bus.subscribe("scan", self._on_scan),
                            self.bus.subscribe("nav_speed_limit", self._on_speed_limit)]

    async def start(self) -> None:
        """Start the heartbeats (actions also start them on first use)."""
        self._subscribe()
        self._ensure_started()

    def _ensure_started(self) -> None:
        if self._heartbeat_task is None or self._heartbeat_task.done():
            self._heartbeat_task = asyncio.get_running_loop().create_task(
                self._heartbeats(), name="nav.heartbeats")

    async def stop(self) -> None:
        self.cancel_all()
        tasks = [h._task for h in list(self._handles) if h._task is not None]
        tasks += list(self._restart_tasks.values())
        if self._heartbeat_task is not None:
            tasks.append(self._heartbeat_task)
        for t in tasks:
            t.cancel()
        for t in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t
        self._heartbeat_task = None
        for unsub in self._unsubs:
            unsub()
        self._unsubs = []

    async def _heartbeats(self) -> None:
        loop = asyncio.get_running_loop()
        period = 1.0 / self.params.navigator.heartbeat_rate
        t = loop.time()
        while True:
            now = loop.time()
            for comp in self.components.values():
                if comp.alive:
                    comp.seq += 1
                    self.bus.publish(f"heartbeat/{comp.name}", Heartbeat(now, comp.name, comp.seq))
                    if comp.announce:
                        comp.announce = False
                        self._log_component(comp.name, "published")
            t += period
            await asyncio.sleep(max(t - loop.time(), 0.0))

    # ------------------------------------------------------------------------------------
    # bus inputs
    # ------------------------------------------------------------------------------------
    def _now(self) -> float:
        return asyncio.get_running_loop().time()

    @staticmethod
    def _sim_time() -> float | None:
        """Loop time for log lines (rounded like the runtime's), None outside a loop."""
        try:
            return round(asyncio.get_running_loop().time(), 3)
        except RuntimeError:
            return None

    @staticmethod
    def _receipt_time(stamp: float) -> float:
        """When a message arrived: the loop's clock, or its stamp outside a running loop."""
        try:
            return asyncio.get_running_loop().time()
        except RuntimeError:
            return stamp

    def _on_pose(self, msg: LocalizedPose) -> None:
        self._pose = msg.pose
        self._pose_time = self._receipt_time(msg.stamp)

    def _on_odom(self, msg: Odometry) -> None:
        self._odom = msg
        self._odom_time = self._receipt_time(msg.stamp)

    def _on_speed_limit(self, msg: Any) -> None:
        """Nav2's SpeedLimit topic: a float (m/s; None or <= 0 lifts the limit) or a
        ``(limit, percentage)`` pair."""
        if isinstance(msg, tuple):
            self.set_speed_limit(msg[0], bool(msg[1]))
        else:
            self.set_speed_limit(msg)

    def _on_scan(self, msg: LaserScan) -> None:
        self._scan = msg
        self._scan_pose = self._pose
        self._scan_seq += 1

    def _pose_age(self, now: float) -> float:
        return now - self._pose_time

    def _speed(self, now: float) -> Twist:
        if self._odom is not None and now - self._odom_time <= self.params.controller.pose_stale_timeout:
            return self._odom.twist
        return self._last_cmd

    def _motion_pose(self, now: float) -> Pose2D | None:
        """Pose for measuring motion (odom frame if fresh, as Nav2's behaviours do)."""
        if self._odom is not None and now - self._odom_time <= self.params.controller.pose_stale_timeout:
            return self._odom.pose
        if self._pose is not None and self._pose_age(now) <= self.params.controller.pose_stale_timeout:
            return self._pose
        return None

    def _update_local(self, now: float) -> None:
        lc = self.local_costmap
        if self._scan_seq != self._local_seq and self._scan_pose is not None and lc.update_due(now):
            self._local_seq = self._scan_seq
            lc.update(self._scan_pose, self._scan, now)
        elif self._pose is not None:
            lc.follow(self._pose)

    def _update_global(self, now: float) -> None:
        gc = self.global_costmap
        if self._scan_seq != self._global_seq and self._scan_pose is not None and gc.update_due(now):
            self._global_seq = self._scan_seq
            gc.update_from_scan(self._scan, self._scan_pose, now)

    def _publish(self, twist: Twist) -> None:
        self._last_cmd = twist
        self.bus.publish("nav_cmd_vel", twist)

    # ------------------------------------------------------------------------------------
    # components and faults
    # ------------------------------------------------------------------------------------
    def _comp(self, name: str) -> NavComponent:
        try:
            return self.components[name]
        except KeyError:
            raise KeyError(f"unknown navigation component {name!r}; known: {', '.join(COMPONENTS)}") from None

    def component_states(self) -> dict[str, ComponentState]:
        return {n: c.state for n, c in self.components.items()}

    def component_infos(self) -> list[ComponentInfo]:
        rate = self.params.navigator.heartbeat_rate
        return [ComponentInfo(name=n, kind="navigation", streams=(f"heartbeat/{n}",),
                              restartable=True, expected_rate_hz=rate, state=c.state,
                              extra={"hung": c.hung, "failing": c.failing})
                for n, c in self.components.items()]

    def _log_component(self, name: str, event: str) -> None:
        """Tell the simulator's component log (``on_component_event``, set by the driver)."""
        if self.on_component_event is not None:
            self.on_component_event(name, event)

    def crash(self, name: str) -> None:
        """The process dies: state INACTIVE, heartbeats stop, running actions abort."""
        comp = self._comp(name)
        comp.state = ComponentState.INACTIVE
        comp.hung = comp.failing = False
        comp.generation += 1
        task = self._restart_tasks.pop(name, None)
        if task is not None:
            task.cancel()
        comp.changed()
        self._log_component(name, "crashed")
        log.warning("nav_component_crashed", component=name, sim_time=self._sim_time())

    def hang(self, name: str) -> None:
        """The process stops answering: requests are accepted but never served, no heartbeats."""
        comp = self._comp(name)
        comp.hung = True
        comp.changed()
        self._log_component(name, "hung")
        log.warning("nav_component_hung", component=name, sim_time=self._sim_time())

    def fail_until_restart(self, name: str) -> None:
        """Every request fails (planner: NO_VALID_PATH, controller: NO_VALID_CONTROL,
        behaviours: BEHAVIOR_UNKNOWN) until the component is restarted."""
        self._comp(name).failing = True
        self._log_component(name, "failing")
        log.warning("nav_component_failing", component=name, sim_time=self._sim_time())

    async def restart(self, name: str, delay: float | None = None) -> bool:
        """Restart a component; True once it is ACTIVE again (False if it crashed meanwhile)."""
        comp = self._comp(name)
        delay = self.params.navigator.restart_delay if delay is None else delay
        comp.generation += 1
        gen = comp.generation
        comp.state = ComponentState.STARTING
        comp.hung = comp.failing = False
        comp.changed()
        self._log_component(name, "restarting")
        log.info("nav_component_restarting", component=name, delay=delay, sim_time=self._sim_time())
        await asyncio.sleep(max(delay, 0.0))
        if comp.generation != gen:
            return False
        comp.state = ComponentState.ACTIVE
        comp.announce = True  # its first heartbeat goes in the component log
        comp.changed()
        self._log_component(name, "running")
        log.info("nav_component_active", component=name, sim_time=self._sim_time())
        return True

    def restart_in_background(self, name: str, delay: float | None = None) -> asyncio.Task:
        task = asyncio.get_running_loop().create_task(self.restart(name, delay),
                                                      name=f"nav.restart.{name}")
        self._restart_tasks[name] = task
        task.add_done_callback(lambda t, n=name: self._restart_tasks.pop(n, None)
                               if self._restart_tasks.get(n) is t else None)
        return task

    async def _gate(self, comp: NavComponent, gen: int) -> None:
        """Raise if the component went down since ``gen``; block (forever) while it hangs."""
        while True:
            if comp.generation != gen:
                raise _ComponentDown(comp, "crashed" if comp.state is ComponentState.INACTIVE
                                     else "restarted")
            if not comp.hung:
                return
            await comp.wait_change()

    def inject_phantom_obstacle(self, x: float, y: float, radius: float = 0.3,
                                which: str = "both") -> None:
        """Fault hook: a lethal disc in the costmaps that no sensor supports; only
        ``clear_costmaps`` removes it."""
        if which in ("global", "both"):
            self.global_costmap.add_phantom(x, y, radius)
        if which in ("local", "both"):
            self.local_costmap.add_phantom(x, y, radius)

    # ------------------------------------------------------------------------------------
    # speed
    # ------------------------------------------------------------------------------------
    def set_desired_speed(self, speed: float) -> None:
        """The controller's cruise speed (RPP max_linear_vel), capped by the robot's maximum."""
        self.controller.set_desired_speed(speed)

    def set_speed_limit(self, limit: float | None, percentage: bool = False) -> None:
        """Nav2's SpeedLimit: absolute m/s, or % of the desired speed; None lifts it."""
        self.controller.set_speed_limit(limit, percentage)

    # ------------------------------------------------------------------------------------
    # actions
    # ------------------------------------------------------------------------------------
    def _launch(self, handle: NavHandle, coro, motion: bool) -> NavHandle:
        self._ensure_started()
        loop = asyncio.get_running_loop()
        handle.start_time = loop.time()
        if motion:
            old = self._motion
            if old is not None and not old.done():
                old._preempt()
            self._motion = handle
        handle._task = loop.create_task(coro, name=f"nav.{handle.kind}")
        self._handles.add(handle)
        handle._task.add_done_callback(lambda t, h=handle: self._action_done(h, t))
        return handle

    def _action_done(self, handle: NavHandle, task: asyncio.Task) -> None:
        self._handles.discard(handle)
        if not task.cancelled() and task.exception() is not None:
            exc = task.exception()
            log.error("nav_action_failed", action=handle.kind, error=repr(exc), sim_time=self._sim_time(),
                      exc_info=(type(exc), exc, exc.__traceback__))
            if self._motion is handle:
                self._publish(ZERO_TWIST)  # never leave a stale command behind an internal error
        elif not task.cancelled():
            res = task.result()
            log.debug("nav_action_done", action=handle.kind, status=res.status.value,
                      code=getattr(res.error_code, "name", res.error_code), msg=res.error_msg, sim_time=self._sim_time())

    def navigate_to_pose(self, goal: Pose2D, *, behavior_tree: str = "",
                         feedback: Callable[[NavFeedback], None] | None = None) -> NavHandle:
        h = NavHandle("navigate_to_pose", feedback)
        return self._launch(h, self._navigate(h, goal), motion=True)

    def follow_path(self, path: Path, *, controller_id: str = "", goal_checker_id: str = "",
                    progress_checker_id: str = "",
                    feedback: Callable[[NavFeedback], None] | None = None) -> NavHandle:
        h = NavHandle("follow_path", feedback)
        return self._launch(h, self._follow(h, path), motion=True)

    def spin(self, target_yaw: float, *, time_allowance: float = 10.0,
             disable_collision_checks: bool = False) -> NavHandle:
        h = NavHandle("spin")
        b = Spin(target_yaw, self.params.behaviors, self.local_costmap, time_allowance,
                 disable_collision_checks)
        return self._launch(h, self._behave(h, b), motion=True)

    def back_up(self, distance: float, speed: float = 0.025, *, time_allowance: float = 10.0,
                disable_collision_checks: bool = False) -> NavHandle:
        h = NavHandle("backup")
        b = BackUp(distance, speed, self.params.behaviors, self.local_costmap, time_allowance,
                   disable_collision_checks)
        return self._launch(h, self._behave(h, b), motion=True)

    def drive_on_heading(self, distance: float, speed: float = 0.025, *,
                         time_allowance: float = 10.0,
                         disable_collision_checks: bool = False) -> NavHandle:
        h = NavHandle("drive_on_heading")
        b = DriveOnHeading(distance, speed, self.params.behaviors, self.local_costmap,
                           time_allowance, disable_collision_checks)
        return self._launch(h, self._behave(h, b), motion=True)

    def wait(self, duration: float) -> NavHandle:
        h = NavHandle("wait")
        return self._launch(h, self._wait(h, duration), motion=False)

    def dock_robot(self, *, use_dock_id: bool = True, dock_id: str = "", dock_pose: Pose2D | None = None,
                   dock_type: str = "", max_staging_time: float = 1000.0, navigate_to_staging_pose: bool = True,
                   feedback: Callable[[Any], None] | None = None) -> NavHandle:
        """opennav_docking's dock_robot (``sim/nav/docking.py``); feedback is ``DockFeedback``."""
        h = NavHandle("dock_robot", feedback)
        coro = self.docking.dock_robot(h, use_dock_id=use_dock_id, dock_id=dock_id, dock_pose=dock_pose,
                                       dock_type=dock_type, max_staging_time=max_staging_time,
                                       navigate_to_staging_pose=navigate_to_staging_pose)
        return self._launch(h, coro, motion=True)

    def undock_robot(self, *, dock_type: str = "", max_undocking_time: float = 30.0) -> NavHandle:
        """opennav_docking's undock_robot: back out to the staging pose."""
        h = NavHandle("undock_robot")
        return self._launch(h, self.docking.undock_robot(h, dock_type=dock_type,
                                                         max_undocking_time=max_undocking_time), motion=True)

    def cancel_all(self) -> None:
        for h in list(self._handles):
            h.cancel()

    async def compute_path_to_pose(self, goal: Pose2D, *, start: Pose2D | None = None,
                                   planner_id: str = "", use_start: bool = False) -> NavResult:
        self._ensure_started()
        now = self._now()
        if use_start and start is not None:
            s = start
        else:
            if self._pose is None or self._pose_age(now) > self.params.controller.pose_abort_timeout:
                return _abort(E.PLANNER_TF_ERROR, "robot pose is not available")
            s = self._pose
        res = await self._plan_request(s, goal)
        if not res.ok:
            return _abort(res.error_code, res.message)
        path = Path(self._now(), res.points)
        self.current_plan = path
        self.bus.publish("plan", path)
        return NavResult(ActionStatus.SUCCEEDED, path=path)

    # ------------------------------------------------------------------------------------
    # costmap services
    # ------------------------------------------------------------------------------------
    async def _service(self, name: str) -> None:
        comp = self._comp(name)
        if not comp.available:
            raise NavServiceError(f"{name} is not active ({comp.state.value})")
        if comp.hung:
            gen = comp.generation
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(self._gate(comp, gen), self.params.navigator.service_timeout)
            raise NavServiceError(f"{name} did not answer within {self.params.navigator.service_timeout} s")

    async def clear_costmaps(self, which: str = "both") -> None:
        if which not in ("local", "global", "both"):
            raise ValueError(f"which must be 'local', 'global' or 'both', got {which!r}")
        if which in ("global", "both"):
            await self._service(PLANNER)
            self.global_costmap.clear()
            self._global_seq = self._scan_seq  # nothing new to integrate until the next scan
        if which in ("local", "both"):
            await self._service(CONTROLLER)
            self.local_costmap.clear()
            self._local_seq = self._scan_seq
        log.info("nav_costmaps_cleared", which=which, sim_time=self._sim_time())

    async def add_obstacle(self, x: float, y: float, radius: float = 0.1) -> None:
        self.global_costmap.add_obstacle(x, y, radius)
        if self.local_costmap._placed:
            self.local_costmap.recompose()
        log.info("nav_obstacle_added", x=x, y=y, radius=radius, sim_time=self._sim_time())

    async def clear_obstacles(self) -> None:
        self.global_costmap.clear_updates()
        if self.local_costmap._placed:
            self.local_costmap.recompose()
        log.info("nav_obstacles_cleared", sim_time=self._sim_time())

    def is_path_valid(self, path: Path, max_cost: int = 253) -> bool:
        if not self.components[PLANNER].alive:
            return False
        pts = path.points if isinstance(path, Path) else np.asarray(path)
        if len(pts) == 0:
            return False
        try:
            now = self._now()
            self._update_global(now)
        except RuntimeError:  # no running loop: use the costmap as it is
            pass
        start = 0
        if self._pose is not None:
            d = np.hypot(pts[:, 0] - self._pose.x, pts[:, 1] - self._pose.y)
            start = int(np.argmin(d))
        return self.planner.is_path_valid(pts, max_cost, start)

    def path_clearance(self, path: Path) -> float:
        pts = path.points if isinstance(path, Path) else np.asarray(path)
        return self.planner.path_clearance(pts)

    # ------------------------------------------------------------------------------------
    # planner server
    # ------------------------------------------------------------------------------------
    async def _plan_request(self, start: Pose2D, goal: Pose2D) -> PlanResult:
        comp = self.components[PLANNER]
        if not comp.available:
            return PlanResult(E.PLANNER_UNKNOWN, message=f"{PLANNER} is not active ({comp.state.value})")
        gen = comp.generation
        timeout = self.params.navigator.planner_result_timeout
        try:
            if timeout is None:
                await self._gate(comp, gen)
            else:
                try:
                    await asyncio.wait_for(self._gate(comp, gen), timeout)
                except TimeoutError:
                    return PlanResult(E.PLANNER_TIMEOUT, message=f"{PLANNER} gave no result in {timeout} s")
        except _ComponentDown as e:
            return PlanResult(E.PLANNER_UNKNOWN, message=str(e))
        if comp.failing:
            return PlanResult(E.NO_VALID_PATH, message=f"{PLANNER} fails every request (fault)")
        self._update_global(self._now())
        res = self.planner.plan(start, goal)
        if not res.ok:
            log.info("nav_plan_failed", code=res.error_code.name, msg=res.message, sim_time=self._sim_time())
        return res

    # ------------------------------------------------------------------------------------
    # controller server
    # ------------------------------------------------------------------------------------
    async def _follow(self, handle: NavHandle, path: Path) -> NavResult:
        pts = path.points if isinstance(path, Path) else np.asarray(path)
        if pts is None or len(pts) == 0:
            return _abort(E.INVALID_PATH, "empty path")
        return await self._control(handle, np.asarray(pts, dtype=float), goal=None)

    async def _navigate(self, handle: NavHandle, goal: Pose2D) -> NavResult:
        now = self._now()
        try:
            if self._pose is None or self._pose_age(now) > self.params.controller.pose_abort_timeout:
                return _abort(E.PLANNER_TF_ERROR, "robot pose is not available")
            res = await self._plan_request(self._pose, goal)
        except asyncio.CancelledError:
            return self._cancelled(handle, published=False)
        if not res.ok:
            return _abort(res.error_code, res.message)
        self._publish_plan(res.points)
        return await self._control(handle, res.points, goal=goal)

    def _publish_plan(self, points: np.ndarray) -> None:
        path = Path(self._now(), points)
        self.current_plan = path
        self.bus.publish("plan", path)

    def _cancelled(self, handle: NavHandle, published: bool, comp: NavComponent | None = None) -> NavResult:
        if handle.preempted:
            return _abort(E.NONE, "preempted by a new goal")
        if published and (comp is None or comp.alive):
            self._publish(ZERO_TWIST)
        return NavResult(ActionStatus.CANCELED, E.NONE, "canceled")

    async def _control(self, handle: NavHandle, points: np.ndarray, goal: Pose2D | None) -> NavResult:
        comp = self.components[CONTROLLER]
        if not comp.available:
            return _abort(E.CONTROLLER_UNKNOWN, f"{CONTROLLER} is not active ({comp.state.value})")
        gen = comp.generation
        p = self.params.controller
        nav = self.params.navigator
        loop = asyncio.get_running_loop()
        period = 1.0 / p.controller_frequency
        ctrl = self.controller
        ctrl.set_plan(points)
        self.goal_checker.reset()
        self.progress_checker.reset()
        start = loop.time()
        last_valid = start
        published = False  # a non-zero command is out (so stopping means publishing a zero)
        replan_task: asyncio.Task | None = None
        next_replan = start + 1.0 / nav.replan_frequency
        tick = start
        try:
            while True:
                await self._gate(comp, gen)
                now = loop.time()
                if comp.failing:
                    raise _Finish(_abort(E.NO_VALID_CONTROL, f"{CONTROLLER} fails every request (fault)"))
                update = handle._path_update
                if update is not None:  # follow_path preempted by a new path (Nav2 updateGlobalPath)
                    handle._path_update = None
                    ctrl.set_plan(update)
                    self.goal_checker.reset()
                age = self._pose_age(now)
                if age > p.pose_abort_timeout:
                    raise _Finish(_abort(E.CONTROLLER_TF_ERROR,
                                         f"no robot pose for {age:.2f} s"))
                if age > p.pose_stale_timeout:
                    if published:
                        self._publish(ZERO_TWIST)
                        published = False
                else:
                    # replanning (navigate_to_pose only), concurrently with control
                    if goal is not None:
                        if replan_task is not None and replan_task.done():
                            res = replan_task.result()
                            replan_task = None
                            next_replan = now + 1.0 / nav.replan_frequency
                            if not res.ok:
                                raise _Finish(_abort(res.error_code, res.message))
                            ctrl.set_plan(res.points)
                            self._publish_plan(res.points)
                        if replan_task is None and now >= next_replan - 1e-9:
                            replan_task = loop.create_task(self._plan_request(self._pose, goal),
                                                           name="nav.replan")
                    self._update_local(now)
                    pose = self._pose
                    ctrl.update_closest(pose.x, pose.y)
                    remaining = ctrl.remaining_length(pose.x, pose.y)
                    if self.goal_checker.is_goal_reached(pose, ctrl.goal, remaining):
                        raise _Finish(_ok())
                    if not self.progress_checker.check(pose, now):
                        raise _Finish(_abort(E.FAILED_TO_MAKE_PROGRESS, "Failed to make progress"))
                    try:
                        cmd = ctrl.compute(pose, self._speed(now), self.goal_checker)
                        last_valid = now
                    except NoValidControl as e:
                        if p.failure_tolerance > 0 or p.failure_tolerance == -1.0:
                            cmd = ZERO_TWIST
                            if p.failure_tolerance != -1.0 and now - last_valid > p.failure_tolerance:
                                raise _Finish(_abort(E.PATIENCE_EXCEEDED,
                                                     f"Controller patience exceeded: {e}")) from None
                        else:
                            raise _Finish(_abort(E.NO_VALID_CONTROL, str(e))) from None
                    self._publish(cmd)
                    published = True
                    handle._set_feedback(NavFeedback(now, pose, remaining, now - start, 0,
                                                     self._speed(now).linear))
                tick += period
                if tick < loop.time():  # missed deadlines (e.g. a long hang): resync
                    tick = loop.time() + period
                await asyncio.sleep(tick - loop.time())
        except _Finish as f:
            if comp.alive:
                self._publish(ZERO_TWIST)  # Nav2 onGoalExit: publishZeroVelocity
            return f.result
        except _ComponentDown as e:
            return _abort(E.CONTROLLER_UNKNOWN, str(e))
        except asyncio.CancelledError:
            return self._cancelled(handle, published, comp)
        finally:
            if replan_task is not None and not replan_task.done():
                replan_task.cancel()

    # ------------------------------------------------------------------------------------
    # behavior server
    # ------------------------------------------------------------------------------------
    async def _behave(self, handle: NavHandle, b: Behavior) -> NavResult:
        comp = self.components[BEHAVIOR]
        if not comp.available:
            return _abort(E.BEHAVIOR_UNKNOWN, f"{BEHAVIOR} is not active ({comp.state.value})")
        gen = comp.generation
        loop = asyncio.get_running_loop()
        p = self.params
        period = 1.0 / p.behaviors.cycle_frequency
        published = False
        start = loop.time()
        try:
            await self._gate(comp, gen)
            if comp.failing:
                return _abort(E.BEHAVIOR_UNKNOWN, f"{BEHAVIOR} fails every request (fault)")
            mp = self._motion_pose(start)
            if mp is None:
                return _abort(E.BEHAVIOR_TF_ERROR, "Current robot pose is not available.")
            st = b.start(start, mp)
            if st is not None:
                return _abort(st.error_code, st.message)
            tick = start
            while True:
                await self._gate(comp, gen)
                now = loop.time()
                mp = self._motion_pose(now)
                if mp is None or self._pose is None:
                    if self._pose_age(now) > p.controller.pose_abort_timeout:
                        raise _Finish(_abort(E.BEHAVIOR_TF_ERROR, "Current robot pose is not available."))
                    if published:
                        self._publish(ZERO_TWIST)
                        published = False
                else:
                    self._update_local(now)
                    st = b.cycle(now, mp, self._pose)
                    if st.done:
                        raise _Finish(_ok() if st.ok else _abort(st.error_code, st.message))
                    self._publish(st.cmd)
                    published = True
                    handle._set_feedback(NavFeedback(now, self._pose, math.nan, now - start, 0,
                                                     st.cmd.linear))
                tick += period
                if tick < loop.time():
                    tick = loop.time() + period
                await asyncio.sleep(tick - loop.time())
        except _Finish as f:
            if comp.alive:
                self._publish(ZERO_TWIST)  # Nav2 stopRobot()
            return f.result
        except _ComponentDown as e:
            return _abort(E.BEHAVIOR_UNKNOWN, str(e))
        except asyncio.CancelledError:
            return self._cancelled(handle, published, comp)

    async def _wait(self, handle: NavHandle, duration: float) -> NavResult:
        comp = self.components[BEHAVIOR]
        if not comp.available:
            return _abort(E.BEHAVIOR_UNKNOWN, f"{BEHAVIOR} is not active ({comp.state.value})")
        gen = comp.generation
        loop = asyncio.get_running_loop()
        end = loop.time() + max(duration, 0.0)
        try:
            await self._gate(comp, gen)
            while loop.time() < end - 1e-9:
                # sleep, but wake up if the behavior server crashes, hangs or restarts
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(comp.wait_change(), end - loop.time())
                await self._gate(comp, gen)
            return _ok()
        except _ComponentDown as e:
            return _abort(E.BEHAVIOR_UNKNOWN, str(e))
        except asyncio.CancelledError:
            return NavResult(ActionStatus.CANCELED, E.NONE, "canceled")
