"""Goals from any client (Python API, a ROS 2 action, a goal topic) handed to the running tree.

The tree's side is the blackboard hand-off trees/autonomy.xml already uses: the sender writes
``{goal}`` and ``{goal_status} = 'PENDING'``; the tree marks it ``ACTIVE`` (or ``CHARGING``), then ``SUCCEEDED``,
``ABORTED`` or ``REFUSED`` (with ``{goal_reason}``, and ``{goal_detail}`` when an alternative
goal was used). ``GoalIntake`` keeps the requests and their handles and drives that hand-off
from the tick loop's after-tick callback, so it never races a tick:

* one goal at a time; a new goal **preempts** the current one (as Nav2's navigator does: the
  old goal ends ABORTED, "preempted by a newer goal"), or queues behind it (``preempt=False``);
* **cancel** writes ``goal_status = 'CANCELED'`` between ticks: on the next tick the tree's
  ``GoalPending`` fails and the mission is halted (its navigation action cancelled); the goal
  ends CANCELED right after that tick; a preempted goal is released the same way before the next is handed over;
* while a goal runs, feedback (pose, distance remaining, time, recoveries) is computed from
  what the runtime sees (the backup's pose, the tree's ``{path}``) at ``feedback_hz``;
* a goal the tree refuses for battery while it can dock (``goal_status = 'CHARGING'``) is
  **kept**: its state is ``CHARGING`` (``refusals`` counts it) while the robot docks and
  charges, and ``EXECUTING`` again when the tree hands it back; a ROS 2 client sees the action
  still executing, with feedback.

Driver-agnostic: ``runtime.send_goal(pose)`` works with the simulator and with ROS 2; the
ROS 2 driver's action server (ros2/action_server.py) is one more client of ``submit``.
"""

from __future__ import annotations

import asyncio
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import structlog

from ..ports import blackboard_key
from ..status import NodeStatus
from .messages import LocalizedPose, Odometry, Path, Pose2D

log = structlog.get_logger("bt_runtime.goals")

OPEN = ("PENDING", "ACTIVE", "CHARGING")  # CHARGING: refused for battery, kept while the robot charges
TREE_DONE = ("SUCCEEDED", "ABORTED", "REFUSED")
# nav2_msgs/action/NavigateToPose result codes (Jazzy): NONE, UNKNOWN
NONE, UNKNOWN = 0, 9000
ERROR_KEYS = ("nav_error", "plan_error")  # the autonomy tree's error-code entries, newest cause first


class GoalState:
    """A goal's life, in action_msgs/GoalStatus words."""

    PENDING = "PENDING"          # queued, not yet handed to the tree
    EXECUTING = "EXECUTING"      # handed over (the tree has it PENDING or ACTIVE)
    CANCELING = "CANCELING"      # cancel or preemption asked; waiting for the tree to let go
    CHARGING = "CHARGING"        # refused for battery and kept: the robot docks, charges, resumes it
    SUCCEEDED = "SUCCEEDED"
    ABORTED = "ABORTED"
    CANCELED = "CANCELED"
    REJECTED = "REJECTED"        # never accepted (the tree takes no goals)


TERMINAL = (GoalState.SUCCEEDED, GoalState.ABORTED, GoalState.CANCELED, GoalState.REJECTED)


@dataclass(slots=True, frozen=True)
class GoalFeedback:
    """What a client sees while its goal runs (NavigateToPose's feedback, in SI units)."""

    current_pose: Pose2D | None
    distance_remaining: float   # m, along the tree's planned path when it has one
    navigation_time: float      # s since the tree took the goal
    estimated_time_remaining: float  # s at the current speed (0 when standing)
    number_of_recoveries: int   # failed attempts, each followed by a recovery


@dataclass(slots=True, frozen=True)
class GoalResult:
    """How a goal ended. ``outcome`` is the tree's word (SUCCEEDED, ABORTED, REFUSED,
    CANCELED, PREEMPTED, REJECTED); ``status`` the action's (SUCCEEDED, ABORTED, CANCELED,
    REJECTED); ``error_code`` follows nav2_msgs (0 none, 9000 unknown, else the Nav2 error code
    the tree last saw)."""

    status: str
    outcome: str
    error_code: int = NONE
    error_msg: str = ""

    @property
    def succeeded(self) -> bool:
        return self.status == GoalState.SUCCEEDED


