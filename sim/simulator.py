"""The simulator: world + robot + sensors + faults on the running asyncio loop.

    sim = Simulator("apartment", "burger", seed=1)
    sim.subscribe("scan", on_scan)
    await sim.start()              # the physics task runs on the current loop
    sim.command(0.2, 0.0)          # the base command (what the decision gate sends)
    sim.faults.schedule(5.0, Crash(component="lidar"))
    ...
    await sim.stop()

One asyncio task steps the physics at ``physics_hz`` (100 Hz) and, after each step, polls the
sensor drivers, which publish on the :class:`~sim.bus.Bus` at their own rates. Every time is
``loop.time()``: on a :class:`~bt_runtime.runtime.clock.VirtualTimeLoop` a run is bit-for-bit
reproducible from its seed.

Topics: ``scan`` LaserScan, ``imu`` Imu, ``odom`` Odometry, ``bumper`` Contact, ``battery``
BatteryState, ``pose`` LocalizedPose (map frame), ``cmd_vel_out`` Twist (what reached the base),
``ground_truth`` GroundTruth (for recording and judging only, never for the tree),
``component_state`` ComponentInfo (on every state change), ``sim_event`` SimEvent.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import zlib
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from time import perf_counter
from typing import Any

import numpy as np
import structlog
from pydantic import BaseModel, ConfigDict, Field

from bt_runtime.runtime.messages import ComponentInfo, ComponentState, Pose2D, Twist

from .bus import Bus
from .component_log import ComponentLogEntry
from .components import ACTIVE, Component
from .dock import Dock
from .faults import FaultInjector
from .geometry import RayCaster, wrap_angle
from .localization import LocalizationDriver
from .physics import DiffDriveBase, PhysicsWorld
from .raster_cache import world_raster
from .robot import RobotProfile, load_profile
from .sensors import (
    BatteryDriver,
    BatteryModel,
    BumperDriver,
    ImuDriver,
    LidarDriver,
    OdomDriver,
)
from .world import World, lidar_geometry, load_world

log = structlog.get_logger("sim")

COMPONENT_NAMES = ("lidar", "imu", "odom", "bumper", "battery", "localization")


@dataclass(slots=True)
class GroundTruth:
    """The true state (map frame), for recording and judging."""

    stamp: float
    pose: Pose2D
    twist: Twist  # robot frame: forward speed, yaw rate
    in_contact: bool = False


@dataclass(slots=True)
class SimEvent:
    t: float
    kind: str
    data: dict = field(default_factory=dict)


class SimOptions(BaseModel):
    model_config = ConfigDict(extra="forbid")
    physics_hz: float = Field(100.0, gt=0)
    substeps: int = Field(1, ge=1, le=50)  # minimum; more when fast (<= 4 mm travel per substep)
    trajectory_hz: float = Field(10.0, gt=0)  # ground-truth recording and the ground_truth topic
    trajectory_keep: int = Field(100_000, ge=1)  # samples kept (the latest; ~2.8 h at 10 Hz, ~10 MB): a
    # sim-robot may run for days
    max_body_speed: float = Field(3.0, gt=0)  # m/s cap on the body (anti-tunnelling)
    restart_delay: float = Field(1.0, ge=0)  # default for every component
    restart_delays: dict[str, float] = Field(default_factory=dict)  # per component
    spawn: str | tuple[float, float, float] | None = None  # a goal name or (x, y, yaw); default: world.spawn
    log_faults: bool = True  # structlog line per fault


class Simulator:
    """See the module docstring. ``world``/``profile`` are names, paths or loaded models."""

    def __init__(self, world: str | Path | World = "apartment", profile: str | Path | RobotProfile = "burger",
                 seed: int = 0, options: SimOptions | dict | None = None, **option_overrides: Any) -> None:
        if isinstance(options, dict) or options is None:
            options = SimOptions(**{**(options or {}), **option_overrides})
        elif option_overrides:
            options = options.model_copy(update=option_overrides)
        self.options = options
        self.world = world if isinstance(world, World) else load_world(world)
        self.profile = profile if isinstance(profile, RobotProfile) else load_profile(profile)
        self.seed = int(seed)
        self.physics_hz = options.physics_hz
        self.dt = 1.0 / options.physics_hz
        self.bus = Bus()
        self.events: list[SimEvent] = []
        self.component_log: list[ComponentLogEntry] = []

        if options.spawn is None:
            sp = self.world.spawn.to_pose()
        elif isinstance(options.spawn, str):
            sp = self.world.goal(options.spawn)
        else:
            sp = Pose2D(*options.spawn)
        self.spawn = sp
        self.dock = self.world.dock.to_pose() if self.world.dock else None
        self.dock_contacts = Dock(self.dock) if self.dock is not None else None  # truth: when contacts touch

        # physics and obstacles ------------------------------------------------------------
        self.physics = PhysicsWorld(self.profile, sp.x, sp.y, sp.yaw, substeps=options.substeps,
                                    max_body_speed=options.max_body_speed)
        self._static_names: list[str] = []
        for i, ob in enumerate(self.world.obstacles):
            key = f"{i}:{ob.name}" if ob.name else f"{i}"
            self._static_names.append(key)
            self.physics.add_obstacle(key, ob)
        self.dynamic_obstacles: dict[str, Any] = {}
        self.obstacles_version = 0
        self._raycaster: RayCaster | None = None
        self.base = DiffDriveBase(self.profile)

        # components ----------------------------------------------------------------------
        self.battery = BatteryModel(self)
        kw = dict
        self.lidar = LidarDriver(self, **kw(restart_delay=self._delay("lidar")))
        self.imu = ImuDriver(self, **kw(restart_delay=self._delay("imu")))
        self.odom = OdomDriver(self, **kw(restart_delay=self._delay("odom")))
        self.bumper = (BumperDriver(self, **kw(restart_delay=self._delay("bumper")))
                       if self.profile.bumper is not None else None)  # ROSbot 2.0: none
        self.battery_driver = BatteryDriver(self, **kw(restart_delay=self._delay("battery")))
        self.localization = LocalizationDriver(self, **kw(restart_delay=self._delay("localization")))
        self._components: dict[str, Component] = {}
        for c in (self.lidar, self.imu, self.odom, self.bumper, self.battery_driver, self.localization):
            if c is not None:
                self._components[c.name] = c
        self._drivers = list(self._components.values())
        self._schedule_drivers()

        self.faults = FaultInjector(self)

        # state ------------------------------------------------------------------------------
        self._loop: asyncio.AbstractEventLoop | None = None
        self._handle: asyncio.TimerHandle | None = None
        self.error: BaseException | None = None
        self.t0 = 0.0
        self.step_count = 0
        self._prev_v = (0.0, 0.0)
        self._traj: deque[tuple] = deque(maxlen=options.trajectory_keep)
        self._traj_steps = max(1, int(round(self.physics_hz / options.trajectory_hz)))
        self._touching: dict[str, tuple[float, float]] = {}
        self._synthetic: list[tuple[float, float]] = []  # (until, bearing) of pushes
        self.in_contact = False
        self.perf = {"steps": 0, "step_s": 0.0, "physics_s": 0.0}

    # --- helpers ------------------------------------------------------------------------------
    def _delay(self, name: str) -> float:
        return self.options.restart_delays.get(name, self.options.restart_delay)

    def rng(self, name: str) -> np.random.Generator:
        """An independent random stream per name, derived from the seed: adding a stream (a new
        sensor) leaves every other stream unchanged."""
        ss = np.random.SeedSequence(entropy=self.seed, spawn_key=(zlib.crc32(name.encode()),))
        return np.random.Generator(np.random.PCG64(ss))

    @property
    def now(self) -> float:
        loop = self._loop
        if loop is None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                return 0.0
        return loop.time()

    @property
    def running(self) -> bool:
        return self._handle is not None

    def record_event(self, kind: str, **data: Any) -> SimEvent:
        """Log ``kind`` in the run's event record (judging, reports) and on the ``sim_event`` topic."""
        ev = SimEvent(self.now, kind, data)
        self.events.append(ev)
        self.bus.publish("sim_event", ev)
        return ev

    def events_of(self, kind: str) -> list[SimEvent]:
        return [e for e in self.events if e.kind == kind]

    # --- pub/sub ------------------------------------------------------------------------------
    def subscribe(self, topic: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        return self.bus.subscribe(topic, callback)

    # --- lifecycle ----------------------------------------------------------------------------
    async def start(self) -> None:
        if self.running:
            return
        loop = asyncio.get_running_loop()
        self._loop = loop
        self.t0 = loop.time()
        self.step_count = 0
        self._record_truth(self.t0)
        self._schedule_drivers()
        self.error = None
        self._handle = loop.call_at(self.t0 + self.dt, self._tick)
        self.faults.arm()
        self.record_event("sim_started", world=self.world.name, robot=self.profile.name, seed=self.seed)

    async def stop(self) -> None:
        """Stop stepping (and pending faults and restarts). Raises the error that stopped the
        physics, if one did."""
        handle, self._handle = self._handle, None
        if handle is not None:
            handle.cancel()
        self.faults.disarm()
        for c in self._components.values():
            t = c._restart_task
            if t is not None and not t.done():
                t.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await t
        self.record_event("sim_stopped")
        if self.error is not None:
            raise RuntimeError("the simulation stopped on an error") from self.error

    async def run_for(self, duration: float) -> None:
        """Convenience: start (if needed) and let the simulation run for ``duration`` seconds."""
        await self.start()
        await asyncio.sleep(duration)

    def _tick(self) -> None:
        """One physics step, then re-arm the timer for the next one (a timer-callback chain:
        one event-loop iteration per step, about half the cost of a task that sleeps)."""
        k = self.step_count + 1
        loop = self._loop
        try:
            self._step(k, loop.time())
        except Exception as exc:  # an error in the simulation must be visible, not swallowed
            self._handle = None
            self.error = exc
            log.exception("sim_physics_failed", step=k)
            self.record_event("sim_failed", error=repr(exc), step=k)
            return
        self._handle = loop.call_at(self.t0 + (k + 1) * self.dt, self._tick)

    # --- the step -----------------------------------------------------------------------------
    def _schedule_drivers(self) -> None:
        """Which components are due at step k: ``self._due[k % len(self._due)]``."""
        periods = [getattr(d, "period_steps", 1) for d in self._drivers]
        cycle = math.lcm(*periods) if periods else 1
        if cycle > 100_000:  # pathological rates: fall back to polling everyone
            cycle = 1
            self._due = [[d for d in self._drivers]]
            return
        self._due = [[d for d, p in zip(self._drivers, periods) if k % p == 0] for k in range(cycle)]

    def _step(self, k: int, now: float) -> None:
        t_start = perf_counter()
        self.step_count = k
        dt = self.dt
        base = self.base
        if base.update(now, dt):
            self.bus.publish("cmd_vel_out", Twist(0.0, 0.0))
            self.record_event("cmd_timeout")
        v, w = base.v, base.w
        phys = self.physics
        phys.step(v, w, dt)
        t_phys = perf_counter()
        perf = self.perf
        perf["physics_s"] += t_phys - t_start
        vx, vy, yaw = phys.vx, phys.vy, phys.angle
        pvx, pvy = self._prev_v
        self._prev_v = (vx, vy)
        axw, ayw = (vx - pvx) / dt, (vy - pvy) / dt
        c, s = math.cos(yaw), math.sin(yaw)
        imu = self.imu
        a_fwd, a_left = c * axw + s * ayw, -s * axw + c * ayw
        imu.accumulate(a_fwd, a_left, phys.wz, dt)
        odom = self.odom
        if odom.state is not ACTIVE:
            pass  # a crashed (or starting) odometry driver integrates nothing
        elif v != 0.0 or w != 0.0:
            odom.integrate(v, w, dt, now)
        else:
            odom.v = odom.w = 0.0
        self.battery.integrate(v, w, dt, now)
        if phys.contacts or self._touching or self._synthetic:
            self._update_contacts(now, c, s, math.hypot(pvx, pvy))
        due = self._due
        for d in due[k % len(due)]:
            d.poll(k, now)
        if k % self._traj_steps == 0:
            self._record_truth(now)
        perf["steps"] += 1
        perf["step_s"] += perf_counter() - t_start

    def _update_contacts(self, now: float, c: float, s: float, speed_before: float) -> None:
        """Collision events for judging (with the true contact points), and the bumper's
        switches: which segments the contact bearings fall in (robot frame)."""
        bx, by = self.physics.x, self.physics.y
        touching: dict[str, tuple[float, float]] = {}
        bearings: list[float] = []
        for cp in self.physics.contacts:
            touching.setdefault(cp.obstacle, cp.point)
            dx, dy = cp.point[0] - bx, cp.point[1] - by
            bearings.append(math.atan2(-s * dx + c * dy, c * dx + s * dy))
        for name, pt in touching.items():
            if name not in self._touching:
                self.record_event("collision", obstacle=name, point=pt, commanded_v=self.base.v,
                                   body_speed=speed_before)
        for name in self._touching:
            if name not in touching:
                self.record_event("collision_end", obstacle=name)
        self._touching = touching
        self._synthetic = [(until, bearing) for until, bearing in self._synthetic if now < until]
        bearings.extend(bearing for _, bearing in self._synthetic)
        self.in_contact = bool(bearings)
        if self.bumper is not None:
            self.bumper.press(now, bearings)

    def _record_truth(self, now: float) -> None:
        phys = self.physics
        x, y, vx, vy, wz = phys.x, phys.y, phys.vx, phys.vy, phys.wz
        yaw = wrap_angle(phys.angle)
        fwd = vx * math.cos(yaw) + vy * math.sin(yaw)
        self._traj.append((now, x, y, yaw, fwd, wz, self.in_contact))
        self.bus.publish("ground_truth", GroundTruth(now, Pose2D(x, y, yaw), Twist(fwd, wz), self.in_contact))

    # --- the base -----------------------------------------------------------------------------
    def command(self, linear: float, angular: float) -> Twist:
        """Set the base command (m/s, rad/s). Clamped to the profile's limits; the base stops
        after ``cmd_timeout`` without a command. Publishes what reached the base on
        ``cmd_vel_out`` and returns it."""
        v, w = self.base.command(linear, angular, self.now)
        if not self.base.enabled:
            v = w = 0.0
        out = Twist(v, w)
        self.bus.publish("cmd_vel_out", out)
        return out

    send_velocity = command  # the RobotDriver protocol's name

    def emergency_zero(self) -> None:
        """Zero the base command from any thread (the runtime's off-loop watchdog): the base
        ramps down from its next physics step; ``cmd_vel_out`` is published on the loop."""
        loop = self._loop
        now = loop.time() if loop is not None else 0.0  # a real loop's clock is time.monotonic
        self.base.command(0.0, 0.0, now)
        if loop is not None and not loop.is_closed():
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                loop.call_soon_threadsafe(self.bus.publish, "cmd_vel_out", Twist(0.0, 0.0))

    def on_battery_depleted(self) -> None:
        """The battery model reports an empty battery: the base stops."""
        self.base.enabled = False
        self.record_event("battery_depleted")
        self.bus.publish("cmd_vel_out", Twist(0.0, 0.0))

    def on_battery_restored(self) -> None:
        """The battery model reports charge again: the base may move."""
        self.base.enabled = True
        self.record_event("battery_restored", soc=self.battery.soc)

    # --- truth --------------------------------------------------------------------------------
    @property
    def pose(self) -> Pose2D:
        """Ground-truth pose (map frame)."""
        phys = self.physics
        return Pose2D(phys.x, phys.y, wrap_angle(phys.angle))

    @property
    def twist(self) -> Twist:
        """Ground-truth velocity in the robot frame."""
        phys = self.physics
        if phys._dirty:  # an impulse since the last step
            phys.vx, phys.vy = phys.body.velocity
        yaw = phys.angle
        return Twist(phys.vx * math.cos(yaw) + phys.vy * math.sin(yaw), phys.wz)

    def trajectory(self) -> np.ndarray:
        """Ground truth recorded at ``trajectory_hz`` (the latest ``trajectory_keep`` samples):
        columns t, x, y, yaw, v, w, in_contact."""
        return np.array(self._traj, dtype=float).reshape(-1, 7)

    def apply_impulse(self, ix: float, iy: float, point: tuple[float, float] | None = None) -> None:
        """An external impulse (N*s, map frame) on the robot."""
        self.physics.apply_impulse(ix, iy, point)

    def touch(self, bearing: float, duration: float) -> None:
        """Something touches the body at ``bearing`` (robot frame) for ``duration`` seconds
        (the push fault): the bumper segments there close."""
        self._synthetic.append((self.now + duration, float(bearing)))

    def apply_force(self, fx: float, fy: float, duration: float) -> None:
        """An external force (N, map frame) on the robot's centre for ``duration`` seconds."""
        self.physics.forces.append([float(fx), float(fy), float(duration)])

    def reset_pose(self, pose: Pose2D) -> None:
        """Put the robot at a pose, standing still (the current command is dropped), and
        re-initialise odometry (0, 0, 0) and the localization there (like setting AMCL's
        initial pose)."""
        self.physics.teleport(pose.x, pose.y, pose.yaw)
        base = self.base
        base.v = base.w = base.target_v = base.target_w = 0.0
        base.timed_out = True
        self._prev_v = (0.0, 0.0)
        o = self.odom
        o.x = o.y = o.yaw = o.v = o.w = 0.0
        self.imu.yaw = 0.0
        self.localization.reset(pose)
        self.record_event("reset_pose", x=pose.x, y=pose.y, yaw=pose.yaw)

    # --- components ---------------------------------------------------------------------------
    def components(self) -> list[ComponentInfo]:
        return [c.info() for c in self._components.values()]

    def component(self, name: str) -> Component:
        try:
            return self._components[name]
        except KeyError:
            raise KeyError(f"no component {name!r}; components: {sorted(self._components)}") from None

    def register_component(self, component: Component) -> None:
        """Add a component (e.g. the Nav2 stand-in's servers) to the registry; it is polled
        after every physics step."""
        self._components[component.name] = component
        self._drivers.append(component)
        self._schedule_drivers()

    def component_state(self, name: str) -> ComponentState:
        return self.component(name).state

    def crash(self, name: str, reason: str = "crash") -> None:
        self.component(name).crash(reason)

    async def restart(self, name: str) -> bool:
        """Restart a component; True once it runs again, False if the restart failed."""
        return await self.component(name).restart()

    def log_component(self, name: str, event: str, detail: str = "") -> None:
        """An entry in the simulator's component log (``sim.component_log``)."""
        self.component_log.append(ComponentLogEntry(self.now, name, event, detail))

    def on_component_changed(self, comp: Component, old: ComponentState, reason: str) -> None:
        """A component reports a state change: recorded, logged and published."""
        new = comp.state
        if new is ComponentState.STARTING:
            self.log_component(comp.name, "restarting")
        elif new is ComponentState.ACTIVE:
            self.log_component(comp.name, "running")
        elif old is ComponentState.STARTING:
            self.log_component(comp.name, "restart_failed", reason)
        else:
            self.log_component(comp.name, "crashed", reason)
        self.record_event("component_state", component=comp.name, old=old.value, new=comp.state.value,
                           reason=reason)
        log.info("component_state", sim_time=round(self.now, 4), component=comp.name,
                 old=old.value, new=comp.state.value, reason=reason)
        self.bus.publish("component_state", comp.info())

    # --- obstacles ----------------------------------------------------------------------------
    def obstacles(self, *, dynamic: bool = True) -> list:
        """The world's obstacles, plus (by default) those added at run time."""
        out = list(self.world.obstacles)
        if dynamic:
            out.extend(self.dynamic_obstacles.values())
        return out

    def add_obstacle(self, obstacle, name: str | None = None) -> str:
        """Add an obstacle (a world obstacle model) at run time; returns its name."""
        name = name or obstacle.name or f"dynamic/{len(self.dynamic_obstacles) + 1}"
        if name in self.dynamic_obstacles:
            raise ValueError(f"an obstacle named {name!r} exists already")
        if obstacle.name != name:
            obstacle = obstacle.model_copy(update={"name": name})
        self.dynamic_obstacles[name] = obstacle
        self.physics.add_obstacle(f"dyn:{name}", obstacle)
        self._obstacles_changed()
        self.record_event("obstacle_added", name=name, blocks_lidar=obstacle.blocks_lidar,
                           blocks_body=obstacle.blocks_body, bbox=obstacle.bbox())
        return name

    def remove_obstacle(self, name: str) -> bool:
        if self.dynamic_obstacles.pop(name, None) is None:
            return False
        self.physics.remove_obstacle(f"dyn:{name}")
        self._obstacles_changed()
        self.record_event("obstacle_removed", name=name)
        return True

    def _obstacles_changed(self) -> None:
        self.obstacles_version += 1
        self._raycaster = None

    def raycaster(self) -> RayCaster:
        rc = self._raycaster
        if rc is None:
            rc = self._raycaster = RayCaster(*lidar_geometry(self.obstacles()))
        return rc

    def rasterize(self, resolution: float = 0.05, *, layer: str = "lidar", dynamic: bool = False,
                  inflate: float = 0.0, padding: float = 0.0):
        """Occupancy raster of the world (static only by default, like a pre-built SLAM map). The
        world's own shapes come from a per-process cache (sim/raster_cache.py)."""
        extra = list(self.dynamic_obstacles.values()) if dynamic else []
        return world_raster(self.world.obstacles, extra, self.world.bounds, resolution,
                            layer=layer, inflate=inflate, padding=padding)
