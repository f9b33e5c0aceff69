"""Sensor drivers: lidar ``scan``, ``imu``, wheel ``odom``, ``bumper`` and ``battery`` (the
AMCL-like ``pose``, component ``localization``, is in ``sim.localization``). Each is a :class:`~sim.components.Driver`
polled by the simulator's physics task; each draws its noise from its own random stream.

Frames: ``scan`` beams are in the sensor frame (angle 0 = the robot's forward axis; the sensor
sits at the profile's mounting offset). ``odom`` and the IMU's integrated ``yaw`` are in the
odom frame (the pose where the simulator started = (0, 0, 0)). ``pose`` is in the map frame.
Ranges follow REP 117: +inf = nothing within range_max, -inf = closer than range_min, NaN = an
erroneous reading.
"""

from __future__ import annotations

import math
from time import perf_counter
from typing import TYPE_CHECKING

import numpy as np

from bt_runtime.runtime.messages import (
    POWER_SUPPLY_CHARGING,
    POWER_SUPPLY_DISCHARGING,
    POWER_SUPPLY_FULL,
    BatteryState,
    Contact,
    Imu,
    LaserScan,
    Odometry,
    Pose2D,
    Twist,
)

from .components import ACTIVE, Driver
from .geometry import wrap_angle

if TYPE_CHECKING:  # pragma: no cover
    from .simulator import Simulator


def soc_after(soc: float, power_w: float, voltage: float, capacity_ah: float, dt: float) -> float:
    """The paper's battery model with the capacity term (SoC in %):
    ``SoC -= P / V * dt / 3600 / C_Ah * 100``, clamped to [0, 100]."""
    soc = soc - power_w / voltage * dt / 3600.0 / capacity_ah * 100.0
    return 0.0 if soc < 0.0 else 100.0 if soc > 100.0 else soc


class _NoiseBuffer:
    """Standard normals drawn in chunks (fewer generator calls on the 100 Hz path)."""

    __slots__ = ("_rng", "_buf", "_i")

    def __init__(self, rng: np.random.Generator, chunk: int = 4096) -> None:
        self._rng = rng
        self._buf = rng.standard_normal(chunk).tolist()
        self._i = 0

    def __call__(self) -> float:
        i = self._i
        if i >= len(self._buf):
            self._buf = self._rng.standard_normal(len(self._buf)).tolist()
            i = 0
        self._i = i + 1
        return self._buf[i]


# ---------------------------------------------------------------------------------------------
class LidarDriver(Driver):
    def __init__(self, sim: Simulator, **kw) -> None:
        spec = sim.profile.lidar
        super().__init__(sim, "lidar", "scan", spec.rate_hz, **kw)
        self.spec = spec
        self.increment = spec.angle_increment
        self.cast_time = 0.0  # perf_counter seconds spent ray casting (for benchmarks)
        self.casts = 0

    def true_ranges(self) -> np.ndarray:
        """Noise-free ranges from the current ground-truth pose (inf beyond range_max)."""
        sim = self.sim
        phys = sim.physics
        x, y, yaw = phys.x, phys.y, phys.angle
        s = self.spec
        c, sn = math.cos(yaw), math.sin(yaw)
        ox, oy = x + c * s.x - sn * s.y, y + sn * s.x + c * s.y
        return sim.raycaster().cast(ox, oy, yaw, s.samples, s.angle_min, self.increment, s.range_max)

    def sample(self, now: float) -> LaserScan:
        t0 = perf_counter()  # accounting only; time itself comes from the loop
        r = self.true_ranges()
        s = self.spec
        sigma = s.noise_sigma * self.noise_scale(now)
        finite = np.isfinite(r)
        if sigma > 0:
            r = r + np.where(finite, self.rng.standard_normal(r.shape[0]) * sigma, 0.0)
        r[finite & (r < s.range_min)] = -np.inf
        self.cast_time += perf_counter() - t0
        self.casts += 1
        return LaserScan(now, s.angle_min, self.increment, s.range_min, s.range_max, r)

    def corrupt(self, msg: LaserScan, mode: str) -> LaserScan:
        n = len(msg.ranges)
        if mode == "nan":
            ranges = np.full(n, np.nan)
        else:
            ranges = self.fault_rng.uniform(-1.0, 2 * self.spec.range_max, n)
        return LaserScan(msg.stamp, msg.angle_min, msg.angle_increment, msg.range_min, msg.range_max, ranges)


