"""The runtime's messages as ROS 2 messages, on the writer thread: CDR bytes for the high-rate
types (through ``layout.py``), and for the others plain tuples of their fields encoded by the
compiled encoder (``cdr_encoder.py``; no rosbags message objects built per message).

Each converter takes ``(state, topic, t, payload)`` and returns ``[(topic, typename, msg)]``
(one input may give several outputs: an odometry message also gives the odom -> base_link
transform). ``ConvertState`` keeps what a conversion needs from earlier messages (the last
odometry pose, to publish map -> odom from a localized pose).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np

from .cdr_encoder import encoder
from .config import Frames
from .layout import Layout
from .types import msg_class

T = msg_class
Time = T("builtin_interfaces/msg/Time")
Header = T("std_msgs/msg/Header")
Vector3 = T("geometry_msgs/msg/Vector3")
Point = T("geometry_msgs/msg/Point")
Quaternion = T("geometry_msgs/msg/Quaternion")
Pose = T("geometry_msgs/msg/Pose")
PoseStamped = T("geometry_msgs/msg/PoseStamped")
PoseWithCovariance = T("geometry_msgs/msg/PoseWithCovariance")
Twist = T("geometry_msgs/msg/Twist")
TwistWithCovariance = T("geometry_msgs/msg/TwistWithCovariance")
Transform = T("geometry_msgs/msg/Transform")
TransformStamped = T("geometry_msgs/msg/TransformStamped")
TFMessage = T("tf2_msgs/msg/TFMessage")
LaserScan = T("sensor_msgs/msg/LaserScan")
Imu = T("sensor_msgs/msg/Imu")
BatteryState = T("sensor_msgs/msg/BatteryState")
Odometry = T("nav_msgs/msg/Odometry")
Path = T("nav_msgs/msg/Path")
OccupancyGrid = T("nav_msgs/msg/OccupancyGrid")
MapMetaData = T("nav_msgs/msg/MapMetaData")
DiagnosticArray = T("diagnostic_msgs/msg/DiagnosticArray")
DiagnosticStatus = T("diagnostic_msgs/msg/DiagnosticStatus")
KeyValue = T("diagnostic_msgs/msg/KeyValue")
Log = T("rcl_interfaces/msg/Log")
BehaviorTreeLog = T("nav2_msgs/msg/BehaviorTreeLog")
BehaviorTreeStatusChange = T("nav2_msgs/msg/BehaviorTreeStatusChange")

COV36 = np.zeros(36, np.float64)
COV9 = np.zeros(9, np.float64)
NO_COV9 = np.array([-1.0] + [0.0] * 8)  # REP 145: -1 in the first element = not provided
EMPTY32 = np.zeros(0, np.float32)
LOG_INFO, LOG_WARN, LOG_ERROR = 20, 30, 40

Output = list[tuple[str, str, Any]]

PATH_T, BATTERY_T, GRID_T = "nav_msgs/msg/Path", "sensor_msgs/msg/BatteryState", "nav_msgs/msg/OccupancyGrid"
TF_T, TREE_LOG_T = "tf2_msgs/msg/TFMessage", "nav2_msgs/msg/BehaviorTreeLog"
DIAG_T, LOG_T = "diagnostic_msgs/msg/DiagnosticArray", "rcl_interfaces/msg/Log"
NO_CELLS = b""  # an empty float32[]


def stamp(t: float) -> Any:
    sec, ns = divmod(int(round(t * 1e9)), 1_000_000_000)
    return Time(sec, ns)


def quat(yaw: float) -> Any:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def pose(x: float, y: float, yaw: float) -> Any:
    return Pose(position=Point(x=float(x), y=float(y), z=0.0), orientation=quat(yaw))


def transform(t: float | Any, parent: str, child: str, x: float, y: float, yaw: float) -> Any:
    """``t``: seconds, or a Time already made for the same instant."""
    when = stamp(t) if isinstance(t, float | int) else t
    return TransformStamped(header=Header(stamp=when, frame_id=parent), child_frame_id=child,
                            transform=Transform(translation=Vector3(x=float(x), y=float(y), z=0.0),
                                                rotation=quat(yaw)))


def twist(linear: float, angular: float) -> Any:
    return Twist(linear=Vector3(x=float(linear), y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=float(angular)))


@dataclass
class ConvertState:
    """Conversion state of one writer thread. The high-rate types (imu, odometry, tf, twist,
    scan) are encoded through a ``Layout`` each (``layout.py``: rosbags' bytes of a template
    message with the changing fields rewritten), made on first use and kept here."""

    frames: Frames = field(default_factory=Frames)
    tf_topic: str = "/tf"
    odom_pose: tuple[float, float, float] | None = None  # last odom -> base_link
    layouts: dict[Any, Layout] = field(default_factory=dict)
    # loop-clock seconds -> robot time (the driver's ``robot_time``: ROS time under --driver ros2);
    # None: the loop clock is the robot's clock (the simulator)
    robot_time: Callable[[float], float | None] | None = None
    # odometry-like topic -> a geometry_msgs/msg/PoseStamped topic of the same pose (Foxglove's 3D
    # panel draws poses, not nav_msgs/msg/Odometry)
    pose_topics: dict[str, str] = field(default_factory=dict)

    def robot(self, t: float) -> float:
        """A loop-clock time as robot time, the time of every stamp and log time in a recording."""
        to_robot = self.robot_time
        if to_robot is None:
            return t
        robot = to_robot(t)
        return t if robot is None else robot

    def sec_ns(self, t: float) -> tuple[int, int]:
        """``(sec, nanosec)`` of the robot time at loop-clock time ``t``."""
        return divmod(int(round(self.robot(t) * 1e9)), 1_000_000_000)

    def stamp(self, t: float) -> Any:
        """builtin_interfaces/msg/Time of the robot time at loop-clock time ``t``."""
        return Time(*self.sec_ns(t))

    def layout(self, key: Any, make: Callable[..., Layout], *args: Any) -> Layout:
        found = self.layouts.get(key)
        if found is None:
            found = self.layouts[key] = shared_layout(make, *args)
        return found


@cache
def shared_layout(make: Callable[..., Layout], *args: Any) -> Layout:
    """A layout is fixed by its maker and arguments (frames, scan length) and never changes once
    made: one per process, so a campaign's recordings (``scenarios --record``) do not each learn
    the same offsets again (~5 ms a recording)."""
    return make(*args)


def _fields(prefix: tuple[str | int, ...], names: str, code: str = "d") -> list[tuple[tuple[str | int, ...], str]]:
    return [((*prefix, name), code) for name in names]


STAMP = _fields(("header", "stamp"), ("sec",), "i") + _fields(("header", "stamp"), ("nanosec",), "I")
# pose: position x y z, orientation x y z w (adjacent on the wire: one slot run)
POSE = _fields(("pose", "pose", "position"), "xyz") + _fields(("pose", "pose", "orientation"), "xyzw")
TWIST = _fields(("linear",), "xyz") + _fields(("angular",), "xyz")


def odometry_layout(frame: str, child: str) -> Layout:
    msg = Odometry(header=Header(stamp=Time(0, 0), frame_id=frame), child_frame_id=child,
                   pose=PoseWithCovariance(pose=pose(0.0, 0.0, 0.0), covariance=COV36.copy()),
                   twist=TwistWithCovariance(twist=twist(0.0, 0.0), covariance=COV36.copy()))
    return Layout("nav_msgs/msg/Odometry", msg, STAMP + POSE + [(("twist", "twist", *p), c) for p, c in TWIST])


def pose_stamped_layout(frame: str) -> Layout:
    msg = PoseStamped(header=Header(stamp=Time(0, 0), frame_id=frame), pose=pose(0.0, 0.0, 0.0))
    return Layout("geometry_msgs/msg/PoseStamped", msg, STAMP + _fields(("pose", "position"), "xyz")
                  + _fields(("pose", "orientation"), "xyzw"))


def tf_layout(parent: str, child: str) -> Layout:
    msg = TFMessage(transforms=[transform(0.0, parent, child, 0.0, 0.0, 0.0)])
    first = ("transforms", 0)
    return Layout("tf2_msgs/msg/TFMessage", msg,
                  [((*first, *p), c) for p, c in STAMP]
                  + _fields((*first, "transform", "translation"), "xyz")
                  + _fields((*first, "transform", "rotation"), "xyzw"))


def imu_layout(frame: str) -> Layout:
    msg = Imu(header=Header(stamp=Time(0, 0), frame_id=frame), orientation=quat(0.0),
              orientation_covariance=COV9.copy(), angular_velocity=Vector3(x=0.0, y=0.0, z=0.0),
              angular_velocity_covariance=COV9.copy(), linear_acceleration=Vector3(x=0.0, y=0.0, z=0.0),
              linear_acceleration_covariance=COV9.copy())
    return Layout("sensor_msgs/msg/Imu", msg, STAMP + _fields(("orientation",), "xyzw")
                  + _fields(("angular_velocity",), "xyz") + _fields(("linear_acceleration",), "xyz"))


def twist_layout() -> Layout:
    return Layout("geometry_msgs/msg/Twist", twist(0.0, 0.0), TWIST)


SCAN_FLOATS = ("angle_min", "angle_max", "angle_increment", "time_increment", "scan_time", "range_min", "range_max")


def scan_layout(frame: str, n: int) -> Layout:
    msg = LaserScan(header=Header(stamp=Time(0, 0), frame_id=frame), angle_min=0.0, angle_max=0.0,
                    angle_increment=0.0, time_increment=0.0, scan_time=0.0, range_min=0.0, range_max=0.0,
                    ranges=np.zeros(n, np.float32), intensities=EMPTY32)
    ranges = [(("ranges", 0), f"{n}f")] if n else []
    return Layout("sensor_msgs/msg/LaserScan", msg, STAMP + [((name,), "f") for name in SCAN_FLOATS] + ranges)


# -- sensors ------------------------------------------------------------------------------------

def scan(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    ranges = np.ascontiguousarray(m.ranges, dtype="<f4")
    n = len(ranges)
    layout = s.layout(("scan", n), scan_layout, s.frames.laser, n)
    sec, ns = s.sec_ns(m.stamp)
    angle_min, step = float(m.angle_min), float(m.angle_increment)
    values = (sec, ns, angle_min, angle_min + step * max(n - 1, 0), step, 0.0, 0.0, float(m.range_min),
              float(m.range_max))
    data = layout.encode(*values, ranges.tobytes()) if n else layout.encode(*values)
    return [(topic, "sensor_msgs/msg/LaserScan", data)]


def _odometry_bytes(s: ConvertState, layout: Layout, m: Any) -> bytes:
    p, tw = m.pose, m.twist
    sec, ns = s.sec_ns(m.stamp)
    half = p.yaw / 2.0
    return layout.encode(sec, ns, float(p.x), float(p.y), 0.0, 0.0, 0.0, math.sin(half), math.cos(half),
                         float(tw.linear), 0.0, 0.0, 0.0, 0.0, float(tw.angular))


def _tf_bytes(s: ConvertState, layout: Layout, t: float, x: float, y: float, yaw: float) -> bytes:
    sec, ns = s.sec_ns(t)
    half = yaw / 2.0
    return layout.encode(sec, ns, float(x), float(y), 0.0, 0.0, 0.0, math.sin(half), math.cos(half))


def odom(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    f = s.frames
    p = m.pose
    s.odom_pose = (p.x, p.y, p.yaw)
    msg = _odometry_bytes(s, s.layout("odom", odometry_layout, f.odom, f.base), m)
    tf = _tf_bytes(s, s.layout("tf_odom", tf_layout, f.odom, f.base), m.stamp, p.x, p.y, p.yaw)
    return [(topic, "nav_msgs/msg/Odometry", msg), (s.tf_topic, "tf2_msgs/msg/TFMessage", tf)]


def localized(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    """map -> odom, so that map -> odom -> base_link is the localized pose (as AMCL does)."""
    if s.odom_pose is None:
        return []
    ox, oy, oyaw = s.odom_pose
    p = m.pose
    yaw = p.yaw - oyaw
    c, sn = math.cos(yaw), math.sin(yaw)
    x = p.x - (c * ox - sn * oy)
    y = p.y - (sn * ox + c * oy)
    f = s.frames
    tf = _tf_bytes(s, s.layout("tf_map", tf_layout, f.map, f.odom), m.stamp, x, y, yaw)
    return [(topic, "tf2_msgs/msg/TFMessage", tf)]


def imu(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    layout = s.layout("imu", imu_layout, s.frames.imu)
    sec, ns = s.sec_ns(m.stamp)
    half = m.yaw / 2.0
    data = layout.encode(sec, ns, 0.0, 0.0, math.sin(half), math.cos(half), 0.0, 0.0, float(m.yaw_rate),
                         float(m.accel_x), float(m.accel_y), 0.0)
    return [(topic, "sensor_msgs/msg/Imu", data)]


def _supply_status(m: Any) -> int:
    """The monitor's own status (charging, full on the dock...); a reading without one is
    judged from its current, as before: drawing current = discharging."""
    status = int(getattr(m, "power_supply_status", 0) or 0)
    if status:
        return status
    return 2 if m.current > 0 else 0  # DISCHARGING / UNKNOWN


def battery(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    nan = math.nan
    capacity = float(m.capacity_ah) if m.capacity_ah else nan
    msg = ((s.sec_ns(m.stamp), s.frames.base), float(m.voltage), nan, -float(m.current), nan, capacity, capacity,
           float(m.percentage) / 100.0, _supply_status(m), 0, 0, True, NO_CELLS, NO_CELLS, "", "")
    return [(topic, BATTERY_T, encoder(BATTERY_T)(msg))]


def _pose_values(x: float, y: float, yaw: float) -> tuple:
    """geometry_msgs/msg/Pose as the encoder's tuple."""
    half = yaw / 2.0
    return ((float(x), float(y), 0.0), (0.0, 0.0, math.sin(half), math.cos(half)))


