"""The decision gate: the only writer of the robot's velocity (fn_req3, fn_req4).

Priority: emergency stop > tree command > navigation command. The gate applies the current
speed limit, publishes an explicit zero whenever it stops the robot, and outputs zero when the
tree's heartbeat is older than the dead-man timeout or the chosen source is stale, so a
crashed tree or a navigation stack that ignores cancel can never keep the robot moving. Every
switch of source is logged with its reason.

In ``passthrough`` mode (the "without autonomy layer" baseline) it forwards navigation
commands like a plain Nav2 setup does: no dead-man, no tree.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import structlog

from .config import GateConfig
from .messages import ZERO_TWIST, Twist

if TYPE_CHECKING:
    from .backup import DataBackup
    from .driver import RobotDriver

log = structlog.get_logger("bt_runtime.gate")

ESTOP, DEADMAN, TREE, NAV, IDLE = "estop", "deadman", "tree", "nav", "idle"


@dataclass(slots=True, frozen=True)
class GateSwitch:
    t: float
    source: str
    previous: str
    reason: str


class DecisionGate:
    """Multiplexes tree and navigation commands into ``driver.send_velocity``."""

    def __init__(self, driver: RobotDriver, config: GateConfig | None = None, *,
                 clock: Callable[[], float], backup: DataBackup | None = None):
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

    # -- setup ---------------------------------------------------------------------------------
    def attach(self) -> None:
        self._unsubscribe = self.driver.subscribe("nav_cmd_vel", self._on_nav)

    def detach(self) -> None:
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None

    def _on_nav(self, twist: Twist) -> None:
        self._nav = twist
        self._nav_stamp = self.clock()
        if self.config.passthrough:
            self._apply(self.clock())  # a plain Nav2 setup forwards every message at once

    # -- inputs (non-blocking; the tree and the runtime call these) ------------------------------
    def heartbeat(self) -> None:
        """The tree is alive (the tick loop calls this every tick)."""
        self._heartbeat = self.clock()

    def set_tree_command(self, linear: float, angular: float) -> None:
        """Drive with this command; it must be refreshed (it goes stale after
        ``tree_stale_timeout``) or cleared with ``clear_tree_command``."""
        self._tree = Twist(float(linear), float(angular))
        self._tree_stamp = self.clock()

    def clear_tree_command(self) -> None:
        self._tree = None

    @property
    def tree_command_active(self) -> bool:
        return self._tree is not None and self.clock() - self._tree_stamp <= self.config.tree_stale_timeout

    def emergency_stop(self, reason: str) -> None:
        """Stop now (an explicit zero goes out at once) until every reason is released."""
        if reason not in self._estops:
            self._estops[reason] = self.clock()
            log.warning("emergency_stop", reason=reason, sim_time=round(self.clock(), 3))
        self._apply(self.clock())

    def shutdown(self) -> None:
        """Final explicit zero when the runtime stops (not an emergency; logged at info)."""
        self._estops.setdefault("runtime stopped", self.clock())
        log.info("gate_shutdown", sim_time=round(self.clock(), 3))
        self._apply(self.clock())

    def release(self, reason: str) -> None:
        if self._estops.pop(reason, None) is not None:
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

    @property
    def navigation_allowed(self) -> bool:
        return self._nav_allowed

    def set_speed_limit(self, linear: float | None, angular: float | None = None, reason: str = "") -> None:
        """Cap the output speeds (None lifts the cap); also passed on to navigation if it can."""
        if linear is None and angular is None:
            self.speed_limit = None
            self.speed_limit_reason = ""
        else:
            self.speed_limit = (math.inf if linear is None else abs(linear),
                                math.inf if angular is None else abs(angular))
            self.speed_limit_reason = reason
        log.info("speed_limit", linear=linear, angular=angular, reason=reason, sim_time=round(self.clock(), 3))
        nav = getattr(self.driver, "navigation", None)
        setter = getattr(nav, "set_speed_limit", None)
        if callable(setter):
            setter(linear)

    # -- output --------------------------------------------------------------------------------
    async def run(self, start_at: float | None = None) -> None:
        """Publish the gate's decision every period, on absolute deadlines from ``start_at``."""
        loop = asyncio.get_running_loop()
        period = 1.0 / self.config.rate_hz
        start = loop.time() if start_at is None else start_at
        k = max(0, int((loop.time() - start) // period))
        while True:
            k += 1
            await asyncio.sleep(max(0.0, start + k * period - loop.time()))
            if not self.config.passthrough:
                self._apply(loop.time())

    def decide(self, now: float) -> tuple[str, Twist, str]:
        """(source, command before limits, reason) for this instant."""
        cfg = self.config
        if self._estops:
            return ESTOP, ZERO_TWIST, ", ".join(self._estops)
        if cfg.passthrough:
            return NAV, self._nav, "passthrough"
        if now - self._heartbeat > cfg.deadman_timeout:
            return DEADMAN, ZERO_TWIST, f"tree heartbeat {now - self._heartbeat:.3f} s old"
        tree = self._tree
        if tree is not None:
            if now - self._tree_stamp <= cfg.tree_stale_timeout:
                return TREE, tree, "tree command"
            return IDLE, ZERO_TWIST, "tree command stale"
        if not self._nav_allowed:
            return IDLE, ZERO_TWIST, f"navigation blocked: {self._nav_block_reason}"
        if now - self._nav_stamp <= cfg.nav_stale_timeout:
            return NAV, self._nav, "navigation command"
        return IDLE, ZERO_TWIST, "no fresh command"

    def _apply(self, now: float) -> None:
        source, twist, reason = self.decide(now)
        twist = self._limit(twist)
        if source != self.source:
            self.switches.append(GateSwitch(now, source, self.source, reason))
            log.info("gate_source", source=source, previous=self.source, reason=reason, sim_time=round(now, 3))
            self.source = source
        self.driver.send_velocity(twist.linear, twist.angular)
        self.last_output = twist
        self.sent += 1
        if self.backup is not None:
            self.backup.record("cmd_vel", twist, now)
        if self.on_output is not None:
            self.on_output(now, twist, source)

    def _limit(self, twist: Twist) -> Twist:
        limit = self.speed_limit
        if limit is None or twist.is_zero:
            return twist
        vmax, wmax = limit
        v, w = twist.linear, twist.angular
        if abs(v) > vmax:  # scale both, keeping the curvature
            scale = vmax / abs(v)
            v, w = v * scale, w * scale
        if abs(w) > wmax:
            w = math.copysign(wmax, w)
        return Twist(v, w)
