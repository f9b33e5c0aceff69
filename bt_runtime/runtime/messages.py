"""Messages that flow between the driver, the autonomy layer and the tree.

Plain slotted dataclasses (no validation): they travel on the 100 Hz path. Times (``stamp``)
are seconds on the event loop's clock (``loop.time()``), which is the simulation clock in
simulation and the monotonic clock on hardware. Angles are radians, distances metres,
velocities SI, poses in the map frame unless named otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum, IntEnum

import numpy as np


def wrap_angle(angle):
    """``angle`` (a float or a numpy array) wrapped to [-pi, pi): the one convention for yaw
    differences, shared by the nodes and the simulator."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def yaw_from_quaternion(qx: float, qy: float, qz: float, qw: float) -> float:
    """The yaw (rotation about z) of a quaternion, as ROS's tf2 getYaw computes it."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


@dataclass(slots=True, frozen=True)
class Pose2D:
    x: float
    y: float
    yaw: float = 0.0

    def distance_to(self, other: Pose2D) -> float:
        return math.hypot(other.x - self.x, other.y - self.y)

    @classmethod
    def from_string(cls, text: str) -> Pose2D:
        """'x;y[;yaw]' or 'x,y[,yaw]' (how poses are written in XML ports and on the CLI)."""
        sep = ";" if ";" in text else ","
        parts = [p for p in text.replace(" ", "").split(sep) if p]
        if len(parts) not in (2, 3):
            raise ValueError(f"a pose is 'x;y' or 'x;y;yaw', got {text!r}")
        vals = [float(p) for p in parts]
        return cls(*vals)

    def to_string(self) -> str:
        return f"{self.x:g};{self.y:g};{self.yaw:g}"


@dataclass(slots=True, frozen=True)
class Twist:
    """A planar velocity command: forward speed (m/s) and yaw rate (rad/s)."""

    linear: float = 0.0
    angular: float = 0.0

    @property
    def is_zero(self) -> bool:
        return self.linear == 0.0 and self.angular == 0.0


ZERO_TWIST = Twist(0.0, 0.0)


@dataclass(slots=True)
class LaserScan:
    stamp: float
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray  # float32/float64, NaN or inf where nothing was hit

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))


@dataclass(slots=True)
class Imu:
    stamp: float
    yaw_rate: float  # rad/s about z
    accel_x: float  # m/s^2, robot frame (forward)
    accel_y: float  # m/s^2, robot frame (left)
    yaw: float = 0.0  # orientation estimate (integrated), rad


@dataclass(slots=True)
class Odometry:
    stamp: float
    pose: Pose2D  # odom frame
    twist: Twist  # robot frame


@dataclass(slots=True)
class LocalizedPose:
    """The robot's pose in the map frame (AMCL-like), with a scalar uncertainty."""

    stamp: float
    pose: Pose2D
    covariance: float = 0.0


@dataclass(slots=True)
class Contact:
    """A bumper reading: whether it is pressed and which of its segments are (indices into the
    robot's ``RobotInfo.bumper_segments``). A real bumper says nothing about where on the
    segment or how hard, so neither does this message. ``direction`` (robot frame, rad,
    0 = ahead, +pi/2 = left) is for bumpers that report a bearing themselves; NaN otherwise."""

    stamp: float
    in_contact: bool
    segments: tuple[int, ...] = ()
    direction: float = math.nan


# sensor_msgs/BatteryState power_supply_status values
POWER_SUPPLY_UNKNOWN, POWER_SUPPLY_CHARGING, POWER_SUPPLY_DISCHARGING = 0, 1, 2
POWER_SUPPLY_NOT_CHARGING, POWER_SUPPLY_FULL = 3, 4


@dataclass(slots=True)
class BatteryState:
    """A battery monitor's reading. ``power_supply_status`` is sensor_msgs' (0 unknown,
    1 charging, 2 discharging, 3 not charging, 4 full): how a robot learns it is on its charger."""

    stamp: float
    voltage: float
    percentage: float  # state of charge, 0..100
    current: float = 0.0  # A, positive when discharging
    power: float = 0.0  # W being drawn
    capacity_ah: float = 0.0
    power_supply_status: int = POWER_SUPPLY_UNKNOWN

    @property
    def on_charger(self) -> bool:
        """The monitor says a charger is connected (charging, or full on the charger)."""
        return self.power_supply_status in (POWER_SUPPLY_CHARGING, POWER_SUPPLY_FULL)


@dataclass(slots=True)
class Path:
    """A planned path: an (N, 2) or (N, 3) array of map-frame points."""

    stamp: float
    points: np.ndarray

    @property
    def length(self) -> float:
        if len(self.points) < 2:
            return 0.0
        d = np.diff(self.points[:, :2], axis=0)
        return float(np.hypot(d[:, 0], d[:, 1]).sum())

    def __len__(self) -> int:
        return len(self.points)


# ---------------------------------------------------------------------------------------------
# Navigation (Nav2-like) results and error codes
# ---------------------------------------------------------------------------------------------

