"""The gate's reuse of its last decision (gate.py ``_reuse``) under injected faults.

A differential test beside test_gate_reuse.py, written to find the cases it was not designed
for: non-finite and huge commands from every source, emergency stops, releases and shutdown
interleaved, locks flipping and timing out, speed limits of None, 0 and inf, navigation blocked,
the tree command cleared, heartbeats stopping and resuming, scans that go stale or carry NaN/inf
(in the ranges and in the stamp) or cannot be read, zones swapped out and back, clock steps
landing on every threshold and a microsecond (or less) either side, a clock near the epoch
(ROS time), and a driver whose ``send_velocity`` raises. Two gates, one reusing and one that
decides anew every time, must hand the driver, the backup and ``on_output`` the same bits at
every step, and every command they hand the driver must be finite and within the limits.
"""

from __future__ import annotations

import math
import random
import struct

import numpy as np
import pytest

from bt_runtime.runtime.command_limits import MotionLimits
from bt_runtime.runtime.config import GateConfig
from bt_runtime.runtime.gate import DecisionGate, UnsafeCommandError
from bt_runtime.runtime.messages import LaserScan, Twist
from bt_runtime.runtime.twist_mux_config import MuxInputConfig, MuxLockConfig
from tests.helpers import stop_slow_approach_zones

N = 90
INC = 2 * math.pi / N
BIG = 1e308
VALUES = [0.0, -0.0, 0.05, -0.2, 0.4, 1.3, -2.5, 5e-324, BIG, -BIG, math.nan, math.inf, -math.inf]
MAX_V, MAX_W = 0.5, 1.5


def bits(linear: float, angular: float) -> bytes:
    return struct.pack("<dd", linear, angular)


class FaultyBase:
    """Records every command handed to it, to the bit, then raises when told to."""

    def __init__(self):
        self.sent: list[bytes] = []
        self.fail = False

    def send_velocity(self, linear: float, angular: float) -> None:
        self.sent.append(bits(linear, angular))
        if self.fail:
            raise ConnectionError("base unreachable")


class Backup:
    def __init__(self):
        self.records: list[tuple] = []

    def record(self, stream: str, message, stamp: float | None = None) -> None:
        self.records.append((stream, bits(message.linear, message.angular) if isinstance(message, Twist)
                             else repr(message), stamp))


def random_scan(rng: random.Random, now: float):
    """A scan, fresh or old, sometimes with NaN/inf ranges or stamp, sometimes unreadable."""
    kind = rng.random()
    if kind < 0.05:
        return LaserScan(now, 0.0, INC, 0.05, 10.0, None)  # unreadable: dropped, the last one ages
    stamp = rng.choice([now, now, now - 0.1, now - 0.3, now - 0.3 - 1e-6, now - 0.35, now + 0.05,
                        math.nan, math.inf, -math.inf])
    ranges = np.full(N, rng.choice([np.inf, np.nan, 20.0]))
    distance = rng.choice([0.1, 0.25, 0.6, 1.2, 3.0])
    for k in range(rng.randrange(0, 8)):
        ranges[k] = rng.choice([distance + 0.001 * k, math.nan, math.inf, -math.inf, -1.0])
    return LaserScan(stamp, 0.0, INC, 0.05, 10.0, ranges)


def make_gate(clock, reuse: bool, *, passthrough: bool, limited: bool):
    config = GateConfig(passthrough=passthrough, nonfinite_repeats=2,
                        inputs={"teleop": MuxInputConfig(topic="t", priority=100, timeout=0.5),
                                "joy": MuxInputConfig(topic="j", priority=5, timeout=0.0)},
                        locks={"e_stop": MuxLockConfig(topic="e", priority=255, timeout=0.0),
                               "pause": MuxLockConfig(topic="p", priority=15, timeout=0.4)})
    base, backup = FaultyBase(), Backup()
    limits = MotionLimits(MAX_V, MAX_W, max_linear_accel=1.0, max_angular_accel=3.0) if limited else None
    gate = DecisionGate(base, config, clock=clock, backup=backup, limits=limits)
    gate.zones = stop_slow_approach_zones(clock, min_points=2)
    outputs: list[tuple] = []
    gate.on_output = lambda t, twist, source: outputs.append((t, bits(twist.linear, twist.angular), source))
    if not reuse:
        gate._reuse = lambda now: False
    return gate, base, backup, outputs


