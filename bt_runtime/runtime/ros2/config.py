"""The ROS 2 driver's configuration: one pydantic model, loaded from one YAML file.

Every name is a ROS name (relative names go below ``namespace``). The defaults match the
names ``sim-robot`` uses and a TurtleBot3 / ROSbot with Nav2 (Jazzy) and AMCL.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

SAFETY_STREAMS = ("scan", "bumper", "nav_cmd_vel")  # the gate reads them: never deliver_at_tick


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class Qos(_Model):
    reliability: Literal["reliable", "best_effort"] = "best_effort"
    durability: Literal["volatile", "transient_local"] = "volatile"
    depth: int = Field(5, ge=1, le=1000)


class TopicConfig(_Model):
    name: str
    qos: Qos = Field(default_factory=Qos, description="reader QoS; best effort + volatile matches "
                                                          "every writer, reliable or not")


class BumperConfig(TopicConfig):
    type: Literal["bool", "vector3"] = Field(
        "bool", description="std_msgs/Bool (in contact or not), or geometry_msgs/Vector3Stamped: "
                            "x, y = direction of the contact in the base frame, z = impulse (N*s); "
                            "a zero vector is no contact")


class CmdVelConfig(_Model):
    name: str = "cmd_vel"
    stamped: bool = Field(False, description="publish geometry_msgs/TwistStamped (Jazzy's "
                                             "enable_stamped_cmd_vel) instead of Twist")
    frame_id: str = "base_link"
    qos: Qos = Field(default_factory=lambda: Qos(reliability="reliable", depth=10))
    zero_repeat_period: float = Field(
        0.1, ge=0, description="a zero that repeats the last command written (the base stands) goes on the "
                               "wire at most this often (s); any other command, and the first zero, at once. "
                               "0: every command the gate sends (100 Hz while ticking)")


class NavCmdVelConfig(TopicConfig):
    stamped: bool = False


class Topics(_Model):
    scan: TopicConfig = Field(default_factory=lambda: TopicConfig(name="scan"))
    imu: TopicConfig | None = Field(default_factory=lambda: TopicConfig(name="imu"))
    odom: TopicConfig | None = Field(default_factory=lambda: TopicConfig(name="odom"))
    pose: TopicConfig | None = Field(default_factory=lambda: TopicConfig(name="amcl_pose"),
                                     description="geometry_msgs/PoseWithCovarianceStamped (map frame)")
    battery: TopicConfig | None = Field(default_factory=lambda: TopicConfig(name="battery_state"))
    bumper: BumperConfig | None = Field(default_factory=lambda: BumperConfig(name="bumper"))
    cmd_vel: CmdVelConfig = Field(default_factory=CmdVelConfig)
    diagnostics: str | None = Field("/diagnostics", description="diagnostic_msgs/DiagnosticArray: component "
                                    "health from the supervisor at 1 Hz and on every change (None = off)")
    collision_monitor_state: str | None = Field(
        "collision_monitor_state", description="nav2_msgs/CollisionMonitorState: the gate's safety zone "
                                               "acting now, on every change, as collision_monitor (None = off)")
    nav_cmd_vel: NavCmdVelConfig | None = Field(
        default_factory=lambda: NavCmdVelConfig(name="cmd_vel_nav"),
        description="where Nav2's last velocity stage publishes (remapped away from cmd_vel)")


class Navigation(_Model):
    enabled: bool = True
    navigate_to_pose: str = "navigate_to_pose"
    compute_path_to_pose: str = "compute_path_to_pose"
    follow_path: str = "follow_path"
    spin: str = "spin"
    back_up: str = "backup"
    drive_on_heading: str = "drive_on_heading"
    wait: str = "wait"
    dock_robot: str = "dock_robot"  # opennav_docking's docking_server
    undock_robot: str = "undock_robot"
    clear_global_costmap: str = "/global_costmap/clear_entirely_global_costmap"
    clear_local_costmap: str = "/local_costmap/clear_entirely_local_costmap"
    global_costmap: str | None = Field("/global_costmap/costmap", description="nav_msgs/OccupancyGrid "
                                       "used for is_path_valid / path_clearance (None: not used)")
    speed_limit: str | None = Field("speed_limit", description="nav2_msgs/SpeedLimit topic of the "
                                    "controller server (the gate's speed limit is passed on); None = off")
    map_frame: str = "map"
    server_timeout: float = Field(5.0, gt=0, description="wait this long for an action server")
    service_timeout: float = Field(2.0, gt=0)
    server_gone_after: float = Field(1.0, gt=0, description="a goal whose server vanished for this "
                                     "long ends ABORTED")


class GoalServing(_Model):
    """Goals from any ROS 2 client, served by the runtime (see ros2/action_server.py)."""

    enabled: bool = True
    action: str = Field("autonomy/navigate_to_pose", description="nav2_msgs/action/NavigateToPose "
                        "server name (not Nav2's own navigate_to_pose, which the runtime uses)")
    topic: str | None = Field("autonomy/goal_pose", description="geometry_msgs/msg/PoseStamped goals "
                              "(RViz's 2D Goal Pose tool); None = off")
    feedback_hz: float = Field(5.0, gt=0, le=50)


class Component(_Model):
    kind: str = "sensor"
    heartbeat: Literal["streams", "lifecycle"] = Field(
        "streams", description="what proves it alive: data on its streams, or (for servers such as "
                               "Nav2's) its lifecycle node answering get_state with 'active', polled "
                               "at lifecycle.poll_hz (its stream is then lifecycle/<name>)")
    streams: list[str] = Field(default_factory=list)
    rate_hz: float = Field(0.0, ge=0)
    lifecycle_node: str | None = Field(None, description="ROS node offering <node>/change_state and "
                                       "<node>/get_state; None = watched only, not restartable")
    depends_on: list[str] = Field(default_factory=list, description="components it cannot work without "
                                  "(the supervisor restarts those first)")


def _default_components() -> dict[str, Component]:
    return {
        "lidar": Component(streams=["scan"], rate_hz=10.0, lifecycle_node="lidar"),
        "imu": Component(streams=["imu"], rate_hz=50.0, lifecycle_node="imu"),
        "odom": Component(streams=["odom"], rate_hz=20.0, lifecycle_node="odom"),
        "bumper": Component(streams=["bumper"], rate_hz=10.0, lifecycle_node="bumper"),
        "battery": Component(streams=["battery"], rate_hz=1.0, lifecycle_node="battery"),
        "localization": Component(kind="localization", streams=["pose"], rate_hz=10.0,
                                  lifecycle_node="localization", depends_on=["odom"]),
        "planner_server": Component(kind="navigation", heartbeat="lifecycle", lifecycle_node="planner_server"),
        "controller_server": Component(kind="navigation", heartbeat="lifecycle", lifecycle_node="controller_server"),
        "behavior_server": Component(kind="navigation", heartbeat="lifecycle", lifecycle_node="behavior_server"),
    }


class Validation(_Model):
    """Limits beyond which a message is dropped (and counted in ``driver.dropped``)."""

    max_scan_beams: int = Field(20000, gt=0)
    max_nan_fraction: float = Field(0.5, ge=0, le=1, description="scans with more NaN ranges are dropped")
    max_range: float = Field(1000.0, gt=0)
    max_speed: float = Field(20.0, gt=0, description="m/s, odometry and velocity commands")
    max_yaw_rate: float = Field(50.0, gt=0)
    max_accel: float = Field(500.0, gt=0)
    max_position: float = Field(1e5, gt=0)
    max_voltage: float = Field(1000.0, gt=0)


class RobotConfig(_Model):
    """What the autonomy layer may know about the robot (``RobotInfo``); defaults: TurtleBot3
    burger. ``null`` for the whole section: the runtime's defaults."""

    radius: float = Field(0.105, gt=0)
    max_linear: float = Field(0.22, gt=0)
    max_angular: float = Field(2.84, gt=0)
    max_linear_accel: float = Field(1.0, gt=0, description="m/s^2: the gate ramps commands up no faster")
    max_angular_accel: float = Field(12.5, gt=0, description="rad/s^2")
    capacity_ah: float = Field(1.8, gt=0)
    voltage_nominal: float = Field(11.1, gt=0)
    idle_power_w: float = Field(6.0, ge=0)
    k_linear: float = Field(12.0, ge=0, description="W per m/s")
    k_angular: float = Field(1.0, ge=0, description="W per rad/s")
    lidar_x: float = Field(-0.032, description="m: the scan frame's origin in the base frame (safety zones)")
    lidar_y: float = Field(0.0, description="m")
    lidar_yaw: float = Field(0.0, description="rad: the scan frame's yaw in the base frame")


