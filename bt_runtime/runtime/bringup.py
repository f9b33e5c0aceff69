"""Bring-up of managed (lifecycle) nodes at start, as nav2_lifecycle_manager's ``startup()`` does.

nav2_lifecycle_manager (navigation2, src/lifecycle_manager.cpp) configures every node of its
``node_names`` in order, then activates every one in order; each step is a ``change_state``
call followed by a ``get_state`` that must report the transition's goal state; the first node
that fails stops the bring-up ("Failed to bring up all requested nodes. Aborting bringup.") and
its diagnostics turn ERROR. We do the same, with two differences that let this run next to
Nav2's own manager: a node already configured (or active) is not configured again, and a
transition refused while the node reached the goal state anyway (someone else moved it) counts
as done. The sequence is driver-agnostic: a driver that has lifecycle nodes offers
``BringupDriver`` (the ROS 2 driver does); the supervisor runs it and reports the outcome.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import structlog

log = structlog.get_logger("bt_runtime.bringup")

# lifecycle_msgs/msg/State and Transition ids (the wire values)
UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = 1, 2, 3, 4
CONFIGURE, CLEANUP, ACTIVATE, DEACTIVATE = 1, 2, 3, 4
STATE_LABELS = {0: "unknown", 1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized", 10: "configuring",
                11: "cleaningup", 12: "shuttingdown", 13: "activating", 14: "deactivating",
                15: "errorprocessing"}
TRANSITION_LABELS = {CONFIGURE: "configure", CLEANUP: "cleanup", ACTIVATE: "activate", DEACTIVATE: "deactivate"}
GOAL_STATE = {CONFIGURE: INACTIVE, CLEANUP: UNCONFIGURED, ACTIVATE: ACTIVE, DEACTIVATE: INACTIVE}


def state_label(state: int | None) -> str:
    return "no answer" if state is None else STATE_LABELS.get(state, f"state {state}")


@runtime_checkable
class BringupDriver(Protocol):
    """What a driver with lifecycle nodes offers the bring-up (and lifecycle restarts)."""

    def bringup_plan(self) -> BringupPlan | None:
        """The nodes to bring up, in order, with their timeouts; None: nothing to bring up."""

    async def node_state(self, node: str, timeout: float) -> int | None:
        """The node's lifecycle state id (``get_state``); None when it does not answer."""

    async def change_node_state(self, node: str, transition: int, timeout: float) -> bool | None:
        """``change_state``: True/False as the node answers, None when it does not answer."""


@dataclass(frozen=True)
class BringupPlan:
    nodes: tuple[str, ...]
    components: dict[str, str]  # node -> the supervised component it is (if any)
    service_timeout: float  # wait this long for a node's lifecycle services (Nav2: 5 s)
    transition_timeout: float  # per change_state call


@dataclass
class NodeOutcome:
    node: str
    component: str | None
    state: str = "unconfigured"  # its lifecycle state when the bring-up finished with it
    steps: list[str] = field(default_factory=list)  # what we did: "configure", "activate", "already active"
    error: str = ""


@dataclass
class BringupReport:
    """How the bring-up went: ``status`` running, active (every node active), failed or off."""

    status: str = "off"
    nodes: list[NodeOutcome] = field(default_factory=list)
    failed_node: str | None = None
    reason: str = ""
    started_at: float | None = None
    finished_at: float | None = None

    @property
    def failed(self) -> bool:
        return self.status == "failed"

    def describe(self) -> str:
        if self.status == "failed":
            return f"bring-up failed: {self.failed_node}: {self.reason}"
        if self.status == "active":
            return f"bring-up: {len(self.nodes)} lifecycle node(s) active ({', '.join(n.node for n in self.nodes)})"
        return f"bring-up: {self.status}"

    def to_dict(self) -> dict:
        return {"status": self.status, "failed_node": self.failed_node, "reason": self.reason,
                "nodes": [{"node": n.node, "component": n.component, "state": n.state, "steps": n.steps,
                           "error": n.error} for n in self.nodes]}


class BringupError(Exception):
    """One node would not reach its goal state; the message says why, for a person."""


async def _settled_state(driver: BringupDriver, node: str, timeout: float,
                         clock: Callable[[], float]) -> int | None:
    """The node's primary state, waiting (up to ``timeout``) while it is in a transition state."""
    deadline = clock() + timeout
    while True:
        state = await driver.node_state(node, max(0.05, deadline - clock()))
        if state is None or state <= FINALIZED or clock() >= deadline:
            return state
        await asyncio.sleep(0.05)