class GoalHandle:
    """One goal: await it for its ``GoalResult``; ``feedback`` is the latest ``GoalFeedback``;
    ``cancel()`` halts it; ``on_feedback`` callbacks run on the loop at ``feedback_hz``."""

    _ids = 0

    def __init__(self, intake: GoalIntake, pose: Pose2D, source: str):
        GoalHandle._ids += 1
        self.id = GoalHandle._ids
        self.pose = pose
        self.source = source
        self.state = GoalState.PENDING
        self.feedback: GoalFeedback | None = None
        self.on_feedback: list[Callable[[GoalFeedback], Any]] = []
        self.result_future: asyncio.Future = intake.loop.create_future()
        self.submitted_at = intake.clock()
        self.started_at: float | None = None
        self.refusals = 0  # times the tree refused it for battery and kept it to charge first
        self._intake = intake
        self._end_as: GoalResult | None = None  # set by cancel / preemption

    def cancel(self) -> bool:
        """Ask to halt the goal; False when it has already ended."""
        return self._intake.cancel(self)

    @property
    def done(self) -> bool:
        return self.result_future.done()

    @property
    def result(self) -> GoalResult | None:
        return self.result_future.result() if self.result_future.done() else None

    def __await__(self):
        return asyncio.shield(self.result_future).__await__()

    def __repr__(self) -> str:
        return f"GoalHandle({self.id}, {self.pose.to_string()}, {self.state})"


def tree_uses_goal_handoff(tree: Any) -> bool:
    """Whether any port of ``tree`` refers to ``{goal_status}`` (trees/autonomy.xml does)."""
    for node in tree.nodes():
        for name, raw in {**node.config.input_ports, **node.config.output_ports}.items():
            key = blackboard_key(raw, name) if isinstance(raw, str) else None
            if key and key.lstrip("@") == "goal_status":
                return True
    return False


