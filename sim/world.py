"""World files: obstacles, spawn pose, named goals, dock, bounds; YAML validated with pydantic.

A world file looks like::

    name: apartment
    bounds: {xmin: -8, ymin: -6, xmax: 8, ymax: 6}
    spawn: {x: -2.0, y: -1.0, yaw: 0.0}
    dock: {x: -4.6, y: 0.35, yaw: 3.14159}       # optional
    goals:
      kitchen: {x: 3.5, y: 1.0, yaw: 0.0}
    obstacles:
      - {type: polygon, name: wall, points: [[0, 0], [1, 0], [1, 0.15], [0, 0.15]]}
      - {type: segment, a: [0, 0], b: [2, 0], thickness: 0.1}
      - {type: circle, center: [1, 1], radius: 0.15, blocks_lidar: true, blocks_body: true}

``blocks_lidar``: the shape cuts the lidar plane (the lidar sees it); ``blocks_body``: the
robot collides with it. A shape that blocks the body but not the lidar is the paper's
"undetected obstacle" (a low plate, a table base). Polygons must be convex (split concave
shapes). ``load_world("apartment")`` / ``load_world("round_obstacles")`` load the shipped
worlds; any other argument is a path.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from bt_runtime.runtime.messages import Pose2D
from bt_runtime.yaml_files import safe_load

from .geometry import (
    Raster,
    convex_signed_distance,
    is_convex,
    point_segment_distance,
    polygon_area,
    polygon_edges,
    rasterize,
    rectangle_around_segment,
    segment_edges,
)

WORLDS_DIR = Path(__file__).parent / "worlds"
SHIPPED_WORLDS = ("apartment", "round_obstacles")

Point = tuple[float, float]


class WorldError(ValueError):
    """A world file is missing or invalid; the message names the file and the field."""


class PoseSpec(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    x: float
    y: float
    yaw: float = 0.0

    def to_pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)


class _Obstacle(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    name: str = ""
    blocks_lidar: bool = True
    blocks_body: bool = True

    # shapes -------------------------------------------------------------------------------
    def polygon(self) -> np.ndarray | None:
        """CCW vertices (k, 2) when the shape is a polygon (thick segments too), else None."""
        return None

    def lidar_edges(self) -> np.ndarray:
        """One-sided edges (n, 4) as the lidar sees them (empty for circles)."""
        return np.empty((0, 4))

    def circle(self) -> tuple[float, float, float] | None:
        return None

    def bbox(self) -> tuple[float, float, float, float]:
        raise NotImplementedError

    def distance(self, x: float, y: float) -> float:
        """Distance from a point to the shape (<= 0 inside)."""
        raise NotImplementedError


class PolygonObstacle(_Obstacle):
    type: Literal["polygon"] = "polygon"
    points: list[Point] = Field(min_length=3)

    @field_validator("points")
    @classmethod
    def _convex(cls, pts: list[Point]) -> list[Point]:
        arr = np.asarray(pts, dtype=float)
        if not np.all(np.isfinite(arr)):
            raise ValueError("points must be finite numbers")
        if abs(polygon_area(arr)) < 1e-9:
            raise ValueError("polygon has zero area")
        if not is_convex(arr):
            raise ValueError("polygon must be convex (split a concave shape into convex parts)")
        if polygon_area(arr) < 0:  # store counter-clockwise
            pts = list(reversed(pts))
        return [(float(x), float(y)) for x, y in pts]

    def polygon(self) -> np.ndarray:
        return np.asarray(self.points, dtype=float)

    def lidar_edges(self) -> np.ndarray:
        return polygon_edges(self.polygon())

    def bbox(self):
        p = self.polygon()
        return float(p[:, 0].min()), float(p[:, 1].min()), float(p[:, 0].max()), float(p[:, 1].max())

    def distance(self, x: float, y: float) -> float:
        return float(convex_signed_distance(np.array(x), np.array(y), self.polygon()))


class SegmentObstacle(_Obstacle):
    type: Literal["segment"] = "segment"
    a: Point
    b: Point
    thickness: float = Field(default=0.05, ge=0.0)

    @model_validator(mode="after")
    def _length(self) -> SegmentObstacle:
        if math.hypot(self.b[0] - self.a[0], self.b[1] - self.a[1]) < 1e-9:
            raise ValueError("segment end points a and b coincide")
        return self

    def polygon(self) -> np.ndarray | None:
        if self.thickness <= 0:
            return None
        return rectangle_around_segment(self.a, self.b, self.thickness)

    def lidar_edges(self) -> np.ndarray:
        poly = self.polygon()
        return segment_edges(self.a, self.b) if poly is None else polygon_edges(poly)

    def bbox(self):
        h = self.thickness / 2
        return (min(self.a[0], self.b[0]) - h, min(self.a[1], self.b[1]) - h,
                max(self.a[0], self.b[0]) + h, max(self.a[1], self.b[1]) + h)

    def distance(self, x: float, y: float) -> float:
        poly = self.polygon()
        if poly is not None:
            return float(convex_signed_distance(np.array(x), np.array(y), poly))
        return float(point_segment_distance(x, y, segment_edges(self.a, self.b)[:1])[0])


class CircleObstacle(_Obstacle):
    type: Literal["circle"] = "circle"
    center: Point
    radius: float = Field(gt=0.0)

    def circle(self) -> tuple[float, float, float]:
        return (self.center[0], self.center[1], self.radius)

    def bbox(self):
        cx, cy = self.center
        r = self.radius
        return cx - r, cy - r, cx + r, cy + r

    def distance(self, x: float, y: float) -> float:
        return math.hypot(x - self.center[0], y - self.center[1]) - self.radius


Obstacle = Annotated[PolygonObstacle | SegmentObstacle | CircleObstacle, Field(discriminator="type")]
OBSTACLE_TYPES = ("polygon", "segment", "circle")


MAX_WORLD_SIDE = 200.0  # m: a 0.05 m map of 200 x 200 m is 16 M cells


class Bounds(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @model_validator(mode="after")
    def _order(self) -> Bounds:
        if not (self.xmin < self.xmax and self.ymin < self.ymax):
            raise ValueError("bounds need xmin < xmax and ymin < ymax")
        width, height = self.xmax - self.xmin, self.ymax - self.ymin
        if width > MAX_WORLD_SIDE or height > MAX_WORLD_SIDE:  # maps, costmaps and rasters cover the bounds
            cells = (width / 0.05) * (height / 0.05)
            raise ValueError(f"bounds of {width:g} x {height:g} m would need about {cells * 5 / 1e9:.1f} GB "
                             f"of maps at 0.05 m; at most {MAX_WORLD_SIDE:g} m a side")
        return self

    def contains(self, x: float, y: float) -> bool:
        return self.xmin <= x <= self.xmax and self.ymin <= y <= self.ymax

    @property
    def width(self) -> float:
        return self.xmax - self.xmin

    @property
    def height(self) -> float:
        return self.ymax - self.ymin


class World(BaseModel):
    """A static world. Obstacles added at run time (faults) live in the Simulator, not here."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    name: str
    description: str = ""
    source: str = ""
    bounds: Bounds
    spawn: PoseSpec
    goals: dict[str, PoseSpec] = Field(default_factory=dict)
    dock: PoseSpec | None = None
    obstacles: list[Obstacle] = Field(default_factory=list)

    @model_validator(mode="after")
    def _inside(self) -> World:
        for label, pose in [("spawn", self.spawn), *((f"goals.{k}", v) for k, v in self.goals.items()),
                            *([("dock", self.dock)] if self.dock else [])]:
            if not self.bounds.contains(pose.x, pose.y):
                raise ValueError(f"{label} ({pose.x}, {pose.y}) lies outside the bounds")
        return self

    # --- queries ------------------------------------------------------------------------------
    def goal(self, name: str) -> Pose2D:
        try:
            return self.goals[name].to_pose()
        except KeyError:
            raise KeyError(f"world {self.name!r} has no goal {name!r}; goals: {sorted(self.goals)}") from None

    def obstacles_where(self, *, lidar: bool | None = None, body: bool | None = None) -> list:
        """Obstacles filtered by flags (None = either)."""
        return [o for o in self.obstacles
                if (lidar is None or o.blocks_lidar == lidar) and (body is None or o.blocks_body == body)]

    def clearance(self, x: float, y: float, *, body: bool = True, lidar: bool | None = None) -> float:
        """Distance from a point to the nearest obstacle (body-blocking by default; <= 0 inside)."""
        obs = self.obstacles_where(body=True if body else None, lidar=lidar)
        return min((o.distance(x, y) for o in obs), default=math.inf)

    def rasterize(self, resolution: float = 0.05, *, layer: str = "lidar", inflate: float = 0.0,
                  padding: float = 0.0) -> Raster:
        """An occupancy raster of the world's shapes over its bounds.

        ``layer``: 'lidar' (what a SLAM map of this world would contain: the shapes that cut the
        lidar plane), 'body' (what the robot collides with), or 'any'.
        """
        return rasterize_obstacles(self.obstacles, self.bounds, resolution, layer=layer,
                                   inflate=inflate, padding=padding)


