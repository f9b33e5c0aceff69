"""What ``run`` tells the user at the end: a verdict line first, then the figures; the same in
``--summary-json``; and the exit code a script can trust.

Outcomes of goals use one vocabulary (Nav2's action results, plus two for goals the run did
not finish): SUCCEEDED, ABORTED, REFUSED, CANCELED, PREEMPTED (a newer goal, e.g. from a ROS
client, took over), REJECTED (never accepted, e.g. a Nav2 node would not activate), NOT_FINISHED
(the run ended first), NOT_STARTED (never handed over). Angles are radians everywhere (goals in, poses out).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130

SUCCEEDED, ABORTED, REFUSED, CANCELED = "SUCCEEDED", "ABORTED", "REFUSED", "CANCELED"
PREEMPTED, REJECTED = "PREEMPTED", "REJECTED"  # the goal intake's: a newer goal took over; never accepted
NOT_FINISHED, NOT_STARTED = "NOT_FINISHED", "NOT_STARTED"
OUTCOMES = (SUCCEEDED, ABORTED, REFUSED, CANCELED, PREEMPTED, REJECTED, NOT_FINISHED, NOT_STARTED)

# what a tree that completes per goal (Nav2-style) returns, in the goal vocabulary
FROM_TREE_STATUS = {"SUCCESS": SUCCEEDED, "FAILURE": ABORTED}


@dataclass
class GoalOutcome:
    """One goal of ``--goal``: where, how it ended, and why when it did not succeed."""

    x: float
    y: float
    yaw: float  # radians
    outcome: str = NOT_STARTED
    reason: str = ""
    sent_at: float | None = None  # robot time (s) the goal was handed to the tree
    ended_at: float | None = None
    failing_node: dict[str, Any] | None = None
    navigation_error: dict[str, Any] | None = None

    def line(self, index: int) -> str:
        where = f"({self.x:.2f}, {self.y:.2f}, yaw {self.yaw:.2f} rad)"
        text = f"goal {index} {where}: {self.outcome}"
        if self.outcome == SUCCEEDED and self.sent_at is not None and self.ended_at is not None:
            text += f" in {self.ended_at - self.sent_at:.1f} s"
        return text + (f": {self.reason}" if self.reason else "")


@dataclass
class Verdict:
    """Did the run do what was asked? ``code`` is the process exit code."""

    code: int
    reasons: list[str] = field(default_factory=list)

    def line(self) -> str:
        if self.code == EXIT_OK:
            return "result: OK"
        if self.code == EXIT_INTERRUPTED:
            return "result: INTERRUPTED"
        return "result: FAILED (" + "; ".join(self.reasons) + ")"


def verdict(summary: Any, goals: list[GoalOutcome], last_error: str | None, interrupted: bool = False) -> Verdict:
    """Exit non-zero when the tree ended in FAILURE or an error, when every tick errored, or
    when a goal was not reached; each reason in words."""
    reasons = []
    if summary.status == "FAILURE":
        reasons.append("the tree returned FAILURE")
    if summary.ticks and summary.tick_errors >= summary.ticks:
        reasons.append(f"every tick raised an error ({summary.tick_errors} of {summary.ticks})")
    elif last_error is not None:
        reasons.append(f"the last tick raised an error: {last_error}")
    bringup = getattr(summary, "bringup", None)
    if bringup and bringup.get("status") == "failed":
        reasons.append(f"bring-up failed: {bringup.get('failed_node')}: {bringup.get('reason')}")
    for i, g in enumerate(goals):
        if g.outcome != SUCCEEDED:
            reasons.append(f"goal {i} {g.outcome}")
    if interrupted:
        return Verdict(EXIT_INTERRUPTED, reasons)
    return Verdict(EXIT_FAILED if reasons else EXIT_OK, reasons)


def tree_line(summary: Any, uses_goal_handoff: bool) -> str:
    if summary.completed:
        return f"tree: {summary.status} (the root completed)"
    if uses_goal_handoff:
        return f"tree: {summary.status} (this tree runs until stopped and takes goals one by one)"
    return f"tree: {summary.status} (stopped before the root completed)"


def format_summary(summary: Any, runtime: Any, goals: list[GoalOutcome], result: Verdict, *,
                   uses_goal_handoff: bool = False, extra: list[str] = ()) -> str:
    s = summary
    lines = [result.line(), tree_line(s, uses_goal_handoff)]
    lines += [goal.line(i) for i, goal in enumerate(goals)]
    lines += list(extra)
    lines += [
        f"time: {s.sim_time:.2f} s robot time in {s.wall_time:.2f} s wall (x{s.real_time_factor:.1f})",
        f"ticks: {s.ticks}  errors: {s.tick_errors}  overruns: {s.overruns}  "
        f"tick CPU mean {s.tick_cost_mean_ms * 1e3:.1f} us, p99 {s.tick_cost_p99_ms * 1e3:.1f} us "
        f"(wall mean {s.tick_wall_mean_ms * 1e3:.1f} us)  "
        f"lateness p50 {s.lateness_p50_ms * 1e3:.1f} us, p99 {s.lateness_p99_ms * 1e3:.1f} us",
        "health: " + ", ".join(f"{k}={v}" for k, v in s.health.items()),
        f"supervisor events: {s.supervisor_events}  gate switches: {s.gate_switches}"
        + (f"  e-stop: {', '.join(s.estop_reasons)}" if s.estop_reasons else ""),
    ]
    pose = runtime.backup.latest("pose") if runtime is not None else None
    if pose is not None:
        lines.append(f"final pose (estimated): x={pose.pose.x:.2f} m y={pose.pose.y:.2f} m "
                     f"yaw={pose.pose.yaw:.2f} rad")
    return "\n".join(lines)


def summary_dict(summary: Any, goals: list[GoalOutcome], result: Verdict, **extra: Any) -> dict[str, Any]:
    """The JSON summary: every RunSummary field, the verdict, the goals with their reasons."""
    data = {k: v for k, v in summary.__dict__.items() if k != "goal_outcomes"}
    data.update(exit_code=result.code, result="OK" if result.code == EXIT_OK else "FAILED",
                failure_reasons=result.reasons, goals=[asdict(g) for g in goals],
                goal_outcomes=[g.outcome for g in goals], units={"distance": "m", "angle": "rad", "time": "s"})
    data.update(extra)
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in data.items()}
