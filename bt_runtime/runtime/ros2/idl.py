"""ROS 2 message types as Cyclone DDS IDL dataclasses, declared once.

Every class carries the DDS type name rmw_cyclonedds gives it (``<pkg>::msg::dds_::<Type>_``,
``<pkg>::srv::dds_::<Srv>_Request_``, ``<pkg>::action::dds_::<Action>_SendGoal_Request_``...),
and its fields follow the ``.msg`` definition in order and width, so Cyclone's XCDR1
serializer produces the same bytes as ROS 2 (checked against ``rosbags`` in
``tests/runtime/ros2/test_cdr.py``). Messages without fields get rosidl's
``structure_needs_at_least_one_member`` byte.

Services over rmw_cyclonedds put a 16-byte header (``uint64 guid`` of the client's request
writer, ``int64 seq``) before the request or reply fields (DDS-RPC's basic mapping, which
rmw_connextdds can use, a longer one): ``service_wire`` builds those wire types. Actions are three such services (``send_goal``, ``get_result``, ``cancel_goal``)
plus the ``feedback`` and ``status`` topics (rcl_action); ``ActionTypes`` bundles the types of
one action.

Navigation types follow nav2_msgs as shipped in ROS 2 Jazzy (1.3.x, with ``error_code`` and
``error_msg`` in every result). Humble's nav2_msgs differ (no error codes in NavigateToPose's
result) and are not declared here.
(No ``from __future__ import annotations`` here: Cyclone resolves field annotations at runtime.)
"""

from dataclasses import dataclass, field
from typing import Any

from cyclonedds.idl import IdlMeta, IdlStruct
from cyclonedds.idl._type_normalize import get_extended_type_hints
from cyclonedds.idl.types import (
    array,
    float32,
    float64,
    int8,
    int16,
    int32,
    int64,
    sequence,
    uint8,
    uint16,
    uint32,
    uint64,
)

__all__ = [
    "ActionTypes", "BackUp", "BatteryState", "Bool", "ChangeState_Request", "ChangeState_Response",
    "ComputePathToPose", "DiagnosticArray", "DiagnosticStatus", "DockRobot", "DriveOnHeading", "Duration", "Empty", "FollowPath", "GetState_Request",
    "GetState_Response", "GoalInfo", "KeyValue", "GoalStatus", "GoalStatusArray", "Header", "Imu",
    "LaserScan", "MapMetaData", "NavigateToPose", "OccupancyGrid", "String", "Odometry", "Path", "Point", "Pose", "PoseStamped",
    "PoseWithCovariance", "PoseWithCovarianceStamped", "Quaternion", "Spin", "SpeedLimit", "State", "Time",
    "Transition", "Twist", "TwistStamped", "TwistWithCovariance", "UUID", "UndockRobot", "Vector3",
    "Vector3Stamped", "Wait", "request_id", "service_wire", "unwrap", "wrap",
]


def _zeros(n: int, value: Any = 0) -> Any:
    return field(default_factory=lambda: [value] * n)


def _list() -> Any:
    return field(default_factory=list)


def _of(cls: type) -> Any:
    return field(default_factory=cls)


