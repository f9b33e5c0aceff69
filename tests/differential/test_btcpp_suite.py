"""The situations of BT.CPP's own unit tests (``btcpp_suite_cases.py``), run in bt_runtime and
in BT.CPP 4.8.2: same per-step statuses, leaf callbacks, blackboard values and error location."""

from __future__ import annotations

import pytest

from .btcpp_suite_cases import CASES
from .harness import Case, run_oracle, run_ours

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle


def test_case_names_are_unique():
    names = [c.name for c in CASES]
    assert len(names) == len(set(names))


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_same_as_btcpp(case: Case):
    ours, oracle = run_ours(case), run_oracle(case)
    diff = ours.first_difference(oracle)
    assert diff is None, diff
    if case.error is None:
        assert oracle.error is None, f"unexpected error in both engines: {oracle.error}"
    else:
        assert oracle.error_at is not None and oracle.error_at.startswith("step" if case.error == "tick" else case.error), (
            case.error, oracle.error_at, oracle.error)
