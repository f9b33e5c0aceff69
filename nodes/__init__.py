"""The robot behaviour library: health, collision, battery, path and goal nodes, plus the
Nav2-named nodes (``nodes.nav2``) so Nav2's own trees load.

``register_all(factory)`` registers everything; the CLI calls it for every tree it runs.
"""

from __future__ import annotations

from bt_runtime import BehaviorTreeFactory

from . import battery, collision, docking, goals, health, motion_safety, path, safety_zones
from .nav2 import register_nav2_nodes

AUTONOMY_NODES = [
    health.ComponentHealthy, health.ComponentsHealthy, health.AnyComponentDead, health.RequestRestarts,
    health.RestartComponent, health.WaitForHealthy, health.SetSpeedLimit, health.RestoreSpeedLimit,
    health.EmergencyStop, health.ReleaseEmergencyStop, health.IsSafeToContinue, health.RestartServerAfterError,
    collision.CollisionDetected, collision.InContact, collision.EstimateContactPoint, collision.ReverseOut,
    collision.StopRobot, collision.ReleaseRobot, collision.MarkObstacle, collision.ClearCostmaps,
    collision.RelaxCollisionMarks,
    battery.BatteryCanReach, battery.BatteryAbove, battery.RefuseGoal,
    docking.ChargeUntil, docking.GoalStatusIs, docking.OnCharger, docking.WhileGoalStatusIs,
    path.RatePathQuality, path.PathReachesGoal, path.PlannerAnswers,
    path.FindAlternativeGoal, path.EscapeInflation,
    goals.GoalPending, goals.SetGoalStatus, goals.RetryGoal,
    motion_safety.StopBeforeObstacle, safety_zones.SafetyZoneTriggered,
]


def register_autonomy_nodes(factory: BehaviorTreeFactory) -> None:
    for cls in AUTONOMY_NODES:
        factory.register_node_type(cls)


def register_all(factory: BehaviorTreeFactory) -> None:
    register_autonomy_nodes(factory)
    register_nav2_nodes(factory)


__all__ = ["AUTONOMY_NODES", "register_all", "register_autonomy_nodes", "register_nav2_nodes"]
