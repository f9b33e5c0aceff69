"""Safety-zone configuration in Nav2 collision_monitor's YAML format, and the defaults per robot.

    collision_monitor:
      ros__parameters:
        source_timeout: 1.0
        polygons: ["PolygonStop", "PolygonSlow"]
        PolygonStop: {type: circle, radius: 0.2, action_type: stop, min_points: 4}
        PolygonSlow:
          type: polygon
          points: "[[0.5, 0.25], [0.5, -0.25], [0.0, -0.25], [0.0, 0.25]]"
          action_type: slowdown
          slowdown_ratio: 0.5
        observation_sources: ["scan"]
        scan: {type: scan, topic: scan}

A file written for collision_monitor loads as it is: keys that only matter to the ROS node
(topics, frames, visualisation) are accepted and ignored, polygons not listed in ``polygons``
are ignored as collision_monitor ignores them, and an ``approach`` polygon without points (it
follows ``footprint_topic`` there) uses the robot's footprint. Anything we cannot honour
(velocity polygons, point-cloud sources, debouncing) is an error naming the file and field.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .messages import RobotInfo


class SafetyZonesConfigError(ValueError):
    """A collision_monitor file that cannot be used; the message names the file and the field."""


# keys collision_monitor reads that have no meaning here (no separate ROS node, no TF, no markers)
_NODE_IGNORED = {"base_frame_id", "odom_frame_id", "cmd_vel_in_topic", "cmd_vel_out_topic", "state_topic",
                 "transform_tolerance", "base_shift_correction", "stop_pub_timeout", "use_realtime_priority",
                 "enable_stamped_cmd_vel", "use_sim_time", "collision_points_marker_3d"}
_ZONE_IGNORED = {"visualize", "polygon_pub_topic", "footprint_topic", "polygon_sub_topic",
                 "polygon_subscribe_transient_local"}
_SOURCE_IGNORED = {"topic", "transport_type"}


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def parse_points(value: Any) -> tuple[tuple[float, float], ...]:
    """collision_monitor's ``points``: the string "[[x, y], ...]", a list of pairs, or the older
    flat list [x1, y1, x2, y2, ...]."""
    if isinstance(value, str):
        try:
            value = yaml.safe_load(value)
        except yaml.YAMLError as exc:
            raise ValueError(f"points must read as [[x, y], ...]: {exc}") from None
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"points must be [[x, y], ...], got {value!r}")
    if value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        if len(value) % 2:
            raise ValueError(f"a flat points list needs an even count of numbers, got {len(value)}")
        value = [value[i:i + 2] for i in range(0, len(value), 2)]
    out = []
    for k, pair in enumerate(value):
        if (not isinstance(pair, (list, tuple)) or len(pair) != 2
                or not all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in pair)):
            raise ValueError(f"point {k} must be [x, y] in metres, got {pair!r}")
        x, y = float(pair[0]), float(pair[1])
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError(f"point {k} is not finite: {pair!r}")
        out.append((x, y))
    if len(out) < 3:
        raise ValueError(f"a polygon needs at least 3 points, got {len(out)}")
    return tuple(out)


class SubPolygonConfig(_Model):
    """One entry of a velocity polygon's ``velocity_polygons``: its shape and the commands it is
    for (all bounds inclusive; required, as in collision_monitor)."""

    points: tuple[tuple[float, float], ...]
    linear_min: float = Field(description="m/s (holonomic: the speed's magnitude)")
    linear_max: float
    theta_min: float = Field(description="rad/s")
    theta_max: float
    direction_start_angle: float = Field(-math.pi, description="holonomic only: rad")
    direction_end_angle: float = Field(math.pi, description="holonomic only: rad")

    @field_validator("points", mode="before")
    @classmethod
    def _points(cls, value: Any) -> Any:
        return parse_points(value)

    def covers(self, v: float, w: float, holonomic: bool) -> bool:
        """Is the command (v forward, w) within this sub-polygon's ranges?"""
        if not self.theta_min <= w <= self.theta_max:
            return False
        if not holonomic:
            return self.linear_min <= v <= self.linear_max
        speed, direction = abs(v), (0.0 if v >= 0.0 else math.pi)  # a differential base: y = 0
        if not self.linear_min <= speed <= self.linear_max:
            return False
        lo, hi = self.direction_start_angle, self.direction_end_angle
        return lo <= direction <= hi if lo <= hi else (direction >= lo or direction <= hi)


