"""The simulator's own log of its processes: what happened to each component, as the process
table and the topics would show it, independent of what the autonomy layer believes.

Events: ``crashed``, ``hung``, ``failing`` (faults), ``restarting``, ``running`` (up again
after a restart), ``restart_failed``, and ``published`` (the first message on the component's
topic, or its first heartbeat, after it started running). A restart counts only when the
process ran again *and* published: judging uses this log, not the layer's event log.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True, frozen=True)
class ComponentLogEntry:
    t: float
    component: str
    event: str
    detail: str = ""


FAULT_EVENTS = ("crashed", "hung", "failing")


def restarts(entries: list[ComponentLogEntry], component: str) -> list[tuple[float, float | None]]:
    """(time the restart began, time it published again or None) for each restart of
    ``component``, in order."""
    out: list[tuple[float, float | None]] = []
    running = False
    for e in entries:
        if e.component != component:
            continue
        if e.event == "restarting":
            out.append((e.t, None))
            running = False
        elif e.event == "running" and out:
            running = True
        elif e.event == "published" and out and running and out[-1][1] is None:
            out[-1] = (out[-1][0], e.t)
        elif e.event in FAULT_EVENTS or e.event == "restart_failed":
            running = False
    return out


def first_fault(entries: list[ComponentLogEntry], component: str) -> ComponentLogEntry | None:
    return next((e for e in entries if e.component == component and e.event in FAULT_EVENTS), None)