class GoalIntake:
    """The runtime's goal queue; ``on_tick`` (the tick loop's after-tick callback) moves it on."""

    def __init__(self, runtime: Any, *, feedback_hz: float = 5.0):
        self.runtime = runtime
        self.loop = runtime.loop
        self.clock = runtime.clock
        self.feedback_period = 1.0 / feedback_hz
        self.queue: deque[GoalHandle] = deque()
        self.current: GoalHandle | None = None
        self._attempts_seq = 0
        self._in_hand: GoalHandle | None = None
        self._next_feedback = 0.0
        self._error_seq: dict[str, int] = {}
        self.finished: list[GoalHandle] = []  # every ended goal, for summaries and tests

    # -- clients -----------------------------------------------------------------------------
    def submit(self, pose: Pose2D, *, preempt: bool = True, source: str = "api") -> GoalHandle:
        """Queue a goal; with ``preempt`` it replaces the current and queued ones."""
        handle = GoalHandle(self, pose, source)
        tree = self.runtime.tree
        if not (math.isfinite(pose.x) and math.isfinite(pose.y) and math.isfinite(pose.yaw)):
            self._finish(handle, GoalResult(GoalState.REJECTED, "REJECTED", UNKNOWN, "goal pose is not finite"))
            return handle
        refused = self.runtime.supervisor.goals_refused()
        if refused:  # a Nav2 node would not activate: nothing could carry the goal out
            self._finish(handle, GoalResult(GoalState.REJECTED, "REJECTED", UNKNOWN, refused))
            return handle
        if tree is None or not tree_uses_goal_handoff(tree):
            self._finish(handle, GoalResult(GoalState.REJECTED, "REJECTED", UNKNOWN,
                                            "the tree takes no goals: none of its ports uses {goal_status}"))
            return handle
        if preempt:
            while self.queue:
                self._finish(self.queue.popleft(), GoalResult(GoalState.ABORTED, "PREEMPTED", UNKNOWN,
                                                              "preempted by a newer goal"))
            if self.current is not None and self.current.state is not GoalState.CANCELING:
                self._release(self.current, GoalResult(GoalState.ABORTED, "PREEMPTED", UNKNOWN,
                                                       "preempted by a newer goal"))
        self.queue.append(handle)
        log.info("goal_received", goal=pose.to_string(), source=source, id=handle.id, preempt=preempt,
                 sim_time=round(self.clock(), 3))
        return handle

    def cancel(self, handle: GoalHandle) -> bool:
        if handle.done:
            return False
        if handle in self.queue:
            self.queue.remove(handle)
            self._finish(handle, GoalResult(GoalState.CANCELED, "CANCELED", NONE, "canceled"))
            return True
        if handle is self.current and handle.state is not GoalState.CANCELING:
            self._release(handle, GoalResult(GoalState.CANCELED, "CANCELED", NONE, "canceled"))
        return True

    def close(self, why: str = "the runtime stopped") -> None:
        """End every goal (ABORTED): nobody will tick the tree for them any more."""
        for handle in [*([self.current] if self.current else []), *self.queue]:
            self._finish(handle, GoalResult(GoalState.ABORTED, "ABORTED", UNKNOWN, why))
        self.queue.clear()
        self.current = None

    # -- the tree's side (after every tick) --------------------------------------------------
    def on_tick(self, status: NodeStatus) -> None:
        try:
            self._advance(status)
        except Exception as exc:  # a goal bookkeeping error must never stop the tick loop
            log.exception("goal_intake_failed")
            for handle in {self._in_hand, self.current} - {None}:
                self._finish(handle, GoalResult(GoalState.ABORTED, "ABORTED", UNKNOWN, f"internal error: {exc!r}"))
        self._in_hand = None

    def _advance(self, status: NodeStatus) -> None:
        current = self.current
        if current is not None:
            if current.state is GoalState.CANCELING:  # the tree has ticked with CANCELED: halted
                self._finish(current, current._end_as)
            else:
                self._follow(current)
            if status is NodeStatus.SUCCESS or status is NodeStatus.FAILURE:
                if self.current is not None:  # the whole tree ended: nobody works on the goal
                    self._finish(self.current, GoalResult(GoalState.ABORTED, "ABORTED", UNKNOWN,
                                                          f"the tree stopped ({status.name})"))
                return
        if self.current is None and self.queue:
            self._in_hand = self.queue.popleft()
            self._hand_over(self._in_hand)

    def _bb(self):
        return self.runtime.tree.root_blackboard

    def _hand_over(self, handle: GoalHandle) -> None:
        bb = self._bb()
        bb.set("goal", handle.pose)
        bb.set("goals", [handle.pose])
        for key in ("goal_reason", "goal_detail"):
            if _entry(bb, key)[1]:
                bb.set(key, "")
        bb.set("goal_status", "PENDING")
        self._error_seq = {k: _entry(bb, k)[1] for k in ERROR_KEYS}
        self._attempts_seq = _entry(bb, "goal_attempts")[1]
        self.current = handle
        handle.state = GoalState.EXECUTING
        handle.started_at = self.clock()
        self._next_feedback = handle.started_at
        log.info("goal_handed_over", goal=handle.pose.to_string(), id=handle.id, sim_time=round(self.clock(), 3))

    def _follow(self, handle: GoalHandle) -> None:
        bb = self._bb()
        tree_status = bb.get("goal_status", default="")
        if tree_status in TREE_DONE:
            self._finish(handle, self._result_of(tree_status))
            return
        if tree_status not in OPEN:  # someone else closed it (e.g. an operator wrote CANCELED)
            self._finish(handle, GoalResult(GoalState.ABORTED, str(tree_status) or "ABORTED", UNKNOWN,
                                            f"goal status set to {tree_status!r} outside the goal intake"))
            return
        charging = tree_status == "CHARGING"
        if charging != (handle.state is GoalState.CHARGING):
            handle.state = GoalState.CHARGING if charging else GoalState.EXECUTING
            if charging:
                handle.refusals += 1
            log.info("goal_kept_for_charging" if charging else "goal_resumed", id=handle.id,
                     goal=handle.pose.to_string(), sim_time=round(self.clock(), 3))
        now = self.clock()
        if now >= self._next_feedback:
            self._next_feedback = now + self.feedback_period
            self._publish_feedback(handle, now)

    def _release(self, handle: GoalHandle, result: GoalResult) -> None:
        """Close the goal on the tree's side; it ends after the tree has ticked with that."""
        handle.state = GoalState.CANCELING
        handle._end_as = result
        bb = self._bb()
        if bb.get("goal_status", default="") in OPEN:
            bb.set("goal_status", "CANCELED")
        log.info("goal_releasing", id=handle.id, why=result.error_msg, sim_time=round(self.clock(), 3))

    def _finish(self, handle: GoalHandle, result: GoalResult) -> None:
        if handle is self.current:
            self.current = None
        handle.state = result.status
        if not handle.result_future.done():
            handle.result_future.set_result(result)
        self.finished.append(handle)
        log.info("goal_finished", id=handle.id, status=result.status, outcome=result.outcome,
                 error_code=result.error_code, error_msg=result.error_msg, sim_time=round(self.clock(), 3))

    # -- what the client is told ------------------------------------------------------------
    def _result_of(self, tree_status: str) -> GoalResult:
        bb = self._bb()
        reason = str(bb.get("goal_reason", default="") or "")
        if tree_status == "SUCCEEDED":
            detail = str(bb.get("goal_detail", default="") or "")
            msg = f"alternative goal used: {detail}" if detail else ""
            return GoalResult(GoalState.SUCCEEDED, "SUCCEEDED", NONE, msg)
        if tree_status == "REFUSED":  # the battery (BatteryCanReach), or a goal refused outright (outside the map)
            battery = not reason or "battery" in reason.lower()
            return GoalResult(GoalState.ABORTED, "REFUSED", UNKNOWN,
                              ("refused: battery" + (f" ({reason})" if reason else "")) if battery
                              else f"refused: {reason}")
        return GoalResult(GoalState.ABORTED, "ABORTED", self._error_code(), reason or "aborted by the tree")

    def _error_code(self) -> int:
        """The Nav2 error code the tree wrote during this goal, else UNKNOWN."""
        bb = self._bb()
        for key in ERROR_KEYS:
            value, seq = _entry(bb, key)
            if seq != self._error_seq.get(key, 0) and value:
                return int(value)
        return UNKNOWN

    def _publish_feedback(self, handle: GoalHandle, now: float) -> None:
        feedback = self.feedback_now(handle, now)
        handle.feedback = feedback
        for callback in list(handle.on_feedback):
            try:
                callback(feedback)
            except Exception:
                log.exception("goal_feedback_callback_failed", id=handle.id)

    def feedback_now(self, handle: GoalHandle, now: float) -> GoalFeedback:
        backup = self.runtime.backup
        bb = self._bb()
        pose_msg = backup.latest("pose")
        odom = backup.latest("odom")
        pose = (pose_msg.pose if isinstance(pose_msg, LocalizedPose)
                else odom.pose if isinstance(odom, Odometry) else None)
        target = _entry(bb, "nav_goal")[0]
        target = target if isinstance(target, Pose2D) else handle.pose
        path = _entry(bb, "path")[0]
        remaining = remaining_distance(pose, target, path if isinstance(path, Path) else None)
        speed = abs(odom.twist.linear) if isinstance(odom, Odometry) else 0.0
        attempts, seq = _entry(bb, "goal_attempts")
        if seq == self._attempts_seq or not isinstance(attempts, int):
            attempts = 0  # none yet, or written for an earlier goal
        return GoalFeedback(current_pose=pose, distance_remaining=remaining,
                            navigation_time=now - (handle.started_at or now),
                            estimated_time_remaining=remaining / speed if speed > 0.01 else 0.0,
                            number_of_recoveries=int(attempts or 0))


