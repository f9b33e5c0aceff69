"""Safety zones on the lidar scan, with the semantics of Nav2's collision_monitor.

Zones are polygons or circles in the robot's base frame, each with an action:

* ``stop``: at least ``min_points`` scan points inside: the command becomes zero;
* ``slowdown``: the command is scaled by ``slowdown_ratio``;
* ``limit``: the command is scaled (keeping its curvature) so that |v| <= ``linear_limit`` and
  |w| <= ``angular_limit``;
* ``approach``: the zone is the robot's footprint; the command is simulated forward in steps of
  ``simulation_time_step`` for up to ``time_before_collision`` seconds and, if the footprint
  would take in ``min_points`` points after t seconds, scaled by t / time_before_collision (so
  the robot keeps that many seconds away from a collision; points already inside: stop).
  Motion away from the obstacle simulates free and stays allowed;
* ``none``: drawn, never acts.

Zones are evaluated in the configured order; a stop ends the evaluation, and otherwise the most
restrictive result wins (smallest v^2 + w^2), as collision_monitor does. A scan source older
than its ``source_timeout`` (or none yet) stops the robot under the name "invalid source".

Scan points are turned into the base frame once per scan (with the lidar's mount from the
robot's profile) and the counts for the static zones are kept per scan, so a command costs a
dictionary lookup plus, for approach zones, one vectorised forward simulation of the points
that the robot can reach within ``time_before_collision``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import structlog

from .messages import ZERO_TWIST, LaserScan, RobotInfo, Twist
from .safety_zones_config import CollisionMonitorConfig, ZoneConfig, default_config, load_collision_monitor

if TYPE_CHECKING:
    from .backup import DataBackup
    from .config import SafetyZonesSettings
    from .driver import RobotDriver

log = structlog.get_logger("bt_runtime.gate")

INVALID_SOURCE = "invalid source"
STREAM = "safety_zone"  # the data backup's history of zone state changes


@dataclass(slots=True, frozen=True)
class ZoneState:
    """What the zones did to the last command: ``action`` is 'none' when nothing acted, and
    ``zone`` names the polygon (or "invalid source"), as collision_monitor's state topic."""

    stamp: float
    action: str = "none"
    zone: str = ""
    source: str = ""  # the gate's source whose command it was
    points: int = 0  # scan points that triggered it

    @property
    def triggered(self) -> bool:
        return self.action != "none"


NO_ACTION = ZoneState(-math.inf)


