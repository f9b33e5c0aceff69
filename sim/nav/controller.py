"""Regulated Pure Pursuit (nav2_regulated_pure_pursuit_controller) with Nav2's goal and
progress checkers and the controller server's path handling. Synchronous and allocation-light:
one ``compute`` per control cycle (20 Hz), the async loop lives in ``stack.py``.

Per cycle, as Nav2 does it:
  1. prune the plan to the pose closest to the robot (searched at most
     ``max_robot_pose_search_dist`` along the path from the last closest pose; never backwards)
     and cut it where it leaves the local costmap (half its size);
  2. pick the carrot at the lookahead distance (circle-segment interpolation);
  3. rotate in place towards the goal heading once the goal's xy is reached, or towards the
     path when the carrot is more than ``rotate_to_heading_min_angle`` off; otherwise regulate
     the speed by curvature, by proximity to obstacles (cost at the robot, inverting the
     inflation formula) and on approach to the goal, and steer ``w = v * curvature``;
  4. forward-simulate the command on the local costmap up to the carrot or
     ``max_allowed_time_to_collision_up_to_carrot``; a collision raises ``NoValidControl``.
"""

from __future__ import annotations

import math

import numpy as np

from bt_runtime.runtime.messages import Pose2D, Twist, wrap_angle

from .costmap import FREE_SPACE, NO_INFORMATION, LocalCostmap
from .params import ControllerParams, RobotParams


class NoValidControl(Exception):
    """RPP found no safe command this cycle (Nav2's nav2_core::NoValidControl)."""


class GoalChecker:
    """nav2_controller::SimpleGoalChecker."""

    def __init__(self, xy_tolerance: float = 0.25, yaw_tolerance: float = 0.25,
                 stateful: bool = True, path_length_tolerance: float = 1.0):
        self.xy_tolerance = xy_tolerance
        self.yaw_tolerance = yaw_tolerance
        self.stateful = stateful
        self.path_length_tolerance = path_length_tolerance
        self._check_xy = True

    def reset(self) -> None:
        self._check_xy = True

    def is_xy_reached(self, pose: Pose2D, goal: Pose2D, remaining_path: float) -> bool:
        if remaining_path > self.path_length_tolerance:
            return False
        if self._check_xy:
            dx, dy = pose.x - goal.x, pose.y - goal.y
            if dx * dx + dy * dy > self.xy_tolerance * self.xy_tolerance:
                return False
            if self.stateful:  # latch: once xy is reached only the heading is checked
                self._check_xy = False
        return True

    def is_goal_reached(self, pose: Pose2D, goal: Pose2D, remaining_path: float) -> bool:
        if not self.is_xy_reached(pose, goal, remaining_path):
            return False
        return abs(wrap_angle(goal.yaw - pose.yaw)) <= self.yaw_tolerance


class ProgressChecker:
    """nav2_controller::SimpleProgressChecker: move ``radius`` within ``time_allowance``."""

    def __init__(self, radius: float = 0.5, time_allowance: float = 10.0):
        self.radius = radius
        self.time_allowance = time_allowance
        self._baseline: Pose2D | None = None
        self._baseline_time = 0.0

    def reset(self) -> None:
        self._baseline = None

    def check(self, pose: Pose2D, now: float) -> bool:
        b = self._baseline
        if b is None or math.hypot(pose.x - b.x, pose.y - b.y) > self.radius:
            self._baseline = pose
            self._baseline_time = now
            return True
        return not (now - self._baseline_time > self.time_allowance)


