"""opennav_docking's BT nodes (``opennav_docking_bt``): ``DockRobot`` and ``UndockRobot``.

They send goals to the navigation client's ``dock_robot`` / ``undock_robot`` (the Nav2
stand-in's docking server in simulation, opennav_docking's actions over ROS 2) with Nav2's
ports and outputs:

* ``DockRobot``: ``use_dock_id`` (then ``dock_id``) or ``dock_pose`` + ``dock_type``;
  ``max_staging_time``, ``navigate_to_staging_pose``. SUCCESS when docked and charging
  (``success`` true, ``num_retries``, error code 0); FAILURE with the server's error code
  (901 DOCK_NOT_IN_DB, 902 DOCK_NOT_VALID, 903 FAILED_TO_STAGE, 904 FAILED_TO_DETECT_DOCK,
  905 FAILED_TO_CONTROL, 906 FAILED_TO_CHARGE, 907 TIMEOUT, 999 UNKNOWN); cancelled: SUCCESS.
  (Upstream reads ``max_staging_time`` only together with ``dock_pose``; here it is always read.)
* ``UndockRobot``: ``dock_type``, ``max_undocking_time``; the same outputs without
  ``num_retries`` (902, 905, 999).
"""

from __future__ import annotations

from typing import Any

from bt_runtime.ports import BOOL, FLOAT, STRING, input_port, output_port
from bt_runtime.runtime.messages import NavResult
from bt_runtime.status import NodeStatus

from ..robot import navigation
from ..types import ERROR_CODE, POSE
from .bases import BtActionNode, error_ports, safe_set_output, server_ports
from .common import log

UNKNOWN = 999


class DockRobot(BtActionNode):
    """Docks the robot at a charging dock (opennav_docking ``dock_robot``); see the module docstring."""

    server = "dock_robot"

    @classmethod
    def provided_ports(cls):
        return [input_port("use_dock_id", BOOL, True, "Whether to use the dock's ID or dock pose fields"),
                input_port("dock_id", STRING, description="Dock ID or name to use"),
                input_port("dock_pose", POSE, description="The dock pose, if not using dock id"),
                input_port("dock_type", STRING, description="The dock plugin type, if using dock pose"),
                input_port("max_staging_time", FLOAT, 1000.0, "Maximum time to navigate to the staging pose"),
                input_port("navigate_to_staging_pose", BOOL, True, "Whether to autonomously navigate to "
                                                                    "staging pose"),
                output_port("success", BOOL, description="If the action was successful"),
                output_port("num_retries", ERROR_CODE, description="The number of retries"),
                *error_ports("Dock robot"), *server_ports("dock_robot")]

    def on_tick(self) -> None:
        use_id = bool(self.get_input("use_dock_id", True))
        goal: dict[str, Any] = {"use_dock_id": use_id,
                                "max_staging_time": float(self.get_input("max_staging_time", 1000.0)),
                                "navigate_to_staging_pose": bool(self.get_input("navigate_to_staging_pose", True))}
        if use_id:
            goal["dock_id"] = self.get_input("dock_id", "") or ""
        else:
            pose = self.get_input("dock_pose", None)
            if pose is None:
                log.warning("nav2_dock_pose_missing", node=self.config.path)
                self.should_send_goal = False
                safe_set_output(self, "error_code_id", 902)
                safe_set_output(self, "error_msg", "use_dock_id is false and no dock_pose is given")
                safe_set_output(self, "success", False)
                return
            goal["dock_pose"] = pose
            goal["dock_type"] = self.get_input("dock_type", "") or ""
        self.goal = goal

    def send_goal(self) -> Any:
        return navigation(self).dock_robot(**self.goal)

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "success", True)
        safe_set_output(self, "num_retries", int(result.num_retries))
        return super().on_success(result)

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "success", False)
        safe_set_output(self, "num_retries", int(result.num_retries))
        if not int(result.error_code):
            result.error_code = UNKNOWN
        return super().on_aborted(result)


class UndockRobot(BtActionNode):
    """Undocks the robot back to its staging pose (opennav_docking ``undock_robot``)."""

    server = "undock_robot"

    @classmethod
    def provided_ports(cls):
        return [input_port("dock_type", STRING, description="The dock plugin type"),
                input_port("max_undocking_time", FLOAT, 30.0, "Maximum time to undock"),
                output_port("success", BOOL, description="If the action was successful"),
                *error_ports("Undock robot"), *server_ports("undock_robot")]

    def on_tick(self) -> None:
        self.goal = {"dock_type": self.get_input("dock_type", "") or "",
                     "max_undocking_time": float(self.get_input("max_undocking_time", 30.0))}

    def send_goal(self) -> Any:
        return navigation(self).undock_robot(**self.goal)

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "success", True)
        return super().on_success(result)

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "success", False)
        if not int(result.error_code):
            result.error_code = UNKNOWN
        return super().on_aborted(result)
