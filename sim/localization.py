"""The AMCL-like localization component (``pose``, map frame), judging from the data it gets.

Like AMCL it listens to the robot's topics, not to the simulator's internals: ``odom`` for the
motion between updates, ``imu`` for the heading change (as robot_localization fuses the
gyro), and ``scan`` for the correction. Each update:

1. *Predict*: the estimate moves by the odometry increment since the previous update (with the
   odometry's slip and scale errors; the gyro's yaw change replaces the wheels' when the IMU
   is fresh). An odometry jump that no motion explains (the odometry driver restarted from
   zero) is not motion: the increment is dropped and the estimate kept.
2. *Correct*, only with a usable scan: recent, not a repeat of the previous one (a frozen
   driver), and mostly valid ranges (NaN, negative or beyond range_max is invalid). The scan
   matching itself is not simulated: its outcome is modelled as a pull towards the true pose
   plus a correlated (AR(1)) error, a first-order convergence with time constant
   ``convergence_s``, so after an outage the pose re-converges over a few seconds, never
   snapping to the truth. Without usable scans it is dead reckoning and its covariance grows.

Without odometry (none for ``odom_timeout``) nothing is published, as AMCL without the
odom -> base_link transform.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from bt_runtime.runtime.messages import Imu, LaserScan, LocalizedPose, Odometry, Pose2D

from .components import Driver
from .geometry import wrap_angle

if TYPE_CHECKING:  # pragma: no cover
    from .simulator import Simulator


def scan_usable(scan: LaserScan, previous: LaserScan | None, min_valid: float, min_features: int = 10) -> bool:
    """A scan a scan matcher can use: at least ``min_valid`` of its ranges valid (finite within
    [range_min, range_max], or +inf for "nothing in range"), at least ``min_features`` of them
    hitting something (an empty scan matches anywhere), and not an exact repeat of the previous
    one (sensor noise makes real scans differ)."""
    r = np.asarray(scan.ranges, dtype=float)
    if r.size == 0:
        return False
    hits = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    if int(hits.sum()) < min_features or float((hits | (r == np.inf)).mean()) < min_valid:
        return False
    return previous is None or not (previous is scan or np.array_equal(np.asarray(previous.ranges), r))


class LocalizationDriver(Driver):
    """See the module docstring."""

    odom_timeout = 0.5  # s without odometry: no transform, no pose
    scan_timeout = 0.5  # s: an older scan does not correct
    min_valid = 0.7  # share of valid ranges a usable scan needs
    convergence_s = 1.5  # s, time constant of the pull towards the scan-matched pose
    dr_growth = 0.0025  # m^2 per second of dead reckoning (~5 cm per second, 1 sigma)

    def __init__(self, sim: Simulator, **kw) -> None:
        spec = sim.profile.localization
        super().__init__(sim, "localization", "pose", spec.rate_hz, **kw)
        self.spec = spec
        self.max_speed = sim.profile.max_linear
        self._noise = self._normals()
        self.ex = self.ey = self.eyaw = 0.0  # the scan matcher's correlated error
        self.covariance = spec.sigma_xy ** 2
        self.estimate: Pose2D = sim.spawn
        self.dead_reckoning = False
        self._odom: Odometry | None = None
        self._odom_seen = -math.inf
        self._odom_ref: Odometry | None = None  # odometry at the previous update
        self._imu_yaw = 0.0  # gyro-integrated heading since the previous update
        self._imu_seen = -math.inf
        self._imu_last: float | None = None
        self._scan: LaserScan | None = None
        self._scan_seen = -math.inf
        self._scan_prev: LaserScan | None = None
        self._scan_good = False
        self._first_update: float | None = None
        bus = sim.bus
        bus.subscribe("odom", self._on_odom)
        bus.subscribe("imu", self._on_imu)
        bus.subscribe("scan", self._on_scan)

    def _normals(self):
        rng = self.rng

        def draw() -> float:
            return float(rng.standard_normal())
        return draw

    # --- inputs (what a real localization node receives) ---------------------------------------
    def _on_odom(self, msg: Odometry) -> None:
        p, t = msg.pose, msg.twist
        if all(math.isfinite(v) for v in (p.x, p.y, p.yaw, t.linear, t.angular)):
            self._odom = msg
            self._odom_seen = self.sim.now

    def _on_imu(self, msg: Imu) -> None:
        now = self.sim.now
        if not math.isfinite(msg.yaw_rate):
            return
        if self._imu_last is not None and now - self._imu_last < 0.2:
            self._imu_yaw += msg.yaw_rate * (now - self._imu_last)
        self._imu_last = now
        self._imu_seen = now

    def _on_scan(self, msg: LaserScan) -> None:
        self._scan_good = scan_usable(msg, self._scan, self.min_valid)
        self._scan_prev, self._scan = self._scan, msg
        self._scan_seen = self.sim.now

    # --- the update ---------------------------------------------------------------------------
    def _increment(self, now: float) -> tuple[float, float, float]:
        """Robot-frame motion (dx, dy, dyaw) since the previous update; (0, 0, 0) across an
        odometry jump."""
        odom, ref = self._odom, self._odom_ref
        self._odom_ref = odom
        imu_yaw, self._imu_yaw = self._imu_yaw, 0.0
        if ref is None or odom is ref:
            return 0.0, 0.0, 0.0
        a, b = ref.pose, odom.pose
        dxm, dym = b.x - a.x, b.y - a.y
        elapsed = max(odom.stamp - ref.stamp, 1.0 / self.rate_hz)
        if math.hypot(dxm, dym) > 1.5 * self.max_speed * elapsed + 0.05:
            self.sim.record_event("localization_odom_jump", jump=round(math.hypot(dxm, dym), 3))
            return 0.0, 0.0, 0.0  # the odometry restarted: no motion to apply
        c, s = math.cos(a.yaw), math.sin(a.yaw)
        dyaw = wrap_angle(b.yaw - a.yaw)
        if now - self._imu_seen < 0.2:
            dyaw = imu_yaw
        return c * dxm + s * dym, -s * dxm + c * dym, dyaw

    def sample(self, now: float) -> LocalizedPose | None:
        if self._odom is None or now - self._odom_seen > self.odom_timeout:
            self._odom_ref = None  # the transform is gone; the next odometry starts afresh
            return None
        dx, dy, dyaw = self._increment(now)
        e = self.estimate
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        est = Pose2D(e.x + c * dx - s * dy, e.y + s * dx + c * dy, wrap_angle(e.yaw + dyaw))
        dt = 1.0 / self.rate_hz
        if self._first_update is None:
            self._first_update = now
        if self._scan is None:  # the lidar's first scan may still be on its way
            usable = now - self._first_update <= self.scan_timeout
        else:
            usable = self._scan_good and now - self._scan_seen <= self.scan_timeout
        if usable:
            est = self._correct(est, now, dt)
        else:
            self.covariance += self.dr_growth * dt
        if usable == self.dead_reckoning:
            self.dead_reckoning = not usable
            self.sim.record_event("localization_mode", mode="dead_reckoning" if not usable else "scan_matching")
        self.estimate = est
        return LocalizedPose(now, est, self.covariance)

    def _correct(self, est: Pose2D, now: float, dt: float) -> Pose2D:
        """Pull the estimate towards the scan-matched pose (truth + AR(1) error)."""
        sp = self.spec
        rho = sp.correlation
        q = math.sqrt(1 - rho * rho)
        k = self.noise_scale(now)
        nz = self._noise
        self.ex = rho * self.ex + q * sp.sigma_xy * k * nz()
        self.ey = rho * self.ey + q * sp.sigma_xy * k * nz()
        self.eyaw = rho * self.eyaw + q * sp.sigma_yaw * k * nz()
        truth = self.sim.pose
        tx, ty, tyaw = truth.x + self.ex, truth.y + self.ey, truth.yaw + self.eyaw
        gain = 1.0 - math.exp(-dt / self.convergence_s)
        floor = sp.sigma_xy ** 2
        self.covariance = floor + (self.covariance - floor) * (1.0 - gain)
        return Pose2D(est.x + gain * (tx - est.x), est.y + gain * (ty - est.y),
                      wrap_angle(est.yaw + gain * wrap_angle(tyaw - est.yaw)))

    def reset(self, pose: Pose2D) -> None:
        """Set the initial pose (as an /initialpose message does)."""
        self.estimate = pose
        self._odom_ref = None
        self.covariance = self.spec.sigma_xy ** 2

    def corrupt(self, msg: LocalizedPose, mode: str) -> LocalizedPose:
        if mode == "nan":
            return LocalizedPose(msg.stamp, Pose2D(math.nan, math.nan, math.nan), math.nan)
        g = self.garbage
        return LocalizedPose(msg.stamp, Pose2D(msg.pose.x + g(5.0), msg.pose.y + g(5.0), g(math.pi)),
                             msg.covariance)
