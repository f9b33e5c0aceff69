"""The CDR bytes of every declared ROS 2 type equal what ROS 2 puts on the wire.

``rosbags`` serializes ROS 2 messages to CDR from the ``.msg`` definitions (its own store for
the standard packages, and the nav2_msgs / service / action definitions below, copied from the
Jazzy interface files). Each IDL type is filled with random values (strings with non-ASCII
characters, sequences of several lengths, fixed arrays, nested headers), serialized by Cyclone
and by rosbags, and compared byte for byte; fields are matched by name from the ROS definition,
so a missing, extra, reordered or mis-sized field fails.
"""

import math
import random
import struct

import pytest

pytest.importorskip("cyclonedds")
rosbags_typesys = pytest.importorskip("rosbags.typesys")
np = pytest.importorskip("numpy")

from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl._type_normalize import get_extended_type_hints  # noqa: E402
from cyclonedds.idl.types import array, sequence  # noqa: E402

from bt_runtime.runtime.ros2 import idl  # noqa: E402

# Jazzy definitions (nav2_msgs 1.3.x, lifecycle_msgs, action_msgs services) -------------------
ACTION_DEFS = {
    "NavigateToPose": ("geometry_msgs/PoseStamped pose\nstring behavior_tree",
                       "uint16 NONE=0\nuint16 error_code\nstring error_msg",
                       "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
                       "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\n"
                       "float32 distance_remaining"),
    "ComputePathToPose": ("geometry_msgs/PoseStamped goal\ngeometry_msgs/PoseStamped start\nstring planner_id\n"
                          "bool use_start",
                          "nav_msgs/Path path\nbuiltin_interfaces/Duration planning_time\nuint16 error_code\n"
                          "string error_msg", ""),
    "FollowPath": ("nav_msgs/Path path\nstring controller_id\nstring goal_checker_id\nstring progress_checker_id",
                   "std_msgs/Empty result\nuint16 error_code\nstring error_msg",
                   "float32 distance_to_goal\nfloat32 speed"),
    "Spin": ("float32 target_yaw\nbuiltin_interfaces/Duration time_allowance",
             "builtin_interfaces/Duration total_elapsed_time\nuint16 error_code\nstring error_msg",
             "float32 angular_distance_traveled"),
    "BackUp": ("geometry_msgs/Point target\nfloat32 speed\nbuiltin_interfaces/Duration time_allowance",
               "builtin_interfaces/Duration total_elapsed_time\nuint16 error_code\nstring error_msg",
               "float32 distance_traveled"),
    "DriveOnHeading": ("geometry_msgs/Point target\nfloat32 speed\nbuiltin_interfaces/Duration time_allowance",
                       "builtin_interfaces/Duration total_elapsed_time\nuint16 error_code\nstring error_msg",
                       "float32 distance_traveled"),
    "Wait": ("builtin_interfaces/Duration time",
             "builtin_interfaces/Duration total_elapsed_time\nuint16 error_code\nstring error_msg",
             "builtin_interfaces/Duration time_left"),
    "DockRobot": ("bool use_dock_id true\nstring dock_id\ngeometry_msgs/PoseStamped dock_pose\nstring dock_type\n"
                  "float32 max_staging_time 1000.0\nbool navigate_to_staging_pose true",
                  "uint16 NONE=0\nuint16 DOCK_NOT_IN_DB=901\nuint16 UNKNOWN=999\nbool success true\n"
                  "uint16 error_code 0\nuint16 num_retries 0\nstring error_msg",
                  "uint16 NONE=0\nuint16 WAIT_FOR_CHARGE=4\nuint16 state\nbuiltin_interfaces/Duration docking_time\n"
                  "uint16 num_retries 0"),
    "UndockRobot": ("string dock_type\nfloat32 max_undocking_time 30.0",
                    "uint16 NONE=0\nuint16 DOCK_NOT_VALID=902\nbool success true\nuint16 error_code 0\n"
                    "string error_msg", ""),
}
SERVICE_DEFS = {
    "lifecycle_msgs/srv/ChangeState_Request": "lifecycle_msgs/Transition transition",
    "lifecycle_msgs/srv/ChangeState_Response": "bool success",
    "lifecycle_msgs/srv/GetState_Request": "",
    "lifecycle_msgs/srv/GetState_Response": "lifecycle_msgs/State current_state",
    "action_msgs/srv/CancelGoal_Request": "action_msgs/GoalInfo goal_info",
    "action_msgs/srv/CancelGoal_Response": "int8 ERROR_NONE=0\nint8 return_code\naction_msgs/GoalInfo[] goals_canceling",
    "nav2_msgs/srv/ClearEntireCostmap_Request": "std_msgs/Empty request",
    "nav2_msgs/srv/ClearEntireCostmap_Response": "std_msgs/Empty response",
    "nav2_msgs/msg/SpeedLimit": "std_msgs/Header header\nbool percentage\nfloat64 speed_limit",
    "nav2_msgs/msg/CollisionMonitorState": "uint8 DO_NOTHING=0\nuint8 STOP=1\nuint8 SLOWDOWN=2\nuint8 APPROACH=3\n"
                                           "uint8 LIMIT=4\nuint8 action_type\nstring polygon_name",
}


