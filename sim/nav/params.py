"""Parameters of the Nav2 stand-in, with their Nav2 names and where each default comes from.

Sources (copied under ``shared/reference/nav2/params``):
  [tb3]   turtlebot3_navigation2 ``param/burger.yaml`` (Jazzy and later)
  [nav2]  Nav2 code defaults (nav2_regulated_pure_pursuit_controller, nav2_controller,
          nav2_behaviors, nav2_costmap_2d, nav2_smac_planner)
  [brief] the project's choices (paper: 0.25 m/s, controller at 20 Hz, progress 0.5 m / 10 s)
Deviations from Nav2 are marked "deviation" with the reason.
"""

from __future__ import annotations

from pathlib import Path

import yaml
from pydantic import BaseModel, ConfigDict, Field


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class RobotParams(_Model):
    """The robot as the navigation stack sees it (circular footprint)."""

    radius: float = Field(0.1, gt=0)  # [tb3] robot_radius
    max_linear_vel: float = Field(0.3, gt=0)  # [tb3] max_vel_x
    max_angular_vel: float = Field(1.0, gt=0)  # [tb3] max_vel_theta
    max_linear_accel: float = Field(2.5, gt=0)  # [nav2] RPP max_linear_accel / tb3 decel_lim_x
    max_angular_accel: float = Field(3.2, gt=0)  # [tb3] acc_lim_theta
    laser_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # scan origin in the robot frame


class CostmapParams(_Model):
    """One costmap (Nav2 ``global_costmap`` / ``local_costmap``)."""

    footprint_padding: float = 0.01  # [nav2] footprint_padding
    inflation_radius: float = Field(0.5, gt=0)  # [tb3] inflation_layer.inflation_radius
    cost_scaling_factor: float = Field(5.0, gt=0)  # [tb3] inflation_layer.cost_scaling_factor
    obstacle_max_range: float = 2.5  # [tb3] scan.obstacle_max_range
    obstacle_min_range: float = 0.0  # [tb3]
    raytrace_max_range: float = 3.0  # [tb3] scan.raytrace_max_range
    raytrace_min_range: float = 0.0  # [tb3]
    # deviation: Nav2's default is false; a simulated LiDAR reports "nothing within range" as
    # inf, and clearing along those beams is what removes obstacles that went away.
    inf_is_valid: bool = True
    footprint_clearing_enabled: bool = True  # [nav2]
    track_unknown_space: bool = True  # [tb3] global: true (local: false, see LocalCostmapParams)
    lethal_cost_threshold: int = 100  # [nav2] static layer: occupancy >= this is lethal
    update_frequency: float = Field(1.0, gt=0)  # [tb3] global 1 Hz
    use_static_layer: bool = True
    use_obstacle_layer: bool = True


class LocalCostmapParams(CostmapParams):
    width: float = Field(3.0, gt=0)  # [tb3] 3 x 3 m rolling window
    height: float = Field(3.0, gt=0)
    track_unknown_space: bool = False  # [nav2] default (tb3 local sets nothing)
    update_frequency: float = Field(5.0, gt=0)  # [tb3] local 5 Hz
    use_static_layer: bool = False  # [tb3] local plugins: obstacle (+voxel) + inflation only


class PlannerParams(_Model):
    """Grid planner (cost-aware 8-connected A*, like Smac2D; GridBased in Nav2 terms)."""

    cost_penalty: float = Field(2.0, ge=0)  # [nav2] Smac2D cost_penalty
    allow_unknown: bool = True  # [tb3] GridBased.allow_unknown
    # deviation: NavFn's tolerance is 0.5 m (it plans to the nearest free cell); 0 makes an
    # occupied goal fail with GOAL_OCCUPIED, which the autonomy layer wants to see.
    tolerance: float = Field(0.0, ge=0)
    smooth: bool = True
    # accept the cached relaxed-optimal path if its master cost is within this fraction of the
    # lower bound (bounded suboptimality; 0 = exact). See planner.py.
    suboptimality_tolerance: float = Field(0.01, ge=0)
    # A* with the cached heuristic runs in Python; beyond this many expansions the planner
    # switches to a compiled Dijkstra (scipy) on the whole grid.
    max_python_expansions: int = Field(6000, gt=0)
    # nodes a search may settle before giving up with PLANNER_TIMEOUT (Smac max_iterations).
    max_iterations: int = Field(1_000_000, gt=0)
    heuristic_cache_size: int = Field(8, ge=1)


