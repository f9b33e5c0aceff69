"""Emergency detection in motion (fn_req2): slow down or stop *before* a collision.

``StopBeforeObstacle`` watches the lidar for obstacles in the robot's swept corridor (its
width plus a margin) in the direction it is commanded to move. When the free distance ahead
gets shorter than the stopping distance (v^2 / 2a + v * reaction time + margin) it caps the
forward speed at what still stops in time, down to zero, by overriding the navigation command
in the decision gate (turning stays allowed, so the controller can steer away; moving away from
the obstacle is never limited). It only acts on fresh scans, and lets go of the gate as soon
as the corridor is clear. Free distances are computed once per scan, so a tick costs a few
comparisons.
"""

from __future__ import annotations

import math

import numpy as np

from bt_runtime import NodeStatus, SyncActionNode
from bt_runtime.node import NodeConfig
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.messages import LaserScan

SUCCESS = NodeStatus.SUCCESS


def free_distances(scan: LaserScan, half_width: float, radius: float) -> tuple[float, float]:
    """(ahead, behind): how far the circular body (``radius``) can move forward/back before it
    touches a scan point (inf if none). Points in the side margin (up to ``half_width`` from
    the axis) count once they lie beyond the body's front/back; one already beside the body
    does not (the body passes it without touching), so a robot pushed against a wall can still
    drive along it or away from it.

    Only the few beams whose point lies within the corridor (finite, ``|r sin| <=`` the wider
    of the two widths) are looked at one by one; numpy would spend more in a dozen calls on so
    few values than the arithmetic costs."""
    r = np.asarray(scan.ranges, dtype=float)
    cos_sin, side, axial = _beam_directions(scan.angle_min, scan.angle_increment, len(r))
    widest = max(half_width, radius)
    near = np.flatnonzero(np.abs(r) * side <= widest)  # |r sin| <= widest; never a NaN or inf range
    if widest < _AXIAL_REACH and len(axial):  # (a body narrower than 1e-15 m: axial beams explicitly)
        near = np.union1d(near, axial[np.isfinite(r[axial])])
    ahead = behind = math.inf
    rr = radius * radius
    for x, y in (r[near, None] * cos_sin[near]).tolist():  # (r cos, r sin) of each
        y = abs(y)
        if y <= radius:  # in the body's path: travel until the circle reaches it
            room = rr - y * y
            reach = math.sqrt(room) if room > 0.0 else 0.0
        elif y <= half_width and abs(x) >= radius:  # in the margin band, beyond the front/back
            reach = radius
        else:
            continue
        if x > 0.0:
            ahead = min(ahead, x - reach)
        elif x < 0.0:
            behind = min(behind, -x - reach)
    return max(ahead, 0.0), max(behind, 0.0)


_DIRECTIONS: dict[tuple[float, float, int], tuple[np.ndarray, ...]] = {}
# |sin| of an axial beam (sin 0) is taken as the smallest double, so an inf range stays inf
# (inf * 0 would be NaN, with numpy's warning); a finite range times it is at most:
_TINY = float(np.nextafter(0.0, 1.0))
_AXIAL_REACH = np.finfo(float).max * _TINY


def _beam_directions(angle_min: float, increment: float, n: int) -> tuple[np.ndarray, ...]:
    """(cos, sin) pairs, |sin| (never 0) of every beam's angle and the indices of the axial
    beams, computed once per scan geometry (a lidar keeps one)."""
    key = (angle_min, increment, n)
    found = _DIRECTIONS.get(key)
    if found is None:
        if len(_DIRECTIONS) > 8:
            _DIRECTIONS.clear()
        angles = angle_min + increment * np.arange(n)
        sin = np.sin(angles)
        found = _DIRECTIONS[key] = (np.column_stack((np.cos(angles), sin)), np.maximum(np.abs(sin), _TINY),
                                    np.flatnonzero(sin == 0.0))
    return found


def allowed_speed(free: float, deceleration: float, reaction: float, margin: float) -> float:
    """The fastest speed that still stops ``margin`` short of an obstacle ``free`` m away:
    v * reaction + v^2 / (2 * deceleration) = free - margin."""
    room = free - margin
    if room <= 0.0:
        return 0.0
    a, t = deceleration, reaction
    return a * (-t + math.sqrt(t * t + 2.0 * room / a))


class StopBeforeObstacle(SyncActionNode):
    """Cap the speed towards an obstacle on the scan so the robot stops before it (always
    SUCCESS; ``free_ahead`` reports the free distance in the direction of motion)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("deceleration", float, 0.5, "m/s^2 the base can brake with, conservatively"),
                input_port("reaction", float, 0.2, "s from scan to braking (scan age, tick, gate)"),
                input_port("margin", float, 0.05, "m kept between the footprint and the obstacle"),
                input_port("side_margin", float, 0.03, "m added to the robot's half width"),
                input_port("max_scan_age", float, 0.5, "s; older scans are not trusted"),
                output_port("free_ahead", float, "{free_ahead}")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._scan_id = 0
        self._free = (math.inf, math.inf)
        self._overriding = False
        self._params: tuple[float, ...] | None = None
        self._reported = math.nan
        super().__init__(name, config)

    def _settings(self) -> tuple[float, ...]:
        """The ports, read once (literal settings; a tick must stay cheap)."""
        if self._params is None:
            self._params = tuple(float(self.get_input(n)) for n in
                                 ("deceleration", "reaction", "margin", "side_margin", "max_scan_age"))
        return self._params

    def tick(self):
        ctx = self.context
        backup = ctx.backup
        decel, reaction, margin, side_margin, max_age = self._settings()
        scan = backup.latest("scan")
        age = backup.age("scan")
        if scan is None or age is None or age > max_age:
            return self._let_go()
        if id(scan) != self._scan_id:
            self._scan_id = id(scan)
            radius = ctx.robot.radius
            self._free = free_distances(scan, radius + side_margin, radius)
        nav = backup.latest("nav_cmd_vel")
        if nav is None or ctx.gate.tree_command_active and not self._overriding:
            return self._let_go()  # someone else in the tree is driving
        v = nav.linear
        free = self._free[0] if v >= 0 else self._free[1]
        if not abs(free - self._reported) < 0.01:
            self._reported = free
            self.set_output("free_ahead", float(free))
        allowed = allowed_speed(free, decel, reaction, margin)
        if abs(v) <= allowed:
            return self._let_go()
        ctx.gate.set_tree_command(math.copysign(allowed, v), nav.angular)
        self._overriding = True
        return SUCCESS

    def _let_go(self):
        if self._overriding:
            self._overriding = False
            self.context.gate.clear_tree_command()
        return SUCCESS

    def halt(self) -> None:
        if self._overriding:
            self._overriding = False
            self.context.gate.clear_tree_command()
        super().halt()
