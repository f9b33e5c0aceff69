"""twist_mux's selection rules for the decision gate's inputs and locks (our own code).

The rules, as ros-teleop/twist_mux (ROS 2 branch, 4.x) applies them:

* An input is **fresh** while its last command is at most ``timeout`` seconds old; with timeout
  0 it never goes stale once it has sent something. Among the fresh inputs that are not
  masked, the one with the highest priority wins.
* A lock is **locked** while its last ``std_msgs/Bool`` said true, or (timeout > 0) when it
  has been silent for longer than its timeout, including before its first message: a lock
  with a timeout is a heartbeat, and a dead publisher locks. The lock priority is the highest
  priority of the locked locks (0 when none is locked).
* An input whose priority is **lower** than the lock priority is masked; equal or higher
  priorities are not (twist_mux's own example gives a "pause" lock the joystick's priority
  "so it'll not block it").
* Equal priorities: twist_mux keeps the first it meets, and it meets them in the order ROS
  lists parameters (sorted by name). The gate ranks its own sources first (tree, then
  navigation) and the other inputs by name.

Departures, because the gate is a safety device rather than a relay: twist_mux republishes
the winner's messages and publishes nothing when nothing is fresh; the gate publishes zero
then, and the emergency stop and the dead-man stand above every input (see gate.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import structlog

from .messages import ZERO_TWIST, Twist
from .twist_mux_config import MuxInputConfig, MuxLockConfig

log = structlog.get_logger("bt_runtime.gate")

INPUT_STREAM = "cmd_vel_input/"  # driver streams: cmd_vel_input/<name> (Twist), lock/<name> (bool)
LOCK_STREAM = "lock/"


@dataclass(slots=True)
class MuxInput:
    """An extra velocity input and its last command."""

    name: str
    topic: str
    priority: int
    timeout: float
    stamped: bool = False
    command: Twist = ZERO_TWIST
    stamp: float = -math.inf
    reason: str = ""  # why it wins, for the gate's switch log

    def __post_init__(self) -> None:
        self.reason = f"{self.name} input (priority {self.priority})"

    def fresh(self, now: float) -> bool:
        if self.stamp == -math.inf:
            return False
        return self.timeout == 0 or now - self.stamp <= self.timeout

    def expiry(self) -> float:
        return self.stamp + self.timeout if self.timeout > 0 else math.inf


@dataclass(slots=True)
class MuxLock:
    """A lock and its last value."""

    name: str
    topic: str
    priority: int
    timeout: float
    value: bool = False
    stamp: float = -math.inf

    def locked(self, now: float) -> bool:
        return self.value or (self.timeout > 0 and now - self.stamp > self.timeout)

    def expiry(self) -> float:
        return self.stamp + self.timeout if self.timeout > 0 else math.inf


class TwistMux:
    """The extra inputs and the locks; the gate asks it which input wins at an instant."""

    def __init__(self, inputs: dict[str, MuxInputConfig], locks: dict[str, MuxLockConfig]):
        self.inputs = {name: MuxInput(name, spec.topic or "", spec.priority, spec.timeout, spec.stamped)
                       for name, spec in sorted(inputs.items())}
        self.locks = {name: MuxLock(name, spec.topic, spec.priority, spec.timeout)
                      for name, spec in sorted(locks.items())}
        self._ranked = sorted(self.inputs.values(), key=lambda i: -i.priority)  # stable: name order on ties
        self._armed: list[MuxLock] = []  # the locks that are or can become locked (per tick: usually none)
        self._arm()
        top_lock = max(self.locks.values(), key=lambda lk: lk.priority, default=None)
        for entry in self._ranked:
            if top_lock is not None and entry.priority >= top_lock.priority:
                log.warning("gate_input_above_every_lock", input=entry.name, priority=entry.priority,
                            lock=top_lock.name, lock_priority=top_lock.priority,
                            note="no lock masks this input (the gate's emergency stop still does)")
            if entry.timeout == 0:
                log.warning("gate_input_never_stale", input=entry.name,
                            note="timeout 0: its last command stands until another one comes")

    def set_command(self, name: str, twist: Twist, now: float) -> None:
        entry = self.inputs[name]
        entry.command = twist
        entry.stamp = now

    def set_lock(self, name: str, value: bool, now: float) -> bool:
        """Record a lock message; True when the lock's value changed."""
        lock = self.locks[name]
        changed = lock.value != value
        lock.value = value
        lock.stamp = now
        if changed:
            self._arm()
        return changed

    def _arm(self) -> None:
        self._armed = [lk for lk in self.locks.values() if lk.value or lk.timeout > 0]

    def lock(self, now: float) -> tuple[int, str]:
        """(lock priority, the name of the lock that sets it); (0, "") when nothing is locked."""
        best, name = 0, ""
        for lock in self._armed:
            if lock.priority > best and lock.locked(now):
                best, name = lock.priority, lock.name
        return best, name

    def lock_reason(self, now: float, name: str) -> str:
        lock = self.locks[name]
        why = "true" if lock.value else (f"silent for {now - lock.stamp:.3f} s" if lock.stamp > -math.inf
                                         else "no message yet")
        return f"lock {name} ({why}, priority {lock.priority})"

    def best(self, now: float, above: int) -> MuxInput | None:
        """The fresh input with the highest priority that is > ``above`` (None: none)."""
        for entry in self._ranked:
            if entry.priority <= above:
                return None
            if entry.fresh(now):
                return entry
        return None

    def masked(self, now: float, lock_priority: int) -> list[str]:
        """Fresh inputs that the lock priority masks."""
        return [e.name for e in self._ranked if e.priority < lock_priority and e.fresh(now)]

    def next_change(self, now: float) -> float:
        """The next instant an input goes stale or a lock times out (inf: none pending)."""
        soonest = math.inf
        for item in (*self.inputs.values(), *self.locks.values()):
            t = item.expiry()
            if now < t < soonest:
                soonest = t
        return soonest