class ControllerParams(_Model):
    """Controller server + Regulated Pure Pursuit + goal/progress checkers."""

    controller_frequency: float = Field(20.0, gt=0)  # [brief] (nav2 bringup 20, tb3 10)
    desired_linear_vel: float = Field(0.25, gt=0)  # [brief] the paper's speed (RPP max_linear_vel)
    lookahead_dist: float = 0.6  # [nav2]
    min_lookahead_dist: float = 0.3  # [nav2]
    max_lookahead_dist: float = 0.9  # [nav2]
    lookahead_time: float = 1.5  # [nav2]
    use_velocity_scaled_lookahead_dist: bool = False  # [nav2]
    rotate_to_heading_angular_vel: float = 1.8  # [nav2] (clamped to the robot's max)
    use_rotate_to_heading: bool = True  # [nav2]
    rotate_to_heading_min_angle: float = 0.785  # [nav2]
    max_angular_accel: float = 3.2  # [nav2]
    min_approach_linear_velocity: float = 0.05  # [nav2]
    approach_velocity_scaling_dist: float = 0.6  # [nav2]
    use_collision_detection: bool = True  # [nav2]
    max_allowed_time_to_collision_up_to_carrot: float = 1.0  # [nav2]
    use_regulated_linear_velocity_scaling: bool = True  # [nav2]
    regulated_linear_scaling_min_radius: float = 0.9  # [nav2]
    regulated_linear_scaling_min_speed: float = 0.25  # [nav2]
    use_cost_regulated_linear_velocity_scaling: bool = True  # [nav2]
    cost_scaling_dist: float = 0.6  # [nav2]
    cost_scaling_gain: float = 1.0  # [nav2]
    failure_tolerance: float = 0.3  # [tb3] controller_server.failure_tolerance
    # goal checker (SimpleGoalChecker)
    xy_goal_tolerance: float = 0.25  # [tb3]
    yaw_goal_tolerance: float = 0.25  # [tb3]
    stateful_goal_checker: bool = True  # [tb3]
    path_length_tolerance: float = 1.0  # [nav2]
    # progress checker (SimpleProgressChecker)
    required_movement_radius: float = 0.5  # [brief] (nav2 bringup 0.5, tb3 jazzy 0.1)
    movement_time_allowance: float = 10.0  # [tb3]
    # pose freshness: stop commanding after this long without a pose, abort after the second
    pose_stale_timeout: float = 0.5  # [brief]
    pose_abort_timeout: float = 1.0  # [brief] -> CONTROLLER_TF_ERROR
    max_robot_pose_search_dist: float = 2.2  # [nav2] default = local costmap half-diagonal


class BehaviorParams(_Model):
    """Behavior server (Spin, BackUp, DriveOnHeading, Wait)."""

    cycle_frequency: float = Field(10.0, gt=0)  # [tb3]
    simulate_ahead_time: float = 2.0  # [tb3]
    max_rotational_vel: float = 1.0  # [tb3]
    min_rotational_vel: float = 0.4  # [tb3]
    rotational_acc_lim: float = 3.2  # [tb3]
    acceleration_limit: float = 2.5  # [nav2] drive_on_heading / backup
    deceleration_limit: float = -2.5  # [nav2]
    minimum_speed: float = 0.10  # [nav2]


class NavigatorParams(_Model):
    """The navigate_to_pose orchestration and the component model."""

    replan_frequency: float = Field(1.0, gt=0)  # [nav2] RateController hz=1.0 in the default tree
    # None = wait for the planner forever (Nav2: a hung planner leaves the action running)
    planner_result_timeout: float | None = None
    service_timeout: float = 1.0  # [nav2] wait_for_service_timeout 1000 ms (costmap services)
    heartbeat_rate: float = Field(10.0, gt=0)  # [brief]
    restart_delay: float = 2.0  # seconds a restarted component spends STARTING
    feedback_rate: float = Field(10.0, gt=0)


class NavParams(_Model):
    global_costmap: CostmapParams = Field(default_factory=CostmapParams)
    local_costmap: LocalCostmapParams = Field(default_factory=LocalCostmapParams)
    planner: PlannerParams = Field(default_factory=PlannerParams)
    controller: ControllerParams = Field(default_factory=ControllerParams)
    behaviors: BehaviorParams = Field(default_factory=BehaviorParams)
    navigator: NavigatorParams = Field(default_factory=NavigatorParams)

    @classmethod
    def from_yaml(cls, path: str | Path) -> NavParams:
        data = yaml.safe_load(Path(path).read_text()) or {}
        return cls.model_validate(data)