class RegulatedPurePursuit:
    def __init__(self, params: ControllerParams, robot: RobotParams, costmap: LocalCostmap):
        self.params = params
        self.robot = robot
        self.costmap = costmap
        self.base_max_linear_vel = min(params.desired_linear_vel, robot.max_linear_vel)
        self.max_linear_vel = self.base_max_linear_vel
        self.control_duration = 1.0 / params.controller_frequency
        self.xs: list[float] = []
        self.ys: list[float] = []
        self.yaws: list[float] = []
        self._xs = np.empty(0)
        self._ys = np.empty(0)
        self._cum = np.empty(0)
        self.closest = 0
        self.carrot: tuple[float, float] = (0.0, 0.0)  # robot frame, for inspection
        self.is_rotating_to_heading = False

    # -- configuration -------------------------------------------------------------------
    def set_desired_speed(self, speed: float) -> None:
        self.base_max_linear_vel = min(max(speed, 0.0), self.robot.max_linear_vel)
        self.max_linear_vel = self.base_max_linear_vel

    def set_speed_limit(self, limit: float | None, percentage: bool = False) -> None:
        """Nav2 SpeedLimit: None (or 0) restores the base speed; else a % or an absolute m/s."""
        if limit is None or limit <= 0.0:
            self.max_linear_vel = self.base_max_linear_vel
        elif percentage:
            self.max_linear_vel = self.base_max_linear_vel * min(limit, 100.0) / 100.0
        else:
            self.max_linear_vel = min(limit, self.base_max_linear_vel)

    def set_plan(self, points: np.ndarray, keep_progress: bool = False) -> None:
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or len(pts) < 1:
            raise ValueError("a plan needs at least one pose")
        self._xs = np.ascontiguousarray(pts[:, 0])
        self._ys = np.ascontiguousarray(pts[:, 1])
        self.xs = self._xs.tolist()
        self.ys = self._ys.tolist()
        if pts.shape[1] >= 3:
            self.yaws = pts[:, 2].tolist()
        else:  # headings along the path, the last one copied
            d = np.diff(pts[:, :2], axis=0)
            yaw = np.arctan2(d[:, 1], d[:, 0]).tolist() if len(d) else [0.0]
            self.yaws = yaw + [yaw[-1]]
        seg = np.hypot(np.diff(self._xs), np.diff(self._ys))
        self._cum = np.concatenate([[0.0], np.cumsum(seg)])
        if not keep_progress:
            self.closest = 0

    @property
    def goal(self) -> Pose2D:
        return Pose2D(self.xs[-1], self.ys[-1], self.yaws[-1])

    # -- path handling -------------------------------------------------------------------
    def update_closest(self, x: float, y: float) -> int:
        """Advance ``closest`` to the path pose nearest the robot within the search distance."""
        i0 = self.closest
        cum = self._cum
        j = int(np.searchsorted(cum, cum[i0] + self.params.max_robot_pose_search_dist, side="right"))
        j = max(j, i0 + 1)
        dx = self._xs[i0:j] - x
        dy = self._ys[i0:j] - y
        k = int(np.argmin(dx * dx + dy * dy))
        self.closest = i0 + k
        return self.closest

    def remaining_length(self, x: float, y: float) -> float:
        i = self.closest
        return math.hypot(self.xs[i] - x, self.ys[i] - y) + float(self._cum[-1] - self._cum[i])

    # -- the control law -----------------------------------------------------------------
    def compute(self, pose: Pose2D, speed: Twist, goal_checker: GoalChecker) -> Twist:
        p = self.params
        x, y, yaw = pose.x, pose.y, pose.yaw
        c, s = math.cos(yaw), math.sin(yaw)
        i0 = self.update_closest(x, y)
        xs, ys, n = self.xs, self.ys, len(self.xs)
        extent = max(self.costmap.width, self.costmap.height) * self.costmap.resolution / 2.0
        extent2 = extent * extent
        # transformed (robot-frame) plan from the closest pose to where it leaves the costmap
        tx: list[float] = []
        ty: list[float] = []
        for i in range(i0, n):
            dx, dy = xs[i] - x, ys[i] - y
            if dx * dx + dy * dy > extent2 and tx:
                break
            tx.append(c * dx + s * dy)
            ty.append(-s * dx + c * dy)
        # lookahead
        if p.use_velocity_scaled_lookahead_dist:
            ld = min(max(abs(speed.linear) * p.lookahead_time, p.min_lookahead_dist), p.max_lookahead_dist)
        else:
            ld = p.lookahead_dist
        cx, cy = self._lookahead_point(tx, ty, ld)
        self.carrot = (cx, cy)
        d2 = cx * cx + cy * cy
        curvature = 2.0 * cy / d2 if d2 > 0.001 else 0.0

        transformed_len = 0.0
        for i in range(1, len(tx)):
            transformed_len += math.hypot(tx[i] - tx[i - 1], ty[i] - ty[i - 1])
        remaining = self.remaining_length(x, y)
        goal = self.goal

        linear = self.max_linear_vel
        if p.use_rotate_to_heading and goal_checker.is_xy_reached(pose, goal, remaining):
            self.is_rotating_to_heading = True
            linear, angular = self._rotate(wrap_angle(goal.yaw - yaw), speed)
        elif p.use_rotate_to_heading and abs(math.atan2(cy, cx)) > p.rotate_to_heading_min_angle:
            self.is_rotating_to_heading = True
            linear, angular = self._rotate(math.atan2(cy, cx), speed)
        else:
            self.is_rotating_to_heading = False
            linear = self._constrain(linear, curvature, self.costmap.cost_at(x, y), tx, ty,
                                     transformed_len)
            angular = linear * curvature
            wmax = self.robot.max_angular_vel
            if abs(angular) > wmax:  # keep the curvature, slow both down
                scale = wmax / abs(angular)
                linear *= scale
                angular *= scale

        if p.use_collision_detection and self._collision_imminent(
                x, y, yaw, linear, angular, math.sqrt(d2)):
            return self._closer_carrot(x, y, yaw, tx, ty, ld, speed)
        return Twist(linear, angular)

    def _closer_carrot(self, x: float, y: float, yaw: float, tx: list[float], ty: list[float],
                       ld: float, speed: Twist) -> Twist:
        """Deviation from Nav2 (docs/nav.md): the arc to the carrot cuts through an inflated
        obstacle (the path squeezes past an obstacle, or the robot stands next to its own
        collision mark). If the path itself is free up to the lookahead, follow it more tightly
        instead of giving up: a carrot at half, then a quarter of the lookahead; turn on the spot
        towards it when it is off to the side (a circular robot turning in place sweeps nothing),
        else drive slowly through it if the way there is free. Raises NoValidControl otherwise
        (an obstacle on the path itself, or nothing free)."""
        cm = self.costmap
        c, s = math.cos(yaw), math.sin(yaw)
        ld2 = ld * ld
        for px, py in zip(tx, ty):
            if px * px + py * py > ld2:
                break
            if cm.in_collision(x + c * px - s * py, y + s * px + c * py):
                raise NoValidControl("RegulatedPurePursuitController detected collision ahead!")
        for scale in (0.5, 0.25):
            cx, cy = self._lookahead_point(tx, ty, max(ld * scale, 0.1))
            angle = math.atan2(cy, cx)
            if abs(angle) > 0.3:
                self.is_rotating_to_heading = True
                return Twist(*self._rotate(angle, speed))
            d2 = cx * cx + cy * cy
            if d2 < 1e-6:
                continue
            linear = min(0.1, self.max_linear_vel)
            angular = linear * 2.0 * cy / d2
            if not self._collision_imminent(x, y, yaw, linear, angular, math.sqrt(d2), whole=True):
                return Twist(linear, angular)
        raise NoValidControl("RegulatedPurePursuitController detected collision ahead!")

    def _lookahead_point(self, tx: list[float], ty: list[float], ld: float) -> tuple[float, float]:
        ld2 = ld * ld
        for i in range(len(tx)):
            if tx[i] * tx[i] + ty[i] * ty[i] >= ld2:
                if i == 0:
                    return tx[0], ty[0]
                return _circle_segment_intersection(tx[i - 1], ty[i - 1], tx[i], ty[i], ld)
        return tx[-1], ty[-1]

    def _rotate(self, angle: float, speed: Twist) -> tuple[float, float]:
        p = self.params
        sign = 1.0 if angle > 0.0 else -1.0
        w = sign * min(p.rotate_to_heading_angular_vel, self.robot.max_angular_vel)
        dt = self.control_duration
        w = min(max(w, speed.angular - p.max_angular_accel * dt), speed.angular + p.max_angular_accel * dt)
        max_to_stop = math.sqrt(2.0 * p.max_angular_accel * abs(angle))
        if abs(w) > max_to_stop:
            w = sign * max_to_stop
        return 0.0, w

    def _constrain(self, linear: float, curvature: float, pose_cost: int, tx, ty,
                   transformed_len: float) -> float:
        p = self.params
        curvature_vel = cost_vel = linear
        if p.use_regulated_linear_velocity_scaling and curvature != 0.0:
            radius = abs(1.0 / curvature)
            if radius < p.regulated_linear_scaling_min_radius:
                curvature_vel = linear * (1.0 - abs(radius - p.regulated_linear_scaling_min_radius)
                                          / p.regulated_linear_scaling_min_radius)
        if (p.use_cost_regulated_linear_velocity_scaling and pose_cost != NO_INFORMATION
                and pose_cost != FREE_SPACE):
            k = self.costmap.params.cost_scaling_factor  # RPP's inflation_cost_scaling_factor
            r_ins = self.costmap.inscribed_radius
            d = (k * r_ins - math.log(pose_cost) + math.log(253.0)) / k
            if d < p.cost_scaling_dist:
                cost_vel = linear * (p.cost_scaling_gain * d / p.cost_scaling_dist)
        linear = min(curvature_vel, cost_vel)
        linear = max(linear, p.regulated_linear_scaling_min_speed)
        # approach to the goal
        if transformed_len < p.approach_velocity_scaling_dist:
            scale = math.hypot(tx[-1], ty[-1]) / p.approach_velocity_scaling_dist
            approach = max(linear * scale, p.min_approach_linear_velocity)
            linear = min(linear, approach)
        return min(max(abs(linear), 0.0), self.max_linear_vel)

    def _collision_imminent(self, x: float, y: float, yaw: float, v: float, w: float,
                            carrot_dist: float, whole: bool = False) -> bool:
        """Nav2's forward simulation (``max_allowed_time_to_collision_up_to_carrot`` of travel,
        at most up to the carrot); ``whole``: all the way to ``carrot_dist`` however slow."""
        cm = self.costmap
        # Deviation from Nav2 (docs/nav.md): a robot whose own cell is already inscribed (e.g.
        # beside its collision mark) may make any motion that does not take it deeper, as the
        # behaviours may; Nav2's RPP refuses every command there.
        # (Distances are between cell centres: half a cell of slack, so a step past a lethal cell
        # on the way out is not read as "deeper".)
        d_now = cm.distance_at(x, y) - cm.resolution / 2 if cm.in_collision(x, y) else math.inf
        if abs(v) < 0.01 and abs(w) > 0.01:
            # rotating in place: a circular footprint sweeps nothing new
            return False
        if abs(v) < 1e-9:
            return False
        dt = cm.resolution / abs(v)
        t_max = self.params.max_allowed_time_to_collision_up_to_carrot
        if whole:
            t_max = max(t_max, 2.0 * carrot_dist / abs(v))
        px, py, th = x, y, yaw
        i = 1
        while i * dt < t_max:
            i += 1
            px += dt * v * math.cos(th)
            py += dt * v * math.sin(th)
            th += dt * w
            if math.hypot(px - x, py - y) > carrot_dist:
                break
            if cm.in_collision(px, py) and cm.distance_at(px, py) < d_now - 1e-9:
                return True
        return False


def _circle_segment_intersection(x1: float, y1: float, x2: float, y2: float, r: float):
    """Where the segment p1->p2 (p1 inside, p2 outside the circle of radius r at the origin)
    crosses the circle (Nav2 circleSegmentIntersection)."""
    dx, dy = x2 - x1, y2 - y1
    dr2 = dx * dx + dy * dy
    if dr2 <= 0.0:
        return x2, y2
    D = x1 * y2 - x2 * y1
    disc = max(r * r * dr2 - D * D, 0.0)
    sd = math.sqrt(disc)
    sgn = 1.0 if dy >= 0 else -1.0
    ax = (D * dy + sgn * dx * sd) / dr2
    ay = (-D * dx + abs(dy) * sd) / dr2
    bx = (D * dy - sgn * dx * sd) / dr2
    by = (-D * dx - abs(dy) * sd) / dr2
    # the intersection closer to p2
    if (ax - x2) ** 2 + (ay - y2) ** 2 <= (bx - x2) ** 2 + (by - y2) ** 2:
        return ax, ay
    return bx, by
