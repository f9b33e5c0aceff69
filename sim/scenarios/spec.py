"""Scenario specifications (the paper's Tables II and III) as validated data files.

A scenario names a world, a robot, a start pose, the goals a user sends (and when), the
navigation speeds, a fault schedule, the success criteria (judged from recorded data), a
time limit, the randomisation used across runs, and the paper's result for comparison.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

DATA_DIR = Path(__file__).with_name("data")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


class PoseSpec(_Model):
    x: float
    y: float
    yaw: float = 0.0


class GoalStep(_Model):
    """A goal the user sends: at a time, or when the previous goal has finished."""

    pose: PoseSpec
    at: float | None = Field(None, ge=0, description="send at this time (s since start)")
    after_previous: bool = Field(False, description="send when the previous goal has finished")
    delay: float = Field(0.0, ge=0, description="extra wait after the previous goal finished")
    label: str = ""

    @model_validator(mode="after")
    def _when(self) -> GoalStep:
        if (self.at is None) == (not self.after_previous):
            raise ValueError("a goal needs exactly one of 'at' or 'after_previous: true'")
        return self


NAV_FAULTS = ("nav_crash", "nav_hang", "nav_fail_until_restart", "nav_phantom_obstacle")


class NavFault(_Model):
    """A fault in the navigation stack (planner/controller/behavior servers, costmaps)."""

    kind: Literal["nav_crash", "nav_hang", "nav_fail_until_restart", "nav_phantom_obstacle"]
    component: str = "planner_server"
    x: float = 0.0
    y: float = 0.0
    radius: float = 0.3


def validate_fault(fault: dict[str, Any]) -> None:
    if fault.get("kind") in NAV_FAULTS:
        NavFault.model_validate(fault)
    else:
        from sim.faults import parse_fault

        parse_fault(dict(fault))


class FaultStep(_Model):
    """A fault from sim.faults (``fault`` is its mapping, e.g. {kind: crash, component: lidar})
    or a navigation-stack fault (``nav_*``), at a time, or a time after a goal was sent (the
    robot is driving by then)."""

    fault: dict[str, Any]
    at: float | None = Field(None, ge=0)
    after_goal: int | None = Field(None, ge=0, description="index of the goal this is relative to")
    delay: float = Field(0.0, ge=0)

    @model_validator(mode="after")
    def _when(self) -> FaultStep:
        if (self.at is None) == (self.after_goal is None):
            raise ValueError("a fault needs exactly one of 'at' or 'after_goal'")
        validate_fault(self.fault)  # fail on load, naming the field, not mid-run
        return self


class ComponentReset(_Model):
    kind: Literal["component_reset"]
    component: str


class ReachGoal(_Model):
    kind: Literal["reach_goal"]
    goal: int = 0
    tolerance: float = 0.25
    without_charging: bool = Field(False, description="reached without docking to charge first (the battery "
                                                      "was enough: the layer must not be over-cautious)")


class ChargedThenReached(_Model):
    """Refused at first for battery (no navigation towards it before charging), docked and
    charged (the simulator's contacts and true state of charge), then reached."""

    kind: Literal["charged_then_reached"]
    goal: int = 0
    tolerance: float = 0.25


class GoalRefused(_Model):
    kind: Literal["goal_refused"]
    goal: int = 0
    max_travel: float = Field(0.3, description="m the robot may move while the goal is open")


class AlternativeReached(_Model):
    kind: Literal["alternative_reached"]
    goal: int = 0
    within: float = 1.0


class OutOfContact(_Model):
    kind: Literal["out_of_contact"]
    for_last: float = Field(2.0, description="s without contact at the end of the run")


class ObstacleInMap(_Model):
    kind: Literal["obstacle_in_map"]
    obstacle: str = Field(description="name of the obstacle a fault created")
    within: float = Field(0.3, description="m between the mark and the obstacle")
    only_if_hit: bool = Field(False, description="an obstacle the robot never touched needs no mark "
                                                 "(variants: the robot may pass a box placed on the "
                                                 "static plan without touching it)")


class HitOnce(_Model):
    """The robot never hits the same obstacle twice (contacts closer together than ``merge``
    seconds are one hit: a bounce, not a second run into it)."""

    kind: Literal["hit_once"]
    obstacle: str = Field(description="name of the obstacle a fault created")
    merge: float = Field(0.5, ge=0, description="s between contacts that still count as one hit")


Criterion = Annotated[ComponentReset | ReachGoal | GoalRefused | AlternativeReached | OutOfContact | ObstacleInMap
                      | HitOnce | ChargedThenReached, Field(discriminator="kind")]


class Speeds(_Model):
    linear: float = Field(0.25, gt=0, description="navigation cruise speed, m/s")
    angular: float | None = Field(None, gt=0, description="max angular speed for navigation, rad/s")
    goal_tolerance: float = Field(0.1, gt=0, description="the navigator's xy goal tolerance, m (same in both "
                                                          "modes; tighter than the 0.25 m success criterion so "
                                                          "localization error after a sensor outage has a margin)")


class Jitter(_Model):
    """Randomisation across runs (seeded): start pose, fault times, and the sensor noise that
    follows from the simulator seed."""

    start_xy: float = Field(0.05, ge=0)
    start_yaw: float = Field(0.05, ge=0)
    fault_time: float = Field(0.3, ge=0)


class PaperResult(_Model):
    runs: int
    without: float
    with_: float = Field(alias="with")
    real_world_without: float | None = None
    real_world_with: float | None = None


class ScenarioSpec(_Model):
    name: str
    table: Literal["II", "III"] | None = None  # the paper's table (None: a user's own scenario)
    requirements: list[str] = Field(default_factory=list)
    description: str = ""
    world: str = "apartment"
    robot: str = "rosbot2"
    robot_overrides: dict[str, Any] = Field(default_factory=dict,
                                            description="profile fields, e.g. {battery.initial_soc: 10}")
    map_obstacles: list[dict[str, Any]] = Field(
        default_factory=list, description="obstacle faults applied before the map is rendered (on the map)")
    start: PoseSpec
    goals: list[GoalStep] = Field(default_factory=list)
    speeds: Speeds = Field(default_factory=Speeds)
    faults: list[FaultStep] = Field(default_factory=list)
    success: list[Criterion]
    time_limit: float = Field(60.0, gt=0)
    settle: float = Field(1.0, ge=0, description="s to keep running after the last goal finished")
    jitter: Jitter = Field(default_factory=Jitter)
    paper: PaperResult | None = None  # the paper's result (None: a user's own scenario)

    @model_validator(mode="after")
    def _goal_indices(self) -> ScenarioSpec:
        n = len(self.goals)
        for c in self.success:
            if hasattr(c, "goal") and not 0 <= c.goal < n:
                raise ValueError(f"success criterion {c.kind} refers to goal {c.goal}, but there are {n} goals")
        for f in self.faults:
            if f.after_goal is not None and not 0 <= f.after_goal < n:
                raise ValueError(f"a fault refers to goal {f.after_goal}, but there are {n} goals")
        return self


class ScenarioError(ValueError):
    """A scenario file that cannot be used; the message names the file and the field."""


def load_scenario(name_or_path: str | Path) -> ScenarioSpec:
    path = Path(name_or_path)
    if not path.suffix:
        path = DATA_DIR / f"{name_or_path}.yaml"
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        names = ", ".join(scenario_names())
        raise ScenarioError(f"{name_or_path}: no such scenario (shipped: {names})") from None
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{path}: not valid YAML: {exc}") from None
    try:
        return ScenarioSpec.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ScenarioError(f"{path}: {where}: {first['msg']}") from None


def load_scenario_files(paths: list[str | Path]) -> list[ScenarioSpec]:
    """User scenario files: each path a YAML file or a folder of them (``*.yaml``/``*.yml``,
    sorted, not recursive). Validated like the shipped ones; errors name the file and field."""
    specs = []
    for item in paths:
        path = Path(item)
        if path.is_dir():
            files = sorted(p for p in path.iterdir() if p.suffix in (".yaml", ".yml") and p.is_file())
            if not files:
                raise ScenarioError(f"{path}: no scenario files (*.yaml, *.yml) in this folder")
        elif path.is_file():
            files = [path]
        else:
            raise ScenarioError(f"{path}: no such file or folder")
        specs.extend(_load_file(f) for f in files)
    return specs


def _load_file(path: Path) -> ScenarioSpec:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: cannot read: {exc}") from None
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{path}: (top level): a scenario is a mapping of fields")
    try:
        return ScenarioSpec.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "(top level)"
        raise ScenarioError(f"{path}: {where}: {first['msg']}") from None


def scenario_names() -> list[str]:
    """The shipped scenarios in the paper's table order."""
    order = ["Lidar_1", "Lidar_2", "Lidar_3", "IMU_1", "IMU_2", "IMU_3", "Odom_1", "Odom_2", "Odom_3",
             "NoPathFound_1", "NoPathFound_2", "Collision_1", "Collision_2", "Battery_1"]
    present = {p.stem for p in DATA_DIR.glob("*.yaml")}
    return [n for n in order if n in present] + sorted(present - set(order))
