"""The decision gate: the only writer of the robot's velocity (fn_req3, fn_req4).

Priority: emergency stop > dead-man > the twist_mux-style inputs (``twist_mux.py``): by
default teleop (100) > tree command (20) > navigation command (10), with locks that mask
lower-priority inputs (by default an ``e_stop`` lock at 255). The gate applies the current
speed limit, publishes an explicit zero whenever it stops the robot, and outputs zero when the
tree's heartbeat is older than the dead-man timeout or the chosen source is stale, so a
crashed tree or a navigation stack that ignores cancel can never keep the robot moving. Every
switch of source is logged with its reason.

In ``passthrough`` mode (the "without autonomy layer" baseline) it forwards navigation
commands like a plain Nav2 setup does: no dead-man, no tree.

Every command, whatever its source, goes through one output path: a non-finite command is
refused (zero goes out, the source is logged and counted; repeated, the tree's node that sent
it fails with ``UnsafeCommandError``, or navigation is cancelled so the node waiting for it
fails), and finite ones are clamped to the robot's speed and acceleration limits and the
current speed limit (``command_limits.py``). With a ``LoopWatchdog`` attached, sends are
serialised with it and every heartbeat refreshes it (``watchdog.py``).

The decision is computed again only when it can differ: every input change bumps ``_version``,
and a decision is reused (``_reuse``) while the version and the zones' scan are the same, the
heartbeat is fresh, no staleness or scan-age threshold lies between then and now (to within a
microsecond: near one the whole decision runs), and the limiter's output is its own fixed
point (a ramp in progress is recomputed). What goes out is the same command, sent, recorded
and announced as the full path would; only the arithmetic is skipped. An idle tree's ticks (a
held zero) take this path.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import structlog

from .clock import is_virtual
from .command_limits import CommandLimiter, MotionLimits, is_finite
from .config import GateConfig
from .messages import ZERO_TWIST, Twist
from .twist_mux import INPUT_STREAM, LOCK_STREAM, TwistMux

if TYPE_CHECKING:
    from .backup import DataBackup
    from .driver import RobotDriver
    from .safety_zones import SafetyZones
    from .watchdog import LoopWatchdog

log = structlog.get_logger("bt_runtime.gate")

ESTOP, DEADMAN, TREE, NAV, IDLE, LOCK = "estop", "deadman", "tree", "nav", "idle", "lock"


class UnsafeCommandError(ValueError):
    """A source kept sending non-finite velocity commands (raised in the node that sent them)."""


@dataclass(slots=True)
class RefusedCommands:
    """Non-finite commands refused from one source."""

    total: int = 0
    consecutive: int = 0
    last: tuple[float, float] = (0.0, 0.0)
    last_time: float = 0.0


@dataclass(slots=True, frozen=True)
class GateSwitch:
    t: float
    source: str
    previous: str
    reason: str


def _same(a: Twist, b: Twist) -> bool:
    """Equal to the bit (a zero's sign included: it goes on the wire)."""
    return (a.linear == b.linear and a.angular == b.angular
            and math.copysign(1.0, a.linear) == math.copysign(1.0, b.linear)
            and math.copysign(1.0, a.angular) == math.copysign(1.0, b.angular))


class DecisionGate:
    """Multiplexes the tree's, navigation's and the extra inputs' commands (twist_mux rules, locks)
    into ``driver.send_velocity``, below the emergency stop and the dead-man."""

    def __init__(self, driver: RobotDriver, config: GateConfig | None = None, *,
                 clock: Callable[[], float], backup: DataBackup | None = None,
                 limits: MotionLimits | None = None):
        self.driver = driver
        self.config = config or GateConfig()
        self.clock = clock
        self.backup = backup
        self._nav: Twist = ZERO_TWIST
        self._nav_stamp = -math.inf
        self._tree: Twist | None = None
        self._tree_stamp = -math.inf
        self._heartbeat = -math.inf
        self._estops: dict[str, float] = {}
        self._nav_allowed = True
        self._nav_block_reason = ""
        self.speed_limit: tuple[float, float] | None = None  # (linear, angular), None = none
        self.speed_limit_reason = ""
        self.source = IDLE
        self.last_output: Twist = ZERO_TWIST
        self.switches: list[GateSwitch] = []
        self.sent = 0
        self._unsubscribe: Callable[[], None] | None = None
        self.on_output: Callable[[float, Twist, str], Any] | None = None
        self.limiter = CommandLimiter(limits)
        self._last_output_time = -math.inf
        self.refused: dict[str, RefusedCommands] = {}
        self.watchdog: LoopWatchdog | None = None
        self.mux = TwistMux(self.config.inputs, self.config.locks)
        self.zones: SafetyZones | None = None  # collision_monitor-style zones (safety_zones.py)
        self._version = 0  # bumped by every change of an input of the decision (see _reuse)
        self._reuse_key: tuple | None = None  # (version, zones, zones' scan generation) of last_output
        self._reuse_until = -math.inf  # last_output holds until then, by the inputs' time thresholds

    # -- setup ---------------------------------------------------------------------------------
    def attach(self) -> None:
        """Subscribe to navigation's command and to every extra input and lock; a driver that
        reads topics (ROS 2) is told which first (``open_command_inputs``, optional)."""
        mux, driver = self.mux, self.driver
        open_inputs = getattr(driver, "open_command_inputs", None)
        if callable(open_inputs) and (mux.inputs or mux.locks):
            open_inputs(list(mux.inputs.values()), list(mux.locks.values()))
        unsubscribe = [driver.subscribe("nav_cmd_vel", self._on_nav)]
        for name in mux.inputs:
            unsubscribe.append(driver.subscribe(INPUT_STREAM + name, self._input_handler(name)))
        for name in mux.locks:
            unsubscribe.append(driver.subscribe(LOCK_STREAM + name, self._lock_handler(name)))

        def unsubscribe_all() -> None:
            for unsub in unsubscribe:
                unsub()

        self._unsubscribe = unsubscribe_all

    def detach(self) -> None:
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None

    def _input_handler(self, name: str) -> Callable[[Twist], None]:
        def on_input(twist: Twist) -> None:
            """A command from an extra input (teleop...): refused if non-finite (the input then
            holds zero while fresh: a broken joystick stops the robot rather than handing it
            back to navigation), published at once if it wins."""
            if self._refuse_if_nonfinite(name, twist.linear, twist.angular):
                twist = ZERO_TWIST
            now = self.clock()
            self.mux.set_command(name, Twist(float(twist.linear), float(twist.angular)), now)
            self._version += 1
            if not self.config.passthrough:
                self._apply(now)

        return on_input

    def _lock_handler(self, name: str) -> Callable[[Any], None]:
        def on_lock(value: Any) -> None:
            now = self.clock()
            locked = bool(getattr(value, "data", value))
            if self.mux.set_lock(name, locked, now):
                (log.warning if locked else log.info)("gate_lock", lock=name, locked=locked, sim_time=round(now, 3))
            self._version += 1  # (the stamp moves a lock's timeout even when its value stays)
            if not self.config.passthrough:
                self._apply(now)

        return on_lock

    def _on_nav(self, twist: Twist) -> None:
        if self._refuse_if_nonfinite(NAV, twist.linear, twist.angular):
            twist = ZERO_TWIST
            if self.refused[NAV].consecutive == self.config.nonfinite_repeats:
                self._cancel_navigation()
        self._nav = twist
        now = self.clock()
        self._nav_stamp = now
        self._version += 1
        # forward at once (a plain Nav2 setup does the same in pass-through mode); when the
        # navigation command is not the chosen source this republishes the current decision
        self._apply(now)

    # -- inputs (non-blocking; the tree and the runtime call these) ------------------------------
    def heartbeat(self) -> None:
        """The tree is alive (the tick loop calls this before every tick)."""
        self._heartbeat = self.clock()
        watchdog = self.watchdog
        if watchdog is not None:
            watchdog.refresh()

    def after_tick(self) -> None:
        """Publish the decision right after a tick, so the tree's commands go out at once."""
        if not self.config.passthrough:
            self._apply(self.clock())

    def set_tree_command(self, linear: float, angular: float) -> None:
        """Drive with this command; it must be refreshed (it goes stale after
        ``tree_stale_timeout``) or cleared with ``clear_tree_command``.

        A non-finite value is refused: the tree commands zero instead; after
        ``nonfinite_repeats`` refusals in a row this raises ``UnsafeCommandError`` (the
        calling node fails)."""
        linear, angular = float(linear), float(angular)
        self._tree_stamp = self.clock()
        self._version += 1
        if self._refuse_if_nonfinite(TREE, linear, angular):
            self._tree = ZERO_TWIST
            record = self.refused[TREE]
            if record.consecutive >= self.config.nonfinite_repeats:
                raise UnsafeCommandError(f"non-finite velocity command ({linear}, {angular}) refused "
                                         f"{record.consecutive} times in a row")
            return
        self._tree = Twist(linear, angular)

    def _refuse_if_nonfinite(self, source: str, linear: float, angular: float) -> bool:
        """Count a non-finite command from ``source`` (True: refused), or reset its streak."""
        record = self.refused.get(source)
        if math.isfinite(linear) and math.isfinite(angular):
            if record is not None:
                record.consecutive = 0
            return False
        if record is None:
            record = self.refused[source] = RefusedCommands()
        record.total += 1
        record.consecutive += 1
        record.last = (linear, angular)
        record.last_time = self.clock()
        if record.consecutive == 1 or record.total % 1000 == 0:
            log.warning("command_refused", source=source, linear=linear, angular=angular,
                        reason="non-finite", total=record.total, sim_time=round(self.clock(), 3))
        return True

    def _cancel_navigation(self) -> None:
        log.error("navigation_cancelled", reason="repeated non-finite navigation commands",
                  sim_time=round(self.clock(), 3))
        cancel = getattr(getattr(self.driver, "navigation", None), "cancel_all", None)
        if callable(cancel):
            try:
                cancel()
            except Exception as exc:
                log.error("navigation_cancel_failed", error=repr(exc))

    def clear_tree_command(self) -> None:
        self._tree = None
        self._version += 1

    @property
    def tree_command_active(self) -> bool:
        return self._tree is not None and self.clock() - self._tree_stamp <= self.config.tree_stale_timeout

    def emergency_stop(self, reason: str) -> None:
        """Stop now (an explicit zero goes out at once) until every reason is released."""
        if reason not in self._estops:
            self._estops[reason] = self.clock()
            self._version += 1
            log.warning("emergency_stop", reason=reason, sim_time=round(self.clock(), 3))
        self._apply(self.clock())

    def shutdown(self) -> None:
        """Final explicit zero when the runtime stops (not an emergency; logged at info)."""
        self._estops.setdefault("runtime stopped", self.clock())
        self._version += 1
        log.info("gate_shutdown", sim_time=round(self.clock(), 3))
        self._apply(self.clock())

    def release(self, reason: str) -> None:
        if self._estops.pop(reason, None) is not None:
            self._version += 1
            log.info("emergency_stop_released", reason=reason, sim_time=round(self.clock(), 3))

    def release_all(self) -> None:
        for reason in list(self._estops):
            self.release(reason)

    @property
    def estop_active(self) -> bool:
        return bool(self._estops)

    @property
    def estop_reasons(self) -> list[str]:
        return list(self._estops)

    def allow_navigation(self, allowed: bool, reason: str = "") -> None:
        """Block navigation commands (e.g. after cancelling navigation: a stack that ignores
        the cancel is held off by the gate)."""
        if allowed != self._nav_allowed:
            log.info("navigation_allowed" if allowed else "navigation_blocked", reason=reason,
                     sim_time=round(self.clock(), 3))
        self._nav_allowed = allowed
        self._nav_block_reason = "" if allowed else reason
        self._version += 1

    @property
    def navigation_allowed(self) -> bool:
        return self._nav_allowed

    def set_speed_limit(self, linear: float | None, angular: float | None = None, reason: str = "") -> None:
        """Cap the output speeds (None lifts the cap); also passed on to navigation if it can."""
        for name, value in (("linear", linear), ("angular", angular)):
            if value is not None and (value != value or value < 0):
                raise ValueError(f"speed limit {name} must be >= 0 m/s or rad/s, got {value!r}")
        if linear is None and angular is None:
            self.speed_limit = None
            self.speed_limit_reason = ""
        else:
            self.speed_limit = (math.inf if linear is None else abs(linear),
                                math.inf if angular is None else abs(angular))
            self.speed_limit_reason = reason
        self._version += 1
        log.info("speed_limit", linear=linear, angular=angular, reason=reason, sim_time=round(self.clock(), 3))
        nav = getattr(self.driver, "navigation", None)
        setter = getattr(nav, "set_speed_limit", None)
        if callable(setter):
            setter(linear)

    # -- output --------------------------------------------------------------------------------
    async def run(self) -> None:
        """The gate's watchdog: wake up when the tree's heartbeat or the chosen source would go
        stale (and at least ``min_rate_hz``), and publish the decision then. Without it, a
        tree that stopped ticking would leave the last command standing."""
        loop = asyncio.get_running_loop()
        if not is_virtual(loop):
            return await self._run_on_timers(loop)
        while True:  # (virtual time: the task path, whose event order is part of a run's trace)
            now = loop.time()
            await asyncio.sleep(max(0.0, self.next_deadline(now) - now))
            if not self.config.passthrough:
                self._apply(loop.time())

    async def _run_on_timers(self, loop: asyncio.AbstractEventLoop) -> None:
        """``run`` on a real-time loop: each wake-up is one timer whose callback applies the
        decision and sets the next (one pass of the loop, as the tick's pacing; a sleeping task
        takes two). An exception in the callback ends the task with it, as it would end the
        loop above."""
        finished = loop.create_future()
        handle: asyncio.TimerHandle | None = None

        def on_timer() -> None:
            nonlocal handle
            try:
                if not self.config.passthrough:
                    self._apply(loop.time())
                handle = loop.call_at(self.next_deadline(loop.time()), on_timer)
            except BaseException as exc:
                if not finished.done():
                    finished.set_exception(exc)
                if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                    raise

        handle = loop.call_at(self.next_deadline(loop.time()), on_timer)
        try:
            await finished
        finally:
            handle.cancel()

    def next_deadline(self, now: float) -> float:
        """The next instant the decision can change by itself (a heartbeat or the chosen
        source going stale), or ``1 / min_rate_hz`` from now. Deadlines already passed have
        been applied, so only future ones count."""
        cfg = self.config
        deadline = now + 1.0 / cfg.min_rate_hz
        if not cfg.passthrough:
            candidates = [self._heartbeat + cfg.deadman_timeout + 1e-6, self.mux.next_change(now) + 1e-6]
            if self.source == TREE:
                candidates.append(self._tree_stamp + cfg.tree_stale_timeout + 1e-6)
            elif self.source == NAV:
                candidates.append(self._nav_stamp + cfg.nav_stale_timeout + 1e-6)
            for candidate in candidates:
                if now < candidate < deadline:
                    deadline = candidate
        return deadline

    def decide(self, now: float) -> tuple[str, Twist, str]:
        """(source, command before limits, reason) for this instant."""
        cfg = self.config
        if self._estops:
            return ESTOP, ZERO_TWIST, ", ".join(self._estops)
        if cfg.passthrough:
            return NAV, self._nav, "passthrough"
        if now - self._heartbeat > cfg.deadman_timeout:
            return DEADMAN, ZERO_TWIST, f"tree heartbeat {now - self._heartbeat:.3f} s old"
        # twist_mux's rule over the tree, navigation and the extra inputs (twist_mux.py): the
        # highest priority among the fresh inputs that no lock masks; ties: tree, navigation,
        # then the extra inputs by name. A tree command set but not refreshed holds its rank
        # with zero until cleared, so a node that stopped refreshing cannot hand over to navigation.
        mux = self.mux
        lock_priority, lock_name = mux.lock(now) if mux.locks else (0, "")
        nav_fresh = self._nav_allowed and now - self._nav_stamp <= cfg.nav_stale_timeout
        priorities = cfg.priorities
        p_tree, p_nav = priorities["tree"], priorities["nav"]
        source, twist, reason, rank = IDLE, ZERO_TWIST, "", -1
        tree = self._tree
        if tree is not None and p_tree >= lock_priority:
            rank = p_tree
            if now - self._tree_stamp <= cfg.tree_stale_timeout:
                source, twist, reason = TREE, tree, "tree command"
            else:
                reason = "tree command stale"
        if nav_fresh and p_nav >= lock_priority and p_nav > rank:
            rank = p_nav
            source, twist = NAV, self._nav
            reason = "navigation command" if tree is None else "navigation command (priority over the tree)"
        if mux.inputs:
            entry = mux.best(now, max(lock_priority - 1, rank))
            if entry is not None:
                return entry.name, entry.command, entry.reason
        if rank >= 0:
            return source, twist, reason
        masked = [name for name, present, p in ((TREE, tree is not None, p_tree), (NAV, nav_fresh, p_nav))
                  if present and p < lock_priority] + mux.masked(now, lock_priority)
        if masked:
            return LOCK, ZERO_TWIST, f"{mux.lock_reason(now, lock_name)} masks {', '.join(masked)}"
        if not self._nav_allowed:
            return IDLE, ZERO_TWIST, f"navigation blocked: {self._nav_block_reason}"
        return IDLE, ZERO_TWIST, "no fresh command"

    def _apply(self, now: float) -> None:
        if self._reuse(now):
            twist = self.last_output
            zones = self.zones
            if zones is not None and zones.enabled and not self.config.passthrough:
                zones.evaluations += 1  # (counted as the full path counts it)
        else:
            twist = self._decide_output(now)
        watchdog = self.watchdog
        try:
            if watchdog is None:
                self.driver.send_velocity(twist.linear, twist.angular)
            else:
                with watchdog.lock:
                    self.driver.send_velocity(twist.linear, twist.angular)
                    watchdog.note_sent(not twist.is_zero)
        except BaseException:  # last_output stays what went before, not this decision: no reuse
            self._reuse_key = None
            raise
        self.last_output = twist
        self._last_output_time = now
        self.sent += 1
        if self.backup is not None:
            self.backup.record("cmd_vel", twist, now)
        if self.on_output is not None:
            self.on_output(now, twist, self.source)

    def _reuse(self, now: float) -> bool:
        """``last_output`` is what the full decision would give at ``now`` (see the module
        docstring): same inputs, same scan, fresh heartbeat, no threshold passed since."""
        zones = self.zones
        return (now < self._reuse_until and now - self._heartbeat <= self.config.deadman_timeout
                and self._reuse_key == (self._version, zones, None if zones is None else zones.generation))

    def _decide_output(self, now: float) -> Twist:
        """The full decision: source, zones, limits; logs a switch of source, and notes how long
        the result may be reused."""
        source, twist, reason = self.decide(now)
        finite = is_finite(twist)
        if not finite:  # every input is checked already; this is the last line
            self._refuse_if_nonfinite(source, twist.linear, twist.angular)
            twist = ZERO_TWIST
        zones = self.zones
        key = (self._version, zones, None if zones is None else zones.generation)
        errors = 0 if zones is None else zones.errors
        if zones is not None and not self.config.passthrough:  # every source, before the final clamp
            twist = zones.filter(twist, now, source)
        limited = self.limiter.apply(twist, self.last_output, now - self._last_output_time, self.speed_limit)
        if source != self.source:
            self.switches.append(GateSwitch(now, source, self.source, reason))
            log.info("gate_source", source=source, previous=self.source, reason=reason, sim_time=round(now, 3))
            self.source = source
        # reusable: a decision that does not hang on the heartbeat's age, reached without a
        # refusal or a zones error (those are logged and counted each time), at the limiter's
        # fixed point (a ramp still moving depends on the time since the last output)
        if (source != DEADMAN and finite and (zones is None or zones.errors == errors)
                and _same(limited, self.limiter.clamp(twist, self.speed_limit))):
            self._reuse_key = key
            self._reuse_until = self._thresholds(now)
        else:
            self._reuse_key = None
        return limited

    def _thresholds(self, now: float) -> float:
        """The first instant after ``now`` at which the decision can change by time alone (an
        input or the tree's or navigation's command going stale, a lock timing out, the scan
        getting too old), less a microsecond; thresholds passed within the last millisecond
        count as ahead (equality at a threshold is decided by the full path)."""
        cfg = self.config
        times = [self._tree_stamp + cfg.tree_stale_timeout, self._nav_stamp + cfg.nav_stale_timeout]
        mux = self.mux
        for item in (*mux.inputs.values(), *mux.locks.values()):
            times.append(item.expiry())
        zones = self.zones
        if zones is not None:
            times.append(zones.valid_until())
        until = math.inf
        recent = now - 1e-3
        for t in times:
            if recent < t < until:
                until = t
        return until - 1e-6
