"""The simulator as a ROS 2 robot on DDS (``python -m bt_runtime sim-robot``).

Publishes the simulated robot's sensors under the names a ROS 2 robot with Nav2 uses, takes
velocity commands on ``cmd_vel``, serves Nav2's actions and costmap services from the Nav2
stand-in (``sim.nav.NavStack``), and a lifecycle interface per sensor driver:

| ROS name | type | from |
|---|---|---|
| ``scan`` | sensor_msgs/LaserScan (sensor-data QoS) | lidar |
| ``imu`` | sensor_msgs/Imu | IMU |
| ``odom`` | nav_msgs/Odometry | wheel odometry |
| ``amcl_pose`` | geometry_msgs/PoseWithCovarianceStamped (transient local) | localization |
| ``map`` | nav_msgs/OccupancyGrid (reliable, transient local: late joiners get it) | the world, as map_server |
| ``battery_state`` | sensor_msgs/BatteryState | battery |
| ``bumper`` | std_msgs/Bool; ``bumper_contact``: geometry_msgs/Vector3Stamped (direction, impulse) | bumper |
| ``cmd_vel`` (in) | geometry_msgs/Twist (or TwistStamped) | -> the base |
| ``cmd_vel_nav`` | geometry_msgs/Twist | the stand-in's controller (Nav2 remapped) |
| ``navigate_to_pose``, ``compute_path_to_pose``, ``follow_path``, ``spin``, ``backup``, ``drive_on_heading``, ``wait`` | nav2_msgs actions | NavStack |
| ``dock_robot``, ``undock_robot`` | nav2_msgs/action/DockRobot, UndockRobot (opennav_docking's names; the world's dock is ``home_dock``) | NavStack's docking server |
| ``/global_costmap/clear_entirely_global_costmap``, ``/local_costmap/...`` | nav2_msgs/srv/ClearEntireCostmap | NavStack |
| ``<component>/get_state``, ``<component>/change_state`` (sensors and planner_server, controller_server, behavior_server) | lifecycle_msgs services, managed-node state machine (sim/ros2_lifecycle.py): the Nav2 servers start unconfigured unless ``nav_autostart`` | ``Simulator.crash``/``restart``, ``NavStack.crash``/``restart`` |
| ``speed_limit`` (in) | nav2_msgs/SpeedLimit | ``NavStack.set_speed_limit`` |
| ``sim/ground_truth`` | geometry_msgs/PoseStamped, 10 Hz: the true pose, for judging only | simulator |
| ``sim/fault`` (in) | std_msgs/String, a JSON fault (``{"kind": "crash", "component": "lidar"}``; ``nav_crash``/``nav_hang``/``nav_fail_until_restart`` with a nav server ``component``) | ``sim.faults``, ``NavStack`` |

A DDS peer cannot share a virtual clock, so this runs on the wall clock. Header stamps are
ROS time (the system clock): each sensor message carries the time it was taken (its simulator
stamp on the system clock), so a driver fault that republishes old data (``stale``) goes out
with its old stamp, as a real driver's would.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
from typing import Any

import structlog

from bt_runtime.runtime.messages import ActionStatus, Path, Pose2D
from bt_runtime.runtime.ros2 import dds, idl
from bt_runtime.runtime.ros2.convert import pose2d_of, pose_msg, quaternion_of

from .driver import SimDriver
from .faults import Crash, parse_fault
from .ros2_lifecycle import EmulatedLifecycleNode, take_down

log = structlog.get_logger("sim.ros2_robot")

S = idl.GoalStatus
T = idl.Transition
ST = idl.State
STATUS = {ActionStatus.SUCCEEDED: S.STATUS_SUCCEEDED, ActionStatus.CANCELED: S.STATUS_CANCELED,
          ActionStatus.ABORTED: S.STATUS_ABORTED}
# the stand-in reports Spin's 70x codes for every behaviour; Jazzy numbers them per action
BACKUP_CODES = {700: 710, 701: 711, 702: 712, 703: 714, 704: 713}
DRIVE_CODES = {700: 720, 701: 721, 702: 722, 703: 723, 704: 724}
WAIT_CODES = {700: 740, 701: 741}
FIRST_ACTIVATION = 0.3  # s: activating a configured stand-in server (a restart after a crash takes longer)


def parse_crash(text: str) -> tuple[str, float]:
    """'lidar@3.5' -> ('lidar', 3.5)."""
    name, sep, t = text.partition("@")
    if not sep or not name:
        raise ValueError(f"--crash expects COMPONENT@SECONDS, got {text!r}")
    return name.strip(), float(t)


def _header(frame: str, stamp: float | None = None) -> idl.Header:
    """A header stamped ``stamp`` (ROS time, s), or now."""
    return idl.Header(stamp=idl.Time.now() if stamp is None else idl.Time.from_sec(stamp), frame_id=frame)


def _stamped(pose: Pose2D, frame: str = "map") -> idl.PoseStamped:
    return idl.PoseStamped(header=_header(frame), pose=pose_msg(pose))


def _path_msg(path: Path | None) -> idl.Path:
    if path is None:
        return idl.Path(header=_header("map"))
    pts = path.points
    return idl.Path(header=_header("map"), poses=[
        _stamped(Pose2D(float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else 0.0)) for p in pts])


class SimRobot:
    """A simulated robot serving ROS 2 topics, services and actions over DDS."""

    LIFECYCLE = ("lidar", "imu", "odom", "bumper", "battery", "localization")
    NAV_LIFECYCLE = ("planner_server", "controller_server", "behavior_server")

    def __init__(self, world: str = "apartment", robot: str = "burger", seed: int = 0, domain_id: int = 0, *,
                 namespace: str = "", crashes: list[tuple[str, float]] | tuple = (), cruise_speed: float | None = None,
                 stamped_cmd_vel: bool = False, cyclonedds_uri: str | None = None,
                 goal_tolerance: float | None = None, nav_autostart: bool = False,
                 refuse_activate: tuple[str, ...] | list[str] = (),
                 spawn: tuple[float, float, float] | None = None, service_mapping: str = "cyclonedds"):
        self.world, self.robot, self.seed = world, robot, seed
        self.spawn = spawn  # None: the world's spawn pose
        self.domain_id = domain_id
        self.namespace = namespace
        self.crashes = list(crashes)
        self.cruise_speed = cruise_speed
        self.stamped_cmd_vel = stamped_cmd_vel
        self.cyclonedds_uri = cyclonedds_uri
        self.goal_tolerance = goal_tolerance
        self.nav_autostart = nav_autostart  # the stand-in's servers start active (else unconfigured)
        self.refuse_activate = tuple(refuse_activate)  # lifecycle nodes whose on_activate fails
        self.service_mapping = service_mapping  # request ids as rmw_cyclonedds (default) or DDS-RPC basic
        self.lifecycle_nodes: dict[str, EmulatedLifecycleNode] = {}
        self.driver: SimDriver | None = None
        self.node: dds.DdsNode | None = None
        self.commands = 0
        self.published: dict[str, int] = {}
        self._unsub: list[Any] = []
        self._servers: list[Any] = []
        self.cmd_receive_times: list[tuple[float, float]] = []  # (loop time, linear) for benchmarks
        self._ros_offset = 0.0  # system clock - loop clock, fixed at start

    @property
    def sim(self):
        return self.driver.sim

    # -- start / stop ------------------------------------------------------------------------------
    async def start(self) -> None:
        self._ros_offset = idl.Time.now().to_sec() - asyncio.get_running_loop().time()  # ROS time: system clock
        nav_params = ({"controller": {"xy_goal_tolerance": self.goal_tolerance}}
                      if self.goal_tolerance is not None else None)
        extra = {"spawn": self.spawn} if self.spawn is not None else {}
        self.driver = driver = SimDriver(self.world, self.robot, seed=self.seed, cruise_speed=self.cruise_speed,
                                         nav_params=nav_params, **extra)
        sim = driver.sim
        self.node = node = dds.DdsNode(self.domain_id, namespace=self.namespace, cyclonedds_uri=self.cyclonedds_uri,
                                       service_mapping=self.service_mapping)
        pub = node.publisher
        writers = {
            "scan": pub("scan", idl.LaserScan, dds.SENSOR_DATA),
            "imu": pub("imu", idl.Imu, dds.SENSOR_DATA),
            "odom": pub("odom", idl.Odometry),
            "pose": pub("amcl_pose", idl.PoseWithCovarianceStamped, dds.LATCHED),
            "battery": pub("battery_state", idl.BatteryState),
            "bumper": pub("bumper", idl.Bool),
            "bumper_contact": pub("bumper_contact", idl.Vector3Stamped),
            "nav_cmd_vel": pub("cmd_vel_nav", idl.Twist),
            "ground_truth": pub("sim/ground_truth", idl.PoseStamped),
        }
        self.writers = writers
        self._publish_map(node)
        convert = {"scan": self._scan, "imu": self._imu, "odom": self._odom, "pose": self._pose,
                   "battery": self._battery, "nav_cmd_vel": self._twist,
                   "ground_truth": lambda m: _stamped(m.pose)}
        for stream, fn in convert.items():
            self._unsub.append(sim.subscribe(stream, self._forward(stream, writers[stream], fn)))
        self._unsub.append(sim.subscribe("bumper", self._bumper))

        cmd_type = idl.TwistStamped if self.stamped_cmd_vel else idl.Twist
        node.subscription("cmd_vel", cmd_type, dds.QosProfile(reliable=False, depth=10), self._on_cmd_vel)
        node.subscription("sim/fault", idl.String, dds.DEFAULT, self._on_fault)
        node.subscription("speed_limit", idl.SpeedLimit, dds.DEFAULT, self._on_speed_limit)

        nav = driver.navigation
        A = dds.ActionServer
        self._servers = [
            A(node, "navigate_to_pose", idl.NavigateToPose, self._navigate),
            A(node, "compute_path_to_pose", idl.ComputePathToPose, self._compute_path),
            A(node, "follow_path", idl.FollowPath, self._follow_path),
            A(node, "spin", idl.Spin, self._behaviour("spin")),
            A(node, "backup", idl.BackUp, self._behaviour("backup")),
            A(node, "drive_on_heading", idl.DriveOnHeading, self._behaviour("drive_on_heading")),
            A(node, "wait", idl.Wait, self._behaviour("wait")),
            A(node, "dock_robot", idl.DockRobot, self._dock),
            A(node, "undock_robot", idl.UndockRobot, self._undock),
        ]
        for which in ("global", "local"):
            self._servers.append(dds.ServiceServer(
                node, f"/{which}_costmap/clear_entirely_{which}_costmap", idl.ClearEntireCostmap_Request,
                idl.ClearEntireCostmap_Response, self._clear(nav, which)))
        present = {c.name for c in sim.components()}  # a robot without a bumper has no bumper node
        self.lifecycle_nodes = {}
        for name in (*self.LIFECYCLE, *self.NAV_LIFECYCLE):
            if name not in present and name not in self.NAV_LIFECYCLE:
                continue
            lc = self.lifecycle_nodes[name] = self._lifecycle_node(name)
            self._servers.append(dds.ServiceServer(node, f"{name}/get_state", idl.GetState_Request,
                                                   idl.GetState_Response, lc.get_state))
            self._servers.append(dds.ServiceServer(node, f"{name}/change_state", idl.ChangeState_Request,
                                                   idl.ChangeState_Response, lc.change_state))
        await driver.start()
        for name in self.NAV_LIFECYCLE:  # Nav2's servers wait for a lifecycle manager (unless autostart)
            if self.lifecycle_nodes[name].recorded != ST.PRIMARY_STATE_ACTIVE:
                take_down(nav, name)
        t0 = asyncio.get_running_loop().time()
        for component, t in self.crashes:
            sim.faults.schedule(t0 + t, Crash(component=component))
        log.info("sim_robot_started", world=self.world, robot=self.robot, domain_id=self.domain_id,
                 namespace=node.fq(""), crashes=self.crashes)

    async def stop(self) -> None:
        for unsub in self._unsub:
            unsub()
        self._unsub.clear()
        for server in self._servers:
            server.close()
        if self.driver is not None:
            with contextlib.suppress(Exception):
                await self.driver.stop()
        if self.node is not None:
            self.node.close()
            self.node = None

    def _publish_map(self, node: dds.DdsNode) -> None:
        """The world on ``map``, once, latched (reliable, transient local), as map_server does."""
        from .ros2_map import occupancy_msg, world_grid

        self.map_msg = occupancy_msg(world_grid(self.world, self.driver.map))
        self.writers["map"] = node.publisher("map", idl.OccupancyGrid, dds.LATCHED)
        self.writers["map"].write(self.map_msg)

    # -- sensors -> DDS ----------------------------------------------------------------------------
    def ros_time(self, sim_stamp: float) -> float:
        """ROS time (system clock) of a simulator stamp (this process's loop clock)."""
        return sim_stamp + self._ros_offset

    def _forward(self, stream: str, writer: Any, convert: Any):
        def forward(msg: Any) -> None:
            if self.node is None or self.node.closed:
                return
            writer.write(convert(msg))
            self.published[stream] = self.published.get(stream, 0) + 1

        return forward

    def _scan(self, m: Any) -> idl.LaserScan:
        n = len(m.ranges)
        return idl.LaserScan(header=_header("base_scan", self.ros_time(m.stamp)), angle_min=m.angle_min,
                             angle_max=m.angle_min + m.angle_increment * (n - 1), angle_increment=m.angle_increment,
                             time_increment=0.0, scan_time=0.0, range_min=m.range_min, range_max=m.range_max,
                             ranges=m.ranges.astype("float32").tolist())

    def _imu(self, m: Any) -> idl.Imu:
        return idl.Imu(header=_header("imu_link", self.ros_time(m.stamp)), orientation=quaternion_of(m.yaw),
                       angular_velocity=idl.Vector3(0.0, 0.0, m.yaw_rate),
                       linear_acceleration=idl.Vector3(m.accel_x, m.accel_y, 9.81))

    def _odom(self, m: Any) -> idl.Odometry:
        return idl.Odometry(header=_header("odom", self.ros_time(m.stamp)), child_frame_id="base_footprint",
                            pose=idl.PoseWithCovariance(pose=pose_msg(m.pose)),
                            twist=idl.TwistWithCovariance(twist=idl.Twist(
                                linear=idl.Vector3(m.twist.linear, 0.0, 0.0),
                                angular=idl.Vector3(0.0, 0.0, m.twist.angular))))

    def _pose(self, m: Any) -> idl.PoseWithCovarianceStamped:
        cov = [0.0] * 36
        cov[0] = cov[7] = m.covariance ** 2
        cov[35] = (m.covariance * 0.5) ** 2
        return idl.PoseWithCovarianceStamped(header=_header("map", self.ros_time(m.stamp)),
                                             pose=idl.PoseWithCovariance(pose=pose_msg(m.pose), covariance=cov))

    def _battery(self, m: Any) -> idl.BatteryState:
        return idl.BatteryState(header=_header("base_link", self.ros_time(m.stamp)), voltage=m.voltage,
                                current=-m.current,
                                charge=math.nan, capacity=m.capacity_ah, design_capacity=m.capacity_ah,
                                percentage=m.percentage / 100.0, present=True,
                                power_supply_status=m.power_supply_status)

    @staticmethod
    def _twist(m: Any) -> idl.Twist:
        return idl.Twist(linear=idl.Vector3(m.linear, 0.0, 0.0), angular=idl.Vector3(0.0, 0.0, m.angular))

    def _bumper(self, m: Any) -> None:
        if self.node is None or self.node.closed:
            return
        self.writers["bumper"].write(idl.Bool(bool(m.in_contact)))
        spec = self.sim.profile.bumper
        bearing = spec.bearing(m.segments) if spec is not None else math.nan
        vec = (idl.Vector3(math.cos(bearing), math.sin(bearing), 1.0) if m.in_contact and math.isfinite(bearing)
               else idl.Vector3())
        self.writers["bumper_contact"].write(idl.Vector3Stamped(header=_header("base_link"), vector=vec))

    # -- DDS -> simulator --------------------------------------------------------------------------
    def _on_cmd_vel(self, samples: list, now: float) -> None:
        m = samples[-1]
        twist = m.twist if self.stamped_cmd_vel else m
        self.sim.command(twist.linear.x, twist.angular.z)
        self.commands += len(samples)
        if len(self.cmd_receive_times) < 100000:
            self.cmd_receive_times.append((now, twist.linear.x))

    def _on_speed_limit(self, samples: list, _now: float) -> None:
        m = samples[-1]
        limit = m.speed_limit if math.isfinite(m.speed_limit) and m.speed_limit > 0 else None
        self.driver.navigation.set_speed_limit(limit, percentage=bool(m.percentage))

    def _on_fault(self, samples: list, _now: float) -> None:
        nav_faults = {"nav_crash": "crash", "nav_hang": "hang", "nav_fail_until_restart": "fail_until_restart"}
        for m in samples:
            try:
                data = json.loads(m.data)
                if data.get("kind") in nav_faults:  # the Nav2 stand-in's servers
                    getattr(self.driver.navigation, nav_faults[data["kind"]])(data.get("component", "planner_server"))
                    continue
                fault = parse_fault(data)
                self.sim.faults.apply(fault)
            except Exception as exc:
                log.warning("sim_robot_bad_fault", data=m.data, error=repr(exc))

    # -- navigation ----------------------------------------------------------------------------------
    async def _run_handle(self, handle: Any) -> Any:
        try:
            return await handle
        except asyncio.CancelledError:
            handle.cancel()
            with contextlib.suppress(Exception, asyncio.CancelledError):
                await asyncio.wait_for(asyncio.shield(handle), 1.0)
            raise

    async def _navigate(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        nav = self.driver.navigation
        target = pose2d_of(goal.pose.pose)
        started = asyncio.get_running_loop().time()

        def feedback(fb: Any) -> None:
            ctx.publish_feedback(idl.NavigateToPose.Feedback(
                current_pose=_stamped(fb.current_pose), navigation_time=idl.Duration.from_sec(asyncio.get_running_loop().time() - started),
                number_of_recoveries=fb.number_of_recoveries,
                distance_remaining=fb.distance_remaining if math.isfinite(fb.distance_remaining) else 0.0))

        result = await self._run_handle(nav.navigate_to_pose(target, behavior_tree=goal.behavior_tree, feedback=feedback))
        return STATUS[result.status], idl.NavigateToPose.Result(error_code=int(result.error_code),
                                                                error_msg=result.error_msg)

    async def _compute_path(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        started = asyncio.get_running_loop().time()
        result = await self.driver.navigation.compute_path_to_pose(
            pose2d_of(goal.goal.pose), start=pose2d_of(goal.start.pose), planner_id=goal.planner_id,
            use_start=goal.use_start)
        return STATUS[result.status], idl.ComputePathToPose.Result(
            path=_path_msg(result.path), planning_time=idl.Duration.from_sec(asyncio.get_running_loop().time() - started),
            error_code=int(result.error_code), error_msg=result.error_msg)

    async def _follow_path(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        import numpy as np

        pts = np.array([[p.pose.position.x, p.pose.position.y, pose2d_of(p.pose).yaw] for p in goal.path.poses],
                       dtype=float).reshape(-1, 3)

        def feedback(fb: Any) -> None:
            ctx.publish_feedback(idl.FollowPath.Feedback(
                distance_to_goal=fb.distance_remaining if math.isfinite(fb.distance_remaining) else 0.0,
                speed=fb.speed))

        result = await self._run_handle(self.driver.navigation.follow_path(
            Path(asyncio.get_running_loop().time(), pts), controller_id=goal.controller_id,
            goal_checker_id=goal.goal_checker_id, progress_checker_id=goal.progress_checker_id, feedback=feedback))
        return STATUS[result.status], idl.FollowPath.Result(error_code=int(result.error_code),
                                                            error_msg=result.error_msg)

    async def _dock(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        def feedback(fb: Any) -> None:
            ctx.publish_feedback(idl.DockRobot.Feedback(state=fb.state, docking_time=idl.Duration.from_sec(
                fb.docking_time), num_retries=fb.num_retries))

        pose = None if goal.use_dock_id else pose2d_of(goal.dock_pose.pose)
        result = await self._run_handle(self.driver.navigation.dock_robot(
            use_dock_id=goal.use_dock_id, dock_id=goal.dock_id, dock_pose=pose, dock_type=goal.dock_type,
            max_staging_time=goal.max_staging_time, navigate_to_staging_pose=goal.navigate_to_staging_pose,
            feedback=feedback))
        return STATUS[result.status], idl.DockRobot.Result(
            success=result.succeeded, error_code=int(result.error_code), num_retries=result.num_retries,
            error_msg=result.error_msg)

    async def _undock(self, goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
        result = await self._run_handle(self.driver.navigation.undock_robot(
            dock_type=goal.dock_type, max_undocking_time=goal.max_undocking_time))
        return STATUS[result.status], idl.UndockRobot.Result(success=result.succeeded, error_code=int(result.error_code),
                                                             error_msg=result.error_msg)

    def _behaviour(self, kind: str):
        types = {"spin": idl.Spin, "backup": idl.BackUp, "drive_on_heading": idl.DriveOnHeading,
                 "wait": idl.Wait}[kind]
        codes = {"backup": BACKUP_CODES, "drive_on_heading": DRIVE_CODES, "wait": WAIT_CODES}.get(kind, {})

        async def execute(goal: Any, ctx: dds.GoalContext) -> tuple[int, Any]:
            nav = self.driver.navigation
            started = asyncio.get_running_loop().time()
            if kind == "spin":
                handle = nav.spin(goal.target_yaw, time_allowance=goal.time_allowance.to_sec() or 10.0)
            elif kind == "backup":
                handle = nav.back_up(goal.target.x, goal.speed, time_allowance=goal.time_allowance.to_sec() or 10.0)
            elif kind == "drive_on_heading":
                handle = nav.drive_on_heading(goal.target.x, goal.speed,
                                              time_allowance=goal.time_allowance.to_sec() or 10.0)
            else:
                handle = nav.wait(goal.time.to_sec())
            result = await self._run_handle(handle)
            code = int(result.error_code)
            return STATUS[result.status], types.Result(
                total_elapsed_time=idl.Duration.from_sec(asyncio.get_running_loop().time() - started),
                error_code=codes.get(code, code), error_msg=result.error_msg)

        return execute

    @staticmethod
    def _clear(nav: Any, which: str):
        async def clear(_request: Any) -> Any:
            await nav.clear_costmaps(which)  # raises when the server is down: no reply, as a dead node
            return idl.ClearEntireCostmap_Response()

        return clear

    # -- lifecycle (sim/ros2_lifecycle.py) ---------------------------------------------------------
    def _lifecycle_node(self, name: str) -> EmulatedLifecycleNode:
        refuse = name in self.refuse_activate
        if name in self.NAV_LIFECYCLE:
            nav = self.driver.navigation
            comp = nav.components[name]
            return EmulatedLifecycleNode(
                name, initial=ST.PRIMARY_STATE_ACTIVE if self.nav_autostart else ST.PRIMARY_STATE_UNCONFIGURED,
                running=lambda: comp.state, hung=lambda: comp.hung, refuse_activate=refuse,
                # a first activation is quick; after a crash it is a process restart (NavStack's delay)
                start=lambda first: nav.restart(name, delay=FIRST_ACTIVATION if first else None),
                stop=lambda: nav.crash(name))
        return EmulatedLifecycleNode(
            name, initial=ST.PRIMARY_STATE_ACTIVE, running=lambda: self.sim.component_state(name),
            refuse_activate=refuse, start=lambda _first: self.sim.restart(name),
            stop=lambda: self.sim.crash(name, reason="deactivated"))

    @property
    def lifecycle(self) -> dict[str, int]:
        """Each lifecycle node's state id."""
        return {name: lc.state() for name, lc in self.lifecycle_nodes.items()}


async def run_sim_robot(robot: SimRobot, duration: float | None = None, ready_line: bool = True) -> None:
    """Start, announce readiness on stdout, run until cancelled / ``duration``, stop."""
    import signal

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    await robot.start()
    if ready_line:
        print(f"sim-robot ready: domain {robot.domain_id}, world {robot.world}, robot {robot.robot}", flush=True)
    try:
        if duration is None:
            await stop.wait()
        else:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), duration)
    finally:
        await robot.stop()
