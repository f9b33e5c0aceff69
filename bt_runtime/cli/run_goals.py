"""``run --goal``: hand the goals to the tree one after the other and record how each ended.

A tree that runs continuously and uses the goal hand-off (``{goal_status}``, like
trees/autonomy.xml) gets each goal when the previous one is SUCCEEDED / ABORTED / REFUSED; a
tree that completes per goal (like Nav2's, trees/navigation.xml) is run once per goal.
"""

from __future__ import annotations

import asyncio
from typing import Any

from ..runtime.messages import Pose2D
from .summary import ABORTED, FROM_TREE_STATUS, NOT_FINISHED, SUCCEEDED, GoalOutcome

HANDOFF_DONE = ("SUCCEEDED", "ABORTED", "REFUSED", "CANCELED")


def uses_goal_handoff(tree: Any) -> bool:
    return "goal_status" in port_keys(tree)


def port_keys(tree: Any) -> set[str]:
    """Blackboard keys the tree's ports refer to (to see whether it uses the goal hand-off)."""
    from ..ports import blackboard_key

    keys = set()
    for node in tree.nodes():
        for name, raw in {**node.config.input_ports, **node.config.output_ports}.items():
            key = blackboard_key(raw, name) if isinstance(raw, str) else None
            if key:
                keys.add(key.lstrip("@"))
    return keys


def outcomes_for(goals: list[Pose2D]) -> list[GoalOutcome]:
    return [GoalOutcome(g.x, g.y, g.yaw) for g in goals]


async def send_goals(runtime: Any, goals: list[Pose2D], outcomes: list[GoalOutcome], witness: Any) -> None:
    """Hand over each goal, wait for its end, note its outcome and, if it failed, why.
    The tree is not ticking yet (``runtime.start(tick=False)``); this starts it."""
    bb = runtime.tree.root_blackboard
    handoff = uses_goal_handoff(runtime.tree)
    for i, goal in enumerate(goals):
        out = outcomes[i]
        bb.set("goal", goal)
        bb.set("goals", [goal])
        out.sent_at = runtime.clock()
        if handoff:
            bb.set("goal_status", "PENDING")
            if i == 0:
                runtime.restart_tree()
            while bb.get("goal_status", default="") not in HANDOFF_DONE:
                if runtime.completed.done():
                    _finish(out, FROM_TREE_STATUS.get(runtime.completed.result().name, ABORTED), runtime, witness)
                    out.reason = f"the tree stopped ({runtime.completed.result().name}); " + out.reason
                    return
                await asyncio.sleep(0.05)
            _finish(out, bb.get("goal_status"), runtime, witness)
        else:
            done = runtime.restart_tree()
            status = (await done).name
            _finish(out, FROM_TREE_STATUS.get(status, status), runtime, witness)


def _finish(out: GoalOutcome, outcome: str, runtime: Any, witness: Any) -> None:
    out.outcome = outcome
    out.ended_at = runtime.clock()
    if outcome != SUCCEEDED:
        out.reason = witness.reason(since=out.sent_at)
        why = witness.to_dict(since=out.sent_at)
        out.failing_node, out.navigation_error = why["failing_node"], why["navigation_error"]


def mark_unfinished(outcomes: list[GoalOutcome], runtime: Any, witness: Any, duration: float | None) -> None:
    """The run ended (``--duration`` or an interrupt) while a goal was under way."""
    for out in outcomes:
        if out.sent_at is not None and out.ended_at is None:
            out.outcome = NOT_FINISHED
            out.ended_at = runtime.clock()
            limit = f"--duration {duration:g} s" if duration is not None else "the run"
            out.reason = f"{limit} ended {out.ended_at - out.sent_at:.1f} s after the goal was handed over"
            why = witness.to_dict(since=out.sent_at)
            out.failing_node, out.navigation_error = why["failing_node"], why["navigation_error"]
        elif out.sent_at is None:
            out.reason = "the run ended before this goal was handed over"
