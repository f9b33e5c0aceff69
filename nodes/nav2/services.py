"""Nav2's service-client nodes (``BtServiceNode``): costmap clearing and path validation,
served by the project's navigation client (``context.navigation``)."""

from __future__ import annotations

from typing import Any

from bt_runtime.ports import BOOL, DOUBLE, STRING, input_port, output_port
from bt_runtime.status import FAILURE, SUCCESS, NodeStatus

from ..robot import navigation
from ..types import GOALS, PATH, POSE, SERVER_TIMEOUT, STRING_LIST
from .bases import BtServiceNode, server_ports
from .common import increment_recovery_count, is_empty


def _which_costmap(service_name: str) -> str:
    name = service_name or ""
    if "local" in name:
        return "local"
    if "global" in name:
        return "global"
    return "both"


class ClearEntireCostmap(BtServiceNode):
    """Clears a costmap's sensor data (``<costmap>/clear_entirely_<costmap>``): local or global
    by ``service_name``, both if the name says neither. Counts as a recovery. ``plugins``
    (Nav2 main: clear only some layers) is accepted; every obstacle layer is cleared."""

    service = "clear_entirely_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("service_name", STRING, description="Service name"),
                input_port("plugins", STRING_LIST, description="List of specific plugins to clear. If "
                                                                "empty, all plugins are cleared."),
                input_port("server_timeout", SERVER_TIMEOUT,
                           description="Server timeout (ms). If not provided, uses the BT Navigator's "
                                       "`default_server_timeout` (20 ms)")]

    def on_tick(self) -> None:
        increment_recovery_count(self)

    def call(self) -> Any:
        return navigation(self).clear_costmaps(_which_costmap(self.get_input("service_name", "") or ""))


class ClearCostmapAroundRobot(ClearEntireCostmap):
    """Nav2 clears the obstacle data within ``reset_distance`` of the robot; the navigation
    client can only clear a whole costmap's sensor data, which this does (a superset)."""

    service = "clear_around_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("reset_distance", DOUBLE, 1.0, "Distance from the robot to clear"),
                *super().provided_ports()]


class ClearCostmapExceptRegion(ClearEntireCostmap):
    """Nav2 clears the obstacle data outside ``reset_distance`` of the robot; the client
    clears the whole costmap's sensor data (a superset)."""

    service = "clear_except_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("reset_distance", DOUBLE, 1.0, "Distance from the robot to keep"),
                *super().provided_ports()]


class ClearCostmapAroundPose(ClearEntireCostmap):
    """Nav2 clears the obstacle data within ``reset_distance`` of ``pose``; the client clears
    the whole costmap's sensor data (a superset)."""

    service = "clear_around_pose"

    @classmethod
    def provided_ports(cls):
        return [input_port("pose", POSE, description="Pose around which to clear"),
                input_port("reset_distance", DOUBLE, 1.0, "Distance from the pose to clear"),
                *super().provided_ports()]


class ValidatePath(BtServiceNode):
    """Nav2 main's path check (planner server ``is_path_valid``): SUCCESS if ``path`` from
    the pose closest to the robot on is free. ``max_cost`` as Nav2 (254 = lethal only), capped
    at 253 (inscribed) because the robot footprint is a circle, as Nav2 does for a
    ``robot_radius`` costmap. ``layer_name``, ``footprint``, ``max_lookahead_distance`` and
    ``collision_poses`` are not supported by the client (accepted, ignored)."""

    service = "is_path_valid"

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Path to validate"),
                input_port("max_cost", "unsigned int", 254, "Maximum cost allowed for a pose"),
                input_port("consider_unknown_as_obstacle", BOOL, False, "Unknown cells are obstacles"),
                input_port("layer_name", STRING, "", "Costmap layer to check (empty: master costmap)"),
                input_port("footprint", STRING, "", "Footprint to check (empty: the robot's)"),
                input_port("stop_at_first_collision", BOOL, True, "Stop at the first pose in collision"),
                input_port("max_lookahead_distance", DOUBLE, -1.0,
                           "Maximum distance along the path to check (negative: all)"),
                output_port("collision_poses", GOALS, description="Poses of the path in collision"),
                *server_ports("is_path_valid", service=True)]

    def on_tick(self) -> None:
        self.path = self.get_input("path", None)

    def call(self) -> Any:
        if is_empty(self.path):
            return False
        max_cost = min(int(self.get_input("max_cost", 254)), 253)
        return bool(navigation(self).is_path_valid(self.path, max_cost))

    def on_completion(self, response: Any) -> NodeStatus:
        return SUCCESS if response else FAILURE
