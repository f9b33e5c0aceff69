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
    # [ours] cells within ``pinch_margin`` m beyond the inscribed radius cost ``pinch_penalty``
    # more each: a plan keeps a margin where the map leaves room for one, and squeezes through a
    # pinch only when there is no reasonable way round (docs/nav.md: the lidar marks an obstacle's
    # edge a cell further out than the static map, so a plan through such a gap is refused by the
    # controller's local costmap, attempt after attempt). 0 disables it.
    pinch_penalty: float = Field(10.0, ge=0)
    pinch_margin: float = Field(0.075, ge=0)
    # [ours] near the map-update layer (collision marks): extra weight from ``mark_penalty`` at
    # the inscribed radius down to 0 at ``mark_halo`` m beyond it. A mark covers where a touch
    # was sensed, not the whole obstacle; a plan keeps a wider berth where it can. 0 disables it.
    mark_penalty: float = Field(4.0, ge=0)
    mark_halo: float = Field(0.3, ge=0)
    allow_unknown: bool = True  # [tb3] GridBased.allow_unknown
    # [nav2] NavFn GridBased.tolerance: an occupied goal is replaced by the nearest plannable
    # cell within this (square) distance; only beyond it does planning fail (GOAL_OCCUPIED)
    tolerance: float = Field(0.5, ge=0)
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
    use_velocity_scaled_lookahead_dist: bool = True  # [brief] (Nav2 code default: false)
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


# ------------------------------------------------------------------------------------------
# Reading a Nav2 parameter file (nav2_bringup / turtlebot3_navigation2 style)
# ------------------------------------------------------------------------------------------

_RPP_KEYS = set(ControllerParams.model_fields) - {
    "controller_frequency", "failure_tolerance", "xy_goal_tolerance", "yaw_goal_tolerance",
    "stateful_goal_checker", "path_length_tolerance", "required_movement_radius",
    "movement_time_allowance", "pose_stale_timeout", "pose_abort_timeout"}


def _node(doc: dict, *names: str) -> dict:
    """``doc[name]['ros__parameters']``, also for the nested ``costmap: costmap:`` form."""
    cur: object = doc
    for n in names:
        cur = cur.get(n, {}) if isinstance(cur, dict) else {}
    return cur.get("ros__parameters", {}) if isinstance(cur, dict) else {}


def _plugin(node: dict, list_key: str, kind: str) -> dict:
    """The first plugin block in ``node[list_key]`` (or any block) whose type contains ``kind``."""
    names = node.get(list_key) or [k for k, v in node.items() if isinstance(v, dict)]
    for name in names:
        block = node.get(name)
        if isinstance(block, dict) and kind in str(block.get("plugin", "")):
            return block
    return {}


def _costmap(node: dict, base: dict) -> dict:
    out = dict(base)
    for key in ("footprint_padding", "track_unknown_space", "update_frequency", "width", "height"):
        if key in node and (key in ("width", "height") or key in CostmapParams.model_fields):
            out[key] = node[key]
    infl = _plugin(node, "plugins", "InflationLayer")
    for key in ("inflation_radius", "cost_scaling_factor"):
        if key in infl:
            out[key] = infl[key]
    obs = _plugin(node, "plugins", "ObstacleLayer") or _plugin(node, "plugins", "VoxelLayer")
    sources = str(obs.get("observation_sources", "")).split()
    src = obs.get(sources[0], {}) if sources else {}
    for key in ("obstacle_max_range", "obstacle_min_range", "raytrace_max_range",
                "raytrace_min_range", "inf_is_valid"):
        if key in src:
            out[key] = src[key]
    if "footprint_clearing_enabled" in obs:
        out["footprint_clearing_enabled"] = obs["footprint_clearing_enabled"]
    plugins = [str(node.get(p, {}).get("plugin", "")) for p in node.get("plugins", [])
               if isinstance(node.get(p), dict)]
    if plugins:
        out["use_static_layer"] = any("StaticLayer" in p for p in plugins)
        out["use_obstacle_layer"] = any("ObstacleLayer" in p or "VoxelLayer" in p for p in plugins)
    return out