# ---------------------------------------------------------------------------------------------
class ImuDriver(Driver):
    """Yaw rate, robot-frame linear acceleration (mean over the publishing period, derived from
    the body's velocity change per physics step, so impacts show as spikes) and the yaw
    integrated from the measured rate (drifts with the gyro bias)."""

    def __init__(self, sim: Simulator, **kw) -> None:
        spec = sim.profile.imu
        super().__init__(sim, "imu", "imu", spec.rate_hz, **kw)
        self.spec = spec
        self.bias = float(self.rng.normal(0.0, spec.gyro_bias_sigma)) if spec.gyro_bias_sigma else 0.0
        self._noise = _NoiseBuffer(self.rng)
        self.yaw = 0.0
        self._ax = self._ay = self._wz = 0.0
        self._n = 0

    def accumulate(self, ax: float, ay: float, wz: float, dt: float) -> None:
        self._ax += ax
        self._ay += ay
        self._wz += wz
        self._n += 1
        self.yaw += (wz + self.bias) * dt

    def _reset(self) -> tuple[float, float, float]:
        n = self._n or 1
        out = (self._ax / n, self._ay / n, self._wz / n)
        self._ax = self._ay = self._wz = 0.0
        self._n = 0
        return out

    def skip(self, now: float) -> None:
        self._reset()

    def sample(self, now: float) -> Imu:
        ax, ay, wz = self._reset()
        k = self.noise_scale(now)
        s = self.spec
        nz = self._noise
        self.yaw = wrap_angle(self.yaw)
        return Imu(now, wz + self.bias + s.gyro_sigma * k * nz(),
                   ax + s.accel_sigma * k * nz(), ay + s.accel_sigma * k * nz(), self.yaw)

    def corrupt(self, msg: Imu, mode: str) -> Imu:
        if mode == "nan":
            return Imu(msg.stamp, math.nan, math.nan, math.nan, math.nan)
        g = self.garbage
        return Imu(msg.stamp, g(50.0), g(200.0), g(200.0), g(math.pi))


# ---------------------------------------------------------------------------------------------
class OdomDriver(Driver):
    """Wheel odometry: integrates the *wheels'* speeds (not the body's motion), with a per-run
    wheel-radius error per wheel, per-step slip noise, and the wheel-slip fault's factors."""

    def __init__(self, sim: Simulator, **kw) -> None:
        spec = sim.profile.odom
        super().__init__(sim, "odom", "odom", spec.rate_hz, **kw)
        self.spec = spec
        p = sim.profile
        self.half_track = p.wheel_separation / 2
        self.track = p.wheel_separation
        self.scale_l = 1.0 + (float(self.rng.normal(0, spec.wheel_scale_sigma)) if spec.wheel_scale_sigma else 0.0)
        self.scale_r = 1.0 + (float(self.rng.normal(0, spec.wheel_scale_sigma)) if spec.wheel_scale_sigma else 0.0)
        self.slip_l = 1.0  # fault factors: >1 over-reads, <1 under-reads
        self.slip_r = 1.0
        self.slip_until = math.inf
        self._noise = _NoiseBuffer(self.rng)
        self.x = self.y = self.yaw = 0.0
        self.v = self.w = 0.0  # measured twist

    def integrate(self, v: float, w: float, dt: float, now: float) -> None:
        """One physics step of wheel travel (the simulator skips it while the wheels stand)."""
        if now >= self.slip_until:
            self.slip_l = self.slip_r = 1.0
            self.slip_until = math.inf
        s = self.spec.slip_sigma
        nz = self._noise
        dl = (v - w * self.half_track) * dt * self.scale_l * self.slip_l * (1.0 + s * nz())
        dr = (v + w * self.half_track) * dt * self.scale_r * self.slip_r * (1.0 + s * nz())
        d = 0.5 * (dl + dr)
        dth = (dr - dl) / self.track
        mid = self.yaw + 0.5 * dth
        self.x += d * math.cos(mid)
        self.y += d * math.sin(mid)
        self.yaw = wrap_angle(self.yaw + dth)
        self.v = d / dt
        self.w = dth / dt

    def on_activate(self) -> None:
        # a restarted base driver counts from zero again, as a real one does
        self.x = self.y = self.yaw = self.v = self.w = 0.0

    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)

    def sample(self, now: float) -> Odometry:
        return Odometry(now, Pose2D(self.x, self.y, self.yaw), Twist(self.v, self.w))

    def corrupt(self, msg: Odometry, mode: str) -> Odometry:
        if mode == "nan":
            return Odometry(msg.stamp, Pose2D(math.nan, math.nan, math.nan), Twist(math.nan, math.nan))
        g = self.garbage
        return Odometry(msg.stamp, Pose2D(g(100.0), g(100.0), g(math.pi)), Twist(g(10.0), g(10.0)))


