"""``run --goal``: hand the goals to the tree one after the other and record how each ended.

A tree that runs continuously and uses the goal hand-off (``{goal_status}``, like
trees/autonomy.xml) gets each goal when the previous one is SUCCEEDED / ABORTED / REFUSED; a
tree that completes per goal (like Nav2's, trees/navigation.xml) is run once per goal.
"""

from __future__ import annotations

import asyncio
from typing import Any

from ..runtime.messages import Pose2D
from .summary import ABORTED, FROM_TREE_STATUS, NOT_FINISHED, NOT_STARTED, REFUSED, SUCCEEDED, GoalOutcome


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
    The tree is not ticking yet (``runtime.start(tick=False)``); this starts it.

    A tree with the goal hand-off gets the goals through the runtime's goal intake
    (``runtime.send_goal``), queued one behind the other: the same path as goals from the
    NavigateToPose action and the goal topic, so a goal from a ROS client preempts them as it
    would preempt its own, and outcomes (REFUSED, PREEMPTED, REJECTED...) are the intake's."""
    if not uses_goal_handoff(runtime.tree):
        for i, goal in enumerate(goals):  # a Nav2-style tree runs once per goal
            bb = runtime.tree.root_blackboard
            bb.set("goal", goal)
            bb.set("goals", [goal])
            outcomes[i].sent_at = runtime.clock()
            status = (await runtime.restart_tree()).name
            _finish(outcomes[i], FROM_TREE_STATUS.get(status, status), runtime, witness)
        return
    runtime.restart_tree()
    handles = [runtime.send_goal(goal, preempt=False) for goal in goals]
    for out, handle in zip(outcomes, handles, strict=True):
        while not handle.done:
            if out.sent_at is None and handle.started_at is not None:
                out.sent_at = handle.started_at  # handed over: its time counts from here
            if runtime.completed.done():  # the tree ended: nobody works on this goal or the next
                status = runtime.completed.result().name
                if handle.started_at is not None:
                    out.sent_at = handle.started_at
                    _finish(out, FROM_TREE_STATUS.get(status, ABORTED), runtime, witness)
                    out.reason = f"the tree stopped ({status}); " + out.reason
                return
            await asyncio.wait({handle.result_future}, timeout=0.05)
        result = handle.result
        out.sent_at = handle.started_at if handle.started_at is not None else out.sent_at
        _finish(out, result.outcome, runtime, witness, result.error_msg)


GENERIC = ("", "aborted by the tree")  # the intake's words when the tree gave no reason


def _finish(out: GoalOutcome, outcome: str, runtime: Any, witness: Any, message: str = "") -> None:
    """Record how a goal ended; why, when it did not succeed: the intake's message (refused:
    battery, preempted, rejected...) and what the tree saw (navigation error, failing node)."""
    out.outcome = outcome
    out.ended_at = runtime.clock()
    if outcome == SUCCEEDED:
        out.reason = "" if message in GENERIC else message  # e.g. "alternative goal used: ..."
        return
    parts = [] if message in GENERIC else [message]
    if out.sent_at is not None:  # it reached the tree: what went wrong there
        why = witness.to_dict(since=out.sent_at)
        out.failing_node, out.navigation_error = why["failing_node"], why["navigation_error"]
        if outcome == REFUSED and parts:
            # the tree decided and said why; the last failing leaf is one of its routine guards
            out.failing_node = None
            nav = witness.last_nav_error(since=out.sent_at)
            if nav is not None:
                parts.append(nav.describe())
        else:
            parts.append(witness.reason(since=out.sent_at))
    out.reason = "; ".join(parts)


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
        elif out.sent_at is None and out.outcome == NOT_STARTED:  # (a REJECTED goal keeps its reason)
            out.reason = "the run ended before this goal was handed over"