class ZoneConfig(_Model):
    """One entry of ``polygons`` (collision_monitor's parameter names and defaults)."""

    type: Literal["polygon", "circle", "velocity_polygon"]
    action_type: Literal["stop", "slowdown", "limit", "approach", "none"]
    points: tuple[tuple[float, float], ...] | None = Field(None, description="polygon: [[x, y], ...], base frame")
    radius: float | None = Field(None, gt=0, description="circle: metres around the base frame's origin")
    enabled: bool = True
    min_points: int = Field(4, ge=1, description="scan points inside that trigger the action")
    max_points: int | None = Field(None, ge=0, description="deprecated: min_points = max_points + 1")
    slowdown_ratio: float = Field(0.5, ge=0, le=1)
    linear_limit: float = Field(0.5, ge=0, description="m/s")
    angular_limit: float = Field(0.5, ge=0, description="rad/s")
    time_before_collision: float = Field(2.0, gt=0, description="approach: s kept before a collision")
    simulation_time_step: float = Field(0.1, gt=0, description="approach: s per simulated step")
    sources_names: list[str] | None = Field(None, description="default: every observation source")
    trigger_consecutive_points: int = Field(1, ge=1, le=1, description="debouncing is not supported")
    release_consecutive_points: int = Field(1, ge=1, le=1, description="debouncing is not supported")
    footprint_radius: float | None = Field(None, gt=0, description="approach without points: the robot's "
                                                                   "radius (set by the loader)")
    velocity_polygons: list[str] | None = Field(None, description="velocity_polygon: its sub-polygons, "
                                                                  "the first covering the command is used")
    holonomic: bool = False
    sub_polygons: dict[str, SubPolygonConfig] = Field(default_factory=dict, description="set by the loader")

    @field_validator("points", mode="before")
    @classmethod
    def _points(cls, value: Any) -> Any:
        return None if value is None else parse_points(value)

    @model_validator(mode="after")
    def _shape(self) -> ZoneConfig:
        if self.type == "circle" and self.radius is None:
            raise ValueError("a circle needs 'radius'")
        if self.type == "polygon" and self.points is None and self.action_type != "approach":
            raise ValueError("a polygon needs 'points' (only an approach polygon may follow the footprint)")
        if self.type == "velocity_polygon":
            if not self.velocity_polygons:
                raise ValueError("a velocity_polygon needs 'velocity_polygons' (a list of names)")
            if self.action_type == "approach":
                raise ValueError("an approach zone is the footprint: a velocity_polygon cannot be one here")
            missing = [n for n in self.velocity_polygons if n not in self.sub_polygons]
            if missing:
                raise ValueError(f"velocity polygon(s) {', '.join(missing)} listed but not defined")
        if self.simulation_time_step > self.time_before_collision:
            raise ValueError("simulation_time_step must not exceed time_before_collision")
        return self

    @property
    def effective_min_points(self) -> int:
        return self.max_points + 1 if self.max_points is not None else self.min_points

    @property
    def vertices(self) -> tuple[tuple[float, float], ...] | None:
        return self.points

    def shape_kind(self) -> str:
        """'circle', 'polygon' or 'velocity_polygon' as evaluated (an approach polygon without
        points: a circle)."""
        if self.type == "velocity_polygon":
            return self.type
        return "circle" if self.type == "circle" or self.points is None else "polygon"


class SourceConfig(_Model):
    type: Literal["scan"] = Field("scan", description="only the lidar scan (the driver's one scan stream)")
    enabled: bool = True
    source_timeout: float | None = Field(None, ge=0, description="s; 0: never stale; default: the node's")


class CollisionMonitorConfig(_Model):
    """The ``ros__parameters`` of a collision_monitor node, as far as the gate uses them."""

    enabled: bool = True
    source_timeout: float = Field(2.0, ge=0, description="s; an older scan stops the robot (0: never)")
    polygons: list[str] = Field(default_factory=list)
    observation_sources: list[str]
    zones: dict[str, ZoneConfig] = Field(default_factory=dict)
    sources: dict[str, SourceConfig] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _names(self) -> CollisionMonitorConfig:
        for name in self.polygons:
            if name not in self.zones:
                raise ValueError(f"polygon {name!r} is listed in 'polygons' but not defined")
        for name in self.observation_sources:
            if name not in self.sources:
                self.sources[name] = SourceConfig()
        for name in self.polygons:
            for src in self.zones[name].sources_names or ():
                if src not in self.observation_sources:
                    raise ValueError(f"{name}.sources_names: {src!r} is not one of observation_sources")
        return self

    def _scan_sources(self) -> list[SourceConfig]:
        return [self.sources[n] for n in self.observation_sources if self.sources[n].enabled]

    @property
    def scan_enabled(self) -> bool:
        return bool(self._scan_sources())

    @property
    def scan_timeout(self) -> float:
        """The tightest timeout of the enabled scan sources (0: never stale)."""
        timeouts = [self.source_timeout if s.source_timeout is None else s.source_timeout
                    for s in self._scan_sources()]
        positive = [t for t in timeouts if t > 0]
        return min(positive) if positive else 0.0

    def zone_sees_scan(self, name: str) -> bool:
        names = self.zones[name].sources_names
        enabled = [n for n in self.observation_sources if self.sources[n].enabled]
        return any(n in enabled for n in (enabled if names is None else names))

    def with_footprint(self, radius: float) -> CollisionMonitorConfig:
        """A copy whose approach polygons without points use a circle of ``radius``."""
        zones = {name: (z.model_copy(update={"footprint_radius": radius})
                        if z.points is None and z.type == "polygon" else z)
                 for name, z in self.zones.items()}
        return self.model_copy(update={"zones": zones})


