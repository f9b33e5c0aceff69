"""Nav2-named behavior-tree nodes, so Nav2's own XML trees run on the project's navigation stack.

``register_nav2_nodes(factory)`` registers every node of ``nav2_behavior_tree`` (Jazzy, plus
the Nav2 main nodes the stock trees use) under Nav2's IDs, with Nav2's port names, types and
defaults: a TreeNodesModel export of the factory shows Nav2's palette. The nodes reach the
robot through the factory's context (``bt_runtime.runtime.context.RuntimeContext``):
``context.navigation`` for actions and services, ``context.backup`` for pose, odometry and
battery.

    from bt_runtime.runtime.app import AutonomyRuntime
    from nodes.nav2 import register_nav2_nodes, start_navigation

    runtime = AutonomyRuntime(driver, config, register=[register_nav2_nodes])
    runtime.load_tree("trees/navigation.xml")      # or Nav2's navigate_to_pose_w_replanning_and_recovery.xml
    start_navigation(runtime.tree.root_blackboard, Pose2D(3.5, -2.5))

Version choices (see docs/nav2_nodes.md): semantics follow Nav2 Jazzy (BT.CPP v4, error codes);
``RoundRobin`` wraps around by default (Jazzy) and takes Nav2 main's ``wrap_around`` port.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from . import actions, conditions, control, decorators, docking, path_ops, services, unavailable
from .common import publish, publish_stamped

if TYPE_CHECKING:
    from bt_runtime.blackboard import Blackboard
    from bt_runtime.factory import BehaviorTreeFactory

__all__ = ["NAV2_NODES", "ERROR_CODE_KEYS", "publish", "publish_stamped", "register_nav2_nodes",
           "start_navigation"]

NAV2_NODES: dict[str, type] = {
    # control
    "PipelineSequence": control.PipelineSequence,
    "RecoveryNode": control.RecoveryNode,
    "RoundRobin": control.RoundRobin,
    # decorators
    "RateController": decorators.RateController,
    "DistanceController": decorators.DistanceController,
    "SpeedController": decorators.SpeedController,
    "GoalUpdatedController": decorators.GoalUpdatedController,
    "GoalUpdater": decorators.GoalUpdater,
    "PathLongerOnApproach": decorators.PathLongerOnApproach,
    "SingleTrigger": decorators.SingleTrigger,
    # conditions
    "GoalUpdated": conditions.GoalUpdated,
    "GlobalUpdatedGoal": conditions.GlobalUpdatedGoal,
    "IsGoalNearby": conditions.IsGoalNearby,
    "IsPathValid": conditions.IsPathValid,
    "PathExpiringTimer": conditions.PathExpiringTimer,
    "AreErrorCodesPresent": conditions.AreErrorCodesPresent,
    "WouldAControllerRecoveryHelp": conditions.WouldAControllerRecoveryHelp,
    "WouldAPlannerRecoveryHelp": conditions.WouldAPlannerRecoveryHelp,
    "WouldARouteRecoveryHelp": conditions.WouldARouteRecoveryHelp,
    "WouldASmootherRecoveryHelp": conditions.WouldASmootherRecoveryHelp,
    "ArePosesNear": conditions.ArePosesNear,
    "IsStuck": conditions.IsStuck,
    "IsBatteryLow": conditions.IsBatteryLow,
    "IsBatteryCharging": conditions.IsBatteryCharging,
    "GoalReached": conditions.GoalReached,
    "TimeExpired": conditions.TimeExpired,
    "DistanceTraveled": conditions.DistanceTraveled,
    "TransformAvailable": conditions.TransformAvailable,
    "InitialPoseReceived": conditions.InitialPoseReceived,
    "IsWithinPathTrackingBounds": conditions.IsWithinPathTrackingBounds,
    # actions: planner, controller, behaviours, navigator
    "ComputePathToPose": actions.ComputePathToPose,
    "ComputePathThroughPoses": actions.ComputePathThroughPoses,
    "SmoothPath": actions.SmoothPath,
    "FollowPath": actions.FollowPath,
    "Spin": actions.Spin,
    "BackUp": actions.BackUp,
    "DriveOnHeading": actions.DriveOnHeading,
    "Wait": actions.Wait,
    "NavigateToPose": actions.NavigateToPose,
    "NavigateThroughPoses": actions.NavigateThroughPoses,
    "CancelControl": actions.CancelControl,
    "CancelSpin": actions.CancelSpin,
    "CancelBackUp": actions.CancelBackUp,
    "CancelDriveOnHeading": actions.CancelDriveOnHeading,
    "CancelWait": actions.CancelWait,
    # services
    "ClearEntireCostmap": services.ClearEntireCostmap,
    "ClearCostmapAroundRobot": services.ClearCostmapAroundRobot,
    "ClearCostmapExceptRegion": services.ClearCostmapExceptRegion,
    "ClearCostmapAroundPose": services.ClearCostmapAroundPose,
    "ValidatePath": services.ValidatePath,
    # selectors
    "PlannerSelector": actions.PlannerSelector,
    "ControllerSelector": actions.ControllerSelector,
    "GoalCheckerSelector": actions.GoalCheckerSelector,
    "ProgressCheckerSelector": actions.ProgressCheckerSelector,
    "SmootherSelector": actions.SmootherSelector,
    "PathHandlerSelector": actions.PathHandlerSelector,
    # path and goal utilities
    "TruncatePath": path_ops.TruncatePath,
    "TruncatePathLocal": path_ops.TruncatePathLocal,
    "RemovePassedGoals": path_ops.RemovePassedGoals,
    "GetPoseFromPath": path_ops.GetPoseFromPath,
    "ConcatenatePaths": path_ops.ConcatenatePaths,
    "GetCurrentPose": path_ops.GetCurrentPose,
    "AppendGoalPoseToGoals": path_ops.AppendGoalPoseToGoals,
    "GetNextFewGoals": path_ops.GetNextFewGoals,
    # docking server (opennav_docking)
    "DockRobot": docking.DockRobot,
    "UndockRobot": docking.UndockRobot,
    # no server in this stack: load, fail when ticked
    "ComputeRoute": unavailable.ComputeRoute,
    "ComputeAndTrackRoute": unavailable.ComputeAndTrackRoute,
    "CancelComputeAndTrackRoute": unavailable.CancelComputeAndTrackRoute,
    "ExtractRouteNodesAsGoals": unavailable.ExtractRouteNodesAsGoals,
    "AssistedTeleop": unavailable.AssistedTeleop,
    "CancelAssistedTeleop": unavailable.CancelAssistedTeleop,
    "FollowObject": unavailable.FollowObject,
    "CancelFollowObject": unavailable.CancelFollowObject,
    "ReinitializeGlobalLocalization": unavailable.ReinitializeGlobalLocalization,
    "ToggleCollisionMonitor": unavailable.ToggleCollisionMonitor,
}

# The blackboard keys bt_navigator zeroes at the start of every goal (Jazzy
# ``error_code_names``), so "would a recovery help?" never reads a previous goal's error.
ERROR_CODE_KEYS = ("compute_path_error_code", "follow_path_error_code")


def register_nav2_nodes(factory: BehaviorTreeFactory) -> None:
    """Register every Nav2-named node type (``NAV2_NODES``) in ``factory``."""
    for registration_id, cls in NAV2_NODES.items():
        factory.register_node_type(cls, registration_id)


def start_navigation(blackboard: Blackboard, goal: Any, *, goal_key: str = "goal",
                     error_code_keys: tuple[str, ...] = ERROR_CODE_KEYS) -> None:
    """What bt_navigator does when a NavigateToPose goal arrives: write the goal and zero the
    error-code keys and the recovery counter. Call before the tree's first tick of a goal
    (and halt the tree between goals, as the navigator does)."""
    blackboard.set(goal_key, goal)
    for key in error_code_keys:
        blackboard.set(key, 0)
    blackboard.set("number_recoveries", 0)
