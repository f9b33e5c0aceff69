"""Collision behaviours (fn_req6): detect, back out, locate the obstacle, mark it, re-plan.

Detection works from the bumper (which of its segments closed) or, for robots without one
(the paper's ROSbot, Sec. III-F), from an IMU acceleration spike and its direction. Either
gives a contact arc on the body's edge; placed with the robot's *own* pose estimate it says
where the obstacle is (``nodes.contact``). Nothing here sees the physics' contact point or
the true pose. Backing out retraces the recent commands from the data backup when the robot
ran into the obstacle, or moves away from the contact otherwise.
"""

from __future__ import annotations

import math

import structlog

from bt_runtime import AsyncActionNode, ConditionNode, NodeStatus, StatefulActionNode, SyncActionNode
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.messages import Contact, Imu, Pose2D, wrap_angle

from .contact import ContactArc, ObstacleMarks, marks_of, segments_arc
from .robot import robot_pose
from .stall import MotionMismatch
from .types import CONTACT_ARC, POSE

SUCCESS, FAILURE, RUNNING = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING
log = structlog.get_logger("nodes.collision")


def bumper_arc(context, contact) -> tuple[float, float] | None:
    """(middle bearing, half width) in the robot frame of a pressed bumper, or None. Uses the
    pressed segments and the robot's segment spans; a bumper that reports a bearing itself
    (ROS 2 Vector3 bumpers) gets a quarter-turn arc around it."""
    if not isinstance(contact, Contact) or not contact.in_contact:
        return None
    arc = segments_arc(context.robot.bumper_segments, contact.segments)
    if arc is not None:
        return arc
    if math.isfinite(contact.direction):
        return contact.direction, math.pi / 4
    return None


class ImpactDetector:
    """Watches the IMU stream in the data backup for acceleration spikes (impacts).

    Each call looks only at the samples that arrived since the previous call and remembers the
    latest spike, so a 100 Hz condition costs almost nothing. The obstacle is on the side
    opposite to the acceleration it caused.
    """

    __slots__ = ("_since", "_spike")

    def __init__(self) -> None:
        self._since = -math.inf
        self._spike: tuple[float, float, float] | None = None  # (time, magnitude, bearing)

    def __call__(self, context, window: float, threshold: float) -> tuple[float, float] | None:
        """(magnitude, contact bearing in the robot frame) of a spike above ``threshold`` within
        the last ``window`` seconds, or None."""
        samples = context.backup.buffers.get("imu")
        if samples is not None:
            for stamp, msg in samples.since_stamped(self._since):
                if stamp <= self._since or not isinstance(msg, Imu):
                    continue
                ax, ay = msg.accel_x, msg.accel_y
                if math.isfinite(ax) and math.isfinite(ay):
                    magnitude = math.hypot(ax, ay)
                    if magnitude > threshold and (self._spike is None or stamp - self._spike[0] > window
                                                  or magnitude > self._spike[1]):
                        self._spike = (stamp, magnitude, math.atan2(-ay, -ax))
                self._since = stamp
        spike = self._spike
        if spike is None or context.clock() - spike[0] > window:
            return None
        return spike[1], spike[2]


