"""Does a box the lidar cannot see leave the goal reachable? (the collision variants' fairness)

A collision variant puts a box on the robot's static-map path. Placed in a corridor or a
doorway narrower than the box plus the robot's width, it cuts the goal off for good: no layer
could reach it, even one that knew the box exactly. The generator keeps only boxes that leave
a way, checked with the navigation stack's own planner on the static map with the true box
rasterised into it (the truth is fine here: this judges the variant, not the robot).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from bt_runtime.runtime.messages import Pose2D


@lru_cache(maxsize=8)
def _static(world: str, robot: str):
    """(raster, robot params) of the static map a run of (world, robot) starts with."""
    from ..driver import robot_params_for
    from ..simulator import Simulator

    sim = Simulator(world, robot, seed=0)
    return sim.rasterize(0.05, layer="lidar"), robot_params_for(sim)


def box_cells(shape: tuple[int, int], resolution: float, origin: tuple[float, float],
              x: float, y: float, yaw: float, width: float, depth: float) -> np.ndarray:
    """Mask of the grid cells a box (centre, yaw, ``depth`` along yaw, ``width`` across) touches."""
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]]
    dx = origin[0] + (cols + 0.5) * resolution - x
    dy = origin[1] + (rows + 0.5) * resolution - y
    c, s = math.cos(yaw), math.sin(yaw)
    half = resolution / 2
    return (np.abs(c * dx + s * dy) <= depth / 2 + half) & (np.abs(-s * dx + c * dy) <= width / 2 + half)


def path_with_box(world: str, robot: str, start: tuple[float, float], goal: tuple[float, float],
                  box: dict) -> float:
    """Length (m) of the plan from ``start`` to ``goal`` with ``box`` (x, y, yaw, width, depth)
    in the static map; inf if the box cuts the goal off."""
    from ..bus import Bus
    from ..nav import NavStack, OccupancyGrid

    raster, params = _static(world, robot)
    data = np.where(raster.data > 0, 100, 0).astype(np.int8)
    data[box_cells(data.shape, raster.resolution, (raster.origin[0], raster.origin[1]), box["x"], box["y"],
                   box["yaw"], box["width"], box["depth"])] = 100
    grid = OccupancyGrid(data, raster.resolution, (raster.origin[0], raster.origin[1], 0.0))
    res = static_plans(NavStack(Bus(), grid, robot=params).planner).plan(Pose2D(*start), Pose2D(*goal))
    if not res.ok or res.points is None or len(res.points) < 2:
        return math.inf
    return float(np.hypot(*np.diff(res.points[:, :2], axis=0).T).sum())


def static_plans(planner):
    """The planner as the generator uses it: shortest cost-aware paths without the pinch
    penalty (``PlannerParams.pinch_penalty``), so the variants drawn from a seed (where a box
    stands along the path, which trips qualify) stay the same whatever the layer's planner
    prefers; whether a way exists does not depend on it."""
    planner.params = planner.params.model_copy(update={"pinch_penalty": 0.0})
    return planner


__all__ = ["box_cells", "path_with_box", "static_plans"]
