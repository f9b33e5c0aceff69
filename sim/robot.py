"""Robot profiles as data: body, drive limits, sensors and battery, from YAML (pydantic).

Shipped profiles (``sim/robots/*.yaml``): ``burger`` (the default), ``waffle`` and
``rosbot2``. ``load_profile(name_or_path, **overrides)`` loads one; overrides are dotted
field names (``load_profile("burger", **{"battery.initial_soc": 30})``) or nested dicts.

The paper's scenarios drive at 0.25 m/s. A TurtleBot3 burger cannot (0.22 m/s; commands
above are clamped), so those scenarios use ``rosbot2`` (the paper's real robot, 0.9 m/s in
its ROS 2 controller configuration); ``waffle`` (0.26 m/s) could too.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from bt_runtime.yaml_files import safe_load

from .world import format_validation_error

ROBOTS_DIR = Path(__file__).parent / "robots"
SHIPPED_PROFILES = ("burger", "waffle", "rosbot2")
DEFAULT_PROFILE = "burger"


class ProfileError(ValueError):
    """A robot profile is missing or invalid; the message names the file and the field."""


class _Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)  # .inf/.nan: a clear error, not a runaway


class LidarSpec(_Spec):
    samples: int = Field(360, ge=8, le=4096)
    angle_min: float = 0.0  # first beam, sensor frame (rad); beams cover 2*pi
    range_min: float = Field(0.12, gt=0)
    range_max: float = Field(3.5, gt=0)
    rate_hz: float = Field(5.0, gt=0)
    noise_sigma: float = Field(0.01, ge=0)  # m, Gaussian
    x: float = 0.0  # mounting position in the base frame (m)
    y: float = 0.0
    z: float = 0.18  # informational: the world's blocks_lidar flags are for a ~0.13-0.18 m plane

    @model_validator(mode="after")
    def _ranges(self) -> LidarSpec:
        if self.range_min >= self.range_max:
            raise ValueError("range_min must be below range_max")
        return self

    @property
    def angle_increment(self) -> float:
        return 2 * math.pi / self.samples


class ImuSpec(_Spec):
    rate_hz: float = Field(50.0, gt=0)
    gyro_sigma: float = Field(2e-4, ge=0)  # rad/s white noise per sample
    gyro_bias_sigma: float = Field(1e-3, ge=0)  # rad/s, constant bias drawn once per run
    accel_sigma: float = Field(1.7e-2, ge=0)  # m/s^2 white noise per sample


class OdomSpec(_Spec):
    rate_hz: float = Field(50.0, gt=0)
    wheel_scale_sigma: float = Field(0.003, ge=0)  # relative wheel-radius error per wheel, drawn once
    slip_sigma: float = Field(0.02, ge=0)  # relative per-step noise on each wheel's travel


class LocalizationSpec(_Spec):
    rate_hz: float = Field(10.0, gt=0)
    sigma_xy: float = Field(0.02, ge=0)  # m, AR(1) error around ground truth
    sigma_yaw: float = Field(0.01, ge=0)  # rad
    correlation: float = Field(0.9, ge=0, lt=1)  # AR(1) coefficient per update


class BumperSegment(_Spec):
    """One bumper switch: it closes when the body is touched between ``from_deg`` and
    ``to_deg`` (robot frame, counter-clockwise, 0 = straight ahead; the span may cross 180)."""

    name: str
    from_deg: float = Field(ge=-360, le=360)
    to_deg: float = Field(ge=-360, le=360)

    @property
    def start(self) -> float:
        return math.radians(self.from_deg)

    @property
    def width(self) -> float:
        """Angular span (rad, in (0, 2*pi])."""
        w = (self.to_deg - self.from_deg) % 360.0
        return math.radians(w if w > 0 else 360.0)

    def contains(self, bearing: float) -> bool:
        return (bearing - self.start) % (2 * math.pi) <= self.width


class BumperSpec(_Spec):
    """A contact bumper as segments with known angular spans; it reports which are pressed
    (never where, nor how hard)."""

    rate_hz: float = Field(10.0, gt=0)
    segments: list[BumperSegment] = Field(min_length=1)

    def pressed(self, bearing: float) -> tuple[int, ...]:
        """Indices of the segments a touch at ``bearing`` (robot frame, rad) closes."""
        return tuple(i for i, seg in enumerate(self.segments) if seg.contains(bearing))

    def bearing(self, pressed: tuple[int, ...]) -> float:
        """The middle of the pressed segments (circular mean of their centres), NaN if none."""
        if not pressed:
            return math.nan
        x = y = 0.0
        for i in pressed:
            seg = self.segments[i]
            mid = seg.start + seg.width / 2
            x += math.cos(mid)
            y += math.sin(mid)
        return math.atan2(y, x)

    def spans(self) -> tuple[tuple[float, float], ...]:
        """(start, width) per segment in radians, as the autonomy layer is told them."""
        return tuple((seg.start, seg.width) for seg in self.segments)


class BatterySpec(_Spec):
    capacity_ah: float = Field(gt=0)
    voltage_full: float = Field(gt=0)
    voltage_empty: float = Field(gt=0)
    idle_power_w: float = Field(ge=0)  # W: computer, sensors, electronics
    k_linear: float = Field(ge=0)  # W per m/s of |v|
    k_angular: float = Field(ge=0)  # W per rad/s of |w|
    charge_power_w: float = Field(20.0, ge=0)  # W into the battery while docked
    initial_soc: float = Field(100.0, ge=0, le=100)  # %
    rate_hz: float = Field(1.0, gt=0)

    @model_validator(mode="after")
    def _volts(self) -> BatterySpec:
        if self.voltage_empty >= self.voltage_full:
            raise ValueError("voltage_empty must be below voltage_full")
        return self

    def voltage(self, soc: float) -> float:
        """Open-circuit voltage, linear in the state of charge."""
        s = min(max(soc, 0.0), 100.0) / 100.0
        return self.voltage_empty + (self.voltage_full - self.voltage_empty) * s

    def power(self, v: float, w: float) -> float:
        return self.idle_power_w + self.k_linear * abs(v) + self.k_angular * abs(w)


class RobotProfile(_Spec):
    name: str
    description: str = ""
    radius: float = Field(gt=0)  # the body is a circle of this radius around base_link
    mass: float = Field(gt=0)  # kg
    wheel_radius: float = Field(gt=0)
    wheel_separation: float = Field(gt=0)  # effective track for the kinematics
    max_linear: float = Field(gt=0)  # m/s
    max_angular: float = Field(gt=0)  # rad/s
    max_linear_accel: float = Field(gt=0)  # m/s^2
    max_angular_accel: float = Field(gt=0)  # rad/s^2
    cmd_timeout: float = Field(0.5, gt=0)  # s without a command -> stop
    traction_force: float | None = Field(None, gt=0)  # N the wheels can push with (default m*g*0.8)
    lidar: LidarSpec = Field(default_factory=LidarSpec)
    imu: ImuSpec = Field(default_factory=ImuSpec)
    odom: OdomSpec = Field(default_factory=OdomSpec)
    localization: LocalizationSpec = Field(default_factory=LocalizationSpec)
    battery: BatterySpec
    bumper: BumperSpec | None = None  # None: no bumper, collisions are sensed by the IMU alone

    @property
    def max_wheel_speed(self) -> float:
        """Max wheel rim speed (m/s): enough for max_linear straight or max_angular in place."""
        return max(self.max_linear, self.max_angular * self.wheel_separation / 2)

    @property
    def traction(self) -> float:
        return self.traction_force if self.traction_force is not None else self.mass * 9.81 * 0.8


def _set_dotted(data: dict, key: str, value: Any) -> None:
    parts = key.split(".")
    node = data
    for p in parts[:-1]:
        node = node.setdefault(p, {})
    node[parts[-1]] = value


def _merge(base: dict, over: dict) -> dict:
    out = dict(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _merge(out[k], v)
        else:
            out[k] = v
    return out


_PARSED: dict[tuple[str, int, int], Any] = {}  # (path, mtime_ns, size) -> parsed YAML


def _parsed_profile(path: Path) -> Any:
    """A profile file's YAML, parsed once per process while the file is unchanged (a campaign
    loads the same profile for every run)."""
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    if key not in _PARSED:
        try:
            data = safe_load(path.read_text())
        except yaml.YAMLError as err:
            raise ProfileError(f"{path}: not valid YAML: {err}") from None
        if len(_PARSED) >= 16:
            _PARSED.clear()
        _PARSED[key] = data
    return _PARSED[key]


def load_profile(name_or_path: str | Path = DEFAULT_PROFILE, **overrides: Any) -> RobotProfile:
    text = str(name_or_path)
    path = ROBOTS_DIR / f"{text}.yaml" if text in SHIPPED_PROFILES else Path(name_or_path)
    if not path.exists():
        raise ProfileError(f"{path}: no such robot profile (shipped: {', '.join(SHIPPED_PROFILES)})")
    data = copy.deepcopy(_parsed_profile(path))  # the caller's overrides change its own copy
    if not isinstance(data, dict):
        raise ProfileError(f"{path}: (top level): a robot profile is a mapping")
    for key, value in overrides.items():
        if isinstance(value, dict):
            data[key] = _merge(data.get(key, {}), value)
        else:
            _set_dotted(data, key, value)
    try:
        return RobotProfile.model_validate(data)
    except ValidationError as err:
        raise ProfileError(format_validation_error(str(path), err)) from None
