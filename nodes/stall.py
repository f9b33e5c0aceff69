"""Contacts the wheels and the IMU disagree about: glancing touches and blocked motion.

A robot without a bumper (the ROSbot 2.0) learns of a hard hit from the IMU's spike
(``collision.ImpactDetector``, 6 m/s^2). A glancing touch at 0.05-0.2 m/s makes no such spike
(1-3 m/s^2 in the collision variants), and a robot pushing slowly against something makes
none at all. Both still leave a trace a real robot senses, in its own data only:

* **Unexplained acceleration.** The base cannot accelerate its body harder than its ramp
  (``max_linear_accel``) forwards, nor sideways other than the turn's ``v * w``: an IMU
  acceleration beyond both (with margins for noise) is a push from outside. The obstacle lies
  opposite to that excess.
* **Blocked motion.** The wheels (odometry's twist) keep turning at a steady speed while the
  IMU says the body lost most of that speed: something holds it. The obstacle lies in the
  direction of travel.

Frozen or invalid readings never count: a sample must be finite, must not repeat the previous
one exactly (noise makes real readings differ; a frozen driver re-stamps one reading), and the
IMU and odometry must be healthy by the supervisor.
"""

from __future__ import annotations

import math
from collections import deque

from bt_runtime.runtime.messages import Imu, Odometry

FORWARD_SLACK = 1.15  # times the base's acceleration limit the body may show (ramp timing)
FORWARD_MARGIN = 0.15  # m/s^2 more (IMU noise, odometry noise)
LATERAL_MARGIN = 0.25  # m/s^2 around v * w (turn estimate from odometry speed and gyro rate)
ODOM_MAX_AGE = 0.25  # s: an older odometry twist explains nothing


def _seen(buffer, since: float) -> bool:
    """Nothing in ``buffer`` is stamped after ``since`` (the samples a call would skip)."""
    last = buffer.latest_stamped() if buffer is not None else None
    return last is None or last[0] <= since