def select_layer(obstacles, layer: str) -> list:
    if layer == "lidar":
        return [o for o in obstacles if o.blocks_lidar]
    if layer == "body":
        return [o for o in obstacles if o.blocks_body]
    if layer == "any":
        return [o for o in obstacles if o.blocks_lidar or o.blocks_body]
    raise ValueError(f"layer is 'lidar', 'body' or 'any', got {layer!r}")


def rasterize_obstacles(obstacles, bounds: Bounds, resolution: float = 0.05, *, layer: str = "lidar",
                        inflate: float = 0.0, padding: float = 0.0) -> Raster:
    obs = select_layer(obstacles, layer)
    polys = [p for o in obs if (p := o.polygon()) is not None]
    circles = np.array([c for o in obs if (c := o.circle()) is not None], dtype=float).reshape(-1, 3)
    thin = [segment_edges(o.a, o.b)[:1] for o in obs if isinstance(o, SegmentObstacle) and o.thickness <= 0]
    edges = np.vstack(thin) if thin else np.empty((0, 4))
    ox, oy = bounds.xmin - padding, bounds.ymin - padding
    w = int(math.ceil((bounds.width + 2 * padding) / resolution - 1e-9))
    h = int(math.ceil((bounds.height + 2 * padding) / resolution - 1e-9))
    return rasterize(polys, circles, edges, (ox, oy), (w, h), resolution, inflate=inflate)


