"""sim.nav.params: defaults and reading Nav2 parameter files."""

from __future__ import annotations

import pytest
import yaml

from sim.nav.params import NavParams, RobotParams, load_nav2_params
from tests.sim.nav.fixtures import REFERENCE

PARAMS = REFERENCE.parent / "nav2" / "params"
TB3_BURGER = PARAMS / "tb3_nav2_params_burger_jazzy+.yaml"


def test_defaults_are_the_turtlebot3_and_paper_values():
    p, r = NavParams(), RobotParams()
    assert (r.radius, r.max_linear_vel, r.max_angular_vel) == (0.1, 0.3, 1.0)
    assert (p.global_costmap.inflation_radius, p.global_costmap.cost_scaling_factor) == (0.5, 5.0)
    assert (p.local_costmap.width, p.local_costmap.height, p.local_costmap.update_frequency) == (3, 3, 5)
    assert p.controller.desired_linear_vel == 0.25 and p.controller.controller_frequency == 20
    assert (p.controller.xy_goal_tolerance, p.controller.yaw_goal_tolerance) == (0.25, 0.25)
    assert (p.controller.required_movement_radius, p.controller.movement_time_allowance) == (0.5, 10)
    assert p.navigator.replan_frequency == 1.0
    with pytest.raises(ValueError):
        NavParams.model_validate({"controller": {"no_such_key": 1}})


def test_from_yaml(tmp_path):
    f = tmp_path / "nav.yaml"
    f.write_text(yaml.safe_dump({"controller": {"desired_linear_vel": 0.2},
                                 "planner": {"cost_penalty": 3.0}}))
    p = NavParams.from_yaml(f)
    assert p.controller.desired_linear_vel == 0.2 and p.planner.cost_penalty == 3.0


@pytest.mark.skipif(not TB3_BURGER.exists(), reason="shared/reference/nav2/params not available")
def test_reads_the_turtlebot3_nav2_parameters():
    robot, nav = load_nav2_params(TB3_BURGER)
    assert robot.radius == 0.1 and robot.max_linear_vel == 0.3 and robot.max_linear_accel == 3.0
    assert nav.local_costmap.inflation_radius == 0.5 and nav.global_costmap.cost_scaling_factor == 5.0
    assert nav.controller.controller_frequency == 10.0
    assert nav.controller.required_movement_radius == 0.1
    assert not nav.local_costmap.use_static_layer and nav.global_costmap.use_static_layer
    assert nav.global_costmap.raytrace_max_range == 3.0 and nav.global_costmap.obstacle_max_range == 2.5
    jazzy, jnav = load_nav2_params(PARAMS / "nav2_params_jazzy.yaml")
    assert jazzy.radius == 0.22 and jazzy.max_angular_vel == 1.9
    assert jnav.global_costmap.inflation_radius == 0.7 and jnav.global_costmap.cost_scaling_factor == 3.0