class MotionMismatch:
    """Reads the new IMU and odometry samples from the data backup on each call and remembers
    the latest contact it implies: (time, bearing in the robot frame, kind)."""

    __slots__ = ("_imu_since", "_odom_since", "_odom", "_prev_imu", "_prev_twist", "_body",
                 "_wheels", "event")

    def __init__(self) -> None:
        self._imu_since = -math.inf
        self._odom_since = -math.inf
        self._odom: tuple[float, float, float] | None = None  # (stamp, v, w) of a fresh twist
        self._prev_imu: tuple[float, float, float] | None = None
        self._prev_twist: tuple[float, float] | None = None
        self._body: deque[tuple[float, float]] = deque()  # (stamp, forward speed change)
        self._wheels: deque[tuple[float, float]] = deque()  # (stamp, wheel speed)
        self.event: tuple[float, float, str] | None = None

    def reset(self) -> None:
        self._odom = self._prev_imu = self._prev_twist = None
        self._body.clear()
        self._wheels.clear()

    def __call__(self, context, *, threshold: float, stall_speed: float, stall_window: float,
                 window: float) -> tuple[float, str] | None:
        """(contact bearing in the robot frame, 'push' | 'blocked') of a contact sensed within
        the last ``window`` s, or None."""
        sup = getattr(context, "supervisor", None)
        buffers = context.backup.buffers
        if sup is not None and any(n in sup.components and not sup.is_healthy(n) for n in ("imu", "odom")):
            self.reset()  # a failed sensor explains nothing; start afresh once it is back
            self._skip(buffers)
            return self._recent(context, window)
        odom = buffers.get("odom")
        imu = buffers.get("imu")
        if _seen(imu, self._imu_since) and _seen(odom, self._odom_since):
            return self._recent(context, window)  # no sample since the last call (IMU ~50 Hz, ticks 100 Hz)
        odoms = [o for o in odom.since_stamped(self._odom_since) if o[0] > self._odom_since] if odom is not None else []
        imus = imu.since_stamped(self._imu_since) if imu is not None else []
        a_max = float(getattr(context.robot, "max_linear_accel", 1.0)) * FORWARD_SLACK + FORWARD_MARGIN
        k = 0
        for stamp, msg in imus:
            if stamp <= self._imu_since:
                continue
            while k < len(odoms) and odoms[k][0] <= stamp:  # the wheels as of this IMU sample
                self._take_odom(*odoms[k])
                k += 1
            self._take_imu(stamp, msg, a_max, threshold, stall_speed, stall_window)
            self._imu_since = stamp
        for item in odoms[k:]:
            self._take_odom(*item)
        return self._recent(context, window)

    def _skip(self, buffers) -> None:
        for name in ("imu", "odom"):
            buf = buffers.get(name)
            last = buf.latest_stamped() if buf is not None else None
            if last is not None:
                if name == "imu":
                    self._imu_since = last[0]
                else:
                    self._odom_since = last[0]

    def _recent(self, context, window: float) -> tuple[float, str] | None:
        ev = self.event
        if ev is None or context.clock() - ev[0] > window:
            return None
        return ev[1], ev[2]

    def _take_odom(self, stamp: float, msg) -> None:
        self._odom_since = max(self._odom_since, stamp)
        if not isinstance(msg, Odometry):
            return
        v, w = msg.twist.linear, msg.twist.angular
        if not (math.isfinite(v) and math.isfinite(w)):
            self._odom = None
            return
        frozen = self._prev_twist == (v, w) and (v != 0.0 or w != 0.0)
        self._prev_twist = (v, w)
        if frozen:  # a re-stamped reading: the wheels' speed is unknown
            self._odom = None
            self._wheels.clear()
            return
        self._odom = (stamp, v, w)
        self._wheels.append((stamp, v))

    def _take_imu(self, stamp: float, msg, a_max: float, threshold: float, stall_speed: float,
                  stall_window: float) -> None:
        if not isinstance(msg, Imu):
            return
        reading = (msg.accel_x, msg.accel_y, msg.yaw_rate)
        if not all(map(math.isfinite, reading)) or reading == self._prev_imu:
            self._prev_imu = reading
            self._body.clear()
            return
        previous = self._prev_imu
        self._prev_imu = reading
        odom = self._odom
        if odom is None or stamp - odom[0] > ODOM_MAX_AGE or previous is None:
            self._body.clear()
            return
        ax, ay, wz = reading
        _, v, _ = odom
        ex = ax - math.copysign(a_max, ax) if abs(ax) > a_max else 0.0
        ey = ay - v * wz
        ey = ey - math.copysign(LATERAL_MARGIN, ey) if abs(ey) > LATERAL_MARGIN else 0.0
        if math.hypot(ex, ey) > threshold:
            self.event = (stamp, math.atan2(-ey, -ex), "push")
        self._blocked(stamp, ax, v, stall_speed, stall_window)

    def _blocked(self, stamp: float, ax: float, v: float, stall_speed: float, window: float) -> None:
        """Wheels steady at >= stall_speed for the whole window while the body's speed (the IMU
        integrated) fell by most of it."""
        body, wheels = self._body, self._wheels
        dt = stamp - body[-1][0] if body else 0.0
        body.append((stamp, ax * dt))
        while body and body[0][0] < stamp - window:
            body.popleft()
        while len(wheels) > 1 and wheels[1][0] <= stamp - window:
            wheels.popleft()
        if not wheels or wheels[0][0] > stamp - window + 0.1 or len(body) < 3:
            return  # not a full window of wheel speeds yet
        speeds = [s for _, s in wheels]
        lo, hi = min(speeds), max(speeds)
        if min(abs(lo), abs(hi)) < stall_speed or lo * hi <= 0 or hi - lo > 0.2 * max(abs(lo), abs(hi)):
            return  # wheels not turning steadily one way
        lost = -math.copysign(1.0, v) * sum(d for _, d in body)
        if lost > 0.7 * min(abs(lo), abs(hi)):
            self.event = (stamp, 0.0 if v > 0 else math.pi, "blocked")
            body.clear()
