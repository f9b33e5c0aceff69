"""The Nav2 stand-in: occupancy maps, costmaps, planner, Regulated Pure Pursuit, behaviours and
a Nav2-like async action API (``NavStack``). See docs/nav.md."""

from .behaviors import BackUp, DriveOnHeading, Spin, Wait
from .controller import GoalChecker, NoValidControl, ProgressChecker, RegulatedPurePursuit
from .costmap import (
    FREE_SPACE,
    INSCRIBED,
    LETHAL,
    NO_INFORMATION,
    GlobalCostmap,
    LocalCostmap,
    inflation_cost,
)
from .occupancy import OccupancyGrid
from .params import (
    BehaviorParams,
    ControllerParams,
    CostmapParams,
    LocalCostmapParams,
    NavigatorParams,
    NavParams,
    PlannerParams,
    RobotParams,
)
from .planner import GridPlanner, PlanResult
from .stack import COMPONENTS, Heartbeat, NavComponent, NavHandle, NavServiceError, NavStack

__all__ = [
    "COMPONENTS", "FREE_SPACE", "INSCRIBED", "LETHAL", "NO_INFORMATION", "BackUp",
    "BehaviorParams", "ControllerParams", "CostmapParams", "DriveOnHeading", "GlobalCostmap",
    "GoalChecker", "GridPlanner", "Heartbeat", "LocalCostmap", "LocalCostmapParams",
    "NavComponent", "NavHandle", "NavParams", "NavServiceError", "NavStack", "NavigatorParams",
    "NoValidControl", "OccupancyGrid", "PlanResult", "PlannerParams", "ProgressChecker",
    "RegulatedPurePursuit", "RobotParams", "Spin", "Wait", "inflation_cost",
]