class CollisionDetected(ConditionNode):
    """SUCCESS while the bumper is pressed, just after an impact (IMU spike), or just after the
    IMU and the wheels disagreed (a glancing push or blocked motion, ``nodes.stall``); writes
    the contact arc's middle bearing (robot frame, rad, 0 = ahead) and its half width."""

    @classmethod
    def provided_ports(cls):
        return [input_port("source", str, "any", "bumper | imu | motion | any"),
                input_port("imu_threshold", float, 6.0, "m/s^2; well above the base's acceleration limits"),
                input_port("imu_window", float, 0.25, "s of IMU history to look at"),
                input_port("imu_spread", float, 0.35, "rad either side of the impact direction (the "
                                                      "direction, placed with the pose estimate, was "
                                                      "within 0.23 rad of the true contact in the "
                                                      "collision variants)"),
                input_port("motion_threshold", float, 1.0, "m/s^2 of acceleration beyond what the base "
                                                           "can do (its ramp forwards, v*w sideways)"),
                input_port("stall_speed", float, 0.08, "m/s: wheels this fast while the body stops"),
                input_port("motion_spread", float, 0.6, "rad either side of a glancing push or the "
                                                        "blocked direction of travel"),
                output_port("direction", float, "{collision_direction}"),
                output_port("spread", float, "{collision_spread}", "rad either side of direction")]

    def __init__(self, name, config=None):
        super().__init__(name, config)
        self._impacts = ImpactDetector()
        self._motion = MotionMismatch()
        self._reported = None

    def tick(self):
        ctx = self.context
        source = self.get_input("source")
        if source in ("bumper", "any"):
            arc = bumper_arc(ctx, ctx.backup.latest("bumper"))
            if arc is not None:
                self.set_output("direction", float(arc[0]))
                self.set_output("spread", float(arc[1]))
                return SUCCESS
        if source in ("imu", "any"):
            impact = self._impacts(ctx, self.get_input("imu_window"), self.get_input("imu_threshold"))
            if impact is not None:
                self.set_output("direction", impact[1])
                self.set_output("spread", float(self.get_input("imu_spread")))
                return SUCCESS
        if source in ("motion", "any"):
            sensed = self._motion(ctx, threshold=self.get_input("motion_threshold"),
                                  stall_speed=self.get_input("stall_speed"), stall_window=0.4,
                                  window=self.get_input("imu_window"))
            if sensed is not None:
                if self._motion.event is not self._reported:
                    self._reported = self._motion.event
                    log.info("contact_from_motion", kind=sensed[1], bearing=round(sensed[0], 2))
                self.set_output("direction", sensed[0])
                self.set_output("spread", float(self.get_input("motion_spread")))
                return SUCCESS
        return FAILURE


class InContact(ConditionNode):
    """SUCCESS while the bumper reports contact."""

    def tick(self):
        contact = self.context.backup.latest("bumper")
        return SUCCESS if isinstance(contact, Contact) and contact.in_contact else FAILURE


class EstimateContactPoint(SyncActionNode):
    """Where the obstacle is, from the robot's own pose estimate and the sensed contact arc:
    ``arc`` (map frame) and ``point``, the arc's middle pushed ``offset`` beyond the body."""

    @classmethod
    def provided_ports(cls):
        return [input_port("direction", float, "{collision_direction}", "contact bearing, robot frame"),
                input_port("spread", float, "{collision_spread}", "rad either side of direction"),
                input_port("offset", float, 0.05, "m beyond the footprint"),
                output_port("point", POSE, "{contact_point}"),
                output_port("arc", CONTACT_ARC, "{contact_arc}")]

    def tick(self):
        ctx = self.context
        pose = robot_pose(self)
        if pose is None or not all(map(math.isfinite, (pose.x, pose.y, pose.yaw))):
            return FAILURE
        bearing = self.get_input("direction", 0.0)
        spread = self.get_input("spread", 0.0)
        if not math.isfinite(bearing):
            return FAILURE
        spread = min(abs(spread), math.pi) if math.isfinite(spread) else math.pi / 4
        radius = ctx.robot.radius
        arc = ContactArc(pose.x, pose.y, wrap_angle(pose.yaw + bearing), spread, radius, pose.yaw)
        x, y = arc.point_at(arc.bearing, radius + self.get_input("offset"))
        self.set_output("arc", arc)
        self.set_output("point", Pose2D(x, y, 0.0))
        return SUCCESS


