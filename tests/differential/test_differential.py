"""bt_runtime against BT.CPP 4.8.2 (``behaviortreepy``): every case of ``cases.py`` must give the
same per-step root status, leaf callbacks, root node status, blackboard values and error
location in both engines."""

from __future__ import annotations

import pytest

from .cases import CASES
from .harness import Case, run_oracle, run_ours

pytest.importorskip("behaviortreepy", exc_type=ImportError)  # also a broken wheel
pytestmark = pytest.mark.oracle


def test_case_names_are_unique():
    names = [c.name for c in CASES]
    assert len(names) == len(set(names))


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_same_as_btcpp(case: Case):
    ours = run_ours(case)
    oracle = run_oracle(case)
    diff = ours.first_difference(oracle)
    assert diff is None, diff
    if case.error is None:
        assert oracle.error is None, f"unexpected error in both engines: {oracle.error}"
    else:
        where = "step" if case.error == "tick" else case.error
        assert oracle.error_at is not None and oracle.error_at.startswith(where), (
            case.error, oracle.error_at, oracle.error)
