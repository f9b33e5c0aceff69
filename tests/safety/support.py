"""Fault-injection helpers for the safety suite: a recorder of what the base received, and
nodes that misbehave on purpose (drive, then block the loop, send NaN, raise...)."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

from bt_runtime.node import StatefulActionNode
from bt_runtime.ports import input_port
from bt_runtime.status import RUNNING


@dataclass(slots=True, frozen=True)
class Received:
    wall: float  # time.monotonic() when the base got it
    stamp: float  # the simulator's (loop) time
    linear: float
    angular: float

    @property
    def is_zero(self) -> bool:
        return self.linear == 0.0 and self.angular == 0.0


class BaseRecorder:
    """Wraps the simulated base's ``command`` (both the loop's path and the watchdog's
    thread-safe path end there) and keeps every command with its wall time."""

    def __init__(self, sim):
        self.received: list[Received] = []
        self._lock = threading.Lock()
        base = sim.base
        original = base.command

        def command(v, w, now):
            with self._lock:
                self.received.append(Received(time.monotonic(), now, float(v), float(w)))
            return original(v, w, now)

        base.command = command

    def assert_accel_limited(self, max_linear_accel: float, max_angular_accel: float) -> None:
        """Speeding up (away from zero) no faster than the limits; braking is free."""
        for a, b in zip(self.received, self.received[1:]):
            dt = b.stamp - a.stamp
            for prev, cur, limit in ((a.linear, b.linear, max_linear_accel), (a.angular, b.angular, max_angular_accel)):
                if abs(cur) > abs(prev) or prev * cur < 0:
                    base = prev if prev * cur > 0 else 0.0
                    assert abs(cur - base) <= limit * dt + 1e-9, f"{a} -> {b} exceeds {limit}/s^2"

    def after(self, t: float) -> list[Received]:
        return [r for r in self.received if r.wall >= t]

    def assert_safe(self, max_linear: float, max_angular: float) -> None:
        for r in self.received:
            assert math.isfinite(r.linear) and math.isfinite(r.angular), f"non-finite command reached the base: {r}"
            assert abs(r.linear) <= max_linear + 1e-9 and abs(r.angular) <= max_angular + 1e-9, \
                f"over-limit command reached the base: {r}"


class Drive(StatefulActionNode):
    """Commands the given velocity through the gate every tick (RUNNING)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("linear", float, 0.15), input_port("angular", float, 0.0)]

    def on_start(self):
        return self.on_running()

    def on_running(self):
        self.context.gate.set_tree_command(self.get_input("linear"), self.get_input("angular"))
        return RUNNING


class StallLoop(StatefulActionNode):
    """Drives for ``after`` ticks, then blocks the event loop ``seconds`` in real time, once."""

    stalled_at: float | None = None

    @classmethod
    def provided_ports(cls):
        return [input_port("after", int, 50), input_port("seconds", float, 2.0), input_port("linear", float, 0.15)]

    def __init__(self, name, config):
        super().__init__(name, config)
        self.ticks = 0

    def on_start(self):
        return self.on_running()

    def on_running(self):
        self.ticks += 1
        self.context.gate.set_tree_command(self.get_input("linear"), 0.0)
        if self.ticks == self.get_input("after"):
            StallLoop.stalled_at = time.monotonic()
            time.sleep(self.get_input("seconds"))
        return RUNNING


class RaiseIn(StatefulActionNode):
    """Drives for ``after`` ticks, then raises the named exception from its tick."""

    @classmethod
    def provided_ports(cls):
        return [input_port("after", int, 30), input_port("error", str, "KeyboardInterrupt")]

    def __init__(self, name, config):
        super().__init__(name, config)
        self.ticks = 0

    def on_start(self):
        return self.on_running()

    def on_running(self):
        self.ticks += 1
        self.context.gate.set_tree_command(0.15, 0.0)
        if self.ticks >= self.get_input("after"):
            raise {"KeyboardInterrupt": KeyboardInterrupt, "SystemExit": SystemExit,
                   "RuntimeError": RuntimeError}[self.get_input("error")]("injected")
        return RUNNING


def register_fault_nodes(factory) -> None:
    for cls in (Drive, StallLoop, RaiseIn):
        factory.register_node_type(cls)
