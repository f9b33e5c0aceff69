"""Randomized variants of the paper's failure families, as run specs any campaign backend runs.

The paper's 14 scenarios fix the world, the robot, the poses and the fault times. A layer tuned
to them can pass them and still fail the same failures a little differently. This module draws
fair variants per failure family (seeded, reproducible): the world and robot, start and goal
(taken from a pool of free poses and kept only if the static map has a path between them),
fault timing (standing or driving), hang versus crash, stale and NaN data, flapping, two faults
at once, navigation-server crashes and hangs, oblique and corner collisions, goals inside
obstacles, walls, outside the map or behind walls, and battery goals near the range limit.

Each variant is an ordinary ``ScenarioSpec`` (validated like a shipped file, named
``V<index>_<family>``) inside a campaign ``RunSpec`` (runspec.py), so the local pool, Ray,
shards and resumed results files run variants exactly as they run the shipped scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import Any

import numpy as np

from .box_check import path_with_box, static_plans
from .runspec import RunSpec
from .spec import ScenarioSpec

SENSORS = ("lidar", "imu", "odom", "localization")
NAV_SERVERS = ("planner_server", "controller_server", "behavior_server")
WORLDS = ("apartment", "round_obstacles")
ROBOTS = ("rosbot2", "burger", "waffle")
SPEED = 0.25  # m/s, the paper's cruise speed
PAPER = {"runs": 1, "without": 0, "with": 100}


# -- poses ---------------------------------------------------------------------------------------

@lru_cache(maxsize=8)
def _planner(world: str, robot: str):
    """A planner on the static map a run of (world, robot) starts with (cached per process)."""
    from ..bus import Bus
    from ..driver import robot_params_for
    from ..nav import NavStack, OccupancyGrid
    from ..simulator import Simulator

    sim = Simulator(world, robot, seed=0)
    raster = sim.rasterize(0.05, layer="lidar")
    grid = OccupancyGrid(np.where(raster.data > 0, 100, 0).astype(np.int8), raster.resolution,
                         (raster.origin[0], raster.origin[1], 0.0))
    nav = NavStack(Bus(), grid, robot=robot_params_for(sim))
    static_plans(nav.planner)
    return nav.planner, sim.world


def path_length(world: str, robot: str, start: tuple[float, float], goal: tuple[float, float]) -> float:
    """Length (m) of the static-map plan between two points; inf if there is none."""
    from bt_runtime.runtime.messages import Pose2D

    planner, _ = _planner(world, robot)
    res = planner.plan(Pose2D(*start), Pose2D(*goal))
    if not res.ok or res.points is None or len(res.points) < 2:
        return math.inf
    return float(np.hypot(*np.diff(res.points[:, :2], axis=0).T).sum())


def _pose_pool(world: str) -> list[tuple[float, float, float]]:
    _, w = _planner(world, "rosbot2")
    poses = [(w.spawn.x, w.spawn.y, w.spawn.yaw)]
    poses += [(p.x, p.y, p.yaw) for p in w.goals.values()]
    return poses


def _free_pose(rng: np.random.Generator, world: str, near: tuple[float, float, float], spread: float,
               clearance: float) -> tuple[float, float, float]:
    """A pose within ``spread`` of ``near`` at least ``clearance`` from every obstacle."""
    _, w = _planner(world, "rosbot2")
    for _ in range(40):
        x = near[0] + rng.uniform(-spread, spread)
        y = near[1] + rng.uniform(-spread, spread)
        if w.bounds.contains(x, y) and w.clearance(x, y) >= clearance:
            return (float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
    return near


def _trip(rng: np.random.Generator, world: str, robot: str, min_len: float = 1.2,
          max_len: float = 6.0) -> tuple[tuple[float, float, float], tuple[float, float, float], float]:
    """A start and a goal with a static-map path of a reasonable length between them."""
    pool = _pose_pool(world)
    margin = 0.45 if robot == "waffle" else 0.35
    for _ in range(200):
        a = pool[rng.integers(len(pool))]
        b = pool[rng.integers(len(pool))]
        start = _free_pose(rng, world, a, 0.4, margin)
        goal = _free_pose(rng, world, b, 0.4, margin)
        if math.hypot(goal[0] - start[0], goal[1] - start[1]) < min_len:
            continue
        length = path_length(world, robot, start[:2], goal[:2])
        if min_len <= length <= max_len:
            return start, goal, length
    raise RuntimeError(f"no start/goal pair with a {min_len}-{max_len} m path in {world} for {robot}")


def _pose(p: tuple[float, float, float]) -> dict[str, float]:
    return {"x": round(p[0], 3), "y": round(p[1], 3), "yaw": round(p[2], 3)}


def _drive_time(length: float) -> float:
    return length / SPEED * 1.6 + 10.0


def _spec(name: str, table: str, description: str, **fields: Any) -> ScenarioSpec:
    data = {"name": name, "table": table, "requirements": fields.pop("requirements", []),
            "description": description, "paper": PAPER, "jitter": {"start_xy": 0.0, "start_yaw": 0.0,
                                                                    "fault_time": 0.0}}
    data.update(fields)
    return ScenarioSpec.model_validate(data)


def _choice(rng: np.random.Generator, items):
    return items[int(rng.integers(len(items)))]


# -- sensor failures -----------------------------------------------------------------------------

def _sensor_fault(rng: np.random.Generator, component: str, frozen_pose_detectable: bool = False
                  ) -> tuple[str, list[dict[str, Any]]]:
    """A way for a sensor driver to fail: crash, hang, stale or NaN data, garbage, flapping,
    or a first restart that fails; frozen (one reading re-stamped). A frozen odometry or
    localization pose is only detectable while the robot is told to move and the lidar or the
    IMU shows that it does (a standing robot's pose rightly stays put): ``frozen_pose_detectable``."""
    ways = ["crash", "hang", "stale", "nan", "flapping", "restart_fails"]
    if component in ("lidar", "imu") or frozen_pose_detectable:  # a re-stamped frozen reading shows
        ways.append("frozen")
    if component == "lidar":  # plausible-looking garbage is detectable by range checks only in a scan
        ways.append("garbage")
    how = _choice(rng, tuple(ways))
    if how == "crash":
        return how, [{"kind": "crash", "component": component}]
    if how == "hang":
        return how, [{"kind": "stall", "component": component, "duration": 600.0, "mode": "silent"}]
    if how in ("stale", "frozen"):
        return how, [{"kind": "stall", "component": component, "duration": 600.0, "mode": how}]
    if how in ("nan", "garbage"):
        return how, [{"kind": "corrupt", "component": component, "duration": 600.0, "mode": how}]
    if how == "flapping":
        return how, [{"kind": "crash", "component": component}, {"kind": "crash", "component": component,
                                                                  "_later": float(rng.uniform(4.0, 7.0))}]
    return how, [{"kind": "restart_policy", "component": component, "fail_next": 1},
                 {"kind": "crash", "component": component}]


def sensor_variant(rng: np.random.Generator, index: int) -> ScenarioSpec:
    world, robot = _choice(rng, WORLDS), _choice(rng, ROBOTS)
    start, goal, length = _trip(rng, world, robot)
    driving = bool(rng.integers(2))
    two = rng.uniform() < 0.25
    components = list(rng.choice(SENSORS, size=2 if two else 1, replace=False))
    faults, hows = [], []
    t_fault = float(rng.uniform(1.0, 3.0)) if not driving else float(rng.uniform(1.0, 5.0))
    witnesses_ok = not {"lidar", "imu"} & set(components)  # what shows a frozen pose is moving
    for comp in components:
        how, steps = _sensor_fault(rng, comp, driving and witnesses_ok)
        hows.append(f"{comp} {how}")
        for step in steps:
            later = step.pop("_later", 0.0)
            when = {"after_goal": 0, "delay": t_fault + later} if driving else {"at": 2.0 + t_fault + later}
            faults.append({"fault": step, **when})
    goals = [{"at": 1.0, "pose": _pose(goal)}] if driving else []
    success = [{"kind": "component_reset", "component": c} for c in components]
    if driving:
        success.append({"kind": "reach_goal", "goal": 0, "tolerance": 0.25})
    limit = (_drive_time(length) + 30.0) if driving else 25.0
    last_fault = max((f.get("delay", 0.0) if driving else f.get("at", 0.0)) for f in faults)
    return _spec(f"V{index:04d}_sensor", "III", f"{' + '.join(hows)} while "
                 f"{'driving' if driving else 'standing'} ({robot} in {world})",
                 requirements=["fn_req1", "fn_req2", "fn_req5"], world=world, robot=robot,
                 start=_pose(start), goals=goals, faults=faults, success=success, time_limit=limit,
                 settle=last_fault + 12.0,  # a fault after the goal was reached must still be handled
                 speeds={"linear": SPEED})


# -- navigation servers --------------------------------------------------------------------------

def nav_server_variant(rng: np.random.Generator, index: int) -> ScenarioSpec:
    world, robot = _choice(rng, WORLDS), _choice(rng, ROBOTS)
    start, goal, length = _trip(rng, world, robot)
    server = _choice(rng, NAV_SERVERS)
    kinds = ["nav_crash", "nav_hang"] + (["nav_fail_until_restart"] if server != "behavior_server" else [])
    kind = _choice(rng, kinds)
    before = rng.uniform() < 0.25
    when = {"at": 0.5} if before else {"after_goal": 0, "delay": float(rng.uniform(0.5, 5.0))}
    faults = [{"fault": {"kind": kind, "component": server}, **when}]
    if rng.uniform() < 0.2:  # a second server fails too
        other = _choice(rng, [s for s in NAV_SERVERS if s != server])
        faults.append({"fault": {"kind": "nav_crash", "component": other}, "after_goal": 0,
                       "delay": float(rng.uniform(0.5, 6.0))})
    success = [{"kind": "reach_goal", "goal": 0, "tolerance": 0.25}]
    return _spec(f"V{index:04d}_nav_server", "II", f"{server} {kind.removeprefix('nav_')} "
                 f"{'before the goal' if before else 'while driving'} ({robot} in {world})",
                 requirements=["fn_req1", "fn_req7"], world=world, robot=robot, start=_pose(start),
                 goals=[{"at": 1.0, "pose": _pose(goal)}], faults=faults, success=success,
                 time_limit=_drive_time(length) + 30.0, speeds={"linear": SPEED})


# -- unreachable goals ---------------------------------------------------------------------------

def _wall_point(rng: np.random.Generator, world: str, near: tuple[float, float],
                start: tuple[float, float]) -> tuple[float, float] | None:
    """A point inside a wall or obstacle of the world, within 2.5 m of ``near`` and at least
    1.5 m from ``start`` (so reaching an alternative means driving towards it)."""
    _, w = _planner(world, "rosbot2")
    for _ in range(300):
        x = near[0] + rng.uniform(-2.5, 2.5)
        y = near[1] + rng.uniform(-2.5, 2.5)
        if w.bounds.contains(x, y) and w.clearance(x, y, lidar=True) <= 0.0 and \
                math.hypot(x - start[0], y - start[1]) >= 1.5:
            return float(x), float(y)
    return None


# The layer's documented rule for alternatives (trees/autonomy.xml, nodes/path.py): candidates on
# rings 0.1 m apart up to 0.85 m from the goal, 16 per ring (the first facing the robot), at least
# the robot's radius + 0.1 m from lethal cells, reachable by a plan. The generator applies the same
# rule on the world's geometry; the costmap's 5 cm cells and the scan's re-marking blur clearance by
# up to BLUR either way, so a target whose best candidate lies within BLUR of the floor is
# ambiguous and is not used (the expected outcome would be a coin toss, not a property of the layer).
ALT_RADIUS, ALT_STEP, ALT_DIRECTIONS, ALT_MARGIN, BLUR = 0.85, 0.1, 16, 0.1, 0.07


def _alternative_expected(world: str, robot: str, start, target,
                          disc: tuple[float, float, float] | None = None) -> bool | None:
    """True if the layer's rule finds a safe reachable alternative near ``target``, False if it
    cannot, None if that hangs on the costmap's discretisation. ``disc`` (x, y, radius): an
    obstacle added to the map at run time."""
    from bt_runtime.runtime.messages import Pose2D
    from nodes.path import ring_candidates

    from ..robot import load_profile

    _, w = _planner(world, robot)
    need = load_profile(robot).radius + ALT_MARGIN
    best = -math.inf
    for c in ring_candidates(Pose2D(*target[:2]), Pose2D(*start[:2]), ALT_RADIUS, ALT_STEP, ALT_DIRECTIONS):
        if not w.bounds.contains(c.x, c.y):
            continue
        clear = w.clearance(c.x, c.y)
        if disc is not None:
            clear = min(clear, math.hypot(c.x - disc[0], c.y - disc[1]) - disc[2])
        if clear <= best or clear < need - BLUR:
            continue
        if path_length(world, robot, start[:2], (c.x, c.y)) < math.inf:
            best = clear
            if best >= need + BLUR:
                return True
    if best < need - BLUR:
        return False
    return None


def unreachable_goal_variant(rng: np.random.Generator, index: int) -> ScenarioSpec:
    world, robot = _choice(rng, WORLDS), _choice(rng, ROBOTS)
    start, goal, length = _trip(rng, world, robot, max_len=5.0)
    how = _choice(rng, ("in_obstacle", "in_wall", "outside_map", "phantom"))
    map_obstacles, faults = [], []
    criterion: dict[str, Any] = {"kind": "alternative_reached", "goal": 0, "within": 1.0}
    target = goal
    expected: bool | None = None
    if how == "in_wall":
        for _ in range(10):  # a wall point whose outcome the layer's rule decides clearly
            point = _wall_point(rng, world, goal[:2], start[:2])
            if point is None:
                break
            expected = _alternative_expected(world, robot, start, point)
            if expected is not None:
                target = (point[0], point[1], goal[2])
                break
        else:
            point = None
        if point is None or expected is None:
            how = "in_obstacle"
    if how == "in_obstacle":
        for radius in (float(rng.uniform(0.15, 0.4)), 0.3, 0.2):
            expected = _alternative_expected(world, robot, start, goal, (goal[0], goal[1], radius))
            if expected is not None:
                break
        map_obstacles.append({"kind": "obstacle_at", "x": goal[0], "y": goal[1], "radius": radius,
                              "name": "at_goal"})
    elif how == "outside_map":
        _, w = _planner(world, "rosbot2")
        b = w.bounds
        side = int(rng.integers(4))
        out = float(rng.uniform(1.2, 3.0))  # beyond the alternative-goal radius: only refusing is right
        x = float(np.clip(goal[0], b.xmin + 0.5, b.xmax - 0.5))
        y = float(np.clip(goal[1], b.ymin + 0.5, b.ymax - 0.5))
        x, y = ((b.xmin - out, y), (b.xmax + out, y), (x, b.ymin - out), (x, b.ymax + out))[side]
        target = (x, y, goal[2])
        criterion = {"kind": "goal_refused", "goal": 0, "max_travel": 0.3}
    elif how == "phantom":  # a phantom obstacle on the goal in the costmaps (no sensor supports it): clear, re-plan
        faults.append({"fault": {"kind": "nav_phantom_obstacle", "x": goal[0], "y": goal[1], "radius": 0.3},
                       "at": 0.5})
        criterion = {"kind": "reach_goal", "goal": 0, "tolerance": 0.25}
    if criterion["kind"] == "alternative_reached" and expected is False:
        how += " (no safe point near it: refuse)"
        criterion = {"kind": "goal_refused", "goal": 0, "max_travel": 0.3}
    return _spec(f"V{index:04d}_unreachable_goal", "II", f"goal {how.replace('_', ' ')} ({robot} in {world})",
                 requirements=["fn_req7", "fn_req8"], world=world, robot=robot, start=_pose(start),
                 map_obstacles=map_obstacles, goals=[{"at": 1.0, "pose": _pose(target)}], faults=faults,
                 success=[criterion], time_limit=_drive_time(length) + 30.0, speeds={"linear": SPEED})


# -- collisions ----------------------------------------------------------------------------------

def _box_on_path(rng: np.random.Generator, world: str, robot: str, start, goal, how: str) -> dict[str, float]:
    """A 0.3 m box on the static-map path, 35-60 % along it: square to it, turned 0.4-1 rad
    (oblique), or also 0.1-0.18 m to a side (corner)."""
    from bt_runtime.runtime.messages import Pose2D

    planner, _ = _planner(world, robot)
    pts = planner.plan(Pose2D(*start[:2]), Pose2D(*goal[:2])).points
    along = float(rng.uniform(0.35, 0.6))
    i = int(along * (len(pts) - 1))
    x, y, heading = float(pts[i, 0]), float(pts[i, 1]), float(pts[min(i + 3, len(pts) - 1), 2])
    yaw = heading + (float(rng.uniform(0.4, 1.0)) * (1 if rng.integers(2) else -1) if how != "on_path" else 0.0)
    lateral = float(rng.uniform(0.1, 0.18)) * (1 if rng.integers(2) else -1) if how == "corner" else 0.0
    x -= lateral * math.sin(heading)
    y += lateral * math.cos(heading)
    return {"x": round(x, 3), "y": round(y, 3), "yaw": round(yaw, 3), "width": 0.3, "depth": 0.3}


HITTER = {"ahead": 0.0, "width": 0.3, "depth": 0.3}  # the pushed variants' box, against the body's front


def _hitter_box(robot: str, start) -> dict[str, float]:
    """Where the pushed variant's hitter stays (``invisible_obstacle`` with ``ahead``, placed
    in front of the standing robot at ``start``), as a box for ``path_with_box``."""
    from ..robot import load_profile

    near = load_profile(robot).radius + HITTER["ahead"] + HITTER["depth"] / 2
    x, y, yaw = start
    return {"x": x + near * math.cos(yaw), "y": y + near * math.sin(yaw), "yaw": yaw,
            "width": HITTER["width"], "depth": HITTER["depth"]}


def collision_variant(rng: np.random.Generator, index: int) -> ScenarioSpec:
    world, robot = _choice(rng, WORLDS), _choice(rng, ROBOTS)
    start, goal, length = _trip(rng, world, robot, min_len=2.5)
    how = _choice(rng, ("on_path", "oblique", "corner", "pushed"))
    faults: list[dict[str, Any]] = []
    success: list[dict[str, Any]] = [{"kind": "out_of_contact", "for_last": 2.0},
                                     {"kind": "reach_goal", "goal": 0, "tolerance": 0.25}]
    if how == "pushed":
        for _ in range(30):  # a hitter that leaves the goal reachable (as the boxes on the path)
            detour = path_with_box(world, robot, start[:2], goal[:2], _hitter_box(robot, start))
            if detour < math.inf:
                length = max(length, detour)
                break
            start, goal, length = _trip(rng, world, robot, min_len=2.5)
        faults.append({"fault": {"kind": "invisible_obstacle", **HITTER, "name": "hitter"}, "at": 2.0})
        faults.append({"fault": {"kind": "push", "impulse": float(rng.uniform(0.5, 1.2)),
                                 "direction": 3.1416}, "at": 2.0})
        success.append({"kind": "hit_once", "obstacle": "hitter"})
        goals = [{"at": 6.0, "pose": _pose(goal)}]
    else:
        box = None
        for _ in range(30):  # a box that leaves the goal reachable (sim/scenarios/box_check.py)
            box = _box_on_path(rng, world, robot, start, goal, how)
            detour = path_with_box(world, robot, start[:2], goal[:2], box)
            if detour < math.inf:
                length = max(length, detour)
                break
            start, goal, length = _trip(rng, world, robot, min_len=2.5)
        faults.append({"fault": {"kind": "invisible_obstacle", **box, "name": "low_box"}, "at": 0.0})
        success.insert(1, {"kind": "obstacle_in_map", "obstacle": "low_box", "within": 0.3, "only_if_hit": True})
        success.append({"kind": "hit_once", "obstacle": "low_box"})
        goals = [{"at": 1.0, "pose": _pose(goal)}]
    return _spec(f"V{index:04d}_collision", "II", f"{how.replace('_', ' ')} collision ({robot} in {world})",
                 requirements=["fn_req2", "fn_req6"], world=world, robot=robot, start=_pose(start),
                 goals=goals, faults=faults, success=success, time_limit=_drive_time(length) + 45.0,
                 speeds={"linear": SPEED})


# -- battery -------------------------------------------------------------------------------------

# What the battery check of trees/autonomy.xml asks for (nodes/battery.py): the energy of the
# planned path and of the way back to the dock (straight line x 1.5 and a half turn) by the
# nominal model, times the learned factor (nodes/energy.py), times 1.5, plus a 10 % reserve,
# converted to percent at the measured voltage. From the dock, charging stops once the goal
# passes the same check with a 20 % reserve (it must do so below BatteryAbove's 95 %).
SAFETY_FACTOR, RESERVE, CHARGE_RESERVE, DETOUR_FACTOR = 1.5, 10.0, 20.0, 1.5
PATH_SLACK = 0.05  # the layer plans on its own costmap from its estimated pose: +-5 % path energy
SOC_NOISE = 0.3  # three sigmas of the state-of-charge reading's noise (percentage points)
CHECK_BY = 3.0  # s: the near goal is checked by then (far goal at 1 s, refused, near goal 1 s later)


def _battery_info(robot: str, capacity_ah: float):
    from bt_runtime.runtime.messages import RobotInfo

    from ..robot import load_profile

    profile = load_profile(robot)
    b = profile.battery
    info = RobotInfo(radius=profile.radius, max_linear=profile.max_linear, max_angular=profile.max_angular,
                     capacity_ah=capacity_ah, voltage_nominal=(b.voltage_full + b.voltage_empty) / 2,
                     idle_power_w=b.idle_power_w, k_linear=b.k_linear, k_angular=b.k_angular)
    return info, b


def _nominal_wh(world: str, robot: str, start, goal, info) -> float:
    """The nominal model's energy (Wh) for the static-map plan from ``start`` to ``goal``."""
    from bt_runtime.runtime.messages import Pose2D
    from nodes.battery import energy_for_path, path_turning

    planner, _ = _planner(world, robot)
    res = planner.plan(Pose2D(*start[:2]), Pose2D(*goal[:2]))
    if not res.ok or res.points is None or len(res.points) < 2:
        return math.inf
    pts = res.points
    length = float(np.hypot(*np.diff(pts[:, :2], axis=0).T).sum())
    return energy_for_path(length, path_turning(pts, start[2]), min(info.max_linear, SPEED),
                           min(info.max_angular, 1.0), info)


def _dock(world: str, robot: str):
    """The world's dock pose (what the runner puts on the layer's blackboard as ``dock_pose``)."""
    return _planner(world, robot)[1].dock.to_pose()


def _return_wh(world: str, robot: str, goal, info) -> float:
    """The layer's nominal energy (Wh) for the way back from ``goal`` to the dock."""
    from bt_runtime.runtime.messages import Pose2D
    from nodes.battery import return_energy

    return return_energy(Pose2D(*goal[:2]), _dock(world, robot), DETOUR_FACTOR, min(info.max_linear, SPEED),
                         min(info.max_angular, 1.0), info)


def _required_percent(info, spec, energy_wh: float, factor: float, soc: float) -> float:
    return info.percent_for(energy_wh * factor, spec.voltage(soc)) * SAFETY_FACTOR + RESERVE


def _battery_band(info, spec, far_wh: float, near_wh: float) -> tuple[float, float] | None:
    """The initial states of charge for which the layer's documented model must refuse the far
    goal and accept the near one, whatever this unit's true consumption and however the first
    noisy readings move the estimate (``EnergyModel.factor_bounds``); None if there are none.

    Far: refused even for the thriftiest unit the model allows (``low``): then refusing is right,
    not merely cautious. Near: accepted at the most cautious factor the check can use (``high``),
    after ``CHECK_BY`` s of idle drain of the hungriest unit, with the reading's noise."""
    from nodes.energy import EnergyModel

    low, high = EnergyModel.factor_bounds()
    hi = None
    for soc in np.arange(95.0, RESERVE, -0.25):  # the far goal's need falls with the voltage
        if soc < _required_percent(info, spec, far_wh * (1 - PATH_SLACK), low, soc) - SOC_NOISE:
            hi = float(soc)
            break
    if hi is None:
        return None
    drain = info.percent_for(info.idle_power_w * high * CHECK_BY / 3600.0, spec.voltage_empty)
    for soc in np.arange(RESERVE, hi + 1e-9, 0.25):
        checked = soc - drain
        if checked - SOC_NOISE >= _required_percent(info, spec, near_wh * (1 + PATH_SLACK), high, checked):
            return (float(soc), hi) if hi - soc >= 0.5 else None
    return None


STAGING = {"apartment": (-3.9, -1.0, math.pi)}  # the dock's staging pose (dock -4.6, -1.0, facing west)


def battery_variant(rng: np.random.Generator, index: int) -> ScenarioSpec:
    """A near goal within the battery's range, then a far one beyond it: the near goal must be
    reached without docking (the layer is not over-cautious), the far one refused at first, then
    reached after docking and charging at the apartment's dock. The state of charge is drawn
    uniformly from the band where the layer's documented energy model (nodes/energy.py) must
    accept the near goal and refuse the far one (``_battery_band``; the far goal's energy
    counted from the near pose, plus the near trip's over the safety factor, which is what the
    near trip leaves of the charge), and keeps enough, after the near trip, to reach the dock
    (with the hungriest unit and slack: the layer's check reserves it by its model). The charger is fast
    (50 W) "for rapid testing"."""
    world = "apartment"
    robot = _choice(rng, ROBOTS)
    capacity = 0.1
    info, spec = _battery_info(robot, capacity)
    staging = STAGING[world]
    for _ in range(100):
        start, far, far_len = _trip(rng, world, robot, min_len=3.0, max_len=9.0)
        near = _free_pose(rng, world, start, 1.2, 0.4)
        near_len = path_length(world, robot, start[:2], near[:2])
        if not 0.4 <= near_len <= 2.0:
            continue
        if path_length(world, robot, staging[:2], far[:2]) > 4.0 * math.dist(staging[:2], far[:2]):
            continue  # RatePathQuality (max_length_ratio 5) would reject every plan from the dock
        near_wh = _nominal_wh(world, robot, start, near, info)
        far_back_wh = _return_wh(world, robot, far, info)
        band = _battery_band(info, spec, _nominal_wh(world, robot, near, far, info) + far_back_wh
                             + near_wh / SAFETY_FACTOR, near_wh + _return_wh(world, robot, near, info))
        if band is None:
            continue
        from nodes.energy import EnergyModel

        dock = _dock(world, robot)
        charged_wh = (_nominal_wh(world, robot, (dock.x, dock.y, dock.yaw), far, info) + far_back_wh) \
            * EnergyModel.factor_bounds()[1]
        if info.percent_for(charged_wh, spec.voltage(90.0)) * SAFETY_FACTOR + CHARGE_RESERVE > 90.0:
            continue  # the charge the layer waits for on the dock must be well below full
        dock_wh = (near_wh + _nominal_wh(world, robot, near, staging, info)) * 1.2  # the hungriest unit, and slack
        lowest = max(band[0], info.percent_for(dock_wh, spec.voltage_empty) + 2.0)
        if lowest < band[1]:
            soc = float(rng.uniform(lowest, band[1]))
            break
    else:
        raise RuntimeError("no battery variant found")
    return _spec(f"V{index:04d}_battery", "II", f"battery at {soc:.1f} % (band {lowest:.1f}-{band[1]:.1f} %): "
                 f"near goal {near_len:.1f} m reached, far goal {far_len:.1f} m refused, charged at the dock, "
                 f"reached ({robot})", requirements=["fn_req9"], world=world,
                 robot=robot, robot_overrides={"battery.capacity_ah": capacity, "battery.initial_soc": round(soc, 2),
                                               "battery.charge_power_w": 50.0},
                 start=_pose(start),
                 goals=[{"at": 1.0, "pose": _pose(near)},
                        {"after_previous": True, "delay": 1.0, "pose": _pose(far)}],
                 success=[{"kind": "reach_goal", "goal": 0, "tolerance": 0.25, "without_charging": True},
                          {"kind": "charged_then_reached", "goal": 1}],
                 time_limit=_drive_time(near_len) + _drive_time(far_len) + 180.0, speeds={"linear": SPEED})


FAMILIES: dict[str, Callable[[np.random.Generator, int], ScenarioSpec]] = {
    "sensor": sensor_variant,
    "nav_server": nav_server_variant,
    "unreachable_goal": unreachable_goal_variant,
    "collision": collision_variant,
    "battery": battery_variant,
}
WEIGHTS = {"sensor": 0.35, "nav_server": 0.2, "unreachable_goal": 0.15, "collision": 0.2, "battery": 0.1}


def generate(n: int, seed: int = 0, *, families: list[str] | None = None, modes: tuple[str, ...] = ("with",),
             artifacts: dict | None = None, options: dict | None = None) -> list[RunSpec]:
    """``n`` variants (each in every mode), families drawn by weight; reproducible from ``seed``:
    variant ``i`` depends only on (seed, i), so shards and resumed campaigns agree."""
    names = families or list(FAMILIES)
    unknown = [f for f in names if f not in FAMILIES]
    if unknown:
        raise ValueError(f"unknown variant families {unknown}; known: {', '.join(FAMILIES)}")
    out = []
    for i in range(n):
        spec, run_seed = variant(seed, i, names)
        out.extend(RunSpec(spec, mode, i, run_seed, artifacts=dict(artifacts or {}), options=dict(options or {}))
                   for mode in modes)
    return out


def variant(seed: int, index: int, families: list[str] | None = None) -> tuple[ScenarioSpec, int]:
    """Variant ``index`` of the campaign ``seed`` (drawn among ``families``, all by default)
    and its run seed: what ``generate`` yields at that index, without drawing the others."""
    names = families or list(FAMILIES)
    weights = np.array([WEIGHTS[f] for f in names])
    weights /= weights.sum()
    rng = np.random.default_rng([seed, index])
    family = names[int(rng.choice(len(names), p=weights))]
    spec = FAMILIES[family](rng, index)
    return spec, int(rng.integers(2**31))


def family_of(name: str) -> str:
    """The family of a variant from its name (``V0012_nav_server`` -> ``nav_server``)."""
    return name.split("_", 1)[1] if name.startswith("V") and "_" in name else name


__all__ = ["FAMILIES", "family_of", "generate", "path_length", "variant"]