# ---------------------------------------------------------------------------------------------
class BumperDriver(Driver):
    """The bumper's switches: which segments (the profile's angular spans) are pressed. Published
    at once when that changes, and at the bumper rate all the time (like TurtleBot3's
    sensor_state topic), so a watchdog can tell a silent driver from "no contact". The
    simulator says which segments the bodies touch (pymunk's contacts, the push fault); like a
    real bumper, the message carries neither the contact point nor the force."""

    def __init__(self, sim: Simulator, **kw) -> None:
        spec = sim.profile.bumper
        super().__init__(sim, "bumper", "bumper", spec.rate_hz, **kw)
        self.spec = spec
        self.current = Contact(0.0, False)

    def press(self, now: float, bearings: list[float]) -> None:
        """The body is touched at these bearings (robot frame); [] = nothing touches it."""
        pressed = tuple(sorted({i for b in bearings for i in self.spec.pressed(b)}))
        contact = Contact(now, bool(pressed), pressed)
        changed = contact.segments != self.current.segments
        self.current = contact
        if changed and self.state is ACTIVE and now >= self.silent_until and now >= self.stale_until:
            msg = self.corrupt(contact, self.corrupt_mode) if now < self.corrupt_until else contact
            self.last_message = msg
            self.published += 1
            self._publish(self.topic, msg)

    def on_activate(self) -> None:
        # a restarted bumper reports its state at once
        msg = Contact(self.sim.now, self.current.in_contact, self.current.segments)
        self.last_message = msg
        self.published += 1
        self._publish(self.topic, msg)
        self.announce_publishing()

    def sample(self, now: float) -> Contact:
        c = self.current
        return Contact(now, c.in_contact, c.segments)

    def corrupt(self, msg: Contact, mode: str) -> Contact:
        if mode == "nan":
            return Contact(msg.stamp, msg.in_contact, msg.segments, math.nan)
        n = len(self.spec.segments)
        pressed = tuple(int(i) for i in np.flatnonzero(self.fault_rng.integers(0, 2, n)))
        return Contact(msg.stamp, bool(pressed), pressed)