def apply_event(gate: DecisionGate, event: tuple, zones_kept: list) -> str:
    """Run one event on a gate; returns the error it raised (by type), if any."""
    kind, *args = event
    try:
        if kind == "tree":
            gate.set_tree_command(*args)
        elif kind == "clear":
            gate.clear_tree_command()
        elif kind == "nav":
            gate._on_nav(Twist(*args))
        elif kind in ("teleop", "joy"):
            gate._input_handler(kind)(Twist(*args))
        elif kind == "lock":
            gate._lock_handler(args[0])(args[1])
        elif kind == "estop":
            gate.emergency_stop(args[0])
        elif kind == "release":
            gate.release(args[0])
        elif kind == "release_all":
            gate.release_all()
        elif kind == "shutdown":
            gate.shutdown()
        elif kind == "limit":
            gate.set_speed_limit(*args)
        elif kind == "allow":
            gate.allow_navigation(args[0], "test")
        elif kind == "scan":
            if gate.zones is not None:
                gate.zones.on_scan(args[0])
        elif kind == "zones":  # zones taken off the gate and put back (the same object)
            if gate.zones is None:
                gate.zones = zones_kept[0]
            else:
                gate.zones = None
        elif kind == "tick":
            gate.after_tick()
        elif kind == "timer":  # the watchdog task's wake-up
            if not gate.config.passthrough:
                gate._apply(gate.clock())
    except UnsafeCommandError:
        return "unsafe"
    except ConnectionError:
        return "send failed"
    return ""


def random_event(rng: random.Random, now: float) -> tuple | None:
    roll = rng.random()
    command = (rng.choice(VALUES), rng.choice(VALUES))
    if rng.random() < 0.5:
        command = (rng.choice(VALUES[:7]), rng.choice(VALUES[:7]))
    if roll < 0.10:
        return ("tree", *command)
    if roll < 0.12:
        return ("clear",)
    if roll < 0.18:
        return ("nav", *command)
    if roll < 0.21:
        return (rng.choice(["teleop", "joy"]), *command)
    if roll < 0.24:
        return ("lock", rng.choice(["e_stop", "pause"]), rng.random() < 0.4)
    if roll < 0.26:
        return ("estop", rng.choice(["a", "b"]))
    if roll < 0.29:
        return ("release", rng.choice(["a", "b", "runtime stopped"]))
    if roll < 0.30:
        return (rng.choice(["release_all", "shutdown"]),)
    if roll < 0.32:
        limit = rng.choice([(None, None), (0.0, 0.0), (0.1, 0.2), (math.inf, 0.3), (None, 0.0), (0.2, None),
                            (1e-300, 1e-300)])
        return ("limit", *limit)
    if roll < 0.34:
        return ("allow", rng.random() < 0.6)
    if roll < 0.42:
        return ("scan", random_scan(rng, now))
    if roll < 0.43:
        return ("zones",)
    if roll < 0.47:
        return ("timer",)
    return None


def thresholds(gate: DecisionGate) -> list[float]:
    """Every instant at which the decision can change by time alone."""
    cfg = gate.config
    times = [gate._heartbeat + cfg.deadman_timeout, gate._tree_stamp + cfg.tree_stale_timeout,
             gate._nav_stamp + cfg.nav_stale_timeout, gate._reuse_until]
    times += [item.expiry() for item in (*gate.mux.inputs.values(), *gate.mux.locks.values())]
    if gate.zones is not None:
        times.append(gate.zones.valid_until())
    return [t for t in times if math.isfinite(t)]


def check_safe(gate: DecisionGate, sent: list[bytes], limited: bool, step: int) -> None:
    for raw in sent:
        v, w = struct.unpack("<dd", raw)
        assert math.isfinite(v) and math.isfinite(w), f"step {step}: non-finite command {v}, {w} sent"
        if limited:
            assert abs(v) <= MAX_V and abs(w) <= MAX_W, f"step {step}: ({v}, {w}) beyond the robot's limits"
    if sent and gate.speed_limit is not None:
        v, w = struct.unpack("<dd", sent[-1])
        lv, lw = gate.speed_limit  # (exactly: the limiter sets the linear speed to the limit itself)
        assert abs(v) <= lv and abs(w) <= lw, f"step {step}: ({v}, {w}) beyond speed limit {lv}, {lw}"
    if sent and gate.estop_active:
        assert sent[-1] == bits(0.0, 0.0), f"step {step}: moving under an emergency stop"


