"""Components: the simulated processes (sensor drivers, localization) that can crash and restart.

A component is ACTIVE (publishing), STARTING (a restart is under way), or INACTIVE (crashed or
shut down). Sensor drivers are polled by the simulator's physics task on the physics step grid
(a driver at 5 Hz publishes every 20th step of a 100 Hz physics loop): one asyncio task for
the whole simulator instead of one per driver keeps a simulated second cheap, and each driver
still publishes at its own rate with the loop clock's timestamps. Crashing a driver stops its
messages; ``restart()`` brings it back after its restart delay, or fails (stays INACTIVE) while
``fail_next`` > 0.

Driver-level faults (set by the fault injector, cleared by a restart):
  * silent until t: stops publishing without changing state (a hung process);
  * stale until t: republishes the last message unchanged (duplicate, old timestamp), or
    with fresh timestamps ('frozen');
  * corrupt until t: 'nan' or 'garbage' data;
  * noise scale until t: the sensor noise sigma is multiplied.
"""

from __future__ import annotations

import asyncio
import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_runtime.runtime.messages import ComponentInfo, ComponentState

if TYPE_CHECKING:  # pragma: no cover
    from .simulator import Simulator

ACTIVE = ComponentState.ACTIVE
STARTING = ComponentState.STARTING
INACTIVE = ComponentState.INACTIVE

NEG_INF = -math.inf


class Component:
    """A restartable simulated process."""

    kind = "sensor"

    def __init__(self, sim: Simulator, name: str, streams: tuple[str, ...] = (), *,
                 rate_hz: float = 0.0, restart_delay: float = 1.0, restartable: bool = True) -> None:
        self.sim = sim
        self.name = name
        self.streams = streams
        self.rate_hz = rate_hz
        self.restart_delay = restart_delay
        self.restartable = restartable
        self.fail_next = 0
        self.state = ACTIVE
        self.crash_count = 0
        self.restart_count = 0
        self.announce = False  # log the next message published (the first after a restart)
        self._restart_task: asyncio.Task | None = None
        self.clear_faults()

    # --- faults --------------------------------------------------------------------------------
    def clear_faults(self) -> None:
        self.silent_until = NEG_INF
        self.stale_until = NEG_INF
        self.stale_restamp = False  # 'frozen': the stale data goes out with fresh timestamps
        self.corrupt_until = NEG_INF
        self.corrupt_mode = ""
        self.noise_until = NEG_INF
        self.noise_factor = 1.0

    def noise_scale(self, now: float) -> float:
        return self.noise_factor if now < self.noise_until else 1.0

    # --- lifecycle -----------------------------------------------------------------------------
    def info(self) -> ComponentInfo:
        return ComponentInfo(name=self.name, kind=self.kind, streams=self.streams,
                             restartable=self.restartable, expected_rate_hz=self.rate_hz,
                             state=self.state,
                             extra={"restart_delay": self.restart_delay, "fail_next": self.fail_next,
                                    "crashes": self.crash_count, "restarts": self.restart_count})

    def _set_state(self, state: ComponentState, reason: str) -> None:
        if state is self.state:
            return
        old = self.state
        self.state = state
        self.sim.on_component_changed(self, old, reason)
        if state is ACTIVE:
            self.on_activate()

    def on_activate(self) -> None:
        """Hook: the component (re)starts publishing."""

    def announce_publishing(self) -> None:
        """After a (re)start, the first message published goes in the component log."""
        if self.announce:
            self.announce = False
            self.sim.log_component(self.name, "published")

    def crash(self, reason: str = "crash") -> None:
        """Stop the process now (a restart under way is abandoned)."""
        if self._restart_task is not None and not self._restart_task.done():
            self._restart_task.cancel()
        self._restart_task = None
        if self.state is not INACTIVE:
            self.crash_count += 1
        self._set_state(INACTIVE, reason)

    def restart(self) -> asyncio.Task:
        """Start a restart (or join the one under way); the task's result says if it worked."""
        if self._restart_task is None or self._restart_task.done():
            self._restart_task = asyncio.get_running_loop().create_task(
                self._restart(), name=f"sim-restart-{self.name}")
        return self._restart_task

    async def _restart(self) -> bool:
        if not self.restartable:
            self.sim.record_event("restart_refused", component=self.name)
            return False
        self.restart_count += 1
        self._set_state(STARTING, "restart")
        try:
            await asyncio.sleep(self.restart_delay)
        except asyncio.CancelledError:
            return False
        if self.fail_next > 0:
            self.fail_next -= 1
            self._set_state(INACTIVE, "restart failed")
            return False
        self.clear_faults()
        self.announce = True
        self._set_state(ACTIVE, "restarted")
        return True

    period_steps = 1  # poll() after every physics step unless a driver says otherwise

    def poll(self, step: int, now: float) -> None:
        """Called by the physics task after each step at which the component is due (every
        ``period_steps`` steps)."""


class Driver(Component):
    """A sensor driver that publishes one message every ``period_steps`` physics steps."""

    topic = ""

    def __init__(self, sim: Simulator, name: str, topic: str, rate_hz: float, **kw: Any) -> None:
        self.topic = topic
        self.period_steps = max(1, int(round(sim.physics_hz / rate_hz)))
        super().__init__(sim, name, (topic,), rate_hz=sim.physics_hz / self.period_steps, **kw)
        self.rng: np.random.Generator = sim.rng(name)
        self.fault_rng: np.random.Generator = sim.rng(f"{name}/faults")
        self.last_message: Any = None
        self.published = 0
        self._publish: Callable[[str, Any], None] = sim.bus.publish

    def poll(self, step: int, now: float) -> None:
        if self.state is not ACTIVE or now < self.silent_until:
            self.skip(now)
            return
        if now < self.stale_until and self.last_message is not None:
            self.skip(now)
            self.published += 1
            msg = self.last_message
            if self.stale_restamp:
                msg = dataclasses.replace(msg, stamp=now)
            self._publish(self.topic, msg)
            return
        msg = self.sample(now)
        if msg is None:
            return
        if now < self.corrupt_until:
            msg = self.corrupt(msg, self.corrupt_mode)
        self.last_message = msg
        self.published += 1
        self._publish(self.topic, msg)
        if self.announce:
            self.announce_publishing()

    def skip(self, now: float) -> None:
        """A period passed without publishing (down, silent or stale): reset accumulators."""

    def sample(self, now: float) -> Any:  # pragma: no cover - abstract
        raise NotImplementedError

    def corrupt(self, msg: Any, mode: str) -> Any:  # pragma: no cover - abstract
        raise NotImplementedError

    def garbage(self, scale: float) -> float:
        """A random, plausible-looking but wrong value."""
        return float(self.fault_rng.uniform(-scale, scale))
