"""The local backend: a process pool whose dead workers are replaced and their runs retried."""

from __future__ import annotations

from sim.scenarios.backends import LocalBackend
from sim.scenarios.campaign import run_campaign

from .campaign_support import by_key, cheap_plan


def test_a_dying_pool_worker_is_retried_and_every_run_counted_once(tmp_path):
    maker = "tests.scenarios.worker_faults:die_once"
    plan = cheap_plan(runs=1, artifacts={maker: {"marker_dir": str(tmp_path)}})
    result = run_campaign(plan, LocalBackend(jobs=2))
    assert sorted(r["key"] for r in result.results) == sorted(r.key for r in plan)
    assert all(r["artifacts"] == {maker: "survived a retry"} for r in result.results)
    assert len(list(tmp_path.iterdir())) == len(plan)  # every run's first worker died
    inline = run_campaign(cheap_plan(runs=1), LocalBackend(jobs=1))
    assert by_key(result.results) == by_key(inline.results)


def test_a_run_that_raises_is_counted_once_as_failed_with_the_reason():
    plan = cheap_plan(runs=1, options={"no_such_option": 1})  # run_scenario raises TypeError at once
    result = run_campaign(plan, LocalBackend(jobs=1))
    assert [r["key"] for r in result.results] == [r.key for r in plan]
    for r in result.results:
        assert not r["success"]
        [verdict] = r["verdicts"]
        assert verdict["criterion"] == "run_completed"
        assert "TypeError" in verdict["reason"] and "no_such_option" in verdict["reason"]