@pytest.fixture(scope="module")
def store():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_JAZZY)
    defs = dict(SERVICE_DEFS)
    for name, (goal, result, feedback) in ACTION_DEFS.items():
        base = f"nav2_msgs/action/{name}"
        defs[f"{base}_Goal"] = goal
        defs[f"{base}_Result"] = result
        defs[f"{base}_Feedback"] = feedback
        defs[f"{base}_SendGoal_Request"] = f"unique_identifier_msgs/UUID goal_id\n{base}_Goal goal"
        defs[f"{base}_SendGoal_Response"] = "bool accepted\nbuiltin_interfaces/Time stamp"
        defs[f"{base}_GetResult_Request"] = "unique_identifier_msgs/UUID goal_id"
        defs[f"{base}_GetResult_Response"] = f"int8 status\n{base}_Result result"
        defs[f"{base}_FeedbackMessage"] = f"unique_identifier_msgs/UUID goal_id\n{base}_Feedback feedback"
    types = {}
    for name, text in defs.items():
        # rosidl gives a message without fields one uint8 member; rosbags files services
        # under '<pkg>/srv/msg/<Name>', ROS 2 names them '<pkg>/srv/<Name>'
        text = text or "uint8 structure_needs_at_least_one_member"
        for key, value in get_types_from_msg(text, name).items():
            types[key.replace("/srv/msg/", "/srv/")] = value
    ts.register(types)
    return ts


def ros_name(cls) -> str:
    """'nav2_msgs::action::dds_::NavigateToPose_Goal_' -> 'nav2_msgs/action/NavigateToPose_Goal'."""
    typename = cls.__idl_typename__
    assert typename.endswith("_") and "::dds_::" in typename, typename
    return typename[:-1].replace("::dds_::", "::").replace("::", "/")


ALL_TYPES = sorted({
    obj for obj in vars(idl).values()
    if isinstance(obj, type) and issubclass(obj, IdlStruct) and obj is not IdlStruct
} | {t for a in idl.ACTIONS.values() for t in (
    a.Goal, a.Result, a.Feedback, a.SendGoal_Request, a.SendGoal_Response, a.GetResult_Request,
    a.GetResult_Response, a.FeedbackMessage)}, key=lambda c: c.__idl_typename__)

INT_RANGES = {"int8": (-128, 127), "uint8": (0, 255), "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
              "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1), "int64": (-2**63, 2**63 - 1),
              "uint64": (0, 2**64 - 1)}
WORDS = ["", "map", "base_link", "odom", "lidar é", "ünïcode ✓", "a" * 17]


def random_value(tp, rng: random.Random):
    if isinstance(tp, type) and issubclass(tp, IdlStruct):
        return fill(tp, rng)
    if tp is str:
        return rng.choice(WORDS)
    if tp is bool:
        return rng.random() < 0.5
    if isinstance(tp, (array, sequence)):
        n = tp.length if isinstance(tp, array) else rng.choice([0, 1, 3, 5])
        values = [random_value(tp.subtype, rng) for _ in range(n)]
        uint8 = getattr(tp.subtype, "__metadata__", ("",))[0] == "uint8"
        return bytes(values) if uint8 else values  # Cyclone reads uint8[] back as bytes
    kind = tp.__metadata__[0]
    if kind == "float32":
        return float(np.float32(rng.uniform(-1e3, 1e3)))
    if kind == "float64":
        return rng.choice([rng.uniform(-1e6, 1e6), math.pi, -0.0, 1e-300])
    lo, hi = INT_RANGES[kind]
    return rng.randint(lo, hi)