async def transition(driver: BringupDriver, node: str, step: int, timeout: float,
                     clock: Callable[[], float]) -> None:
    """One lifecycle transition, checked as nav2_lifecycle_manager checks it: the call succeeds
    and ``get_state`` then reports the goal state. BringupError (with the reason) otherwise."""
    label = TRANSITION_LABELS[step]
    answer = await driver.change_node_state(node, step, timeout)
    state = await _settled_state(driver, node, timeout, clock)
    if state == GOAL_STATE[step]:
        return  # done (by us, or by another manager in the meantime)
    if answer is None:
        raise BringupError(f"{label}: no answer from {node}/change_state within {timeout:g} s")
    why = "refused" if answer is False else "accepted"
    raise BringupError(f"{label} {why}; the node is {state_label(state)}")


def _no_answer(driver: BringupDriver, node: str, waited: float) -> str:
    """Why get_state got nothing: its service never showed up, or it did and kept silent (a
    driver that can tell offers ``node_found(node)``)."""
    found = getattr(driver, "node_found", None)
    if callable(found) and found(node):
        return (f"its lifecycle service {node}/get_state was found but did not answer within {waited:g} s "
                "(a hung or overloaded node? docs/ros2.md)")
    where = "were not found" if callable(found) else "did not answer"
    return (f"its lifecycle services ({node}/get_state) {where} within {waited:g} s (is it running, on this "
            "domain and namespace, with an RMW whose services we speak? docs/ros2.md)")


async def bring_up(driver: BringupDriver, plan: BringupPlan, clock: Callable[[], float],
                   on_node: Callable[[NodeOutcome, str], Awaitable[None] | None] | None = None,
                   report: BringupReport | None = None) -> BringupReport:
    """Configure every node in order, then activate every node in order; stop at the first
    node that fails. ``on_node(outcome, phase)`` is told of each node as it becomes active
    (phase "active") or fails (phase "failed")."""
    report = report or BringupReport()
    report.status = "running"
    report.started_at = clock()
    report.nodes = [NodeOutcome(n, plan.components.get(n)) for n in plan.nodes]
    log.info("bringup_started", nodes=list(plan.nodes))

    async def tell(outcome: NodeOutcome, phase: str) -> None:
        if on_node is not None:
            result = on_node(outcome, phase)
            if isinstance(result, Awaitable):
                await result

    current: NodeOutcome | None = None
    try:
        for phase in ("configure", "activate"):
            for outcome in report.nodes:
                current = outcome
                # the first contact waits for the node's services to appear (Nav2's service_timeout)
                first = phase == "configure"
                state = await _settled_state(driver, outcome.node,
                                             plan.service_timeout if first else plan.transition_timeout, clock)
                if state is None:
                    raise BringupError(_no_answer(driver, outcome.node,
                                                  plan.service_timeout if first else plan.transition_timeout))
                if state == FINALIZED:
                    raise BringupError("it is finalized (shut down): restart its process")
                if phase == "configure" and state == UNCONFIGURED:
                    await transition(driver, outcome.node, CONFIGURE, plan.transition_timeout, clock)
                    outcome.steps.append("configure")
                    state = INACTIVE
                elif phase == "activate" and state == INACTIVE:
                    await transition(driver, outcome.node, ACTIVATE, plan.transition_timeout, clock)
                    outcome.steps.append("activate")
                    state = ACTIVE
                elif phase == "activate" and state == UNCONFIGURED:  # lost its configuration meanwhile
                    raise BringupError("it went back to unconfigured before its activation")
                elif state == ACTIVE and phase == "configure":
                    outcome.steps.append("already active")
                outcome.state = state_label(state)
                if phase == "activate":
                    log.info("bringup_node_active", node=outcome.node, steps=outcome.steps)
                    await tell(outcome, "active")
    except BringupError as exc:
        assert current is not None
        current.error = str(exc)
        current.state = "failed"
        report.status = "failed"
        report.failed_node = current.node
        report.reason = str(exc)
        report.finished_at = clock()
        log.error("bringup_failed", node=current.node, reason=str(exc),
                  not_active=[n.node for n in report.nodes if n.state != "active"])
        await tell(current, "failed")
        return report
    report.status = "active"
    report.finished_at = clock()
    log.info("bringup_done", nodes=list(plan.nodes), seconds=round(report.finished_at - report.started_at, 3))
    return report
