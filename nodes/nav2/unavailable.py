"""Nav2 nodes whose servers the project's navigation stack does not have (route server,
assisted teleop, object following, AMCL's global relocalization, the
collision monitor). They are registered with Nav2's ports so every stock tree loads and
Groot2 shows the full palette; ticked, they fail at once with the action's UNKNOWN error code
and a log line saying which server is missing (what a Nav2 BT node does when its server is not
up: FAILURE after ``server_timeout``).
"""

from __future__ import annotations

from typing import ClassVar

from bt_runtime.node import StatefulActionNode
from bt_runtime.ports import BOOL, DOUBLE, STRING, input_port, output_port
from bt_runtime.status import FAILURE, SUCCESS, NodeStatus

from ..types import DURATION, ERROR_CODE, GOALS, PATH, POSE, ROUTE
from .bases import error_ports, safe_set_output, server_ports
from .common import log

_warned: set[str] = set()


class UnavailableAction(StatefulActionNode):
    """A Nav2 action node without a server in this navigation stack: FAILURE when ticked."""

    server: ClassVar[str] = ""
    unknown_code: ClassVar[int] = 0

    def on_start(self) -> NodeStatus:
        if self.registration_name not in _warned:
            _warned.add(self.registration_name)
            log.warning("nav2_server_unavailable", node=self.config.path, node_type=self.registration_name,
                        server=self.server, msg="this navigation stack has no such server")
        safe_set_output(self, "error_code_id", self.unknown_code)
        safe_set_output(self, "error_msg", f"no '{self.server}' server in this navigation stack")
        if "success" in self.config.output_ports:
            safe_set_output(self, "success", False)
        return FAILURE

    def on_running(self) -> NodeStatus:
        return FAILURE


class ComputeRoute(UnavailableAction):
    """Route server ``compute_route`` (graph route). Not available: FAILURE, 400."""

    server, unknown_code = "compute_route", 400

    @classmethod
    def provided_ports(cls):
        return [input_port("start", POSE, description="Start pose of the route"),
                input_port("goal", POSE, description="Goal pose of the route"),
                input_port("start_id", "unsigned int", description="Start node id"),
                input_port("goal_id", "unsigned int", description="Goal node id"),
                input_port("use_start", BOOL, False, "Use the start pose instead of the robot pose"),
                input_port("use_poses", BOOL, False, "Use poses instead of node ids"),
                output_port("route", ROUTE, description="Route"),
                output_port("path", PATH, description="Path of the route"),
                output_port("planning_time", DURATION, description="Planning time"),
                *error_ports("Compute route"), *server_ports("compute_route")]


class ComputeAndTrackRoute(UnavailableAction):
    """Route server ``compute_and_track_route``. Not available: FAILURE, 400."""

    server, unknown_code = "compute_and_track_route", 400

    @classmethod
    def provided_ports(cls):
        return [input_port("start", POSE, description="Start pose of the route"),
                input_port("goal", POSE, description="Goal pose of the route"),
                input_port("start_id", "unsigned int", description="Start node id"),
                input_port("goal_id", "unsigned int", description="Goal node id"),
                input_port("use_start", BOOL, False, "Use the start pose instead of the robot pose"),
                input_port("use_poses", BOOL, False, "Use poses instead of node ids"),
                output_port("execution_duration", DURATION, description="Execution duration"),
                output_port("last_node_id", ERROR_CODE, description="Last node id"),
                output_port("next_node_id", ERROR_CODE, description="Next node id"),
                output_port("current_edge_id", ERROR_CODE, description="Current edge id"),
                output_port("route", ROUTE, description="Route"),
                output_port("path", PATH, description="Path of the route"),
                output_port("rerouted", BOOL, description="Whether the route was recomputed"),
                *error_ports("Compute and track route"), *server_ports("compute_and_track_route")]


class ExtractRouteNodesAsGoals(UnavailableAction):
    """Turns a route's nodes into goals. No routes exist without a route server: FAILURE."""

    server = "compute_route"

    @classmethod
    def provided_ports(cls):
        return [input_port("route", ROUTE, description="Route to extract the nodes of"),
                output_port("goals", GOALS, description="The route's nodes as goals")]


class AssistedTeleop(UnavailableAction):
    """Behavior server ``assisted_teleop``. Not available: FAILURE, 730."""

    server, unknown_code = "assisted_teleop", 730

    @classmethod
    def provided_ports(cls):
        return [input_port("is_recovery", BOOL, False, "If true recovery count will be incremented"),
                input_port("time_allowance", DOUBLE, 10.0, "Allowed time for running assisted teleop"),
                *error_ports("Assisted teleop"), *server_ports("assisted_teleop")]


class FollowObject(UnavailableAction):
    """Following server ``follow_object``. Not available: FAILURE."""

    server = "follow_object"

    @classmethod
    def provided_ports(cls):
        return [input_port("pose_topic", STRING, description="Topic of the object's pose"),
                input_port("tracked_frame", STRING, description="Frame of the object"),
                input_port("max_duration", DOUBLE, 0.0, "Maximum duration (0: no limit)"),
                *error_ports("Follow object"), *server_ports("follow_object")]


class ReinitializeGlobalLocalization(UnavailableAction):
    """AMCL's ``reinitialize_global_localization`` service. Not available: FAILURE."""

    server = "reinitialize_global_localization"

    @classmethod
    def provided_ports(cls):
        return [input_port("service_name", STRING, description="Service name"),
                input_port("server_timeout", "std::chrono::milliseconds", description="Server timeout")]


class ToggleCollisionMonitor(UnavailableAction):
    """Collision monitor ``toggle``. The project's decision gate is not a collision monitor:
    FAILURE."""

    server = "collision_monitor/toggle"

    @classmethod
    def provided_ports(cls):
        return [input_port("enable", BOOL, True, "Whether to enable the collision monitor"),
                input_port("service_name", STRING, description="Service name"),
                input_port("server_timeout", "std::chrono::milliseconds", description="Server timeout")]


class _CancelNothing(StatefulActionNode):
    """Cancel node of a server that does not exist here: nothing can be running, SUCCESS."""

    @classmethod
    def provided_ports(cls):
        return server_ports("")

    def on_start(self) -> NodeStatus:
        return SUCCESS

    def on_running(self) -> NodeStatus:
        return SUCCESS


class CancelAssistedTeleop(_CancelNothing):
    """Cancels AssistedTeleop goals (none can exist here): SUCCESS."""


class CancelComputeAndTrackRoute(_CancelNothing):
    """Cancels ComputeAndTrackRoute goals (none can exist here): SUCCESS."""


class CancelFollowObject(_CancelNothing):
    """Cancels FollowObject goals (none can exist here): SUCCESS."""
