"""The gate's reuse of its last decision (gate.py ``_reuse``) changes nothing it sends.

Two gates get the same seeded random stream of events (tree, navigation and teleop commands,
locks with and without timeouts, emergency stops, speed limits, navigation blocks, scans that
trigger the zones or go stale, heartbeats that stop, times just before, at and after every
threshold) and a tick's ``after_tick`` between them; one decides everything anew each time. Every
command sent (to the bit), every switch of source, the zones' state and counters must agree.
"""

from __future__ import annotations

import math
import random
import struct

import numpy as np
import pytest

from bt_runtime.runtime.command_limits import MotionLimits
from bt_runtime.runtime.config import GateConfig
from bt_runtime.runtime.gate import DecisionGate
from bt_runtime.runtime.messages import LaserScan, Twist
from bt_runtime.runtime.twist_mux_config import MuxInputConfig, MuxLockConfig
from tests.helpers import stop_slow_approach_zones

N = 360
INC = 2 * math.pi / N


class Base:
    """What the driver was given, to the bit."""

    def __init__(self):
        self.sent: list[bytes] = []

    def send_velocity(self, linear: float, angular: float) -> None:
        self.sent.append(struct.pack("<dd", linear, angular))


def scan(rng: random.Random, stamp: float) -> LaserScan:
    ranges = np.full(N, np.inf)
    distance = rng.choice([0.25, 0.6, 1.2, 3.0])
    for k in range(rng.randrange(0, 12)):
        ranges[k] = distance + 0.001 * k
    return LaserScan(stamp, 0.0, INC, 0.05, 10.0, ranges)


def make_gate(clock, reuse: bool) -> tuple[DecisionGate, Base]:
    config = GateConfig(inputs={"teleop": MuxInputConfig(topic="t", priority=100, timeout=0.5)},
                        locks={"e_stop": MuxLockConfig(topic="e", priority=255, timeout=0.0),
                               "pause": MuxLockConfig(topic="p", priority=15, timeout=0.4)})
    base = Base()
    gate = DecisionGate(base, config, clock=clock,
                        limits=MotionLimits(0.5, 1.5, max_linear_accel=1.0, max_angular_accel=3.0))
    gate.zones = stop_slow_approach_zones(clock, min_points=3)
    if not reuse:
        gate._reuse = lambda now: False
    return gate, base


def snapshot(gate: DecisionGate) -> tuple:
    z = gate.zones
    return (gate.source, gate.sent, [(s.t, s.source, s.previous, s.reason) for s in gate.switches],
            (z.state, z.evaluations, z.errors), dict((k, (r.total, r.consecutive)) for k, r in gate.refused.items()))


COMMANDS = [(0.0, 0.0), (0.2, 0.0), (0.4, 0.5), (-0.1, 0.3), (0.9, 2.0), (0.3, -0.0), (-0.0, 0.0),
            (math.nan, 0.1), (0.1, math.inf)]