# --------------------------------------------------------------------------------------------
# builtin_interfaces, std_msgs, unique_identifier_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0

    @classmethod
    def now(cls) -> "Time":
        """ROS time: the system (wall) clock, as ROS 2 stamps headers."""
        import time

        return cls.from_sec(time.time())

    @classmethod
    def from_sec(cls, t: float) -> "Time":
        sec = int(t // 1)
        return cls(sec, min(int(round((t - sec) * 1e9)), 999_999_999))

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32 = 0
    nanosec: uint32 = 0

    @classmethod
    def from_sec(cls, t: float) -> "Duration":
        sec = int(t // 1)
        return cls(sec, min(int(round((t - sec) * 1e9)), 999_999_999))

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = _of(Time)
    frame_id: str = ""


@dataclass
class Empty(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    structure_needs_at_least_one_member: uint8 = 0


@dataclass
class Bool(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool = False


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16] = _zeros(16)


# --------------------------------------------------------------------------------------------
# geometry_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Vector3Stamped(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3Stamped_"):
    header: Header = _of(Header)
    vector: Vector3 = _of(Vector3)


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = _of(Point)
    orientation: Quaternion = _of(Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = _of(Header)
    pose: Pose = _of(Pose)


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose = _of(Pose)
    covariance: array[float64, 36] = _zeros(36, 0.0)


@dataclass
class PoseWithCovarianceStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"):
    header: Header = _of(Header)
    pose: PoseWithCovariance = _of(PoseWithCovariance)


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = _of(Vector3)
    angular: Vector3 = _of(Vector3)


@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header = _of(Header)
    twist: Twist = _of(Twist)


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist = _of(Twist)
    covariance: array[float64, 36] = _zeros(36, 0.0)


# --------------------------------------------------------------------------------------------
# sensor_msgs, nav_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header = _of(Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = _list()
    intensities: sequence[float32] = _list()


@dataclass
class Imu(IdlStruct, typename="sensor_msgs::msg::dds_::Imu_"):
    header: Header = _of(Header)
    orientation: Quaternion = _of(Quaternion)
    orientation_covariance: array[float64, 9] = _zeros(9, 0.0)
    angular_velocity: Vector3 = _of(Vector3)
    angular_velocity_covariance: array[float64, 9] = _zeros(9, 0.0)
    linear_acceleration: Vector3 = _of(Vector3)
    linear_acceleration_covariance: array[float64, 9] = _zeros(9, 0.0)


@dataclass
class BatteryState(IdlStruct, typename="sensor_msgs::msg::dds_::BatteryState_"):
    header: Header = _of(Header)
    voltage: float32 = 0.0
    temperature: float32 = 0.0
    current: float32 = 0.0
    charge: float32 = 0.0
    capacity: float32 = 0.0
    design_capacity: float32 = 0.0
    percentage: float32 = 0.0  # 0..1 in ROS (we use 0..100 inside)
    power_supply_status: uint8 = 0
    power_supply_health: uint8 = 0
    power_supply_technology: uint8 = 0
    present: bool = True
    cell_voltage: sequence[float32] = _list()
    cell_temperature: sequence[float32] = _list()
    location: str = ""
    serial_number: str = ""


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header = _of(Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = _of(PoseWithCovariance)
    twist: TwistWithCovariance = _of(TwistWithCovariance)


@dataclass
class Path(IdlStruct, typename="nav_msgs::msg::dds_::Path_"):
    header: Header = _of(Header)
    poses: sequence[PoseStamped] = _list()


@dataclass
class MapMetaData(IdlStruct, typename="nav_msgs::msg::dds_::MapMetaData_"):
    map_load_time: Time = _of(Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = _of(Pose)


@dataclass
class OccupancyGrid(IdlStruct, typename="nav_msgs::msg::dds_::OccupancyGrid_"):
    header: Header = _of(Header)
    info: MapMetaData = _of(MapMetaData)
    data: sequence[int8] = _list()


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


@dataclass
class CollisionMonitorState(IdlStruct, typename="nav2_msgs::msg::dds_::CollisionMonitorState_"):
    """action_type: 0 none, 1 stop, 2 slowdown, 3 approach, 4 limit (nav2_msgs' constants)."""

    action_type: uint8 = 0
    polygon_name: str = ""


# --------------------------------------------------------------------------------------------
# diagnostic_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str = ""
    value: str = ""


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    OK = 0
    WARN = 1
    ERROR = 2
    STALE = 3
    level: int8 = 0  # rosidl "byte" (one octet on the wire; levels are 0..3, and rosbags reads it signed)
    name: str = ""
    message: str = ""
    hardware_id: str = ""
    values: sequence[KeyValue] = _list()


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header = _of(Header)
    status: sequence[DiagnosticStatus] = _list()


# --------------------------------------------------------------------------------------------
# lifecycle_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class State(IdlStruct, typename="lifecycle_msgs::msg::dds_::State_"):
    PRIMARY_STATE_UNKNOWN = 0
    PRIMARY_STATE_UNCONFIGURED = 1
    PRIMARY_STATE_INACTIVE = 2
    PRIMARY_STATE_ACTIVE = 3
    PRIMARY_STATE_FINALIZED = 4
    id: uint8 = 0
    label: str = ""


@dataclass
class Transition(IdlStruct, typename="lifecycle_msgs::msg::dds_::Transition_"):
    TRANSITION_CONFIGURE = 1
    TRANSITION_CLEANUP = 2
    TRANSITION_ACTIVATE = 3
    TRANSITION_DEACTIVATE = 4
    id: uint8 = 0
    label: str = ""


@dataclass
class ChangeState_Request(IdlStruct, typename="lifecycle_msgs::srv::dds_::ChangeState_Request_"):  # noqa: N801
    transition: Transition = _of(Transition)


@dataclass
class ChangeState_Response(IdlStruct, typename="lifecycle_msgs::srv::dds_::ChangeState_Response_"):  # noqa: N801
    success: bool = False


@dataclass
class GetState_Request(IdlStruct, typename="lifecycle_msgs::srv::dds_::GetState_Request_"):  # noqa: N801
    structure_needs_at_least_one_member: uint8 = 0


@dataclass
class GetState_Response(IdlStruct, typename="lifecycle_msgs::srv::dds_::GetState_Response_"):  # noqa: N801
    current_state: State = _of(State)


# --------------------------------------------------------------------------------------------
# action_msgs
# --------------------------------------------------------------------------------------------

@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID = _of(UUID)
    stamp: Time = _of(Time)


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    STATUS_UNKNOWN = 0
    STATUS_ACCEPTED = 1
    STATUS_EXECUTING = 2
    STATUS_CANCELING = 3
    STATUS_SUCCEEDED = 4
    STATUS_CANCELED = 5
    STATUS_ABORTED = 6
    goal_info: GoalInfo = _of(GoalInfo)
    status: int8 = 0


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: sequence[GoalStatus] = _list()


@dataclass
class CancelGoal_Request(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):  # noqa: N801
    goal_info: GoalInfo = _of(GoalInfo)


@dataclass
class CancelGoal_Response(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):  # noqa: N801
    ERROR_NONE = 0
    ERROR_REJECTED = 1
    ERROR_UNKNOWN_GOAL_ID = 2
    ERROR_GOAL_TERMINATED = 3
    return_code: int8 = 0
    goals_canceling: sequence[GoalInfo] = _list()


# --------------------------------------------------------------------------------------------
# nav2_msgs (Jazzy)
# --------------------------------------------------------------------------------------------

@dataclass
class ClearEntireCostmap_Request(IdlStruct, typename="nav2_msgs::srv::dds_::ClearEntireCostmap_Request_"):  # noqa: N801
    request: Empty = _of(Empty)


@dataclass
class ClearEntireCostmap_Response(IdlStruct, typename="nav2_msgs::srv::dds_::ClearEntireCostmap_Response_"):  # noqa: N801
    response: Empty = _of(Empty)


@dataclass
class SpeedLimit(IdlStruct, typename="nav2_msgs::msg::dds_::SpeedLimit_"):
    header: Header = _of(Header)
    percentage: bool = False
    speed_limit: float64 = 0.0  # 0 = no limit


def _struct(name: str, typename: str, fields: list[tuple[str, Any, Any]]) -> type:
    """An IDL dataclass built at import time (for the per-action wrapper types)."""
    namespace = IdlMeta.__prepare__(name, (IdlStruct,), typename=typename)
    namespace["__annotations__"] = {}
    namespace["__module__"] = __name__
    namespace["__qualname__"] = name
    for fname, ftype, default in fields:
        namespace["__annotations__"][fname] = ftype
        namespace[fname] = default
    cls = IdlMeta(name, (IdlStruct,), namespace, typename=typename)
    return dataclass(cls)


class ActionTypes:
    """The DDS types of one ROS 2 action (goal/result/feedback and the rcl_action wrappers)."""

    def __init__(self, pkg: str, name: str, goal: list, result: list, feedback: list):
        self.name = name
        ns = f"{pkg}::action::dds_::{name}"
        self.ros_name = f"{pkg}/action/{name}"
        self.Goal = _struct(f"{name}_Goal", f"{ns}_Goal_", goal or [_NEEDS_MEMBER])
        self.Result = _struct(f"{name}_Result", f"{ns}_Result_", result or [_NEEDS_MEMBER])
        self.Feedback = _struct(f"{name}_Feedback", f"{ns}_Feedback_", feedback or [_NEEDS_MEMBER])
        self.SendGoal_Request = _struct(f"{name}_SendGoal_Request", f"{ns}_SendGoal_Request_", [
            ("goal_id", UUID, _of(UUID)), ("goal", self.Goal, _of(self.Goal))])
        self.SendGoal_Response = _struct(f"{name}_SendGoal_Response", f"{ns}_SendGoal_Response_", [
            ("accepted", bool, False), ("stamp", Time, _of(Time))])
        self.GetResult_Request = _struct(f"{name}_GetResult_Request", f"{ns}_GetResult_Request_", [
            ("goal_id", UUID, _of(UUID))])
        self.GetResult_Response = _struct(f"{name}_GetResult_Response", f"{ns}_GetResult_Response_", [
            ("status", int8, 0), ("result", self.Result, _of(self.Result))])
        self.FeedbackMessage = _struct(f"{name}_FeedbackMessage", f"{ns}_FeedbackMessage_", [
            ("goal_id", UUID, _of(UUID)), ("feedback", self.Feedback, _of(self.Feedback))])

    def __repr__(self) -> str:
        return f"ActionTypes({self.ros_name})"


_NEEDS_MEMBER = ("structure_needs_at_least_one_member", uint8, 0)
_ERRORS = [("error_code", uint16, 0), ("error_msg", str, "")]

NavigateToPose = ActionTypes("nav2_msgs", "NavigateToPose", goal=[
    ("pose", PoseStamped, _of(PoseStamped)), ("behavior_tree", str, "")],
    result=_ERRORS, feedback=[
    ("current_pose", PoseStamped, _of(PoseStamped)), ("navigation_time", Duration, _of(Duration)),
    ("estimated_time_remaining", Duration, _of(Duration)), ("number_of_recoveries", int16, 0),
    ("distance_remaining", float32, 0.0)])

ComputePathToPose = ActionTypes("nav2_msgs", "ComputePathToPose", goal=[
    ("goal", PoseStamped, _of(PoseStamped)), ("start", PoseStamped, _of(PoseStamped)),
    ("planner_id", str, ""), ("use_start", bool, False)],
    result=[("path", Path, _of(Path)), ("planning_time", Duration, _of(Duration)), *_ERRORS],
    feedback=[])

FollowPath = ActionTypes("nav2_msgs", "FollowPath", goal=[
    ("path", Path, _of(Path)), ("controller_id", str, ""), ("goal_checker_id", str, ""),
    ("progress_checker_id", str, "")],
    result=[("result", Empty, _of(Empty)), *_ERRORS],
    feedback=[("distance_to_goal", float32, 0.0), ("speed", float32, 0.0)])

Spin = ActionTypes("nav2_msgs", "Spin", goal=[
    ("target_yaw", float32, 0.0), ("time_allowance", Duration, _of(Duration))],
    result=[("total_elapsed_time", Duration, _of(Duration)), *_ERRORS],
    feedback=[("angular_distance_traveled", float32, 0.0)])

BackUp = ActionTypes("nav2_msgs", "BackUp", goal=[
    ("target", Point, _of(Point)), ("speed", float32, 0.0), ("time_allowance", Duration, _of(Duration))],
    result=[("total_elapsed_time", Duration, _of(Duration)), *_ERRORS],
    feedback=[("distance_traveled", float32, 0.0)])

DriveOnHeading = ActionTypes("nav2_msgs", "DriveOnHeading", goal=[
    ("target", Point, _of(Point)), ("speed", float32, 0.0), ("time_allowance", Duration, _of(Duration))],
    result=[("total_elapsed_time", Duration, _of(Duration)), *_ERRORS],
    feedback=[("distance_traveled", float32, 0.0)])

Wait = ActionTypes("nav2_msgs", "Wait", goal=[("time", Duration, _of(Duration))],
                   result=[("total_elapsed_time", Duration, _of(Duration)), *_ERRORS],
                   feedback=[("time_left", Duration, _of(Duration))])

# opennav_docking (nav2_msgs, Jazzy): result codes 901-907, 999; feedback states 1-5
DockRobot = ActionTypes("nav2_msgs", "DockRobot", goal=[
    ("use_dock_id", bool, True), ("dock_id", str, ""), ("dock_pose", PoseStamped, _of(PoseStamped)),
    ("dock_type", str, ""), ("max_staging_time", float32, 1000.0), ("navigate_to_staging_pose", bool, True)],
    result=[("success", bool, True), ("error_code", uint16, 0), ("num_retries", uint16, 0), ("error_msg", str, "")],
    feedback=[("state", uint16, 0), ("docking_time", Duration, _of(Duration)), ("num_retries", uint16, 0)])

UndockRobot = ActionTypes("nav2_msgs", "UndockRobot", goal=[
    ("dock_type", str, ""), ("max_undocking_time", float32, 30.0)],
    result=[("success", bool, True), ("error_code", uint16, 0), ("error_msg", str, "")],
    feedback=[])

ACTIONS = {a.name: a for a in (NavigateToPose, ComputePathToPose, FollowPath, Spin, BackUp,
                                DriveOnHeading, Wait, DockRobot, UndockRobot)}

_WIRE_CACHE: dict[tuple, type] = {}

# How the request id travels in the payload, per ROS 2 middleware (see docs/ros2.md, "Which
# middleware"): rmw_cyclonedds puts {uint64 guid, int64 seq} before the fields; DDS-RPC's
# *basic* mapping (rmw_connextdds with RMW_CONNEXT_REQUEST_REPLY_MAPPING=basic,
# rmw_connextddsmicro) puts a RequestHeader {SampleIdentity requestId; string instanceName}
# before a request and a ReplyHeader {SampleIdentity relatedRequestId; int32 remoteEx} before
# a reply, SampleIdentity being {octet guid[16]; int32 sn_high; uint32 sn_low}.
SERVICE_MAPPINGS = ("cyclonedds", "rpc_basic")
_HEADERS = {
    ("cyclonedds", "request"): [("guid", uint64, 0), ("seq", int64, 0)],
    ("cyclonedds", "reply"): [("guid", uint64, 0), ("seq", int64, 0)],
    ("rpc_basic", "request"): [("rpc_guid", array[uint8, 16], _zeros(16)), ("rpc_sn_high", int32, 0),
                               ("rpc_sn_low", uint32, 0), ("rpc_instance_name", str, "")],
    ("rpc_basic", "reply"): [("rpc_guid", array[uint8, 16], _zeros(16)), ("rpc_sn_high", int32, 0),
                             ("rpc_sn_low", uint32, 0), ("rpc_remote_ex", int32, 0)],
}


def service_wire(body: type, mapping: str = "cyclonedds", role: str = "request") -> type:
    """The type a service puts on an ``rq/...Request`` or ``rr/...Reply`` topic: the request
    header of ``mapping`` (rmw_cyclonedds's by default) followed by the request or response
    fields, flattened (the same bytes as nesting the body in CDR, and the type may not contain
    a member of its own DDS type name). ``role``: "request" or "reply" (rpc_basic's headers
    differ). ``wrap``/``unwrap``/``request_id`` convert."""
    key = (body, mapping, role)
    wire = _WIRE_CACHE.get(key)
    if wire is None:
        from dataclasses import MISSING, fields

        try:
            members = list(_HEADERS[mapping, role])
        except KeyError:
            raise ValueError(f"service mapping {mapping!r} / role {role!r}: expected one of "
                             f"{SERVICE_MAPPINGS} and request/reply") from None
        hints = get_extended_type_hints(body)
        for f in fields(body):
            default = (field(default_factory=f.default_factory) if f.default_factory is not MISSING
                       else f.default)
            members.append((f.name, hints[f.name], default))
        suffix = "" if mapping == "cyclonedds" else f"_{mapping}_{role}"
        wire = _struct(f"{body.__name__}_Wire{suffix}", body.__idl_typename__, members)
        wire.body_type = body
        wire.body_fields = tuple(f.name for f in fields(body))
        wire.mapping = mapping
        _WIRE_CACHE[key] = wire
    return wire


def wrap(guid: Any, seq: int, body: Any, mapping: str = "cyclonedds", role: str = "request") -> Any:
    """The wire sample for a request/reply body with request id (``guid``, ``seq``): ``guid`` is
    a uint64 for rmw_cyclonedds's mapping, the 16 GUID bytes for rpc_basic."""
    wire = service_wire(type(body), mapping, role)
    fields_ = {name: getattr(body, name) for name in wire.body_fields}
    if mapping == "cyclonedds":
        return wire(guid=guid, seq=seq, **fields_)
    return wire(rpc_guid=list(bytes(guid)), rpc_sn_high=seq >> 32,
                rpc_sn_low=seq & 0xFFFF_FFFF, **fields_)


def request_id(sample: Any) -> tuple[Any, int]:
    """(guid, seq) of a wire sample, in the form ``wrap`` takes."""
    if type(sample).mapping == "cyclonedds":
        return sample.guid, sample.seq
    return bytes(sample.rpc_guid), (sample.rpc_sn_high << 32) | sample.rpc_sn_low


def unwrap(sample: Any) -> Any:
    """The request/reply body of a wire sample."""
    wire = type(sample)
    return wire.body_type(**{name: getattr(sample, name) for name in wire.body_fields})