def fill(cls, rng: random.Random):
    return cls(**{name: random_value(tp, rng) for name, tp in get_extended_type_hints(cls).items()})


DTYPES = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
          "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
          "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64}


def to_rosbags(ts, obj, typename: str):
    """Build the rosbags message for ``typename`` from the IDL object, field by ROS field
    (rosbags node types: 1 base, 2 name, 3 array, 4 sequence)."""

    fields = ts.fielddefs[typename][1]
    idl_names = list(get_extended_type_hints(type(obj)))
    assert idl_names == [f for f, _ in fields], f"{typename}: fields {idl_names} != ROS {[f for f, _ in fields]}"
    kwargs = {}
    for fname, (nodetype, detail) in fields:
        kwargs[fname] = _convert(ts, getattr(obj, fname), int(nodetype), detail)
    return ts.types[typename](**kwargs)


def _convert(ts, value, nodetype: int, detail):
    if nodetype == 1:  # BASE
        return value
    if nodetype == 2:  # NAME
        return to_rosbags(ts, value, detail)
    sub, _n = detail  # ARRAY or SEQUENCE
    sub_type, sub_detail = int(sub[0]), sub[1]
    if sub_type == 1 and sub_detail[0] != "string":
        if isinstance(value, bytes):
            return np.frombuffer(value, dtype=np.uint8).copy()
        return np.array(value, dtype=DTYPES[sub_detail[0]])
    return [_convert(ts, v, sub_type, sub_detail) for v in value]


@pytest.mark.parametrize("cls", ALL_TYPES, ids=lambda c: c.__idl_typename__)
def test_cdr_equals_ros2(store, cls):
    name = ros_name(cls)
    assert name in store.fielddefs, f"no ROS definition for {name}"
    rng = random.Random(name)
    for _ in range(6):
        obj = fill(cls, rng)
        ours = obj.serialize()
        theirs = bytes(store.serialize_cdr(to_rosbags(store, obj, name), name))
        assert ours[:4] == b"\x00\x01\x00\x00", "XCDR1 little endian (CDR_LE), as rmw_cyclonedds writes"
        assert ours == theirs, f"{name}: cyclone {ours.hex()} != ros2 {theirs.hex()}"
        assert cls.deserialize(theirs) == obj  # and we read what ROS 2 writes


def test_default_values_are_ros_defaults(store):
    """Defaults equal rosidl's zero-initialised message (quaternion w stays 0 in ROS; ours is 1)."""
    scan = idl.LaserScan()
    assert scan.serialize() == bytes(store.serialize_cdr(to_rosbags(store, scan, "sensor_msgs/msg/LaserScan"),
                                                         "sensor_msgs/msg/LaserScan"))


@pytest.mark.parametrize("body", [idl.ChangeState_Request, idl.ChangeState_Response, idl.GetState_Request,
                                  idl.GetState_Response, idl.CancelGoal_Request, idl.CancelGoal_Response,
                                  idl.ClearEntireCostmap_Request, idl.ClearEntireCostmap_Response,
                                  idl.NavigateToPose.SendGoal_Request, idl.NavigateToPose.GetResult_Response,
                                  idl.ComputePathToPose.GetResult_Response, idl.Spin.SendGoal_Request])
def test_service_wire_is_header_then_body(store, body):
    """rmw_cyclonedds: request/reply samples are {uint64 guid, int64 seq} then the ROS fields."""
    wire_cls = idl.service_wire(body)
    assert wire_cls.__idl_typename__ == body.__idl_typename__
    rng = random.Random(body.__name__)
    obj = fill(body, rng)
    wire = idl.wrap(0x0123456789ABCDEF, -5, obj)
    assert type(wire) is wire_cls and idl.unwrap(wire) == obj
    name = ros_name(body)
    ros = bytes(store.serialize_cdr(to_rosbags(store, obj, name), name))
    expected = ros[:4] + struct.pack("<Qq", 0x0123456789ABCDEF, -5) + ros[4:]
    assert wire.serialize() == expected
    assert wire_cls.deserialize(expected) == wire


def test_time_conversions():
    t = idl.Time.from_sec(12.25)
    assert (t.sec, t.nanosec) == (12, 250_000_000)
    assert idl.Duration.from_sec(0.9999999999).nanosec <= 999_999_999
    assert abs(idl.Duration.from_sec(3.5).to_sec() - 3.5) < 1e-9
