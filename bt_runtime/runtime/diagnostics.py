"""Component health as ROS diagnostics: one status per component, at 1 Hz and on every change.

The supervisor knows each component's health; ROS tools (rqt_robot_monitor, Foxglove) read
``diagnostic_msgs/DiagnosticArray`` on ``/diagnostics``. This module turns the supervisor's
records into plain ``ComponentDiagnostic`` values and hands them to any driver that offers
``publish_diagnostics(diagnostics, now)`` (the ROS 2 driver does), so nothing here knows DDS.
A change of health is published at once, not at the next 1 Hz beat, so a crashed lidar shows
as ERROR as soon as the supervisor declares it failed.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass

import structlog

from .supervisor import Health, SupervisorEvent, SystemSupervisor

log = structlog.get_logger("bt_runtime.diagnostics")

OK, WARN, ERROR, STALE = 0, 1, 2, 3  # diagnostic_msgs/DiagnosticStatus levels
LEVELS = {Health.OK: OK, Health.RESTARTING: WARN, Health.FAILED: ERROR, Health.DEAD: ERROR,
          Health.UNKNOWN: STALE}


@dataclass(slots=True, frozen=True)
class ComponentDiagnostic:
    name: str  # "supervisor: lidar", as diagnostic aggregators group by prefix
    level: int
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]


def component_diagnostics(supervisor: SystemSupervisor, now: float) -> list[ComponentDiagnostic]:
    """One diagnostic per supervised component: level, message, last-seen age, restarts."""
    last_event: dict[str, SupervisorEvent] = {}
    for event in supervisor.events:  # one pass over the log, not one per component
        last_event[event.component] = event
    out = []
    for name, record in supervisor.components.items():
        state = record.state
        last = last_event.get(name)
        reason = last.reason if last is not None and last.state is state else ""
        message = state.value + (f": {reason}" if reason else "")
        age = "never" if record.last_seen is None else f"{max(0.0, now - record.last_seen):.3f}"
        values = (("state", state.value), ("last_seen_age_s", age), ("restarts", str(record.restarts)),
                  ("failed_restarts", str(record.failed_restarts)), ("failures", str(record.failures)),
                  ("kind", record.kind), ("critical", str(record.critical).lower()))
        if record.problem:
            values += (("last_problem", record.problem),)
        out.append(ComponentDiagnostic(f"supervisor: {name}", LEVELS.get(state, STALE), message, name, values))
    bringup = getattr(supervisor, "bringup", None)
    if bringup is not None and bringup.status != "off":  # the lifecycle bring-up, as nav2_lifecycle_manager reports "Nav2 Health"
        level = {"active": OK, "running": WARN}.get(bringup.status, ERROR)
        out.append(ComponentDiagnostic("supervisor: bringup", level, bringup.describe(), "bringup",
                                       tuple((n.node, n.error or n.state) for n in bringup.nodes)))
    return out


class DiagnosticsPublisher:
    """Publishes the supervisor's view every ``period`` seconds and on every health change."""

    def __init__(self, supervisor: SystemSupervisor, publish: Callable[[list[ComponentDiagnostic], float], None],
                 clock: Callable[[], float], period: float = 1.0):
        self.supervisor = supervisor
        self.publish = publish
        self.clock = clock
        self.period = period
        self.published = 0
        self.closed = False
        self._pending: asyncio.Handle | None = None
        supervisor.add_listener(self._on_event)

    def close(self) -> None:
        """Publish nothing more (the runtime is stopping and its driver goes away)."""
        self.closed = True
        if self._pending is not None:
            self._pending.cancel()
            self._pending = None

    def _on_event(self, event: SupervisorEvent) -> None:
        if self._pending is None and not self.closed:  # one publication for a burst of events
            self._pending = asyncio.get_running_loop().call_soon(self._publish_now)

    def _publish_now(self) -> None:
        self._pending = None
        if self.closed:
            return
        now = self.clock()
        try:
            self.publish(component_diagnostics(self.supervisor, now), now)
            self.published += 1
        except Exception as exc:  # health reporting must never take the runtime down
            log.warning("diagnostics_publish_failed", error=f"{type(exc).__name__}: {exc}")

    async def run(self) -> None:
        while True:
            self._publish_now()
            await asyncio.sleep(self.period)
