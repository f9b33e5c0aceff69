"""The variant generator: valid, reproducible run specs per failure family, runnable by the
campaign like shipped scenarios, and the layer handling a few of them."""

from __future__ import annotations

import pytest

from bt_runtime.logging_setup import quiet_logging
from sim.scenarios.runner import run_scenario
from sim.scenarios.variants import FAMILIES, family_of, generate


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
