"""The variant generator: valid, reproducible run specs per failure family, runnable by the
campaign like shipped scenarios, and the layer handling a few of them."""

from __future__ import annotations

import math

import pytest

from bt_runtime.logging_setup import quiet_logging
from sim.scenarios.box_check import path_with_box
from sim.scenarios.runner import run_scenario
from sim.scenarios.variants import FAMILIES, family_of, generate, variant


@pytest.fixture(autouse=True)
def _quiet_logs():
    quiet_logging("error")


def test_variants_are_reproducible_from_the_seed_and_differ_across_seeds():
    a = [(r.scenario.model_dump(), r.seed) for r in generate(8, seed=3)]
    b = [(r.scenario.model_dump(), r.seed) for r in generate(8, seed=3)]
    c = [(r.scenario.model_dump(), r.seed) for r in generate(8, seed=4)]
    assert a == b
    assert a != c


@pytest.mark.parametrize("family", list(FAMILIES))
def test_each_family_draws_worlds_robots_and_poses(family):
    runs = generate(6, seed=11, families=[family])
    assert {family_of(r.scenario.name) for r in runs} == {family}
    assert len({(r.scenario.start.x, r.scenario.start.y) for r in runs}) == 6
    assert all(r.scenario.success for r in runs)


def test_unknown_family_is_named():
    with pytest.raises(ValueError, match="unknown variant families"):
        generate(1, families=["teleport"])


@pytest.mark.parametrize("family", ["nav_server", "sensor"])
def test_the_layer_handles_variants(family):
    for run in generate(2, seed=5, families=[family]):
        result = run_scenario(run.scenario, run.mode, run.seed, keep_record=False)
        assert result.success, (run.scenario.description, result.reasons)


def test_a_collision_box_that_cuts_the_goal_off_is_not_drawn():
    """A 0.3 m box across the apartment's hall door leaves no way for a waffle (fair variants
    only: no layer could reach that goal); the same box in the open room leaves one."""
    start, goal = (1.1, 0.45), (3.6, 0.7)  # along the corridor north of the hall wall
    door = {"x": 2.0, "y": 0.45, "yaw": 0.0, "width": 0.3, "depth": 0.3}
    assert path_with_box("apartment", "waffle", start, goal, {**door, "width": 0.6}) == math.inf
    assert path_with_box("apartment", "waffle", (-3.0, -3.0), (0.0, -3.0), {**door, "x": -1.5, "y": -3.0}) < 4.0
    for run in generate(12, seed=2026, families=["collision"]):
        box = next((f.fault for f in run.scenario.faults if f.fault.get("name") == "low_box"), None)
        if box is None:
            continue
        start, goal = run.scenario.start, run.scenario.goals[0].pose
        assert path_with_box(run.scenario.world, run.scenario.robot, (start.x, start.y), (goal.x, goal.y),
                             box) < math.inf


def test_a_box_the_robot_never_touched_needs_no_mark():
    from sim.scenarios.judge import obstacle_in_map
    from sim.scenarios.spec import ObstacleInMap
    from sim.world import CircleObstacle

    record = type("R", (), {"obstacles": {"low_box": CircleObstacle(center=(0.0, 0.0), radius=0.2)},
                            "nav_requests": [], "sim_events": []})()
    assert obstacle_in_map(record, ObstacleInMap(kind="obstacle_in_map", obstacle="low_box", only_if_hit=True)).passed
    assert not obstacle_in_map(record, ObstacleInMap(kind="obstacle_in_map", obstacle="low_box")).passed
    record.sim_events = [type("E", (), {"t": 3.0, "kind": "collision", "data": {"obstacle": "dyn:low_box"}})()]
    assert not obstacle_in_map(record, ObstacleInMap(kind="obstacle_in_map", obstacle="low_box",
                                                     only_if_hit=True)).passed


def test_a_pushed_variant_whose_hitter_cuts_the_goal_off_is_not_drawn():
    """The pushed variants are fairness-checked like the boxes on the path: seed 2028's V0263
    (a waffle facing west in the 0.9 m corridor, the hitter left between it and the goal) had
    no way past the hitter; the generator now draws only hitters that leave one, placed where
    the simulator puts them."""
    from bt_runtime.runtime.messages import Pose2D
    from sim.scenarios.variants import HITTER, _hitter_box
    from sim.simulator import Simulator

    unfair_start, unfair_goal = (0.973, 0.399, -3.109), (-2.84, 1.47)
    assert path_with_box("apartment", "waffle", unfair_start[:2], unfair_goal,
                         _hitter_box("waffle", unfair_start)) == math.inf
    sim = Simulator("apartment", "waffle", seed=0)
    sim.reset_pose(Pose2D(1.0, -3.0, 0.7))
    sim.faults.invisible_obstacle(**HITTER, name="hitter")
    placed = sim.dynamic_obstacles["hitter"].points
    box = _hitter_box("waffle", (1.0, -3.0, 0.7))
    centre = [sum(p[0] for p in placed) / 4, sum(p[1] for p in placed) / 4]
    assert centre == pytest.approx([box["x"], box["y"]], abs=1e-6)
    redrawn, _ = variant(2028, 263)
    assert redrawn.name == "V0263_collision" and "pushed" in redrawn.description
    checked = 0
    for spec in [redrawn] + [r.scenario for r in generate(30, seed=2028, families=["collision"])]:
        if "pushed" not in spec.description:
            continue
        start, goal = spec.start, spec.goals[0].pose
        hitter = _hitter_box(spec.robot, (start.x, start.y, start.yaw))
        assert path_with_box(spec.world, spec.robot, (start.x, start.y), (goal.x, goal.y), hitter) < math.inf, \
            spec.name
        checked += 1
    assert checked >= 4