def _field_path(loc: tuple) -> str:
    return ".".join(str(p) for p in loc if p != "__root__")


def from_parameters(params: dict[str, Any], origin: str = "<collision_monitor>") -> CollisionMonitorConfig:
    """Validate a ``ros__parameters`` mapping; errors name ``origin`` and the field."""
    if not isinstance(params, dict):
        raise SafetyZonesConfigError(f"{origin}: ros__parameters must be a mapping")
    polygons = params.get("polygons", [])
    sources = params.get("observation_sources")
    if sources is None:
        raise SafetyZonesConfigError(f"{origin}: observation_sources: required (e.g. [\"scan\"])")
    for key, value in (("polygons", polygons), ("observation_sources", sources)):
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise SafetyZonesConfigError(f"{origin}: {key}: must be a list of names, got {value!r}")
    node: dict[str, Any] = {"polygons": polygons, "observation_sources": sources, "zones": {}, "sources": {}}
    for key, value in params.items():
        if key in ("polygons", "observation_sources") or key in _NODE_IGNORED:
            continue
        if key in polygons:
            node["zones"][key] = _section(value, origin, key, _ZONE_IGNORED, ZoneConfig)
        elif key in sources:
            if isinstance(value, dict) and value.get("type", "scan") != "scan":
                raise SafetyZonesConfigError(
                    f"{origin}: {key}.type: {value['type']!r} sources are not supported; only 'scan' "
                    f"(the driver's lidar stream)")
            node["sources"][key] = _section(value, origin, key, _SOURCE_IGNORED, SourceConfig)
        elif isinstance(value, dict):
            continue  # a polygon or zone collision_monitor would not use either (not listed)
        elif key in ("enabled", "source_timeout"):
            node[key] = value
        else:
            known = sorted({"enabled", "source_timeout", "polygons", "observation_sources", *_NODE_IGNORED})
            raise SafetyZonesConfigError(f"{origin}: {key}: unknown parameter (collision_monitor's are: "
                                         f"{', '.join(known)})")
    try:
        return CollisionMonitorConfig.model_validate(node)
    except ValidationError as exc:
        raise SafetyZonesConfigError(_errors(origin, exc)) from None


def _section(value: Any, origin: str, name: str, ignored: set[str], model: type[BaseModel]) -> BaseModel:
    if not isinstance(value, dict):
        raise SafetyZonesConfigError(f"{origin}: {name}: must be a mapping of parameters, got {value!r}")
    kept = {k: v for k, v in value.items() if k not in ignored}
    if value.get("type") == "velocity_polygon":  # its sub-polygons are sections of their own
        subs = kept.get("velocity_polygons") or []
        if isinstance(subs, list):
            kept["sub_polygons"] = {sub: _section(kept.pop(sub), origin, f"{name}.{sub}", set(), SubPolygonConfig)
                                    for sub in subs if isinstance(sub, str) and sub in kept}
        kept = {k: v for k, v in kept.items() if not isinstance(v, dict) or k == "sub_polygons"}  # unlisted: unread
    try:
        return model.model_validate(kept)
    except ValidationError as exc:
        raise SafetyZonesConfigError(_errors(origin, exc, prefix=name)) from None


def _errors(origin: str, exc: ValidationError, prefix: str = "") -> str:
    lines = []
    for err in exc.errors():
        path = _field_path(err["loc"])
        path = f"{prefix}.{path}" if prefix and path else (prefix or path)
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = "unknown parameter"
        lines.append(f"{origin}: {path}: {msg}")
    return "\n".join(lines)