def lidar_geometry(obstacles) -> tuple[np.ndarray, np.ndarray]:
    """(edges (N, 4), circles (M, 3)) of the lidar-blocking obstacles, for the ray caster."""
    obs = [o for o in obstacles if o.blocks_lidar]
    edges = [o.lidar_edges() for o in obs]
    edges = [e for e in edges if len(e)]
    circles = [o.circle() for o in obs if o.circle() is not None]
    return (np.vstack(edges) if edges else np.empty((0, 4)),
            np.array(circles, dtype=float).reshape(-1, 3))


# ---------------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------------

def _format_loc(loc: tuple) -> str:
    parts: list[str] = []
    for i, p in enumerate(loc):
        # discriminated unions add the tag ('circle') after the list index: drop it
        if isinstance(p, str) and p in OBSTACLE_TYPES and i > 0 and isinstance(loc[i - 1], int):
            continue
        parts.append(str(p))
    return ".".join(parts) or "(top level)"


def format_validation_error(source: str, err: ValidationError) -> str:
    lines = [f"{source}: {_format_loc(e['loc'])}: {e['msg']}" for e in err.errors()]
    return "\n".join(lines)


def resolve_world_path(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    if text in SHIPPED_WORLDS or (isinstance(name_or_path, str) and "/" not in text and not text.endswith(
            (".yaml", ".yml")) and (WORLDS_DIR / f"{text}.yaml").exists()):
        return WORLDS_DIR / f"{text}.yaml"
    return Path(name_or_path)


def world_from_dict(data: dict, source: str = "<dict>") -> World:
    try:
        return World.model_validate(data)
    except ValidationError as err:
        raise WorldError(format_validation_error(source, err)) from None


_LOADED: dict[tuple[str, int, int], World] = {}  # (path, mtime_ns, size) -> validated world
_LOADED_MAX = 16


def load_world(name_or_path: str | Path) -> World:
    """Load a world by shipped name ('apartment', 'round_obstacles') or by path: a world file,
    or a ROS map_server map (YAML + PGM/PNG, see ``sim.map_world``).

    A campaign loads the same world for every run: a file is parsed and validated once per
    process (while its modification time and size stay the same) and each caller gets its own
    copy: its own obstacle list and goal table, so a simulator that changes its world never
    changes another run's. The shapes and poses in them are frozen models, shared (a deep copy
    cost ~30 ms a run)."""
    path = resolve_world_path(name_or_path)
    if not path.exists():
        raise WorldError(f"{path}: no such world file (shipped worlds: {', '.join(SHIPPED_WORLDS)})")
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    world = _LOADED.get(key)
    if world is None:
        try:
            data = safe_load(path.read_text())
        except yaml.YAMLError as err:
            raise WorldError(f"{path}: not valid YAML: {err}") from None
        if not isinstance(data, dict):
            raise WorldError(f"{path}: (top level): a world file is a mapping")
        from .map_world import looks_like_map, world_from_map

        world = world_from_map(path, data) if looks_like_map(data) else world_from_dict(data, str(path))
        if len(_LOADED) >= _LOADED_MAX:
            _LOADED.pop(next(iter(_LOADED)))
        _LOADED[key] = world
    return world.model_copy(update={"obstacles": list(world.obstacles), "goals": dict(world.goals)})
