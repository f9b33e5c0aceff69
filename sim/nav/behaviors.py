"""Behaviour-server actions (nav2_behaviors): Spin, BackUp, DriveOnHeading, Wait.

Each behaviour is a small synchronous state machine; ``stack.py`` runs it at
``cycle_frequency`` (10 Hz, as Nav2) and publishes its commands. The velocity profiles and the
simulate-ahead collision check follow Nav2's plugins:
  * Spin: w = clamp(sqrt(2 a remaining), min_rotational_vel, max_rotational_vel), relative yaw
    integrated from successive headings.
  * DriveOnHeading / BackUp: accelerate within the accel/decel limits, slow down to stop on the
    distance, never below ``minimum_speed``; distance measured from the start pose.
  * Collision check: the command is simulated ``simulate_ahead_time`` ahead in cycle steps on
    the local costmap; a pose "collides" when the robot's circle there overlaps a lethal cell.
    Deviation: a simulated pose that is not *deeper* into an obstacle than the current one
    (distance to the nearest lethal cell not smaller) is accepted, so a robot that is already
    touching something (e.g. right after the autonomy layer marked a collision point) can
    still back away or turn on the spot. Nav2 refuses every motion in that situation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_runtime.runtime.messages import NavErrorCode, Pose2D, Twist, wrap_angle

from .costmap import LocalCostmap
from .params import BehaviorParams


@dataclass(slots=True)
class BehaviorStatus:
    done: bool
    error_code: NavErrorCode = NavErrorCode.NONE
    message: str = ""
    cmd: Twist | None = None  # the command to publish this cycle (None when done)

    @property
    def ok(self) -> bool:
        return self.error_code is NavErrorCode.NONE


def _in_collision_deeper(cm: LocalCostmap, x: float, y: float, d_now: float) -> bool:
    d = cm.distance_at(x, y)
    return d < cm.inscribed_radius and d < d_now - 1e-9


class Behavior:
    name = "behavior"

    def __init__(self, params: BehaviorParams, costmap: LocalCostmap,
                 time_allowance: float = 10.0, disable_collision_checks: bool = False):
        self.params = params
        self.costmap = costmap
        self.time_allowance = time_allowance
        self.disable_collision_checks = disable_collision_checks
        self.end_time = math.inf

    def start(self, now: float, pose: Pose2D) -> BehaviorStatus | None:
        """Validate the goal; returns a final status on failure, None to run."""
        self.end_time = now + self.time_allowance if self.time_allowance > 0 else math.inf
        return None

    def timed_out(self, now: float) -> bool:
        return now > self.end_time

    def cycle(self, now: float, pose: Pose2D, map_pose: Pose2D) -> BehaviorStatus:
        raise NotImplementedError


class Spin(Behavior):
    name = "spin"

    def __init__(self, target_yaw: float, params: BehaviorParams, costmap: LocalCostmap,
                 time_allowance: float = 10.0, disable_collision_checks: bool = False):
        super().__init__(params, costmap, time_allowance, disable_collision_checks)
        self.cmd_yaw = float(target_yaw)
        self.relative_yaw = 0.0
        self.prev_yaw = 0.0

    def start(self, now: float, pose: Pose2D) -> BehaviorStatus | None:
        super().start(now, pose)
        self.prev_yaw = pose.yaw
        self.relative_yaw = 0.0
        return None

    def cycle(self, now: float, pose: Pose2D, map_pose: Pose2D) -> BehaviorStatus:
        E = NavErrorCode
        if self.timed_out(now):
            return BehaviorStatus(True, E.BEHAVIOR_TIMEOUT,
                                  "Exceeded time allowance before reaching the Spin goal")
        delta = wrap_angle(pose.yaw - self.prev_yaw)
        self.relative_yaw += delta
        self.prev_yaw = pose.yaw
        remaining = abs(self.cmd_yaw) - abs(self.relative_yaw)
        if remaining < 1e-6:
            return BehaviorStatus(True)
        p = self.params
        vel = math.sqrt(2.0 * p.rotational_acc_lim * remaining)
        vel = min(max(vel, p.min_rotational_vel), p.max_rotational_vel)
        # a circular footprint turning on the spot sweeps no new cells: only an already
        # colliding pose could fail, and it is not getting deeper (see module docstring)
        return BehaviorStatus(False, cmd=Twist(0.0, math.copysign(vel, self.cmd_yaw)))


class DriveOnHeading(Behavior):
    name = "drive_on_heading"

    def __init__(self, distance: float, speed: float, params: BehaviorParams,
                 costmap: LocalCostmap, time_allowance: float = 10.0,
                 disable_collision_checks: bool = False):
        super().__init__(params, costmap, time_allowance, disable_collision_checks)
        self.command_x = float(distance)
        self.command_speed = float(speed)
        self.initial: Pose2D | None = None
        self.last_vel: float | None = None

    def start(self, now: float, pose: Pose2D) -> BehaviorStatus | None:
        super().start(now, pose)
        if self.command_x == 0.0 or (self.command_x > 0.0) != (self.command_speed > 0.0):
            return BehaviorStatus(True, NavErrorCode.INVALID_INPUT,
                                  "Speed and command sign did not match")
        self.initial = pose
        self.last_vel = None
        return None

    def cycle(self, now: float, pose: Pose2D, map_pose: Pose2D) -> BehaviorStatus:
        E = NavErrorCode
        if self.timed_out(now):
            return BehaviorStatus(True, E.BEHAVIOR_TIMEOUT,
                                  f"Exceeded time allowance before reaching the {self.name} goal")
        init = self.initial
        distance = math.hypot(pose.x - init.x, pose.y - init.y)
        if distance >= abs(self.command_x):
            return BehaviorStatus(True)
        p = self.params
        f = p.cycle_frequency
        current = 0.0 if self.last_vel is None else self.last_vel
        forward = self.command_speed > 0.0
        if forward:
            lo, hi = current + p.deceleration_limit / f, current + p.acceleration_limit / f
        else:
            lo, hi = current - p.acceleration_limit / f, current - p.deceleration_limit / f
        v = min(max(self.command_speed, lo), hi)
        remaining = abs(self.command_x) - distance
        max_to_stop = math.sqrt(-2.0 * p.deceleration_limit * remaining)
        if max_to_stop < abs(v):
            v = max_to_stop if forward else -max_to_stop
        if abs(v) < p.minimum_speed:
            v = p.minimum_speed if forward else -p.minimum_speed
        if not self.disable_collision_checks and not self._collision_free(distance, v, map_pose):
            return BehaviorStatus(True, E.COLLISION_AHEAD, f"Collision Ahead - Exiting {self.name}")
        self.last_vel = v
        return BehaviorStatus(False, cmd=Twist(v, 0.0))

    def _collision_free(self, distance: float, v: float, pose: Pose2D) -> bool:
        p = self.params
        cm = self.costmap
        d_now = cm.distance_at(pose.x, pose.y)
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        diff = abs(self.command_x) - distance
        max_cycles = int(p.cycle_frequency * p.simulate_ahead_time)
        for k in range(max_cycles):
            change = v * (k / p.cycle_frequency)
            if diff - abs(change) <= 0.0:
                break
            if _in_collision_deeper(cm, pose.x + change * c, pose.y + change * s, d_now):
                return False
        return True


class BackUp(DriveOnHeading):
    name = "backup"

    def __init__(self, distance: float, speed: float, params: BehaviorParams,
                 costmap: LocalCostmap, time_allowance: float = 10.0,
                 disable_collision_checks: bool = False):
        # Nav2 BackUp takes magnitudes and drives backwards
        super().__init__(-abs(distance), -abs(speed), params, costmap, time_allowance,
                         disable_collision_checks)


class Wait(Behavior):
    name = "wait"

    def __init__(self, duration: float, params: BehaviorParams, costmap: LocalCostmap):
        super().__init__(params, costmap, time_allowance=0.0)
        self.duration = float(duration)
        self.until = 0.0

    def start(self, now: float, pose: Pose2D) -> BehaviorStatus | None:
        self.until = now + max(self.duration, 0.0)
        return None

    def cycle(self, now: float, pose: Pose2D, map_pose: Pose2D) -> BehaviorStatus:
        return BehaviorStatus(now >= self.until - 1e-9)