def plan(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    header = (s.sec_ns(m.stamp), s.frames.map)
    rows = np.asarray(m.points, dtype=np.float64).tolist()
    n = len(rows)
    poses = []
    yaw = 0.0  # the last point keeps the heading before it
    for i, row in enumerate(rows):
        if len(row) > 2:
            yaw = row[2]
        elif i + 1 < n:
            nxt = rows[i + 1]
            yaw = math.atan2(nxt[1] - row[1], nxt[0] - row[0])
        half = yaw / 2.0
        poses.append((header, ((row[0], row[1], 0.0), (0.0, 0.0, math.sin(half), math.cos(half)))))
    return [(topic, PATH_T, encoder(PATH_T)((header, poses)))]


def occupancy(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    h, w = m.data.shape
    ox, oy, oyaw = m.origin
    when = s.sec_ns(t)
    msg = ((when, s.frames.map), (when, float(m.resolution), int(w), int(h), _pose_values(ox, oy, oyaw)),
           np.ascontiguousarray(m.data, dtype=np.int8).tobytes())
    return [(topic, GRID_T, encoder(GRID_T)(msg))]


def tf_static(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    x, y, yaw = m
    f = s.frames
    tf = ([((s.sec_ns(t), f.base), f.laser, _pose_values(x, y, yaw))],)
    return [(topic, TF_T, encoder(TF_T)(tf))]


# -- commands -----------------------------------------------------------------------------------

def command(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    data = s.layout("twist", twist_layout).encode(float(m.linear), 0.0, 0.0, 0.0, 0.0, float(m.angular))
    return [(topic, "geometry_msgs/msg/Twist", data)]


# -- the autonomy layer -------------------------------------------------------------------------

def tree_log(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    """m: [(t, node, previous, current)] of one tick, as Nav2's RosTopicLogger sends them."""
    stamps: dict[float, Any] = {}
    events = []
    for et, node, prev, cur in m:
        when = stamps.get(et)
        if when is None:
            when = stamps[et] = s.sec_ns(et)
        events.append((when, node.name, node.config.uid & 0xFFFF, prev.name, cur.name))
    return [(topic, TREE_LOG_T, encoder(TREE_LOG_T)((s.sec_ns(t), events)))]


DIAG_LEVEL = {"ok": 0, "unknown": 3, "restarting": 1, "failed": 2, "dead": 2}


def diagnostics(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    """m: [(name, kind, state, age, restarts, failures)] of every supervised component."""
    status = [(DIAG_LEVEL.get(state, 3), f"supervisor: {name}", state, kind,
               [("last_seen_age_s", "" if age is None else f"{age:.3f}"), ("restarts", str(restarts)),
                ("failures", str(failures))])
              for name, kind, state, age, restarts, failures in m]
    return [(topic, DIAG_T, encoder(DIAG_T)(((s.sec_ns(t), ""), status)))]


def log_line(s: ConvertState, t: float, level: int, name: str, text: str) -> bytes:
    """rcl_interfaces/msg/Log, encoded."""
    return encoder(LOG_T)((s.sec_ns(t), level, name, text, "", "", 0))


def supervisor_event(s: ConvertState, topic: str, t: float, e: Any) -> Output:
    state = e.state.value
    level = LOG_WARN if state in ("failed", "dead") else LOG_INFO
    text = f"{e.component}: {e.previous.value} -> {state}" + (f" ({e.reason})" if e.reason else "")
    return [(topic, LOG_T, log_line(s, e.t, level, "supervisor", text))]


def gate_event(s: ConvertState, topic: str, t: float, e: Any) -> Output:
    level = LOG_WARN if e.source in ("estop", "deadman", "lock") else LOG_INFO
    text = f"{e.previous} -> {e.source}: {e.reason}"
    return [(topic, LOG_T, log_line(s, e.t, level, "gate", text))]


# -- hook kinds ---------------------------------------------------------------------------------

def odometry_like(s: ConvertState, topic: str, t: float, m: Any) -> Output:
    f = s.frames
    msg = _odometry_bytes(s, s.layout(("odometry", topic), odometry_layout, f.map, f.base), m)
    out = [(topic, "nav_msgs/msg/Odometry", msg)]
    pose_topic = s.pose_topics.get(topic)
    if pose_topic:
        p = m.pose
        sec, ns = s.sec_ns(m.stamp)
        half = p.yaw / 2.0
        data = s.layout(("pose", pose_topic), pose_stamped_layout, f.map).encode(
            sec, ns, float(p.x), float(p.y), 0.0, 0.0, 0.0, math.sin(half), math.cos(half))
        out.append((pose_topic, "geometry_msgs/msg/PoseStamped", data))
    return out


def event(s: ConvertState, topic: str, t: float, e: Any) -> Output:
    text = f"{e.kind} " + json.dumps(e.data, default=str, sort_keys=True)
    return [(topic, LOG_T, log_line(s, e.t, LOG_WARN, "sim", text))]


CONVERTERS: dict[str, Callable[[ConvertState, str, float, Any], Output]] = {
    "scan": scan, "odom": odom, "pose": localized, "imu": imu, "battery": battery, "plan": plan,
    "map": occupancy, "tf_static": tf_static, "command": command, "tree_log": tree_log,
    "diagnostics": diagnostics, "supervisor_event": supervisor_event, "gate_event": gate_event,
    "odometry": odometry_like, "event": event,
}

POSE_TYPE = "geometry_msgs/msg/PoseStamped"  # an odometry-like stream's pose_topic (hooks.StreamSpec)

# the type each kind is written as ("odom" also writes tf2_msgs/msg/TFMessage on the tf topic)
KIND_TYPES: dict[str, str] = {
    "scan": "sensor_msgs/msg/LaserScan", "odom": "nav_msgs/msg/Odometry", "pose": "tf2_msgs/msg/TFMessage",
    "imu": "sensor_msgs/msg/Imu", "battery": "sensor_msgs/msg/BatteryState", "plan": "nav_msgs/msg/Path",
    "map": "nav_msgs/msg/OccupancyGrid", "tf_static": "tf2_msgs/msg/TFMessage", "command": "geometry_msgs/msg/Twist",
    "tree_log": "nav2_msgs/msg/BehaviorTreeLog", "diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "supervisor_event": "rcl_interfaces/msg/Log", "gate_event": "rcl_interfaces/msg/Log",
    "odometry": "nav_msgs/msg/Odometry", "event": "rcl_interfaces/msg/Log",
}
