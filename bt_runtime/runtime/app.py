"""The autonomy runtime: one event loop hosting the tree, supervisor, backup, gate and driver.

    async def main():
        runtime = AutonomyRuntime(SimDriver(...))       # inside the running loop
        runtime.load_tree("trees/autonomy.xml")
        runtime.tree.root_blackboard.set("goal", Pose2D(1, 0))
        await runtime.start()
        summary = await runtime.run(duration=60)
        await runtime.stop()

This is the paper's autonomy layer (Fig. 2/3) minus the behaviours, which are nodes.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import structlog

from .. import logging_setup
from ..factory import BehaviorTreeFactory
from ..status import FAILURE, SUCCESS, NodeStatus
from ..tree import Tree
from .backup import DataBackup
from .clock import is_virtual
from .command_limits import MotionLimits
from .config import RuntimeConfig
from .context import RuntimeContext
from .diagnostics import DiagnosticsPublisher
from .driver import RobotDriver
from .gate import DecisionGate
from .goal_intake import GoalHandle, GoalIntake
from .messages import RobotInfo
from .safety_zones import build_safety_zones
from .shutdown import register_live, settle, unregister_live
from .supervisor import SystemSupervisor
from .tick_loop import TickLoop
from .watchdog import LoopWatchdog

log = structlog.get_logger("bt_runtime.runtime")

Registration = Callable[[BehaviorTreeFactory], Any]


@dataclass
class RunSummary:
    """What a run did, for the CLI summary, tests and scenario judging."""

    status: str  # the root's last status, or 'stopped'
    completed: bool
    sim_time: float
    wall_time: float
    ticks: int
    tick_errors: int
    overruns: int
    tick_cost_mean_ms: float  # CPU of the ticking thread
    tick_cost_p99_ms: float
    lateness_p50_ms: float
    lateness_p99_ms: float
    health: dict[str, str] = field(default_factory=dict)
    supervisor_events: int = 0
    gate_switches: int = 0
    estop_reasons: list[str] = field(default_factory=list)
    goal_outcomes: list[str] = field(default_factory=list)
    tick_wall_mean_ms: float = 0.0  # the same ticks in wall time (CPU plus time descheduled)
    bringup: dict | None = None  # the lifecycle bring-up (supervisor.bringup), when there was one

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("inf")


class AutonomyRuntime:
    """Builds and runs the autonomy layer around one tree on the current event loop."""

    def __init__(self, driver: RobotDriver, config: RuntimeConfig | None = None, *,
                 realtime: bool | None = None, register: Iterable[Registration] = ()):
        self.loop = asyncio.get_running_loop()
        self.driver = driver
        self.config = config or RuntimeConfig()
        self.realtime = (not is_virtual(self.loop)) if realtime is None else realtime
        clock = self.loop.time
        self.clock = clock
        cfg = self.config
        robot_info = getattr(driver, "robot_info", None)
        robot = robot_info() if callable(robot_info) else RobotInfo()
        self.backup = DataBackup(driver, cfg.backup, clock=clock)
        self.gate = DecisionGate(driver, cfg.gate, clock=clock, backup=self.backup,
                                 limits=MotionLimits.from_robot(robot))
        self.safety_zones = build_safety_zones(cfg.safety_zones, robot, driver, passthrough=cfg.gate.passthrough,
                                               clock=clock, backup=self.backup)
        self.gate.zones = self.safety_zones
        self.supervisor = SystemSupervisor(driver, cfg.supervisor, clock=clock, gate=self.gate)
        self.backup.supervisor = self.supervisor
        self.context = RuntimeContext(driver, self.supervisor, self.backup, self.gate, cfg, clock, robot=robot)
        self.watchdog = self._make_watchdog()
        self.factory = BehaviorTreeFactory(context=self.context)
        for registration in register:
            registration(self.factory)
        self.tree: Tree | None = None
        self._logs_robot_time = False
        self.tick_loop: TickLoop | None = None
        self.goals = GoalIntake(self)  # goals from the API and the driver's clients (goal_intake.py)
        self.completed: asyncio.Future = self.loop.create_future()
        self._tick_task: asyncio.Task | None = None
        self._service_tasks: list[asyncio.Task] = []
        self.bringup_task: asyncio.Task | None = None
        self.diagnostics: DiagnosticsPublisher | None = None
        self._diagnostics_task: asyncio.Task | None = None
        self._started_wall = 0.0
        self._started_sim = 0.0
        self._grid_origin = 0.0
        self._tick_origin = 0.0
        self.running = False

    def _make_watchdog(self) -> LoopWatchdog | None:
        """The off-loop dead-man (watchdog.py): on for real-time loops unless configured off;
        never in the passthrough baseline (no dead-man there)."""
        cfg = self.config.gate
        wanted = (not is_virtual(self.loop)) if cfg.watchdog is None else cfg.watchdog
        if not wanted or cfg.passthrough:
            return None
        zero = getattr(self.driver, "emergency_zero", None)
        if not callable(zero):
            log.warning("watchdog_unavailable", driver=getattr(self.driver, "name", "?"),
                        reason="the driver has no thread-safe emergency_zero()")
            return None
        return LoopWatchdog(zero, cfg.deadman_timeout)

    # -- tree ----------------------------------------------------------------------------------
    def load_tree(self, source: str | Path, *, tree_id: str | None = None) -> Tree:
        """Load a tree from a file path or XML text (with the runtime's factory)."""
        text = str(source)
        if text.lstrip().startswith("<"):
            tree = (self.factory.create_tree_from_text(text) if tree_id is None else
                    self._register_and_create(text, tree_id))
        else:
            tree = (self.factory.create_tree_from_file(source) if tree_id is None else
                    self._register_file_and_create(source, tree_id))
        self.set_tree(tree)
        return tree

    def _register_and_create(self, text: str, tree_id: str) -> Tree:
        self.factory.register_behavior_tree_from_text(text)
        return self.factory.create_tree(tree_id)

    def _register_file_and_create(self, path: str | Path, tree_id: str) -> Tree:
        self.factory.register_behavior_tree_from_file(path)
        return self.factory.create_tree(tree_id)

    def set_tree(self, tree: Tree) -> None:
        self.tree = tree
        tree.set_clock(self.clock)
        self.tick_loop = TickLoop(tree, self.config.tick, gate=self.gate, supervisor=self.supervisor,
                                  realtime=self.realtime)
        self.tick_loop.on_tick.append(self._on_tick)
        deliver_held = getattr(self.driver, "deliver_held", None)
        if deliver_held is not None:  # (the ROS 2 driver: streams delivered at the tick)
            self.tick_loop.before_tick.append(deliver_held)

    def _on_tick(self, status: NodeStatus) -> None:
        self.goals.on_tick(status)
        if (status is SUCCESS or status is FAILURE) and not self.completed.done():
            self.completed.set_result(status)
            if self.config.tick.stop_on_completion and "tree" in self.supervisor.components:
                self.supervisor.set_watched("tree", False)  # an idle tree is not a dead tree

    # -- lifecycle -----------------------------------------------------------------------------
    async def start(self, *, tick: bool = True) -> None:
        """Start the driver and the services; start ticking unless ``tick`` is False (then the
        tree waits for ``restart_tree()``, as Nav2's navigator waits for a goal)."""
        if self.tree is None:
            raise RuntimeError("load a tree before starting the runtime")
        self._started_wall = time.perf_counter()
        self._started_sim = self.clock()
        self._grid_origin = self.clock()  # the driver's periodic work starts on this grid
        await self.driver.start()
        robot_time = getattr(self.driver, "robot_time", None)
        if callable(robot_time):  # log lines carry the robot's own time (ROS time), not the loop's
            logging_setup.use_robot_time(robot_time)
            self._logs_robot_time = True
        serve_goals = getattr(self.driver, "serve_goals", None)
        if callable(serve_goals):  # e.g. the ROS 2 driver's NavigateToPose action server
            serve_goals(self.goals)
        self.backup.attach()
        self.gate.attach()
        if self.safety_zones is not None:
            self.safety_zones.attach(self.driver)
        self.supervisor.attach()
        self.supervisor.register_local("tree", timeout=max(0.5, 5.0 / self.config.tick.rate_hz),
                                       restart=self._restart_tree, auto_restart=True)
        spawn = self.loop.create_task
        period = 1.0 / self.config.tick.rate_hz
        self._tick_origin = self._grid_origin + self.config.tick.phase * period
        self._service_tasks = [spawn(self.supervisor.run(), name="supervisor"),
                               spawn(self.backup.run(), name="backup"),
                               spawn(self.gate.run(), name="gate")]
        for task in self._service_tasks:
            task.add_done_callback(self._watch_service)
        # Nav2's lifecycle nodes configured and activated in order (runtime/bringup.py); await
        # runtime.bringup_task for the report (supervisor.bringup)
        self.bringup_task = spawn(self.supervisor.bring_up(), name="bringup")
        publish = getattr(self.driver, "publish_diagnostics", None)
        if publish is not None:  # health on /diagnostics where the driver speaks ROS (not safety-critical)
            self.diagnostics = DiagnosticsPublisher(self.supervisor, publish, self.clock)
            self._diagnostics_task = spawn(self.diagnostics.run(), name="diagnostics")
        self.running = True
        register_live(self)
        if self.watchdog is not None:
            self.gate.watchdog = self.watchdog
            self.watchdog.start()
        if tick:
            self.gate.heartbeat()  # the first tick is due within one period: no spurious dead-man
            self._start_tick_task()
        else:
            self.supervisor.set_watched("tree", False)
        log.info("runtime_started", driver=getattr(self.driver, "name", "?"), realtime=self.realtime,
                 sim_time=round(self.clock(), 3))

    def _start_tick_task(self) -> None:
        assert self.tick_loop is not None
        self._tick_task = task = self.loop.create_task(self.tick_loop.run(self._tick_origin), name="tick")
        hold = getattr(self.driver, "hold_until_tick", None)
        if hold is not None and self.realtime:  # held streams wait for the tick while it runs
            hold(True)
            task.add_done_callback(lambda t: hold(False) if self._tick_task is t else None)

    @property
    def tick_task(self) -> asyncio.Task | None:
        return self._tick_task

    def restart_tree(self) -> asyncio.Future:
        """Run the tree again from its root (e.g. for a new goal); returns the future that
        completes with the root's final status."""
        task = self._tick_task
        if task is not None and not task.done():
            task.cancel()
        if self.tree is not None:
            self._halt_tree_logged()
        self.completed = self.loop.create_future()
        self.supervisor.set_watched("tree", True)
        self.gate.heartbeat()
        self._start_tick_task()
        return self.completed

    async def _restart_tree(self) -> bool:
        """The supervisor's restart of the 'tree' component: halt it, start a new tick task."""
        task = self._tick_task
        if task is not None and not task.done():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        if self.tree is not None:
            self._halt_tree_logged()
        self._start_tick_task()
        return True

    def send_goal(self, pose: Any, *, preempt: bool = True) -> GoalHandle:
        """Hand a goal (a ``Pose2D``) to the tree through the goal hand-off; await the handle for
        its result, read ``handle.feedback``, ``handle.cancel()`` to halt it. A new goal preempts
        the current one unless ``preempt`` is False (then it queues). The tree must be ticking."""
        return self.goals.submit(pose, preempt=preempt)

    async def run(self, duration: float | None = None) -> RunSummary:
        """Run until the tree completes or ``duration`` seconds (loop time) have passed."""
        if duration is None:
            await asyncio.shield(self.completed)
        else:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.shield(self.completed), duration)
        return self.summary()

    async def stop(self) -> None:
        """Zero the base at once, stop ticking, halt the tree (cancelling async actions), send
        the final zero and stop the driver. Bounded: tasks that ignore cancellation are
        abandoned after ``config.shutdown_timeout`` with a warning naming them (the node, for
        an AsyncActionNode), and so is a driver that does not stop in time."""
        if not self.running:
            return
        self.running = False
        timeout = self.config.shutdown_timeout
        self.gate.shutdown()  # zero first: nothing below may delay it
        if self.diagnostics is not None:
            self.diagnostics.close()
        await settle([t for t in (self._tick_task, *self._service_tasks, self._diagnostics_task, self.bringup_task)
                      if t is not None],
                     timeout, what="runtime stop")
        if self.tree is not None:
            node_tasks = [t for t in asyncio.all_tasks(self.loop) if t.get_name().startswith("bt:")]
            self._halt_tree_logged()
            await settle(node_tasks, timeout, what="halting the tree")
        self.gate.shutdown()  # the last word: the 'runtime stopped' e-stop holds every later output at zero
        self.goals.close()
        if self.watchdog is not None:
            self.watchdog.stop()
        self.supervisor.detach()
        self.gate.detach()
        if self.safety_zones is not None:
            self.safety_zones.detach()
        self.backup.detach()
        try:
            await asyncio.wait_for(self.driver.stop(), timeout)
        except TimeoutError:
            log.warning("driver_stop_abandoned", driver=getattr(self.driver, "name", "?"),
                        reason=f"did not stop within {timeout:.1f} s")
        except Exception as exc:
            log.error("driver_stop_failed", error=repr(exc))
        unregister_live(self)
        log.info("runtime_stopped", sim_time=round(self.clock(), 3))
        if self._logs_robot_time:
            logging_setup.use_robot_time(None)
            self._logs_robot_time = False

    def _halt_tree_logged(self) -> None:
        """Halt the tree; a node that fails to halt is logged (every node is halted anyway)."""
        try:
            self.tree.halt_tree()
        except Exception as exc:
            log.error("halt_error", error=str(exc), error_type=type(exc).__name__)

    def _watch_service(self, task: asyncio.Task) -> None:
        """A service task (supervisor, backup, gate) that dies stops the robot: without it the
        runtime is not what it promises."""
        if task.cancelled() or not self.running:
            return
        exc = task.exception()
        log.error("service_crashed", service=task.get_name(), error=repr(exc))
        self.gate.emergency_stop(f"{task.get_name()} crashed")

    async def __aenter__(self) -> AutonomyRuntime:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # -- reporting -----------------------------------------------------------------------------
    def summary(self) -> RunSummary:
        loop_stats = self.tick_loop.stats if self.tick_loop else None
        late = loop_stats.lateness_percentiles() if loop_stats else {}
        cost = loop_stats.cost_percentiles() if loop_stats else {}
        completed = self.completed.done()
        status = self.completed.result().name if completed else (
            self.tick_loop.status.name if self.tick_loop else "IDLE")
        return RunSummary(
            status=status, completed=completed,
            sim_time=self.clock() - self._started_sim,
            wall_time=time.perf_counter() - self._started_wall,
            ticks=loop_stats.count if loop_stats else 0,
            tick_errors=loop_stats.errors if loop_stats else 0,
            overruns=loop_stats.overruns if loop_stats else 0,
            tick_cost_mean_ms=(loop_stats.cost_mean * 1e3) if loop_stats else 0.0,
            tick_cost_p99_ms=cost.get("p99", 0.0) * 1e3,
            tick_wall_mean_ms=(loop_stats.wall_mean * 1e3) if loop_stats else 0.0,
            lateness_p50_ms=late.get("p50", 0.0) * 1e3,
            lateness_p99_ms=late.get("p99", 0.0) * 1e3,
            health=self.supervisor.summary(),
            supervisor_events=len(self.supervisor.events),
            gate_switches=len(self.gate.switches),
            estop_reasons=self.gate.estop_reasons,
            bringup=self.supervisor.bringup.to_dict() if self.supervisor.bringup.status != "off" else None,
        )
