"""The campaign's "failed runs, by reason" list: alike reasons group, and keep their numbers."""

from sim.scenarios.campaign import failure_reasons


def _run(*verdicts):
    return {"verdicts": [{"criterion": c, "passed": False, "reason": r} for c, r in verdicts]}


def test_reasons_differing_in_numbers_group_and_show_the_range():
    runs = [_run(("component_reset(lidar)", "crashed at 2.5 s, never restarted")),
            _run(("component_reset(lidar)", "crashed at 3.25 s, never restarted"),
                 ("reach_goal(0)", "not reached: closest approach 1.2 m")),
            _run(("component_reset(lidar)", "crashed at 2.5 s, never restarted"))]
    assert failure_reasons(runs) == {
        "component_reset(lidar): crashed at 2.5..3.25 s, never restarted": 3,
        "reach_goal(0): not reached: closest approach 1.2 m": 1,
    }


def test_passed_verdicts_and_hash_signs_of_the_reason_itself():
    runs = [{"verdicts": [{"criterion": "reach_goal(0)", "passed": True, "reason": "ok"},
                          {"criterion": "note", "passed": False, "reason": "bag #3 of 4 missing"}]}]
    assert failure_reasons(runs) == {"note: bag #3 of 4 missing": 1}