def _entry(bb: Any, key: str) -> tuple[Any, int]:
    """(value or None, write count) of a blackboard entry, 0 writes when absent or empty."""
    entry = bb.get_entry(key)
    if entry is None or entry.is_empty:
        return None, 0
    return entry.value, entry.sequence_id


def remaining_distance(pose: Pose2D | None, target: Pose2D, path: Path | None) -> float:
    """Metres still to go: along ``path`` from the robot's projection on it when the path leads
    to ``target`` (within 0.5 m), else the straight line; NaN without a pose."""
    if pose is None:
        return math.nan
    pts = path.points if path is not None else None
    if pts is None or len(pts) < 2 or math.hypot(pts[-1, 0] - target.x, pts[-1, 1] - target.y) > 0.5:
        return pose.distance_to(target)
    a, b = pts[:-1, :2], pts[1:, :2]
    seg = b - a
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    p = np.array([pose.x, pose.y])
    t = np.clip(((p - a) * seg).sum(axis=1) / np.maximum(lengths ** 2, 1e-12), 0.0, 1.0)
    closest = a + seg * t[:, None]
    gaps = np.hypot(closest[:, 0] - p[0], closest[:, 1] - p[1])
    i = int(np.argmin(gaps))
    return float(gaps[i] + (1.0 - t[i]) * lengths[i] + lengths[i + 1:].sum())