class Shape:
    """A polygon or circle in the base frame, tested against many points at once."""

    def __init__(self, *, radius: float | None = None, vertices=None):
        if vertices is None:
            if radius is None:
                raise ValueError("an approach polygon without points needs the robot's footprint radius")
            self.radius = float(radius)
            self.vertices = None
            self.reach = self.radius
        else:
            v = np.asarray(vertices, dtype=float)
            self.radius = math.nan
            self.vertices = v
            xi, yi = v[:, 0], v[:, 1]
            xj, yj = np.roll(xi, 1), np.roll(yi, 1)  # edge from the previous vertex, as the ray test goes
            dy = yj - yi
            flat = dy == 0.0
            self._edge = (xi, yi, yj, np.where(flat, 0.0, (xj - xi) / np.where(flat, 1.0, dy)))
            self.reach = float(np.hypot(xi, yi).max())
        # squared distance beyond which no point can be inside (the shape lies in the disk of
        # radius ``reach``; the margin keeps points near its rim, where rounding lives, tested)
        self._far = (self.reach * (1.0 + 1e-9) + 1e-12) ** 2

    def inside(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """A boolean mask over points (any shape): strictly inside the circle, or inside the
        polygon by ray crossing along +x (a point on an edge may count either way)."""
        if self.vertices is None:
            return x * x + y * y < self.radius * self.radius
        xi, yi, yj, slope = self._edge
        xs, ys = x[..., None], y[..., None]
        crosses = (ys <= yj) == (ys > yi)
        hits = crosses & (xi + (ys - yi) * slope > xs)
        return (np.count_nonzero(hits, axis=-1) & 1).astype(bool)

    def count(self, x: np.ndarray, y: np.ndarray, d2: np.ndarray | None = None) -> int:
        """Points inside (as ``inside``); ``d2``: the points' squared distances ``x*x + y*y``,
        computed once per scan, so a polygon tests only the few points within its reach."""
        if d2 is None:
            return int(np.count_nonzero(self.inside(x, y)))
        if self.vertices is None:
            return int(np.count_nonzero(d2 < self.radius * self.radius))
        near = d2 <= self._far
        if not near.any():
            return 0
        return int(np.count_nonzero(self.inside(x[near], y[near])))


def shape_of(zone: ZoneConfig) -> Shape | None:
    """The zone's fixed shape (None for a velocity polygon: its shape follows the command)."""
    kind = zone.shape_kind()
    if kind == "circle":
        return Shape(radius=zone.radius if zone.type == "circle" else zone.footprint_radius)
    if kind == "polygon":
        return Shape(vertices=zone.vertices)
    return None


class Zone:
    """One configured zone: its shape, action and parameters."""

    def __init__(self, name: str, cfg: ZoneConfig, sees_scan: bool = True):
        self.name = name
        self.cfg = cfg
        self.shape = shape_of(cfg)
        # velocity_polygon: (sub-polygon, its shape) in order, and the one the last command chose
        self.subs = [(cfg.sub_polygons[n], Shape(vertices=cfg.sub_polygons[n].points))
                     for n in cfg.velocity_polygons or ()]
        self.current: int | None = None
        self.action = cfg.action_type
        self.enabled = cfg.enabled and sees_scan  # a zone given no source never triggers
        self.min_points = cfg.effective_min_points
        steps = int(math.floor(cfg.time_before_collision / cfg.simulation_time_step + 1e-9)) + 1
        self.sim_times = np.arange(steps) * cfg.simulation_time_step  # the time each step reports

    def count(self, x: np.ndarray, y: np.ndarray) -> int:
        return int(np.count_nonzero(self.shape.inside(x, y)))

    def counts(self, x: np.ndarray, y: np.ndarray, d2: np.ndarray | None = None) -> list[int]:
        """Points inside the shape, or inside each sub-polygon of a velocity polygon (``d2``:
        see ``Shape.count``)."""
        if self.shape is not None:
            return [self.shape.count(x, y, d2)]
        return [shape.count(x, y, d2) for _, shape in self.subs]

    def select(self, twist: Twist) -> int | None:
        """The index into ``counts`` for this command: 0 for a fixed shape; for a velocity
        polygon the first sub-polygon covering the command, else the one chosen last (None
        before any was: the zone has no shape yet), as collision_monitor keeps it."""
        if self.shape is not None:
            return 0
        for k, (sub, _) in enumerate(self.subs):
            if sub.covers(twist.linear, twist.angular, self.cfg.holonomic):
                self.current = k
                break
        return self.current

    def collision_time(self, x: np.ndarray, y: np.ndarray, v: float, w: float) -> float:
        """Seconds before the footprint takes in ``min_points`` points when driving (v, w), or
        -1 if not within ``time_before_collision``; 0 if they are inside already. Each step
        moves the robot by the velocity, then turns it and its velocity by w * dt."""
        if self.count(x, y) >= self.min_points:
            return 0.0
        if v == 0.0 and w == 0.0:
            return -1.0
        dt = self.cfg.simulation_time_step
        times = self.sim_times
        n = len(times)
        # only points the footprint can reach within the horizon (the robot moves at most |v| * T)
        reach = abs(v) * dt * n + self.shape.reach
        near = x * x + y * y < reach * reach
        if np.count_nonzero(near) < self.min_points:
            return -1.0
        px, py = x[near], y[near]
        heading = w * dt * np.arange(n)  # the velocity's direction during step k
        ox = np.cumsum(v * dt * np.cos(heading))
        oy = np.cumsum(v * dt * np.sin(heading))
        theta = heading + w * dt  # the robot's yaw after step k
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        dx, dy = px[None, :] - ox[:, None], py[None, :] - oy[:, None]
        inside = self.shape.inside(dx * c + dy * s, -dx * s + dy * c)
        hit = np.flatnonzero(np.count_nonzero(inside, axis=1) >= self.min_points)
        return float(times[hit[0]]) if len(hit) else -1.0


def _smaller(a: Twist, b: Twist) -> bool:
    return a.linear * a.linear + a.angular * a.angular < b.linear * b.linear + b.angular * b.angular


class SafetyZones:
    """Filters every gate command through the zones, on the latest scan of the driver."""

    def __init__(self, config: CollisionMonitorConfig, *, clock: Callable[[], float],
                 lidar_mount: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 footprint_radius: float | None = None, backup: DataBackup | None = None,
                 origin: str = ""):
        if footprint_radius is not None:
            config = config.with_footprint(footprint_radius)
        self.config = config
        self.clock = clock
        self.backup = backup
        self.origin = origin  # the file (or "defaults for ROBOT") the zones came from, for logs
        self.enabled = config.enabled
        self.zones = [Zone(name, config.zones[name], config.zone_sees_scan(name)) for name in config.polygons]
        self.source_timeout = config.scan_timeout
        self.use_scan = config.scan_enabled
        self.mount = lidar_mount
        self._scan: LaserScan | None = None
        self._x = self._y = np.zeros(0)
        self._counts: dict[str, list[int]] = {}
        self._trig: dict[tuple[str, float, float], float] = {}
        self._trig_key: int = 0
        self._cos_sin: tuple[tuple[float, float, int], np.ndarray, np.ndarray] | None = None
        self.state: ZoneState = NO_ACTION
        self.scans = 0
        self.evaluations = 0
        self.generation = 0  # bumped before a scan changes anything (the gate reuses decisions within one)
        self.errors = 0  # filter() calls that failed (and stopped the robot)
        self._unsubscribe: Callable[[], None] | None = None
        self.on_change: Callable[[ZoneState], None] | None = None  # e.g. the ROS 2 driver's state topic

    @classmethod
    def for_robot(cls, robot: RobotInfo, config: CollisionMonitorConfig, **kw) -> SafetyZones:
        return cls(config, lidar_mount=(robot.lidar_x, robot.lidar_y, robot.lidar_yaw),
                   footprint_radius=robot.radius, **kw)

    # -- input -----------------------------------------------------------------------------------
    def attach(self, driver: RobotDriver) -> None:
        self._unsubscribe = driver.subscribe("scan", self.on_scan)

    def detach(self) -> None:
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None

    def on_scan(self, scan: LaserScan) -> None:
        """Turn the scan's valid readings (range_min <= r <= range_max; NaN and inf never are)
        into base-frame points, and count the points inside every static zone. A scan that
        cannot be read is logged and dropped (the last good one goes stale and stops the robot)."""
        try:
            self._take_scan(scan)
        except Exception as exc:
            log.error("safety_zones_scan_dropped", error=repr(exc))

    def _take_scan(self, scan: LaserScan) -> None:
        self.generation += 1
        r = np.asarray(scan.ranges, dtype=float)
        n = len(r)
        key = (scan.angle_min, scan.angle_increment, n)
        cached = self._cos_sin
        if cached is None or cached[0] != key:
            mx, my, myaw = self.mount
            angles = myaw + scan.angle_min + scan.angle_increment * np.arange(n)
            cached = self._cos_sin = (key, np.cos(angles), np.sin(angles))
        _, cos_a, sin_a = cached
        with np.errstate(invalid="ignore"):
            ok = (r >= scan.range_min) & (r <= scan.range_max)
        rv = r[ok]
        mx, my, _ = self.mount
        self._x = mx + rv * cos_a[ok]
        self._y = my + rv * sin_a[ok]
        self._scan = scan
        self._trig.clear()
        x, y = self._x, self._y
        d2 = x * x + y * y
        self._counts = {z.name: z.counts(x, y, d2) for z in self.zones if z.enabled and z.action != "approach"}
        self.scans += 1

    # -- the filter --------------------------------------------------------------------------------
    def scan_valid(self, now: float) -> bool:
        """A scan has arrived and is at most ``source_timeout`` old; with a timeout of 0 the
        source is never invalid, not even before its first scan (as collision_monitor)."""
        if self.source_timeout == 0.0:
            return True
        scan = self._scan
        return scan is not None and now - scan.stamp <= self.source_timeout

    def valid_until(self) -> float:
        """When the current scan gets too old (inf: it never does, or there is none: the next
        one comes with a new ``generation``)."""
        scan = self._scan
        if not self.use_scan or self.source_timeout == 0.0 or scan is None:
            return math.inf
        return scan.stamp + self.source_timeout

    def filter(self, twist: Twist, now: float, source: str = "") -> Twist:
        """The command the zones allow (``twist`` itself when none acts); records the state.
        An error inside stops the robot (logged) rather than the gate."""
        if not self.enabled:
            return twist
        try:
            return self._filter(twist, now, source)
        except Exception as exc:
            self.errors += 1
            log.error("safety_zones_failed", error=repr(exc), sim_time=round(now, 3))
            return ZERO_TWIST

    def _filter(self, twist: Twist, now: float, source: str) -> Twist:
        self.evaluations += 1
        action, zone, points, out = "none", "", 0, twist
        if self.use_scan and not self.scan_valid(now):
            action, zone, out = "stop", INVALID_SOURCE, ZERO_TWIST
        else:
            for z in self.zones:
                if not z.enabled:
                    continue
                if action == "stop":
                    break
                if z.action == "approach":
                    t, inside = self._approach_time(z, twist)
                    if t < 0.0:
                        continue
                    ratio = t / z.cfg.time_before_collision
                    safe = Twist(twist.linear * ratio, twist.angular * ratio)
                    if _smaller(safe, out):
                        action, zone, points, out = "approach", z.name, inside, safe
                    continue
                index = z.select(twist)
                counts = self._counts.get(z.name)
                count = counts[index] if counts and index is not None and self.use_scan else 0
                if count < z.min_points or z.action == "none":
                    continue
                if z.action == "stop":
                    action, zone, points, out = "stop", z.name, count, ZERO_TWIST
                    continue
                if z.action == "slowdown":
                    k = z.cfg.slowdown_ratio
                else:  # limit: one ratio for both, keeping the curvature
                    k = 1.0
                    if twist.linear != 0.0:
                        k = min(k, z.cfg.linear_limit / abs(twist.linear))
                    if twist.angular != 0.0:
                        k = min(k, z.cfg.angular_limit / abs(twist.angular))
                    k = min(max(k, 0.0), 1.0)
                safe = Twist(twist.linear * k, twist.angular * k)
                if _smaller(safe, out):
                    action, zone, points, out = z.action, z.name, count, safe
        if action != self.state.action or zone != self.state.zone:
            self._report(ZoneState(now, action, zone, source, points), twist, out)
        return out

    def _approach_time(self, z: Zone, twist: Twist) -> tuple[float, int]:
        """(collision time, points in the footprint then), cached per scan and command."""
        if not self.use_scan:
            return -1.0, 0
        key = (z.name, twist.linear, twist.angular)
        t = self._trig.get(key)
        if t is None:
            if len(self._trig) > 64:  # a ramping command: keep the cache small
                self._trig.clear()
            t = self._trig[key] = z.collision_time(self._x, self._y, twist.linear, twist.angular)
        return t, (z.min_points if t >= 0.0 else 0)

    def _report(self, state: ZoneState, before: Twist, after: Twist) -> None:
        previous = self.state
        self.state = state
        if state.triggered:
            log.info("safety_zone", action=state.action, zone=state.zone, source=state.source,
                     points=state.points, linear=round(before.linear, 3), angular=round(before.angular, 3),
                     allowed_linear=round(after.linear, 3), allowed_angular=round(after.angular, 3),
                     sim_time=round(state.stamp, 3))
        else:
            log.info("safety_zone_clear", previous=previous.zone, sim_time=round(state.stamp, 3))
        if self.backup is not None:
            self.backup.record(STREAM, state, state.stamp)
        if self.on_change is not None:
            try:
                self.on_change(state)
            except Exception as exc:  # publishing the state must never stop the gate
                log.error("safety_zone_publish_failed", error=repr(exc))


def build_safety_zones(settings: SafetyZonesSettings, robot: RobotInfo, driver: RobotDriver, *,
                       passthrough: bool, clock: Callable[[], float],
                       backup: DataBackup | None = None) -> SafetyZones | None:
    """The zones the runtime's settings ask for: the file's, or the defaults sized for ``robot``;
    None when off, in passthrough mode (the baseline has no layer), or when defaults are asked
    for a robot whose driver has no scan stream (a file is taken at its word)."""
    if not settings.enabled or passthrough:
        return None
    if settings.file is not None:
        config, origin = load_collision_monitor(settings.file), str(settings.file)
    else:
        if not _has_scan(driver):
            log.warning("safety_zones_off", reason="the driver has no component with a scan stream")
            return None
        config, origin = default_config(robot), "defaults"
    zones = SafetyZones.for_robot(robot, config, clock=clock, backup=backup, origin=origin)
    publish = getattr(driver, "publish_collision_monitor_state", None)
    if callable(publish):  # where the driver speaks ROS: collision_monitor_state on every change
        zones.on_change = lambda state: publish(state.action, state.zone)
    log.info("safety_zones", origin=origin, zones=[f"{z.name}:{z.action}" for z in zones.zones if z.enabled],
             source_timeout=zones.source_timeout, lidar_mount=list(zones.mount))
    return zones


def _has_scan(driver: RobotDriver) -> bool:
    try:
        return any("scan" in info.streams for info in driver.components())
    except Exception:  # a driver that cannot list its components yet: assume the usual lidar
        return True