class ReverseOut(StatefulActionNode):
    """Back out of a collision through the gate (tree commands beat navigation).

    If the robot was driving into the contact, the recent commands from the data backup are
    replayed backwards (newest first, negated, at most ``speed``); otherwise it moves straight
    away from the contact. Done once out of contact and ``clearance`` m further, or after
    ``max_distance`` m; FAILURE after ``timeout`` s.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("direction", float, "{collision_direction}", "contact bearing, robot frame"),
                input_port("speed", float, 0.1, "m/s"),
                input_port("max_distance", float, 0.4, "m"),
                input_port("clearance", float, 0.1, "m travelled after contact ends"),
                input_port("history", float, 3.0, "s of commands to retrace"),
                input_port("timeout", float, 10.0, "s")]

    def on_start(self):
        ctx = self.context
        self._t0 = ctx.clock()
        self._speed = abs(self.get_input("speed"))
        self._max = self.get_input("max_distance")
        self._clearance = self.get_input("clearance")
        self._timeout = self.get_input("timeout")
        self._plan = self._make_plan(self.get_input("direction", 0.0), self.get_input("history"))
        self._start = self._odom_pose()
        self._free_at: Pose2D | None = None
        return self.on_running()

    def _odom_pose(self) -> Pose2D | None:
        odom = self.context.backup.latest("odom")
        return odom.pose if odom is not None else None

    def _make_plan(self, direction: float, history: float) -> list[tuple[float, float, float]]:
        """Segments (end time offset, v, w) to command."""
        motion = self.context.backup.recent_motion(history)
        forward = sum(c.linear for _, c in motion)
        ran_into_it = motion and abs(wrap_angle(direction - (0.0 if forward >= 0 else math.pi))) < math.radians(100)
        speed = self._speed
        if ran_into_it:
            plan, elapsed = [], 0.0
            reversed_motion = list(reversed(motion))
            for i, (stamp, cmd) in enumerate(reversed_motion):
                older = reversed_motion[i + 1][0] if i + 1 < len(reversed_motion) else stamp - 0.01
                dt = max(0.0, stamp - older)
                scale = min(1.0, speed / abs(cmd.linear)) if cmd.linear else 1.0
                elapsed += dt / max(scale, 1e-3)
                plan.append((elapsed, -cmd.linear * scale, -cmd.angular * scale))
            if plan:
                return plan
        # standing, or hit from the side/behind: move directly away from the contact
        along = -math.cos(direction)
        v = speed * (1.0 if along >= 0 else -1.0) if abs(along) > 0.3 else -speed
        return [(self._timeout, v, 0.0)]

    def on_running(self):
        ctx = self.context
        now = ctx.clock()
        elapsed = now - self._t0
        if elapsed > self._timeout:
            ctx.gate.clear_tree_command()
            return FAILURE
        pose = self._odom_pose()
        travelled = pose.distance_to(self._start) if pose is not None and self._start is not None else elapsed * self._speed
        contact = ctx.backup.latest("bumper")
        in_contact = isinstance(contact, Contact) and contact.in_contact
        if not in_contact and self._free_at is None:
            self._free_at = pose
        cleared = (self._free_at is not None and pose is not None
                   and pose.distance_to(self._free_at) >= self._clearance)
        if travelled >= self._max or cleared or (not in_contact and elapsed > self._plan[-1][0]):
            ctx.gate.clear_tree_command()
            return SUCCESS
        v, w = self._command_at(elapsed)
        ctx.gate.set_tree_command(v, w)
        return RUNNING

    def _command_at(self, elapsed: float) -> tuple[float, float]:
        for end, v, w in self._plan:
            if elapsed <= end:
                return v, w
        v = -self._speed  # plan exhausted but still touching: keep backing off
        return v, 0.0

    def on_halted(self):
        self.context.gate.clear_tree_command()


class StopRobot(SyncActionNode):
    """Command zero through the gate at tree priority (navigation cannot move the robot)."""

    def tick(self):
        self.context.gate.set_tree_command(0.0, 0.0)
        return SUCCESS


class ReleaseRobot(SyncActionNode):
    """Drop the tree's command so navigation drives again."""

    def tick(self):
        self.context.gate.clear_tree_command()
        return SUCCESS


