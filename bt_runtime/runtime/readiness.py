"""Start-up readiness: wait until every component has reported before goals are handed over.

A goal handed over in the first milliseconds meets a robot whose battery, localization and
planner have not spoken yet: the tree then refuses it ("not enough battery") or restarts a
planner that was merely starting. ``wait_until_reported`` waits, with a timeout, and names
the components still silent.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field

from .supervisor import Health


@dataclass
class Readiness:
    waited: float  # seconds (loop time)
    silent: list[str] = field(default_factory=list)  # never reported within the timeout
    failed: list[str] = field(default_factory=list)  # reported, then failed (FAILED / DEAD)

    @property
    def ready(self) -> bool:
        return not self.silent and not self.failed

    def describe(self) -> str:
        parts = []
        if self.silent:
            parts.append(f"no message yet from {', '.join(self.silent)}")
        if self.failed:
            parts.append(f"not OK: {', '.join(self.failed)}")
        return "; ".join(parts) or "every component reported"


async def wait_until_reported(supervisor, clock, timeout: float, *, exclude: tuple[str, ...] = ("tree",),
                              poll: float = 0.02) -> Readiness:
    """Wait until every watched component has sent a message (or ``timeout`` s of loop time
    pass). Never heard from is what counts: after the supervisor's start-up grace a silent
    component reads FAILED, and it is still worth waiting for."""
    start = clock()
    records = {n: r for n, r in supervisor.components.items() if n not in exclude and r.watched}
    while True:
        states = {n: supervisor.health(n) for n in records}
        silent = [n for n, r in records.items()
                  if states[n] is Health.UNKNOWN or (r.last_seen is None and r.last_message is None)]
        if not silent or clock() - start >= timeout:
            failed = [n for n, s in states.items() if s in (Health.FAILED, Health.DEAD) and n not in silent]
            return Readiness(clock() - start, silent, failed)
        await asyncio.sleep(poll)