class NavErrorCode(IntEnum):
    """Nav2's action error codes (nav2_msgs), so recovery logic can branch on them."""

    NONE = 0
    # ComputePathToPose (planner server)
    PLANNER_UNKNOWN = 200
    PLANNER_INVALID_PLANNER = 201
    PLANNER_TF_ERROR = 202
    START_OUTSIDE_MAP = 203
    GOAL_OUTSIDE_MAP = 204
    START_OCCUPIED = 205
    GOAL_OCCUPIED = 206
    PLANNER_TIMEOUT = 207
    NO_VALID_PATH = 208
    # FollowPath (controller server)
    CONTROLLER_UNKNOWN = 100
    INVALID_CONTROLLER = 101
    CONTROLLER_TF_ERROR = 102
    INVALID_PATH = 103
    PATIENCE_EXCEEDED = 104
    FAILED_TO_MAKE_PROGRESS = 105
    NO_VALID_CONTROL = 106
    CONTROLLER_TIMED_OUT = 107
    # Behaviours (Spin / BackUp / DriveOnHeading / Wait)
    BEHAVIOR_UNKNOWN = 700
    BEHAVIOR_TIMEOUT = 701
    BEHAVIOR_TF_ERROR = 702
    COLLISION_AHEAD = 703
    INVALID_INPUT = 704
    # NavigateToPose (bt navigator)
    NAVIGATE_UNKNOWN = 9000
    NAVIGATE_FAILED = 9001
    NAVIGATE_CANCELED = 9002


class ActionStatus(Enum):
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"
    CANCELED = "canceled"


@dataclass(slots=True)
class NavResult:
    status: ActionStatus
    error_code: NavErrorCode = NavErrorCode.NONE
    error_msg: str = ""
    path: Path | None = None  # compute_path_to_pose returns the path here
    num_retries: int = 0  # dock_robot: the retries the docking server used

    @property
    def succeeded(self) -> bool:
        return self.status is ActionStatus.SUCCEEDED


@dataclass(slots=True)
class NavFeedback:
    stamp: float
    current_pose: Pose2D
    distance_remaining: float = math.nan
    navigation_time: float = 0.0
    number_of_recoveries: int = 0
    speed: float = 0.0


@dataclass(slots=True)
class DockFeedback:
    """dock_robot's feedback (nav2_msgs/action/DockRobot): ``state`` 1 NAV_TO_STAGING_POSE,
    2 INITIAL_PERCEPTION, 3 CONTROLLING, 4 WAIT_FOR_CHARGE, 5 RETRY; seconds since the start."""

    stamp: float
    state: int
    docking_time: float = 0.0
    num_retries: int = 0


# ---------------------------------------------------------------------------------------------
# Components (lifecycle as the driver sees it)
# ---------------------------------------------------------------------------------------------

class ComponentState(Enum):
    """What the driver knows of a component's process: it runs, it is starting, it is down."""

    ACTIVE = "active"
    STARTING = "starting"
    INACTIVE = "inactive"  # crashed or shut down
    UNKNOWN = "unknown"


@dataclass(slots=True)
class ComponentInfo:
    name: str
    kind: str  # 'sensor', 'navigation', 'base', ...
    streams: tuple[str, ...] = ()  # the streams whose messages prove it alive
    restartable: bool = True
    expected_rate_hz: float = 0.0
    state: ComponentState = ComponentState.UNKNOWN
    extra: dict = field(default_factory=dict)


@dataclass(slots=True, frozen=True)
class RobotInfo:
    """What the autonomy layer may know about the robot (from the driver's configuration).

    The power model is the paper's: P = idle + k_linear * |v| + k_angular * |w| (W), and the
    state of charge drops by P / V * dt / 3600 / capacity_ah * 100 percent.
    """

    radius: float = 0.105
    max_linear: float = 0.22
    max_angular: float = 2.84
    max_linear_accel: float = 1.0  # m/s^2; the decision gate ramps commands up no faster
    max_angular_accel: float = 12.5  # rad/s^2
    capacity_ah: float = 1.8
    voltage_nominal: float = 11.1
    idle_power_w: float = 6.0
    k_linear: float = 12.0  # W per m/s
    k_angular: float = 1.0  # W per rad/s
    # bumper segments as (start, width) in radians, robot frame, counter-clockwise from ahead;
    # empty: the robot has no bumper (collisions are sensed by the IMU alone)
    bumper_segments: tuple[tuple[float, float], ...] = ()
    # the lidar's mount in the base frame (m, m, rad): scans are in its frame (the safety zones
    # turn them into the base frame with it)
    lidar_x: float = 0.0
    lidar_y: float = 0.0
    lidar_yaw: float = 0.0

    def power(self, linear: float, angular: float = 0.0) -> float:
        return self.idle_power_w + self.k_linear * abs(linear) + self.k_angular * abs(angular)

    def percent_for(self, energy_wh: float, voltage: float | None = None) -> float:
        """State-of-charge percentage that ``energy_wh`` costs at ``voltage``."""
        volts = voltage or self.voltage_nominal
        return energy_wh / volts / self.capacity_ah * 100.0
