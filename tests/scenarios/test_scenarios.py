"""The paper's 14 scenarios, each with and without the autonomy layer (virtual time, fixed seed).

With the layer every scenario must succeed. Without it every scenario must fail, and for the
real reason: the criterion listed here is the one the plain navigation stack cannot meet
(a driver nobody restarts, a goal nobody refuses, an obstacle nobody maps, ...).
"""

from __future__ import annotations

import pytest
import structlog

from bt_runtime.logging_setup import quiet_logging
from sim.scenarios.runner import TREES, run_scenario
from sim.scenarios.spec import scenario_names

SEED = 7

# criterion that must fail without the autonomy layer, and a phrase of its recorded reason
WITHOUT_FAILS = {
    **{f"{s}_{i}": (f"component_reset({c})", "never restarted")
       for s, c in (("Lidar", "lidar"), ("IMU", "imu"), ("Odom", "odom")) for i in (1, 2, 3)},
    "NoPathFound_1": ("component_reset(planner_server)", "never restarted"),
    "NoPathFound_2": ("alternative_reached(0)", "from the goal"),
    "Collision_1": ("reach_goal(0)", "not reached"),
    "Collision_2": ("obstacle_in_map(low_box)", "not in the map"),
    "Battery_1": ("charged_then_reached(0)", "never docked"),
}


@pytest.fixture(autouse=True)
def _quiet_logs():
    quiet_logging("error")
    yield
    structlog.reset_defaults()


def test_every_scenario_has_an_expected_baseline_failure():
    assert set(scenario_names()) == set(WITHOUT_FAILS)


@pytest.mark.parametrize("name", scenario_names())
def test_with_autonomy_layer(name):
    result = run_scenario(name, "with", SEED)
    assert result.success, result.reasons


@pytest.mark.parametrize("name", scenario_names())
def test_without_autonomy_layer_fails_for_the_real_reason(name):
    if not TREES["without"].exists():
        pytest.skip("trees/navigation.xml (the Nav2-style baseline) is not available")
    result = run_scenario(name, "without", SEED)
    assert not result.success
    criterion, phrase = WITHOUT_FAILS[name]
    failed = {v.criterion: v.reason for v in result.verdicts if not v.passed}
    assert criterion in failed, f"expected {criterion} to fail, failures: {failed}"
    assert phrase in failed[criterion], failed[criterion]


def test_runs_are_reproducible():
    a = run_scenario("Lidar_2", "with", SEED)
    b = run_scenario("Lidar_2", "with", SEED)
    assert (a.record.trajectory == b.record.trajectory).all()
    assert [(e.t, e.component, e.state) for e in a.record.supervisor_events] == \
           [(e.t, e.component, e.state) for e in b.record.supervisor_events]