def load_collision_monitor(path: str | Path) -> CollisionMonitorConfig:
    """Read a collision_monitor parameter file (``collision_monitor: ros__parameters: ...``; the
    node may have another name if the file holds only one node)."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise SafetyZonesConfigError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise SafetyZonesConfigError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict) or not data:
        raise SafetyZonesConfigError(f"{path}: expected 'collision_monitor: ros__parameters: ...'")
    if "collision_monitor" in data:
        node = data["collision_monitor"]
    elif "ros__parameters" in data:
        node = data
    elif len(data) == 1:
        node = next(iter(data.values()))
    else:
        raise SafetyZonesConfigError(f"{path}: no 'collision_monitor' node among {', '.join(map(str, data))}")
    if not isinstance(node, dict) or "ros__parameters" not in node:
        raise SafetyZonesConfigError(f"{path}: collision_monitor: expected a 'ros__parameters' mapping")
    return from_parameters(node["ros__parameters"], str(path))


def default_config(robot: RobotInfo) -> CollisionMonitorConfig:
    """Zones for a robot of ``robot``'s size and speed (see docs/safety_zones.md for why):

    * ``FootprintApproach`` (approach): the footprint plus 3 cm; keeps the robot
      ``max(1 s, v_max / a_max)`` from a collision, so it brakes in time at any speed and can
      always turn on the spot or move away;
    * ``PolygonSlow`` (slowdown 0.5): a box 0.3 m ahead of the front, as wide as the robot + 5 cm
      on each side;
    * ``PolygonStop`` (stop): the footprint plus 1 cm, for what comes at the robot.
    """
    r = robot.radius
    horizon = max(1.0, round(robot.max_linear / robot.max_linear_accel, 2))
    ahead, half = round(r + 0.3, 3), round(r + 0.05, 3)
    params = {
        "source_timeout": 1.0,
        "polygons": ["PolygonStop", "PolygonSlow", "FootprintApproach"],
        "PolygonStop": {"type": "circle", "radius": round(r + 0.01, 3), "action_type": "stop", "min_points": 4},
        "PolygonSlow": {"type": "polygon", "action_type": "slowdown", "slowdown_ratio": 0.5, "min_points": 4,
                        "points": [[ahead, half], [ahead, -half], [0.0, -half], [0.0, half]]},
        "FootprintApproach": {"type": "circle", "radius": round(r + 0.03, 3), "action_type": "approach",
                              "time_before_collision": horizon, "simulation_time_step": 0.05, "min_points": 4},
        "observation_sources": ["scan"],
        "scan": {"type": "scan", "topic": "scan"},
    }
    return from_parameters(params, "defaults")


def _points_text(points) -> str:
    return "[" + ", ".join(f"[{x:g}, {y:g}]" for x, y in points) + "]"


def to_yaml(config: CollisionMonitorConfig) -> str:
    """The configuration as a collision_monitor parameter file."""
    params: dict[str, Any] = {"enabled": config.enabled, "source_timeout": config.source_timeout,
                              "polygons": list(config.polygons)}
    for name in config.polygons:
        z = config.zones[name]
        entry: dict[str, Any] = {"type": z.type, "action_type": z.action_type}
        if z.type == "circle":
            entry["radius"] = z.radius
        elif z.points is not None:
            entry["points"] = _points_text(z.points)
        if z.type == "velocity_polygon":
            entry.update(velocity_polygons=list(z.velocity_polygons or ()), holonomic=z.holonomic)
            for sub_name in z.velocity_polygons or ():
                sub = z.sub_polygons[sub_name]
                entry[sub_name] = {"points": _points_text(sub.points), **sub.model_dump(exclude={"points"})}
        entry["min_points"] = z.effective_min_points
        if z.action_type == "slowdown":
            entry["slowdown_ratio"] = z.slowdown_ratio
        if z.action_type == "limit":
            entry.update(linear_limit=z.linear_limit, angular_limit=z.angular_limit)
        if z.action_type == "approach":
            entry.update(time_before_collision=z.time_before_collision,
                         simulation_time_step=z.simulation_time_step)
        if not z.enabled:
            entry["enabled"] = False
        params[name] = entry
    params["observation_sources"] = list(config.observation_sources)
    for name in config.observation_sources:
        s = config.sources[name]
        params[name] = {"type": "scan", "topic": "scan", "enabled": s.enabled}
        if s.source_timeout is not None:
            params[name]["source_timeout"] = s.source_timeout
    return yaml.safe_dump({"collision_monitor": {"ros__parameters": params}}, sort_keys=False)
