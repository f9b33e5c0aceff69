"""``run --goal`` goals go through the runtime's goal intake, the path of action and topic goals:
a goal from another client preempts them as it preempts its own, and the outcome says so."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace

import pytest

from bt_runtime.cli.run import notes_to_print
from bt_runtime.cli.run_goals import mark_unfinished, outcomes_for, send_goals
from bt_runtime.cli.summary import EXIT_FAILED, verdict
from bt_runtime.runtime.explain import FailureWitness
from bt_runtime.runtime.messages import Pose2D
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")


@pytest.mark.virtual_time
async def test_cli_goals_are_queued_in_the_intake_and_a_client_goal_preempts_them(runtime):
    rt = await runtime(AUTONOMY, seed=1, tick=False)
    witness = FailureWitness.attach(rt)
    goals = [Pose2D(3.5, -2.5, 0.0), Pose2D(0.0, -4.0, 0.0)]
    outcomes = outcomes_for(goals)
    try:
        await asyncio.sleep(1.0)  # components report
        cli = asyncio.get_running_loop().create_task(send_goals(rt, goals, outcomes, witness))
        await asyncio.wait_for(_until(lambda: rt.goals.current is not None), 10)
        assert [h.pose for h in rt.goals.queue] == [goals[1]]  # the second waits its turn in the intake
        await asyncio.sleep(2.0)
        client = rt.goals.submit(Pose2D(-1.0, -2.0, 0.0), source="action")  # e.g. RViz over NavigateToPose
        await asyncio.wait_for(cli, 10)
        client_result = await asyncio.wait_for(client, 60)
    finally:
        await rt.stop()
        witness.detach()
    assert [o.outcome for o in outcomes] == ["PREEMPTED", "PREEMPTED"]
    assert outcomes[0].reason.startswith("preempted by a newer goal")
    assert outcomes[0].sent_at is not None and outcomes[0].ended_at > outcomes[0].sent_at
    assert outcomes[1].sent_at is None  # never handed over
    mark_unfinished(outcomes, rt, witness, None)  # the run ends: the outcomes keep their reasons
    assert outcomes[1].reason.startswith("preempted by a newer goal")
    assert client_result.succeeded, client_result


def test_a_failed_bring_up_fails_the_run_with_the_node_named():
    summary = SimpleNamespace(status="RUNNING", ticks=10, tick_errors=0,
                              bringup={"status": "failed", "failed_node": "planner_server",
                                       "reason": "activate refused; the node is inactive"})
    result = verdict(summary, [], None)
    assert result.code == EXIT_FAILED
    assert result.reasons == ["bring-up failed: planner_server: activate refused; the node is inactive"]
    # the note that says the same is not printed a second time under the result line
    notes = ["bring-up failed: planner_server: activate refused; the node is inactive", "picture: run.png"]
    assert notes_to_print(notes, result) == ["picture: run.png"]


async def _until(predicate) -> None:
    while not predicate():
        await asyncio.sleep(0.01)
