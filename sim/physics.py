"""Physics: the world's body-blocking shapes and the robot in a pymunk space, and the
differential-drive base that turns (v, w) commands into wheel speeds.

The robot is a dynamic circle. The drive is a kinematic *control body* whose velocity is set to
what the wheels do; a pivot joint and a gear joint (no position correction, bounded force and
torque = the wheels' traction) drag the robot along. pymunk resolves contacts, so a wall wins
over the wheels: pushing into an obstacle stalls the robot while the wheels keep turning (and
the wheel odometry keeps counting). External impulses move the robot against that traction.
The body speed is capped (3 m/s by default) and the space is stepped in substeps, so the robot
never tunnels through a wall whatever it is commanded or hit with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pymunk

from .robot import RobotProfile

ROBOT_CT = 1
OBSTACLE_CT = 2


@dataclass(slots=True)
class ContactPoint:
    point: tuple[float, float]  # on the obstacle, map frame
    impulse: float  # N*s in this substep
    obstacle: str


class DiffDriveBase:
    """Command handling of the base: clamping, command timeout, acceleration limits, wheels.

    ``v``/``w`` is what the wheels do now (after limits); the odometry integrates it.
    """

    def __init__(self, profile: RobotProfile) -> None:
        self.p = profile
        self.target_v = 0.0
        self.target_w = 0.0
        self.v = 0.0
        self.w = 0.0
        self.last_command = -math.inf
        self.timed_out = True
        self.enabled = True
        self._half_track = profile.wheel_separation / 2

    def clamp(self, v: float, w: float) -> tuple[float, float]:
        """Clamp a command to the base's limits (NaN -> 0, +-inf -> the limit); keeps the
        curvature when a wheel would exceed its max speed."""
        p = self.p
        v = 0.0 if v != v else min(max(v, -p.max_linear), p.max_linear)
        w = 0.0 if w != w else min(max(w, -p.max_angular), p.max_angular)
        vl, vr = v - w * self._half_track, v + w * self._half_track
        m = max(abs(vl), abs(vr))
        if m > p.max_wheel_speed:
            k = p.max_wheel_speed / m
            v, w = v * k, w * k
        return v, w

    def command(self, v: float, w: float, now: float) -> tuple[float, float]:
        v, w = self.clamp(float(v), float(w))
        self.target_v, self.target_w = v, w
        self.last_command = now
        self.timed_out = False
        return v, w

    def update(self, now: float, dt: float) -> bool:
        """Advance the wheel speeds by one step; True when the command just timed out."""
        timed_out_now = False
        if not self.timed_out and now - self.last_command > self.p.cmd_timeout:
            self.timed_out = True
            timed_out_now = True
        if self.timed_out or not self.enabled:
            tv = tw = 0.0
        else:
            tv, tw = self.target_v, self.target_w
        dv = self.p.max_linear_accel * dt
        dw = self.p.max_angular_accel * dt
        v, w = self.v, self.w
        self.v = tv if abs(tv - v) <= dv else v + (dv if tv > v else -dv)
        self.w = tw if abs(tw - w) <= dw else w + (dw if tw > w else -dw)
        return timed_out_now

    def wheel_speeds(self) -> tuple[float, float]:
        """(left, right) wheel angular speeds, rad/s."""
        r = self.p.wheel_radius
        return (self.v - self.w * self._half_track) / r, (self.v + self.w * self._half_track) / r


class PhysicsWorld:
    """The pymunk space: static obstacles (only body-blocking ones), the robot, the drive."""

    def __init__(self, profile: RobotProfile, x: float, y: float, yaw: float, *,
                 substeps: int = 1, max_body_speed: float = 3.0) -> None:
        self.profile = profile
        self.substeps = substeps
        self.max_body_speed = max_body_speed
        self.max_substep_travel = 0.004  # m
        space = pymunk.Space()
        space.iterations = 20
        space.collision_slop = 0.001  # pymunk's default (0.1) is 10 cm in our metres
        space.collision_bias = 1e-6  # overlap left after 1 s (default ~2e-3): resolve faster
        space.gravity = (0.0, 0.0)
        self.space = space

        body = pymunk.Body(profile.mass, pymunk.moment_for_circle(profile.mass, 0, profile.radius))
        body.position = (x, y)
        body.angle = yaw
        shape = pymunk.Circle(body, profile.radius)
        shape.friction = 0.3
        shape.elasticity = 0.0
        shape.collision_type = ROBOT_CT
        self.body = body
        self.shape = shape

        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position = (x, y)
        pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
        pivot.max_bias = 0.0
        pivot.max_force = profile.traction
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        gear.max_bias = 0.0
        gear.max_force = profile.traction * profile.wheel_separation / 2
        self.control = control
        space.add(body, shape, control, pivot, gear)

        self.x, self.y, self.angle = x, y, yaw  # cached body state, refreshed by step()
        self.vx = self.vy = self.wz = 0.0
        self._dirty = False
        self.forces: list[list[float]] = []  # [fx, fy, seconds left]: external forces (map frame)
        self._shapes: dict[str, list[pymunk.Shape]] = {}
        self._names: dict[pymunk.Shape, str] = {}
        self.contacts: list[ContactPoint] = []
        space.on_collision(ROBOT_CT, OBSTACLE_CT, post_solve=self._post_solve)

    # --- obstacles -----------------------------------------------------------------------------
    def add_obstacle(self, key: str, obstacle) -> None:
        """Add a world obstacle (pydantic model) as static shapes, if it blocks the body."""
        if not obstacle.blocks_body:
            return
        sb = self.space.static_body
        shapes: list[pymunk.Shape] = []
        poly = obstacle.polygon()
        circle = obstacle.circle()
        if poly is not None:
            shapes.append(pymunk.Poly(sb, [tuple(p) for p in poly]))
        elif circle is not None:
            shapes.append(pymunk.Circle(sb, circle[2], (circle[0], circle[1])))
        else:  # a zero-thickness segment: give it 1 cm so contacts are robust
            shapes.append(pymunk.Segment(sb, obstacle.a, obstacle.b, 0.005))
        for s in shapes:
            s.friction = 0.5
            s.elasticity = 0.0
            s.collision_type = OBSTACLE_CT
            self._names[s] = key
        self.space.add(*shapes)
        self._shapes[key] = shapes

    def remove_obstacle(self, key: str) -> None:
        shapes = self._shapes.pop(key, [])
        if shapes:
            self.space.remove(*shapes)
            for s in shapes:
                self._names.pop(s, None)

    def _post_solve(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data) -> None:
        other = arbiter.shapes[1]
        impulse = arbiter.total_impulse.length
        name = self._names.get(other, "?")
        for cp in arbiter.contact_point_set.points:
            self.contacts.append(ContactPoint((cp.point_b.x, cp.point_b.y), impulse, name))

    # --- stepping ------------------------------------------------------------------------------
    def step(self, v: float, w: float, dt: float) -> None:
        """Drive with wheel-level (v, w) for dt seconds; contacts are collected.

        The step is split into ``substeps`` (more when the body is fast, so it never moves more
        than ``max_substep_travel`` per substep: pymunk finds contacts after moving). After the
        step the body's state is cached in ``x, y, angle, vx, vy, wz`` (pymunk's property
        accessors are slow enough to matter at 100 Hz)."""
        body = self.body
        control = self.control
        self.contacts.clear()
        cap = self.max_body_speed
        if self._dirty:  # an impulse or a teleport since the last step
            self.vx, self.vy = body.velocity
            self._dirty = False
        vx, vy = self.vx, self.vy
        sp = math.hypot(vx, vy)
        if sp > cap:
            body.velocity = (vx * cap / sp, vy * cap / sp)
            sp = cap
        n = self.substeps
        fast = max(sp, abs(v)) * dt / self.max_substep_travel
        if fast > n:
            n = int(math.ceil(fast))
        h = dt / n
        control.angular_velocity = w
        a = self.angle
        for i in range(n):
            if i:
                vx, vy = body.velocity
                sp = math.hypot(vx, vy)
                if sp > cap:
                    body.velocity = (vx * cap / sp, vy * cap / sp)
                a = body.angle
            control.velocity = (v * math.cos(a), v * math.sin(a))
            if self.forces:
                self._apply_forces(h)
            self.space.step(h)
        self.x, self.y = body.position
        self.vx, self.vy = body.velocity
        self.angle = body.angle
        self.wz = body.angular_velocity

    def _apply_forces(self, h: float) -> None:
        fx = fy = 0.0
        for f in self.forces:
            fx += f[0]
            fy += f[1]
            f[2] -= h
        self.forces = [f for f in self.forces if f[2] > 1e-12]
        self.body.apply_force_at_world_point((fx, fy), self.body.position)

    def apply_impulse(self, ix: float, iy: float, point: tuple[float, float] | None = None) -> None:
        """An external impulse (N*s, map frame) at a world point (default: the centre)."""
        p = self.body.position if point is None else point
        self.body.apply_impulse_at_world_point((ix, iy), p)
        self._dirty = True

    def teleport(self, x: float, y: float, yaw: float) -> None:
        self.body.position = (x, y)
        self.body.angle = yaw
        self.body.velocity = (0, 0)
        self.body.angular_velocity = 0
        self.control.position = (x, y)
        self.control.velocity = (0, 0)
        self.control.angular_velocity = 0
        self.space.reindex_shapes_for_body(self.body)
        self.x, self.y, self.angle = x, y, yaw
        self.vx = self.vy = self.wz = 0.0
        self._dirty = False
