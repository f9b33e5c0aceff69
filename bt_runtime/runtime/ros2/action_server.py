"""Goals from any ROS 2 client: a ``nav2_msgs/action/NavigateToPose`` action server and a
``geometry_msgs/msg/PoseStamped`` goal topic, both feeding the runtime's ``GoalIntake``.

* Action (default ``autonomy/navigate_to_pose``): every goal is accepted and preempts the
  running one (the preempted goal ends ABORTED, "preempted by a newer goal", as Nav2's
  navigator does); feedback carries the current pose, distance remaining, navigation time,
  estimated time remaining and number of recoveries; the result's ``error_code`` /
  ``error_msg`` say why a goal did not succeed ("refused: battery ...", the tree's reason, a
  Nav2 error code) and, for a success, whether an alternative goal was used. A cancel request
  halts the goal in the tree; its result is CANCELED once the tree has let go.
* Topic (default ``autonomy/goal_pose``): a pose published there (RViz's 2D Goal Pose tool)
  becomes a goal that preempts the running one; nobody gets its result (use the action).

Goals are in the map frame: a goal stamped in another frame ends ABORTED (no tf here).
"""

from __future__ import annotations

import asyncio
import math
from typing import Any

import structlog

from ..goal_intake import GoalFeedback, GoalIntake, GoalResult, GoalState
from . import dds, idl
from .convert import pose2d_of, pose_msg

log = structlog.get_logger("bt_runtime.ros2.goals")

S = idl.GoalStatus
STATUS = {GoalState.SUCCEEDED: S.STATUS_SUCCEEDED, GoalState.CANCELED: S.STATUS_CANCELED,
          GoalState.ABORTED: S.STATUS_ABORTED, GoalState.REJECTED: S.STATUS_ABORTED}
UNKNOWN = 9000  # nav2_msgs NavigateToPose.Result.UNKNOWN
RELEASE_TIMEOUT = 5.0  # s a cancelled goal may take to be let go by the tree


class GoalActionServer:
    """The NavigateToPose server and the goal topic on ``node``, feeding ``intake``."""

    def __init__(self, node: dds.DdsNode, intake: GoalIntake, *, action: str = "autonomy/navigate_to_pose",
                 topic: str | None = "autonomy/goal_pose", map_frame: str = "map"):
        self.node = node
        self.intake = intake
        self.map_frame = map_frame
        self.types = idl.NavigateToPose
        self.server = dds.ActionServer(node, action, self.types, self._execute)
        self.topic_reader = (node.subscription(topic, idl.PoseStamped, dds.DEFAULT, self._on_goal_poses)
                             if topic else None)
        self.topic_goals: list[Any] = []  # handles of goals that came on the topic
        log.info("goal_server_started", action=self.server.name, topic=topic and node.fq(topic))

    # -- the action ------------------------------------------------------------------------------
    async def _execute(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        frame = goal.pose.header.frame_id.lstrip("/")
        if frame not in ("", self.map_frame):
            return S.STATUS_ABORTED, self._result(UNKNOWN, f"goal frame '{frame}' is not '{self.map_frame}' "
                                                           "(goals are taken in the map frame)")
        handle = self.intake.submit(pose2d_of(goal.pose.pose), source="action")
        handle.on_feedback.append(lambda fb: ctx.publish_feedback(self.feedback_msg(fb)))
        try:
            result: GoalResult = await handle
        except asyncio.CancelledError:  # a cancel request (or the server closing)
            handle.cancel()
            try:
                result = await asyncio.wait_for(handle, RELEASE_TIMEOUT)
            except TimeoutError:
                result = GoalResult(GoalState.CANCELED, "CANCELED", 0, "canceled (the tree did not confirm)")
        return STATUS[result.status], self._result(result.error_code, result.error_msg)

    def _result(self, code: int, msg: str) -> Any:
        return self.types.Result(error_code=int(code), error_msg=msg)

    def feedback_msg(self, fb: GoalFeedback) -> Any:
        pose = idl.PoseStamped(header=idl.Header(stamp=idl.Time.now(), frame_id=self.map_frame),
                               pose=pose_msg(fb.current_pose) if fb.current_pose is not None else idl.Pose())
        remaining = fb.distance_remaining
        return self.types.Feedback(
            current_pose=pose, navigation_time=idl.Duration.from_sec(max(0.0, fb.navigation_time)),
            estimated_time_remaining=idl.Duration.from_sec(max(0.0, fb.estimated_time_remaining)),
            number_of_recoveries=min(fb.number_of_recoveries, 32767),
            distance_remaining=remaining if math.isfinite(remaining) else 0.0)

    # -- the topic -------------------------------------------------------------------------------
    def _on_goal_poses(self, samples: list, _now: float) -> None:
        for msg in samples[-1:]:  # several at once: the newest wins anyway
            frame = msg.header.frame_id.lstrip("/")
            if frame not in ("", self.map_frame):
                log.warning("goal_pose_ignored", frame=frame, reason=f"not in the '{self.map_frame}' frame")
                continue
            self.topic_goals.append(self.intake.submit(pose2d_of(msg.pose), source="topic"))

    def close(self) -> None:
        self.server.close()