@pytest.mark.parametrize("seed", range(12))
def test_reuse_sends_what_a_full_decision_sends_under_faults(seed):
    rng = random.Random(1000 + seed)
    passthrough = seed % 6 == 5
    limited = seed % 3 != 2
    now = [rng.choice([100.0, 1.7e9 + 0.123])]  # virtual time, or ROS time near the epoch
    clock = lambda: now[0]  # noqa: E731
    gates = [make_gate(clock, reuse=True, passthrough=passthrough, limited=limited),
             make_gate(clock, reuse=False, passthrough=passthrough, limited=limited)]
    kept = [[g[0].zones] for g in gates]
    ticking, reused, failures = True, 0, 0
    for step in range(2500):
        fail = rng.random() < 0.04
        for _, base, _, _ in gates:
            base.fail = fail
        failures += fail
        if ticking:
            for gate, *_ in gates:
                gate.heartbeat()
        elif rng.random() < 0.05:
            ticking = True
        if rng.random() < 0.01:
            ticking = False  # the tree stops: the dead-man must zero the robot
        event = random_event(rng, now[0])
        events = [event] if event is not None else []
        if ticking and not passthrough:
            events.append(("tick",))
        before = len(gates[0][1].sent)
        for ev in events:
            if ev[0] == "tick" and gates[0][0]._reuse(now[0]):
                reused += 1
            results = [apply_event(g[0], ev, kept[k]) for k, g in enumerate(gates)]
            assert results[0] == results[1], f"step {step}: {ev}"
        (a, base_a, backup_a, out_a), (b, base_b, backup_b, out_b) = gates
        assert base_a.sent == base_b.sent, f"step {step}: {events}"
        assert backup_a.records == backup_b.records, f"step {step}: {events}"
        assert out_a == out_b, f"step {step}: {events}"
        assert (a.source, a.sent, a.switches, a.last_output) == (b.source, b.sent, b.switches, b.last_output)
        za, zb = kept[0][0], kept[1][0]
        assert (za.state, za.evaluations, za.errors, za.scans) == (zb.state, zb.evaluations, zb.errors, zb.scans)
        assert {k: (r.total, r.consecutive) for k, r in a.refused.items()} == \
               {k: (r.total, r.consecutive) for k, r in b.refused.items()}
        check_safe(a, base_a.sent[before:], limited, step)
        # time: a tick, or exactly on a threshold of either gate, or 1 us / 0.1 us either side
        marks = [t for g in gates for t in thresholds(g[0]) if t > now[0] - 2e-6]
        if marks and rng.random() < 0.35:
            target = rng.choice(marks) + rng.choice([-1e-6, -1e-7, 0.0, 0.0, 1e-7, 1e-6, 1.01e-6])
            now[0] = max(now[0], target)
        else:
            now[0] += rng.choice([0.01, 0.01, 0.01, 0.003, 0.05, 0.12, 0.5])
    if not passthrough:
        assert reused > 100, "the stream must exercise the reuse"
    assert failures > 50


def test_a_failed_send_is_not_reused_as_the_decision():
    """The decision made when the driver raised must go out on the next try: an emergency stop
    whose zero failed to reach the base must not be replaced by the command before it."""
    now = [10.0]
    base = FaultyBase()
    gate = DecisionGate(base, GateConfig(), clock=lambda: now[0])
    gate.heartbeat()
    gate.set_tree_command(0.3, 0.0)
    gate.after_tick()
    gate.after_tick()
    assert base.sent[-1] == bits(0.3, 0.0)
    base.fail = True
    with pytest.raises(ConnectionError):
        gate.emergency_stop("bumper")
    base.fail = False
    now[0] += 0.01
    gate.heartbeat()
    gate.after_tick()  # nothing changed since the stop: the stop's zero, not the 0.3 before it
    assert base.sent[-1] == bits(0.0, 0.0)