# ---------------------------------------------------------------------------------------------
class BatteryModel:
    """The battery's truth: state of charge integrated every physics step (it drains whether or
    not its driver publishes). This robot's consumption constants differ from the profile's
    nominal values by up to ``variation`` (drawn once per run from the seed), as two units of
    one model do; the autonomy layer is told only the nominal values.

    Charging: while the robot's contacts touch the dock's (``sim.dock.Dock.touching``) the
    charger powers the robot and puts ``charge_power_w`` into the battery, so the state of
    charge rises by ``charge_power_w / V / 3600 / capacity_ah * 100`` % per second (V the
    battery's voltage at that charge) up to 100 %. Events ``docked`` / ``undocked`` (contacts)
    and ``charging_started`` / ``charging_stopped`` (with the true state of charge) are
    recorded for judging."""

    variation = 0.10

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        self.spec = sim.profile.battery
        rng = sim.rng("battery/consumption")
        spread = self.variation
        self.idle_power_w, self.k_linear, self.k_angular = (
            nominal * float(rng.uniform(1.0 - spread, 1.0 + spread))
            for nominal in (self.spec.idle_power_w, self.spec.k_linear, self.spec.k_angular))
        self.soc = self.spec.initial_soc
        self.extra_power = 0.0  # W, the drain fault
        self.extra_until = math.inf
        self.power = self.idle_power_w
        self.docked = False  # contacts touch (truth)
        self.charging = False  # current flows in (docked and not full)
        self.depleted = self.soc <= 0.0

    def voltage(self) -> float:
        return self.spec.voltage(self.soc)

    def _contacts_touch(self) -> bool:
        dock = self.sim.dock_contacts
        if dock is None:
            return False
        phys = self.sim.physics
        return dock.touching(phys.x, phys.y, phys.angle)

    def integrate(self, v: float, w: float, dt: float, now: float) -> None:
        spec = self.spec
        if now >= self.extra_until:
            self.extra_power = 0.0
            self.extra_until = math.inf
        power = self.idle_power_w + self.k_linear * abs(v) + self.k_angular * abs(w) + self.extra_power
        docked = self._contacts_touch()
        if docked != self.docked:
            self.docked = docked
            self.sim.record_event("docked" if docked else "undocked", soc=self.soc)
        charging = docked and self.soc < 100.0
        if charging != self.charging:
            self.charging = charging
            self.sim.record_event("charging_started" if charging else "charging_stopped", soc=self.soc)
        self.power = power
        net = -spec.charge_power_w if docked else power  # on the dock the charger powers the robot
        volts = spec.voltage_empty + (spec.voltage_full - spec.voltage_empty) * self.soc * 0.01
        self.soc = soc_after(self.soc, net, volts, spec.capacity_ah, dt)
        if self.soc <= 0.0 and not self.depleted:
            self.depleted = True
            self.sim.on_battery_depleted()
        elif self.soc > 0.0 and self.depleted:
            self.depleted = False
            self.sim.on_battery_restored()


class BatteryDriver(Driver):
    """A battery monitor as small robots have: voltage and state of charge, both with
    measurement noise; no current or power sensor (NaN), except the charger's current while
    docked (negative: flowing in); ``power_supply_status`` CHARGING while the charger's current
    flows, FULL on the charger at 100 %, DISCHARGING otherwise."""

    voltage_sigma = 0.02  # V
    soc_sigma = 0.1  # percentage points

    def __init__(self, sim: Simulator, **kw) -> None:
        super().__init__(sim, "battery", "battery", sim.profile.battery.rate_hz, **kw)
        self.model = sim.battery
        self._noise = _NoiseBuffer(self.rng)

    def sample(self, now: float) -> BatteryState:
        m = self.model
        nz = self._noise
        volts = m.voltage() + self.voltage_sigma * nz()
        soc = min(max(m.soc + self.soc_sigma * nz(), 0.0), 100.0)
        current = -m.spec.charge_power_w / volts if m.charging else math.nan
        status = (POWER_SUPPLY_CHARGING if m.charging else POWER_SUPPLY_FULL if m.docked
                  else POWER_SUPPLY_DISCHARGING)
        return BatteryState(now, volts, soc, current, math.nan, m.spec.capacity_ah, status)

    def corrupt(self, msg: BatteryState, mode: str) -> BatteryState:
        if mode == "nan":
            return BatteryState(msg.stamp, math.nan, math.nan, math.nan, math.nan, msg.capacity_ah,
                                msg.power_supply_status)
        g = self.garbage
        return BatteryState(msg.stamp, abs(g(30.0)), g(300.0), g(20.0), g(100.0), msg.capacity_ah,
                            msg.power_supply_status)


# ---------------------------------------------------------------------------------------------
def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """a (+) b: b expressed in a's frame, brought to a's parent frame."""
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return Pose2D(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap_angle(a.yaw + b.yaw))


def inverse(a: Pose2D) -> Pose2D:
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return Pose2D(-c * a.x - s * a.y, s * a.x - c * a.y, wrap_angle(-a.yaw))