class BringupConfig(_Model):
    """Bring-up at start, as nav2_lifecycle_manager's startup(): configure every node of
    ``node_names`` in order, then activate every one in order (see runtime/bringup.py)."""

    enabled: bool = Field(True, description="bring the nodes up at start (nodes already active are left "
                          "as they are, so this is harmless next to Nav2's own lifecycle_manager)")
    node_names: list[str] = Field(
        default_factory=lambda: ["controller_server", "planner_server", "behavior_server"],
        description="lifecycle nodes in bring-up order (Nav2's navigation_launch.py order); "
                    "a supervised component whose lifecycle_node is listed is reported by component")
    service_timeout: float = Field(5.0, gt=0, description="wait this long for a node's lifecycle services "
                                   "(nav2_lifecycle_manager's service_timeout)")


class LifecycleConfig(_Model):
    transition_timeout: float = Field(3.0, gt=0, description="per change_state call (activate may take "
                                      "as long as the driver needs to start)")
    poll_hz: float = Field(2.0, gt=0, le=50, description="get_state polling of heartbeat: lifecycle components")
    bringup: BringupConfig = Field(default_factory=BringupConfig)


class Ros2Config(_Model):
    """The whole file. ``components`` replaces the default set when given."""

    domain_id: int = Field(0, ge=0, le=232)
    namespace: str = ""
    cyclonedds_uri: str | None = Field(None, description="Cyclone DDS XML or file:// URI; default: "
                                       "the CYCLONEDDS_URI environment variable")
    loopback_only: bool = Field(False, description="use 127.0.0.1 only (a robot on this machine)")
    service_mapping: Literal["cyclonedds", "rpc_basic"] = Field(
        "cyclonedds", description="where services and actions carry the request id: rmw_cyclonedds_cpp's "
        "payload header (also rmw_connextdds with RMW_CONNEXT_CYCLONE_COMPATIBILITY_MODE), or DDS-RPC's basic "
        "mapping (rmw_connextdds with RMW_CONNEXT_REQUEST_REPLY_MAPPING=basic, rmw_connextddsmicro); "
        "rmw_fastrtps_cpp cannot be reached (docs/ros2.md, 'Which middleware')")
    topics: Topics = Field(default_factory=Topics)
    navigation: Navigation = Field(default_factory=Navigation)
    goals: GoalServing = Field(default_factory=GoalServing)
    components: dict[str, Component] = Field(default_factory=_default_components)
    validation: Validation = Field(default_factory=Validation)
    lifecycle: LifecycleConfig = Field(default_factory=LifecycleConfig)
    deliver_at_tick: list[str] = Field(
        default_factory=lambda: ["imu", "odom"],
        description="streams delivered in one batch just before each tick instead of waking the event loop "
        "for every message (a sample waits < 1 tick period; saves a loop pass per message while the "
        "tree ticks). Only streams nothing on the safety path reads: scan, bumper, nav_cmd_vel and "
        "the gate's inputs and locks always wake the loop at once")
    robot: RobotConfig | None = Field(default_factory=RobotConfig)

    @field_validator("cyclonedds_uri")
    @classmethod
    def _cyclonedds_uri(cls, value: str | None) -> str | None:
        """Inline Cyclone XML or ``file://`` paths (comma-separated), checked now rather than
        failing inside Cyclone when the driver starts."""
        if value is None or not value.strip():
            return None
        text = value.strip()
        if text.startswith("<"):
            from lxml import etree

            try:
                etree.fromstring(text.encode(), etree.XMLParser(resolve_entities=False, no_network=True))
            except etree.XMLSyntaxError as exc:
                raise ValueError(f"not well-formed Cyclone DDS XML: {exc}") from None
            return value
        for item in (part.strip() for part in text.split(",")):
            if not item.startswith("file://"):
                raise ValueError(f"expected inline XML (<CycloneDDS>...) or file://PATH, got {item[:80]!r}")
            if not os.path.isfile(item[len("file://"):]):
                raise ValueError(f"{item}: no such file")
        return value

    @field_validator("deliver_at_tick")
    @classmethod
    def _deliver_at_tick(cls, value: list[str]) -> list[str]:
        for stream in value:
            if stream in SAFETY_STREAMS or stream.startswith(("cmd_vel_input/", "lock/")):
                raise ValueError(f"{stream!r} feeds the decision gate (safety zones, commands, locks): "
                                 "it must wake the loop at once, not wait for the tick")
        return value

    @model_validator(mode="after")
    def _lifecycle_heartbeats(self) -> Ros2Config:
        for name, comp in self.components.items():
            if comp.heartbeat == "lifecycle":
                if not comp.lifecycle_node:
                    raise ValueError(f"components.{name}: heartbeat 'lifecycle' needs a lifecycle_node")
                comp.streams = [f"lifecycle/{name}"]
                if comp.rate_hz == 0:
                    comp.rate_hz = self.lifecycle.poll_hz
        return self

    def with_environment(self) -> Ros2Config:
        """ROS's convention: ``ROS_DOMAIN_ID`` names the domain when the file does not."""
        env = os.environ.get("ROS_DOMAIN_ID", "")
        if "domain_id" not in self.model_fields_set and env.isdigit():
            self.domain_id = int(env)
        return self

    def without_components(self, *names: str) -> Ros2Config:
        """A copy that neither reads nor watches the named components: a robot without a bumper
        (the ROSbot 2.0 senses collisions with its IMU) must not wait for one."""
        copy = self.model_copy(deep=True)
        for name in names:
            copy.components.pop(name, None)
            if name == "bumper":
                copy.topics.bumper = None
        return copy

    @classmethod
    def load(cls, path: str | Path) -> Ros2Config:
        import yaml

        path = Path(path)
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except FileNotFoundError:
            raise ValueError(f"ROS 2 config file not found: {path}") from None
        except yaml.YAMLError as exc:
            raise ValueError(f"{path}: {exc}") from None
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise ValueError(f"{path}: {exc}") from None