@pytest.mark.parametrize("seed", range(8))
def test_reused_decisions_send_what_a_full_decision_sends(seed):
    rng = random.Random(seed)
    now = [100.0]
    clock = lambda: now[0]  # noqa: E731
    gates = [make_gate(clock, reuse=True), make_gate(clock, reuse=False)]
    ticking = True
    reused = 0
    for step in range(3000):
        if ticking:
            for gate, _ in gates:
                gate.heartbeat()
        roll = rng.random()
        event = None
        if roll < 0.08:
            event = ("tree", rng.choice(COMMANDS))
        elif roll < 0.10:
            event = ("clear",)
        elif roll < 0.15:
            event = ("nav", rng.choice(COMMANDS))
        elif roll < 0.17:
            event = ("teleop", rng.choice(COMMANDS))
        elif roll < 0.19:
            event = ("lock", rng.choice(["e_stop", "pause"]), rng.random() < 0.3)
        elif roll < 0.20:
            event = ("estop", rng.choice(["a", "b"]))
        elif roll < 0.22:
            event = ("release", rng.choice(["a", "b"]))
        elif roll < 0.23:
            event = ("limit", rng.choice([None, 0.1, 0.3]))
        elif roll < 0.24:
            event = ("allow", rng.random() < 0.7)
        elif roll < 0.30:
            event = ("scan", scan(rng, now[0] - rng.choice([0.0, 0.1, 0.35])))
        elif roll < 0.31:
            ticking = not ticking
        for gate, _ in gates:
            if event is None:
                break
            kind = event[0]
            try:
                if kind == "tree":
                    gate.set_tree_command(*event[1])
                elif kind == "clear":
                    gate.clear_tree_command()
                elif kind == "nav":
                    gate._on_nav(Twist(*event[1]))
                elif kind == "teleop":
                    gate._input_handler("teleop")(Twist(*event[1]))
                elif kind == "lock":
                    gate._lock_handler(event[1])(event[2])
                elif kind == "estop":
                    gate.emergency_stop(event[1])
                elif kind == "release":
                    gate.release(event[1])
                elif kind == "limit":
                    gate.set_speed_limit(event[1], None if event[1] is None else 2 * event[1])
                elif kind == "allow":
                    gate.allow_navigation(event[1], "test")
                elif kind == "scan":
                    gate.zones.on_scan(event[1])
            except ValueError:  # UnsafeCommandError after repeated non-finite tree commands
                pass
        if ticking:
            for gate, _ in gates:
                before = gate.zones.evaluations
                if gate is gates[0][0] and gate._reuse(now[0]):
                    reused += 1
                gate.after_tick()
                assert gate.zones.evaluations == before + 1
        # time moves by a tick, or lands just before, on or after a threshold of the reusing gate
        gate, previous = gates[0][0], now[0]
        if rng.random() < 0.2 and math.isfinite(gate._reuse_until):
            now[0] = max(previous, gate._reuse_until + rng.choice([-1e-7, 0.0, 1e-6, 1.1e-6, 2e-3]))
        else:
            now[0] += rng.choice([0.01, 0.01, 0.01, 0.003, 0.05, 0.12])
        (a, base_a), (b, base_b) = gates
        assert base_a.sent == base_b.sent, f"step {step}: {event}"
        assert snapshot(a) == snapshot(b), f"step {step}: {event}"
        assert a.last_output == b.last_output
    assert reused > 300, "the stream must exercise the reuse"


def test_on_a_real_time_loop_the_gate_task_zeroes_a_silent_tree_and_dies_loudly():
    """``run`` on timers (real time): the dead-man zero goes out once the heartbeat is
    ``deadman_timeout`` old, the decision is republished at ``min_rate_hz``, and an error in the
    decision ends the task with that error (the runtime then stops the robot)."""
    import asyncio

    from bt_runtime.runtime import clock as rt_clock

    async def main():
        loop = asyncio.get_running_loop()
        base = Base()
        gate = DecisionGate(base, GateConfig(deadman_timeout=0.05, min_rate_hz=20.0), clock=loop.time)
        gate.heartbeat()
        gate.set_tree_command(0.2, 0.0)
        task = loop.create_task(gate.run())
        for _ in range(10):  # a tree ticking at 100 Hz
            await asyncio.sleep(0.01)
            gate.heartbeat()
            gate.set_tree_command(0.2, 0.0)
        assert gate.source == "tree"
        stopped = loop.time()
        await asyncio.sleep(0.3)  # the tree stops
        switch = gate.switches[-1]
        assert switch.source == "deadman" and 0.05 <= switch.t - stopped < 0.25  # (late only on a loaded machine)
        assert gate.last_output == Twist(0.0, 0.0)
        sent = gate.sent
        await asyncio.sleep(0.2)
        assert 2 <= gate.sent - sent <= 5  # republished at min_rate_hz (20 Hz)
        gate.limiter.apply = None  # the next decision raises
        gate._reuse = lambda now: False
        with pytest.raises(TypeError):
            await asyncio.wait_for(task, 1.0)

    rt_clock.run(main, virtual=False)