def load_nav2_params(path: str | Path, base: NavParams | None = None,
                     robot: RobotParams | None = None) -> tuple[RobotParams, NavParams]:
    """Read the parts of a Nav2 parameter YAML this stand-in understands (costmaps, controller
    server + RPP/DWB/MPPI velocity limits, goal/progress checkers, planner, behaviour server).
    Everything else keeps the defaults of ``base`` / ``robot``."""
    doc = yaml.safe_load(Path(path).read_text()) or {}
    nav = (base or NavParams()).model_dump()
    rob = (robot or RobotParams()).model_dump()

    lc = _node(doc, "local_costmap", "local_costmap")
    gc = _node(doc, "global_costmap", "global_costmap")
    nav["local_costmap"] = _costmap(lc, nav["local_costmap"])
    nav["global_costmap"] = _costmap(gc, nav["global_costmap"])
    for key in ("width", "height"):
        nav["global_costmap"].pop(key, None)
    radius = gc.get("robot_radius", lc.get("robot_radius"))
    if radius is not None:
        rob["radius"] = radius

    cs = _node(doc, "controller_server")
    ctrl = nav["controller"]
    for key in ("controller_frequency", "failure_tolerance"):
        if key in cs:
            ctrl[key] = cs[key]
    pc = _plugin(cs, "progress_checker_plugins", "ProgressChecker")
    for key in ("required_movement_radius", "movement_time_allowance"):
        if key in pc:
            ctrl[key] = pc[key]
    gch = _plugin(cs, "goal_checker_plugins", "GoalChecker")
    for key in ("xy_goal_tolerance", "yaw_goal_tolerance", "path_length_tolerance"):
        if key in gch:
            ctrl[key] = gch[key]
    if "stateful" in gch:
        ctrl["stateful_goal_checker"] = gch["stateful"]
    fp = next((cs[n] for n in cs.get("controller_plugins", []) if isinstance(cs.get(n), dict)), {})
    kind = str(fp.get("plugin", ""))
    if "RegulatedPurePursuit" in kind:
        for key in _RPP_KEYS:
            if key in fp:
                ctrl[key] = fp[key]
        vel = fp.get("desired_linear_vel", fp.get("max_linear_vel"))  # Humble / Jazzy names
        if vel is not None:
            ctrl["desired_linear_vel"] = vel
            rob["max_linear_vel"] = max(rob["max_linear_vel"], vel)
    elif "DWB" in kind:
        for src, dst in (("max_vel_x", "max_linear_vel"), ("max_vel_theta", "max_angular_vel"),
                         ("acc_lim_x", "max_linear_accel"), ("acc_lim_theta", "max_angular_accel")):
            if src in fp:
                rob[dst] = abs(fp[src])
    elif "MPPI" in kind:
        for src, dst in (("vx_max", "max_linear_vel"), ("wz_max", "max_angular_vel"),
                         ("ax_max", "max_linear_accel"), ("az_max", "max_angular_accel")):
            if src in fp:
                rob[dst] = abs(fp[src])

    ps = _node(doc, "planner_server")
    gb = next((ps[n] for n in ps.get("planner_plugins", []) if isinstance(ps.get(n), dict)), {})
    # deliberately not copied: NavFn's "tolerance" (see PlannerParams.tolerance)
    for key in ("allow_unknown", "cost_penalty"):
        if key in gb:
            nav["planner"][key] = gb[key]

    bs = _node(doc, "behavior_server") or _node(doc, "recoveries_server")
    for key in ("cycle_frequency", "simulate_ahead_time", "max_rotational_vel",
                "min_rotational_vel", "rotational_acc_lim"):
        if key in bs:
            nav["behaviors"][key] = bs[key]
    return RobotParams.model_validate(rob), NavParams.model_validate(nav)
