"""The async driver interface: everything above it talks to "the robot" only through this.

``SimDriver`` (in ``sim/``) and the ROS 2 driver implement it. Nothing above this interface
may know which driver it has. Sensor data arrives through callbacks registered with
``subscribe`` (cheap and deterministic on one event loop); velocity goes out only through
``send_velocity``, and only the decision gate calls it.

Streams:
  ``scan`` LaserScan, ``imu`` Imu, ``odom`` Odometry, ``pose`` LocalizedPose (map frame),
  ``bumper`` Contact, ``battery`` BatteryState, ``nav_cmd_vel`` Twist (what the navigation
  stack's controller wants to send; the gate decides whether it reaches the wheels),
  ``cmd_vel_out`` Twist (what actually went to the base; for recording),
  ``cmd_vel_input/<name>`` Twist (a velocity input of the gate such as teleop, see
  ``twist_mux.py``) and ``lock/<name>`` bool (a gate lock such as ``e_stop``).

A driver that reads inputs from topics may offer ``open_command_inputs(inputs, locks)``
(lists of ``twist_mux.MuxInput`` / ``MuxLock``, each with ``name`` and ``topic``): the gate
calls it before subscribing to those streams. The simulator offers
``publish_command_input(name, linear, angular)`` and ``publish_lock(name, locked)`` instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

from .messages import ComponentInfo, ComponentState, NavFeedback, NavResult, Path, Pose2D

STREAMS = ("scan", "imu", "odom", "pose", "bumper", "battery", "nav_cmd_vel", "cmd_vel_out")

Callback = Callable[[Any], None]
Unsubscribe = Callable[[], None]
FeedbackCallback = Callable[[NavFeedback], None]


@runtime_checkable
class NavigationHandle(Protocol):
    """A running navigation action (navigate_to_pose, follow_path, a behaviour)."""

    def done(self) -> bool: ...

    def result(self) -> NavResult:
        """The result; only valid once ``done()``."""

    def cancel(self) -> None:
        """Request cancellation; the action ends with CANCELED and the controller stops."""

    def __await__(self): ...

    @property
    def feedback(self) -> NavFeedback | None: ...


@runtime_checkable
class NavigationClient(Protocol):
    """A Nav2-like navigation stack: actions, planning, costmap services."""

    def navigate_to_pose(self, goal: Pose2D, *, behavior_tree: str = "",
                         feedback: FeedbackCallback | None = None) -> NavigationHandle: ...

    async def compute_path_to_pose(self, goal: Pose2D, *, start: Pose2D | None = None,
                                   planner_id: str = "", use_start: bool = False) -> NavResult:
        """Plan; ``result.path`` holds the path on success, else a planner error code."""

    def follow_path(self, path: Path, *, controller_id: str = "", goal_checker_id: str = "",
                    progress_checker_id: str = "",
                    feedback: FeedbackCallback | None = None) -> NavigationHandle: ...

    def spin(self, target_yaw: float, *, time_allowance: float = 10.0) -> NavigationHandle: ...

    def back_up(self, distance: float, speed: float = 0.025, *,
                time_allowance: float = 10.0) -> NavigationHandle: ...

    def drive_on_heading(self, distance: float, speed: float = 0.025, *,
                         time_allowance: float = 10.0) -> NavigationHandle: ...

    def wait(self, duration: float) -> NavigationHandle: ...

    def dock_robot(self, *, use_dock_id: bool = True, dock_id: str = "", dock_pose: Pose2D | None = None,
                   dock_type: str = "", max_staging_time: float = 1000.0, navigate_to_staging_pose: bool = True,
                   feedback: Callable[[Any], None] | None = None) -> NavigationHandle:
        """opennav_docking's ``dock_robot``: staging pose, approach, charging sensed from the
        battery. The result's ``error_code`` is DockRobot's (901-907, 999), ``num_retries`` set;
        feedback is ``DockFeedback``."""

    def undock_robot(self, *, dock_type: str = "", max_undocking_time: float = 30.0) -> NavigationHandle:
        """opennav_docking's ``undock_robot``: back out to the staging pose (902, 905, 999)."""

    def cancel_all(self) -> None:
        """Cancel every running navigation action (the controller stops publishing)."""

    async def clear_costmaps(self, which: str = "both") -> None:
        """'local', 'global' or 'both': drop the obstacle-layer contents (not the static map)."""

    async def add_obstacle(self, x: float, y: float, radius: float = 0.1) -> None:
        """Mark an obstacle in the map (persists across costmap clears)."""

    async def clear_obstacles(self) -> None:
        """Remove every obstacle marked with ``add_obstacle`` (to mark them again, smaller)."""

    def is_path_valid(self, path: Path, max_cost: int = 253) -> bool: ...

    def path_clearance(self, path: Path) -> float:
        """Smallest distance (m) from the path to a lethal cell."""


@runtime_checkable
class RobotDriver(Protocol):
    """The robot, simulated or real."""

    name: str
    navigation: NavigationClient

    async def start(self) -> None: ...

    async def stop(self) -> None: ...

    def subscribe(self, stream: str, callback: Callback) -> Unsubscribe: ...

    def send_velocity(self, linear: float, angular: float) -> None:
        """Command the base. Non-blocking. Only the decision gate calls this."""

    def emergency_zero(self) -> None:
        """Command zero at once, from any thread (the off-loop watchdog and the shutdown path
        call it while the event loop may be blocked). Must not touch the event loop's state."""

    def components(self) -> list[ComponentInfo]: ...

    def component_state(self, name: str) -> ComponentState: ...

    async def restart(self, name: str) -> bool:
        """Restart a component; True once it is running again, False if the restart failed."""

    # Optional: ``robot_info() -> RobotInfo`` (footprint, speed limits, power model). The
    # runtime puts it on the context as ``context.robot``; defaults are used if absent.
    # Optional: ``robot_time(loop_time) -> float | None``, the robot's own clock (ROS time) at a
    # loop-clock time, where it differs from the loop clock; log lines' ``sim_time`` use it.
