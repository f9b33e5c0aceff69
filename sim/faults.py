"""Fault injection: crash/restart components, stall, corrupt, noise, wheel slip, pushes,
invisible obstacles, blocked corridors, goals inside obstacles, battery.

Faults are pydantic models (a discriminated union on ``kind``) so scenario files can list them::

    faults:
      - {at: 5.0, kind: crash, component: lidar}
      - {at: 6.0, kind: invisible_obstacle, ahead: 0.5}

Use them through the simulator's injector::

    sim.faults.apply(Crash(component="lidar"))          # now
    sim.faults.schedule(12.0, Push(impulse=0.8))         # at loop time 12.0
    sim.faults.crash("imu"); sim.faults.push(0.5, direction=math.pi / 2)   # shortcuts

Every action is recorded in ``sim.faults.log`` (FaultRecord: loop time, fault, details) and in
the simulator's events, and logged through structlog (``event='fault'``).
"""

from __future__ import annotations

import asyncio
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any, Literal

import structlog
from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, model_validator

from .world import CircleObstacle, PolygonObstacle, SegmentObstacle

if TYPE_CHECKING:  # pragma: no cover
    from .simulator import Simulator

log = structlog.get_logger("sim.faults")

Point = tuple[float, float]


class _Fault(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Crash(_Fault):
    """The component's process dies: it stops publishing and is INACTIVE."""

    kind: Literal["crash"] = "crash"
    component: str


class Restart(_Fault):
    """Restart a component (as the supervisor would)."""

    kind: Literal["restart"] = "restart"
    component: str


class RestartPolicy(_Fault):
    """How the next restarts of a component behave: delay until it runs again, and how many
    of the next restarts fail."""

    kind: Literal["restart_policy"] = "restart_policy"
    component: str
    delay: float | None = Field(None, ge=0)
    fail_next: int | None = Field(None, ge=0)


class Stall(_Fault):
    """Without crashing: 'silent' stops publishing, 'stale' republishes the last message
    (duplicate, old timestamp), 'frozen' republishes the last message's data with fresh
    timestamps (a driver stuck on one reading), for ``duration`` seconds (a restart ends it)."""

    kind: Literal["stall"] = "stall"
    component: str
    duration: float = Field(gt=0)
    mode: Literal["silent", "stale", "frozen"] = "silent"


class Corrupt(_Fault):
    """'nan' or 'garbage' data for ``duration`` seconds (a restart ends it)."""

    kind: Literal["corrupt"] = "corrupt"
    component: str
    duration: float = Field(gt=0)
    mode: Literal["nan", "garbage"] = "nan"


class NoiseBurst(_Fault):
    """The sensor's noise sigma times ``factor`` for ``duration`` seconds."""

    kind: Literal["noise_burst"] = "noise_burst"
    component: str
    duration: float = Field(gt=0)
    factor: float = Field(10.0, gt=0)


class WheelSlip(_Fault):
    """Wheel odometry over-reads (>1) or under-reads (<1) each wheel's travel; unequal
    factors make the odometry's heading drift too. ``duration`` None = until changed."""

    kind: Literal["wheel_slip"] = "wheel_slip"
    left: float = Field(1.0, ge=0)
    right: float = Field(1.0, ge=0)
    factor: float | None = Field(None, ge=0)  # both wheels
    duration: float | None = Field(None, gt=0)


class Push(_Fault):
    """Something hits the robot: an impulse (N*s) moving it towards ``direction`` (robot frame,
    0 = pushed forward, i.e. hit from behind) and a bumper contact on the side it came from."""

    kind: Literal["push"] = "push"
    impulse: float = Field(0.5, gt=0)
    direction: float = 0.0
    contact_duration: float = Field(0.15, ge=0)


class InvisibleObstacle(_Fault):
    """An obstacle that blocks the body but not the lidar, at (x, y) or ``ahead`` metres in
    front of the robot's body (distance from the front of the body to the obstacle's near
    face). A box ``width`` x ``depth`` across the heading, or a circle of ``radius``."""

    kind: Literal["invisible_obstacle"] = "invisible_obstacle"
    x: float | None = None
    y: float | None = None
    yaw: float | None = None
    ahead: float | None = Field(None, ge=0)
    width: float = Field(0.5, gt=0)
    depth: float = Field(0.1, gt=0)
    radius: float | None = Field(None, gt=0)
    name: str = ""

    @model_validator(mode="after")
    def _where(self) -> InvisibleObstacle:
        if (self.ahead is None) == (self.x is None or self.y is None):
            raise ValueError("give either x and y, or ahead")
        return self


class BlockCorridor(_Fault):
    """A wall from a to b (blocks body and lidar by default); remove it by name."""

    kind: Literal["block_corridor"] = "block_corridor"
    a: Point
    b: Point
    thickness: float = Field(0.1, gt=0)
    name: str = ""
    blocks_lidar: bool = True
    blocks_body: bool = True


class ObstacleAt(_Fault):
    """A round obstacle covering a point (or a named goal): puts the goal inside an obstacle."""

    kind: Literal["obstacle_at"] = "obstacle_at"
    x: float | None = None
    y: float | None = None
    goal: str | None = None
    radius: float = Field(0.3, gt=0)
    name: str = ""
    blocks_lidar: bool = True
    blocks_body: bool = True

    @model_validator(mode="after")
    def _where(self) -> ObstacleAt:
        if (self.goal is None) == (self.x is None or self.y is None):
            raise ValueError("give either x and y, or goal")
        return self


class RemoveObstacle(_Fault):
    kind: Literal["remove_obstacle"] = "remove_obstacle"
    name: str


class SetBattery(_Fault):
    kind: Literal["set_battery"] = "set_battery"
    soc: float = Field(ge=0, le=100)


class DrainBattery(_Fault):
    """Drop the state of charge by ``percent`` at once, and/or draw ``power`` extra watts
    (for ``duration`` seconds, None = until changed)."""

    kind: Literal["drain_battery"] = "drain_battery"
    percent: float | None = Field(None, ge=0, le=100)
    power: float | None = Field(None, ge=0)
    duration: float | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _what(self) -> DrainBattery:
        if self.percent is None and self.power is None:
            raise ValueError("give percent and/or power")
        return self


Fault = Annotated[
    Crash | Restart | RestartPolicy | Stall | Corrupt | NoiseBurst | WheelSlip | Push | InvisibleObstacle
    | BlockCorridor | ObstacleAt | RemoveObstacle | SetBattery | DrainBattery,
    Field(discriminator="kind"),
]
_FAULT_ADAPTER: TypeAdapter = TypeAdapter(Fault)


def parse_fault(data: dict) -> Any:
    """A fault model from a mapping (``kind`` selects the type)."""
    return _FAULT_ADAPTER.validate_python(data)


@dataclass(slots=True)
class FaultRecord:
    t: float
    kind: str
    fault: Any
    details: dict = field(default_factory=dict)


class FaultInjector:
    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        self.log: list[FaultRecord] = []
        self._pending: list[tuple[float, Any]] = []
        self._handles: list[asyncio.TimerHandle] = []
        self._tasks: set[asyncio.Task] = set()

    # --- scheduling ---------------------------------------------------------------------------
    def schedule(self, t: float, fault: Any) -> None:
        """Apply ``fault`` (a model or a mapping) at loop time ``t`` (the clock of message
        stamps; a VirtualTimeLoop starts at 0)."""
        if isinstance(fault, dict):
            fault = parse_fault(fault)
        if self.sim.running:
            self._arm_one(t, fault)
        else:
            self._pending.append((t, fault))

    def _arm_one(self, t: float, fault: Any) -> None:
        loop = asyncio.get_running_loop()
        self._handles.append(loop.call_at(max(t, loop.time()), self._fire, fault))

    def _fire(self, fault: Any) -> None:
        try:
            self.apply(fault)
        except Exception:
            log.exception("fault_failed", fault=fault.kind)
            raise

    def arm(self) -> None:
        """Schedule the faults given before the simulator started (it calls this on start)."""
        pending, self._pending = self._pending, []
        for t, fault in pending:
            self._arm_one(t, fault)

    def disarm(self) -> None:
        """Cancel the faults still to come (the simulator calls this on stop)."""
        for h in self._handles:
            h.cancel()
        self._handles.clear()

    # --- applying -----------------------------------------------------------------------------
    def _record(self, fault: Any, **details: Any) -> FaultRecord:
        sim = self.sim
        rec = FaultRecord(sim.now, fault.kind, fault, details)
        self.log.append(rec)
        sim.record_event("fault", fault=fault.kind, **fault.model_dump(exclude={"kind"}), **details)
        if sim.options.log_faults:
            log.info("fault", sim_time=round(rec.t, 4), fault=fault.kind,
                     **fault.model_dump(exclude={"kind"}, exclude_none=True), **details)
        return rec

    def records(self, kind: str | None = None) -> list[FaultRecord]:
        return [r for r in self.log if kind is None or r.kind == kind]

    def apply(self, fault: Any) -> Any:
        """Apply a fault now. Returns: the restart task for ``restart``, the obstacle name for
        obstacle faults, None otherwise."""
        if isinstance(fault, dict):
            fault = parse_fault(fault)
        handler = getattr(self, f"_do_{fault.kind}")
        return handler(fault)

    def _comp(self, fault):
        return self.sim.component(fault.component)

    def _do_crash(self, f: Crash) -> None:
        self._record(f)
        self._comp(f).crash("fault")

    def _do_restart(self, f: Restart) -> asyncio.Task:
        comp = self._comp(f)
        self._record(f, delay=comp.restart_delay, will_fail=comp.fail_next > 0)
        task = comp.restart()
        self._tasks.add(task)

        def done(t: asyncio.Task) -> None:
            self._tasks.discard(t)
            ok = (not t.cancelled()) and t.exception() is None and bool(t.result())
            self.log.append(FaultRecord(self.sim.now, "restart_result", f, {"ok": ok}))

        task.add_done_callback(done)
        return task

    def _do_restart_policy(self, f: RestartPolicy) -> None:
        comp = self._comp(f)
        if f.delay is not None:
            comp.restart_delay = f.delay
        if f.fail_next is not None:
            comp.fail_next = f.fail_next
        self._record(f)

    def _do_stall(self, f: Stall) -> None:
        comp = self._comp(f)
        until = self.sim.now + f.duration
        if f.mode == "silent":
            comp.silent_until = until
        else:
            comp.stale_until = until
            comp.stale_restamp = f.mode == "frozen"
        self._record(f, until=until)

    def _do_corrupt(self, f: Corrupt) -> None:
        comp = self._comp(f)
        comp.corrupt_mode = f.mode
        comp.corrupt_until = self.sim.now + f.duration
        self._record(f, until=comp.corrupt_until)

    def _do_noise_burst(self, f: NoiseBurst) -> None:
        comp = self._comp(f)
        comp.noise_factor = f.factor
        comp.noise_until = self.sim.now + f.duration
        self._record(f, until=comp.noise_until)

    def _do_wheel_slip(self, f: WheelSlip) -> None:
        odom = self.sim.odom
        left, right = (f.factor, f.factor) if f.factor is not None else (f.left, f.right)
        odom.slip_l, odom.slip_r = left, right
        odom.slip_until = math.inf if f.duration is None else self.sim.now + f.duration
        self._record(f)

    def _do_push(self, f: Push) -> None:
        sim = self.sim
        pose = sim.pose
        heading = pose.yaw + f.direction
        ix, iy = f.impulse * math.cos(heading), f.impulse * math.sin(heading)
        sim.apply_impulse(ix, iy)
        # the hit comes from the opposite side of the push
        hit_dir = math.atan2(math.sin(f.direction + math.pi), math.cos(f.direction + math.pi))
        r = sim.profile.radius
        point = (pose.x + r * math.cos(pose.yaw + hit_dir), pose.y + r * math.sin(pose.yaw + hit_dir))
        if f.contact_duration > 0:
            sim.touch(hit_dir, f.contact_duration)
        self._record(f, impulse_xy=(ix, iy), contact_direction=hit_dir, point=point)

    def _do_invisible_obstacle(self, f: InvisibleObstacle) -> str:
        sim = self.sim
        pose = sim.pose
        if f.ahead is not None:
            yaw = pose.yaw
            near = sim.profile.radius + f.ahead
            half = (f.radius if f.radius is not None else f.depth / 2)
            cx = pose.x + (near + half) * math.cos(yaw)
            cy = pose.y + (near + half) * math.sin(yaw)
        else:
            cx, cy = float(f.x), float(f.y)
            yaw = f.yaw if f.yaw is not None else 0.0
        if f.radius is not None:
            ob = CircleObstacle(center=(cx, cy), radius=f.radius, blocks_lidar=False, blocks_body=True)
        else:
            c, s = math.cos(yaw), math.sin(yaw)
            hd, hw = f.depth / 2, f.width / 2
            pts = [(cx + c * dx - s * dy, cy + s * dx + c * dy)
                   for dx, dy in ((-hd, -hw), (hd, -hw), (hd, hw), (-hd, hw))]
            ob = PolygonObstacle(points=pts, blocks_lidar=False, blocks_body=True)
        name = sim.add_obstacle(ob, f.name or None)
        self._record(f, obstacle=name, center=(cx, cy))
        return name

    def _do_block_corridor(self, f: BlockCorridor) -> str:
        ob = SegmentObstacle(a=f.a, b=f.b, thickness=f.thickness, blocks_lidar=f.blocks_lidar,
                             blocks_body=f.blocks_body)
        name = self.sim.add_obstacle(ob, f.name or None)
        self._record(f, obstacle=name)
        return name

    def _do_obstacle_at(self, f: ObstacleAt) -> str:
        if f.goal is not None:
            g = self.sim.world.goal(f.goal)
            x, y = g.x, g.y
        else:
            x, y = float(f.x), float(f.y)
        ob = CircleObstacle(center=(x, y), radius=f.radius, blocks_lidar=f.blocks_lidar,
                            blocks_body=f.blocks_body)
        name = self.sim.add_obstacle(ob, f.name or None)
        self._record(f, obstacle=name, center=(x, y))
        return name

    def _do_remove_obstacle(self, f: RemoveObstacle) -> bool:
        ok = self.sim.remove_obstacle(f.name)
        self._record(f, removed=ok)
        return ok

    def _do_set_battery(self, f: SetBattery) -> None:
        b = self.sim.battery
        before = b.soc
        b.soc = f.soc
        self._record(f, before=before)

    def _do_drain_battery(self, f: DrainBattery) -> None:
        b = self.sim.battery
        before = b.soc
        if f.percent is not None:
            b.soc = max(0.0, b.soc - f.percent)
        if f.power is not None:
            b.extra_power = f.power
            b.extra_until = math.inf if f.duration is None else self.sim.now + f.duration
        self._record(f, before=before, after=b.soc)

    # --- shortcuts ----------------------------------------------------------------------------
    def crash(self, component: str) -> None:
        self.apply(Crash(component=component))

    def restart(self, component: str) -> asyncio.Task:
        return self.apply(Restart(component=component))

    def set_restart_policy(self, component: str, *, delay: float | None = None,
                           fail_next: int | None = None) -> None:
        self.apply(RestartPolicy(component=component, delay=delay, fail_next=fail_next))

    def stall(self, component: str, duration: float, mode: str = "silent") -> None:
        self.apply(Stall(component=component, duration=duration, mode=mode))

    def corrupt(self, component: str, duration: float, mode: str = "nan") -> None:
        self.apply(Corrupt(component=component, duration=duration, mode=mode))

    def noise_burst(self, component: str, duration: float, factor: float = 10.0) -> None:
        self.apply(NoiseBurst(component=component, duration=duration, factor=factor))

    def wheel_slip(self, factor: float | None = None, *, left: float = 1.0, right: float = 1.0,
                   duration: float | None = None) -> None:
        self.apply(WheelSlip(factor=factor, left=left, right=right, duration=duration))

    def push(self, impulse: float = 0.5, direction: float = 0.0, contact_duration: float = 0.15) -> None:
        self.apply(Push(impulse=impulse, direction=direction, contact_duration=contact_duration))

    def invisible_obstacle(self, **kw: Any) -> str:
        return self.apply(InvisibleObstacle(**kw))

    def block_corridor(self, a: Point, b: Point, thickness: float = 0.1, name: str = "") -> str:
        return self.apply(BlockCorridor(a=a, b=b, thickness=thickness, name=name))

    def obstacle_at(self, x: float | None = None, y: float | None = None, *, goal: str | None = None,
                    radius: float = 0.3, name: str = "") -> str:
        return self.apply(ObstacleAt(x=x, y=y, goal=goal, radius=radius, name=name))

    def remove_obstacle(self, name: str) -> bool:
        return self.apply(RemoveObstacle(name=name))

    def set_battery(self, soc: float) -> None:
        self.apply(SetBattery(soc=soc))

    def drain_battery(self, percent: float | None = None, *, power: float | None = None,
                      duration: float | None = None) -> None:
        self.apply(DrainBattery(percent=percent, power=power, duration=duration))