class MarkObstacle(AsyncActionNode):
    """Mark the obstacle in the navigation map (kept across costmap clears).

    With a contact ``arc`` the mark covers it: discs of ``radius`` just outside the body along
    the arc, extended ``margin`` m past each end (the chord plus a margin), so corner and
    oblique hits are covered; ``outward`` m further on the far side of a touch off to one side
    of the front (the obstacle lies that way); rows of discs up to ``depth`` m behind the arc
    (the body behind the touched surface). Nothing is marked where the body stands now. A hit
    within ``merge_distance`` of an earlier mark grows that mark. Without an arc, one disc at
    ``point``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("point", POSE, "{contact_point}"), input_port("radius", float, 0.15, "m"),
                input_port("arc", CONTACT_ARC, "{contact_arc}", "the sensed contact (EstimateContactPoint)"),
                input_port("margin", float, 0.1, "m past each end of the arc"),
                input_port("outward", float, 0.15, "m more past the end away from the heading when the "
                                                    "touch was off to one side of the front"),
                input_port("depth", float, 0.0, "m: rows of discs this far behind the touched arc (the "
                                                 "body behind the surface; 0: the arc only)"),
                input_port("merge_distance", float, 0.3, "m: a hit this close to a mark grows it"),
                input_port("core_radius", float, 0.05, "m: discs of the mark's core (the sensed arc and "
                                                       "``depth`` behind it, no margins), what is left "
                                                       "when RelaxCollisionMarks shrinks it"),
                output_port("mark", int, "{collision_mark}", "index of the mark made or grown")]

    async def run(self):
        ctx = self.context
        radius = self.get_input("radius")
        arc = self.get_input("arc", None)
        core = touch = None
        if isinstance(arc, ContactArc):
            depth = self.get_input("depth")
            points = arc.chord(arc.radius + radius, self.get_input("margin"), self.get_input("outward"))
            points = arc.behind(points, depth, radius)
            core_r = min(max(self.get_input("core_radius"), 0.01), radius)
            core_points = arc.behind(arc.chord(arc.radius + core_r, 0.0), depth, core_r)
            # where the body stands now (it backed out) is free space: a wide arc (two bumper
            # segments, plus margins) reaches behind the contact and must not mark it
            pose = robot_pose(self)
            if pose is not None and all(map(math.isfinite, (pose.x, pose.y))):
                points = _clear_of(points, pose, ctx.robot.radius + radius)
                core_points = _clear_of(core_points, pose, ctx.robot.radius + core_r)
            core = [(x, y, core_r) for x, y in core_points]
            touch = [(*arc.point_at(arc.bearing, arc.radius + core_r), core_r)]
        else:
            point = self.get_input("point")
            points = [(point.x, point.y)]
        index, discs = marks_of(ctx).place(points, radius, self.get_input("merge_distance"), core, touch)
        for x, y, r in discs:
            await ctx.navigation.add_obstacle(x, y, r)
        self.set_output("mark", index)
        return SUCCESS


def _clear_of(points: list[tuple[float, float]], pose: Pose2D, keep: float) -> list[tuple[float, float]]:
    """``points`` at least ``keep`` from the robot's centre (else the middle one)."""
    free = [p for p in points if math.hypot(p[0] - pose.x, p[1] - pose.y) >= keep]
    return free or points[len(points) // 2:len(points) // 2 + 1]


class RelaxCollisionMarks(AsyncActionNode):
    """Shrink the collision marks one stage when a plan finds no way: first to what was sensed
    (``Mark.core``: the touched arc and the body behind it, without the margins and the far-side
    extension), at the next call to a small disc at each touch's middle (``Mark.touch``). A mark
    is wider than what the robot touched, and beside a doorway or in a passage its margin can
    close the only way that the obstacle itself leaves open; the smallest stage lets the robot
    probe the way again (a new touch grows the mark back). The map is marked again from the
    shrunk marks. FAILURE when there was nothing to relax (no marks, or all at their smallest),
    so the caller goes on to its other ways of handling "no path"."""

    async def run(self):
        ctx = self.context
        marks = ctx.extras.get("collision_marks")
        if not isinstance(marks, ObstacleMarks) or not marks.relax():
            return FAILURE
        try:
            await ctx.navigation.clear_obstacles()
            for x, y, r in marks.discs():
                await ctx.navigation.add_obstacle(x, y, r)
        except Exception as exc:  # a navigation that cannot do it fails the node, never the tick
            ctx.extras["relax_marks_error"] = f"{type(exc).__name__}: {exc}"
            return FAILURE
        log.info("collision_marks_relaxed", marks=len(marks.marks), discs=len(marks.discs()))
        return SUCCESS


class ClearCostmaps(AsyncActionNode):
    """Clear the navigation costmaps (obstacle layers): ``local``, ``global`` or ``both``.
    FAILURE (not an exception) when the server that owns a costmap is down or does not answer."""

    @classmethod
    def provided_ports(cls):
        return [input_port("which", str, "both")]

    async def run(self):
        try:
            await self.context.navigation.clear_costmaps(self.get_input("which"))
        except Exception as exc:  # a server that is down fails the node, never the tick
            self.context.extras["clear_costmaps_error"] = f"{type(exc).__name__}: {exc}"
            return FAILURE
        return SUCCESS
