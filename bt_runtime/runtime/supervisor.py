"""The system supervisor: a watchdog over every component (the paper's fn_req1/2/5, non_freq1).

Each component proves it is alive by its messages (sensor streams, navigation heartbeats, the
tree's own tick heartbeat). Only fresh, plausible data counts (``data_checks``): a driver that
republishes old messages, repeats one frozen scan, sends NaN/out-of-range data, or publishes a
frozen pose while the robot is driven and other sensors show it moving (``motion_check``) is as
broken as a silent one. No good data for longer than its timeout (default 1 s) -> FAILED, with the
reason (silent, stale data, invalid data). Restarts
happen on request (the tree asks) or automatically; after ``max_failed_restarts`` (2) failed
restarts a component is DEAD, and a dead critical component stops the robot through the
decision gate. Condition nodes ask through non-blocking queries; every state change is an
event in ``events`` (with loop time) and a structlog line.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Any

import structlog

from .bringup import BringupReport, NodeOutcome, bring_up
from .config import SupervisorConfig
from .data_checks import DataCheck
from .messages import ComponentInfo
from .motion_check import MotionWitness

if TYPE_CHECKING:
    from .driver import RobotDriver
    from .gate import DecisionGate

log = structlog.get_logger("bt_runtime.supervisor")


class Health(Enum):
    UNKNOWN = "unknown"  # not heard from yet (still within the start-up grace)
    OK = "ok"
    FAILED = "failed"  # silent for longer than its timeout
    RESTARTING = "restarting"
    DEAD = "dead"  # restart failed max_failed_restarts times

    @property
    def usable(self) -> bool:
        return self is Health.OK


@dataclass(slots=True, frozen=True)
class SupervisorEvent:
    t: float
    component: str
    state: Health
    previous: Health
    reason: str


class ComponentRecord:
    """What the supervisor knows about one component."""

    __slots__ = ("name", "kind", "streams", "timeout", "critical", "auto_restart", "restartable",
                 "state", "last_seen", "failed_restarts", "restarts", "failures", "restart_fn",
                 "restart_task", "state_since", "watched", "depends_on", "last_message", "problem")

    def __init__(self, name: str, kind: str, streams: tuple[str, ...], timeout: float, critical: bool,
                 auto_restart: bool, restartable: bool,
                 restart_fn: Callable[[], Awaitable[bool]] | None = None):
        self.name = name
        self.kind = kind
        self.streams = streams
        self.timeout = timeout
        self.critical = critical
        self.auto_restart = auto_restart
        self.restartable = restartable
        self.state = Health.UNKNOWN
        self.last_seen: float | None = None  # last good (fresh, valid) message
        self.last_message: float | None = None  # last message of any kind
        self.problem = ""  # what was wrong with the last bad message
        self.failed_restarts = 0
        self.restarts = 0
        self.failures = 0
        self.restart_fn = restart_fn
        self.restart_task: asyncio.Task | None = None
        self.state_since = 0.0
        self.watched = True  # False while it is legitimately silent (e.g. an idle tree)
        self.depends_on: tuple[str, ...] = ()  # components it cannot work without


class SystemSupervisor:
    """Watchdog, health states, restart policy and an event log."""

    def __init__(self, driver: RobotDriver, config: SupervisorConfig | None = None, *,
                 clock: Callable[[], float], gate: DecisionGate | None = None):
        self.driver = driver
        self.config = config or SupervisorConfig()
        self.clock = clock
        self.gate = gate
        self.components: dict[str, ComponentRecord] = {}
        self.events: list[SupervisorEvent] = []
        self._unsubscribe: list[Callable[[], None]] = []
        self._started_at = 0.0
        self._listeners: list[Callable[[SupervisorEvent], Any]] = []
        self._dead: set[str] = set()
        self.motion: MotionWitness | None = None
        self._version = 0  # bumped on every change of state, watch or set of components
        self._not_ok_cache: dict[tuple[str, ...] | None, tuple[int, float, list[str]]] = {}
        self.bringup = BringupReport()  # the lifecycle bring-up at start (bring_up())

    # -- setup ---------------------------------------------------------------------------------
    def attach(self) -> None:
        """Watch every component the driver reports, through its streams."""
        self._started_at = self.clock()
        if self.config.check_data:  # commanded vs measured motion, for the frozen-pose check
            witness = self.motion = MotionWitness(self.clock)
            for stream, callback in (("cmd_vel_out", witness.on_command), ("imu", witness.on_imu),
                                     ("scan", witness.on_scan)):
                self._unsubscribe.append(self.driver.subscribe(stream, callback))
        for info in self.driver.components():
            self._watch_driver_component(info)

    def _watch_driver_component(self, info: ComponentInfo) -> None:
        watch = self.config.components.get(info.name)
        if watch is not None and not watch.watched:
            return
        cfg = self.config
        default = cfg.default_timeout
        if info.expected_rate_hz > 0:  # never less than 2.5 publish periods (a 1 Hz battery)
            default = max(default, 2.5 / info.expected_rate_hz)
        record = ComponentRecord(
            info.name, info.kind, tuple(info.streams),
            timeout=(watch.timeout if watch and watch.timeout else default),
            critical=(watch.critical if watch and watch.critical is not None else True),
            auto_restart=(watch.auto_restart if watch and watch.auto_restart is not None else cfg.auto_restart),
            restartable=info.restartable)
        record.state_since = self.clock()
        record.depends_on = tuple(info.extra.get("depends_on", ()))
        self.components[info.name] = record
        self._version += 1
        for stream in info.streams:
            self._unsubscribe.append(self.driver.subscribe(stream, self._seen_callback(record)))

    def _silence_reason(self, record: ComponentRecord, now: float) -> str:
        """Why no good data arrived: silence, or the problem with the data that did arrive."""
        since = record.last_seen if record.last_seen is not None else self._started_at
        bad_data = record.last_message is not None and record.last_message > since and record.problem
        what = record.problem if bad_data else "silent"
        return f"{what} for {now - since:.2f} s (timeout {record.timeout} s)"

    def register_local(self, name: str, *, timeout: float | None = None, critical: bool = True,
                       restart: Callable[[], Awaitable[bool]] | None = None, auto_restart: bool = False,
                       kind: str = "runtime") -> None:
        """Watch a component of this process (e.g. the tree) that calls ``heartbeat(name)``."""
        watch = self.config.components.get(name)
        if watch is not None:
            timeout = watch.timeout or timeout
            critical = critical if watch.critical is None else watch.critical
            auto_restart = auto_restart if watch.auto_restart is None else watch.auto_restart
        record = ComponentRecord(name, kind, (), timeout or self.config.default_timeout, critical,
                                 auto_restart, restart is not None, restart)
        record.state_since = self.clock()
        self.components[name] = record
        self._version += 1

    def _seen_callback(self, record: ComponentRecord) -> Callable[[Any], None]:
        clock = self.clock
        check = DataCheck(self.config.invalid_share, self.motion) if self.config.check_data else None

        def seen(msg: Any) -> None:
            now = clock()
            record.last_message = now
            if check is not None:
                problem = check(msg)
                if problem is not None:
                    record.problem = problem
                    return
            record.last_seen = now
            if record.state is Health.UNKNOWN or record.state is Health.FAILED:
                self._set_state(record, Health.OK, "messages flowing")

        return seen

    def heartbeat(self, name: str) -> None:
        record = self.components[name]
        record.last_seen = self.clock()
        if record.state is Health.UNKNOWN or record.state is Health.FAILED:
            self._set_state(record, Health.OK, "heartbeat")

    def set_watched(self, name: str, watched: bool) -> None:
        """Stop (or resume) expecting messages from ``name``; resuming restarts its clock."""
        record = self.components[name]
        record.watched = watched
        self._version += 1
        if watched:
            record.last_seen = self.clock()

    def add_listener(self, callback: Callable[[SupervisorEvent], Any]) -> None:
        self._listeners.append(callback)

    def detach(self) -> None:
        for unsubscribe in self._unsubscribe:
            unsubscribe()
        self._unsubscribe.clear()

    # -- the watchdog task -----------------------------------------------------------------------
    async def run(self) -> None:
        """Wake up exactly when the next component could time out, and check.

        Messages only move a component's deadline later, so sleeping until the earliest
        deadline (and at least every ``max_sleep`` s) detects a silence exactly ``timeout``
        after the last message, without polling.
        """
        loop = asyncio.get_running_loop()
        while True:
            now = loop.time()
            await asyncio.sleep(min(self.next_deadline(now), now + self.config.max_sleep) - now)
            self.check()

    def next_deadline(self, now: float) -> float:
        """The earliest time at which a watched component could become FAILED."""
        best = float("inf")
        grace = self.config.startup_grace
        for record in self.components.values():
            if not record.watched:
                continue
            if record.state is Health.OK and record.last_seen is not None:
                deadline = record.last_seen + record.timeout
            elif record.state is Health.UNKNOWN:
                deadline = max(self._started_at, record.state_since) + max(grace, record.timeout)
            else:
                continue
            deadline += 1e-6  # just past the deadline: the check is strict
            if now < deadline < best:
                best = deadline
        return best

    def check(self, now: float | None = None) -> None:
        now = self.clock() if now is None else now
        for record in self.components.values():
            if not record.watched:
                continue
            state = record.state
            if state is Health.OK:
                if record.last_seen is not None and now - record.last_seen > record.timeout:
                    self._fail(record, self._silence_reason(record, now))
            elif state is Health.UNKNOWN:  # the grace runs from the start, or from its bring-up
                if now - max(self._started_at, record.state_since) > max(self.config.startup_grace, record.timeout):
                    self._fail(record, f"never heard from ({record.problem})" if record.problem
                               else "never heard from")

    def _fail(self, record: ComponentRecord, reason: str) -> None:
        record.failures += 1
        blocked = self.failed_dependencies(record.name)
        if blocked:
            reason += f" (needs {', '.join(blocked)})"
        self._set_state(record, Health.FAILED, reason)
        if record.auto_restart and record.restartable and not blocked:
            self.request_restart(record.name)

    def _set_state(self, record: ComponentRecord, state: Health, reason: str) -> None:
        previous = record.state
        if previous is state:
            return
        now = self.clock()
        record.state = state
        record.state_since = now
        self._version += 1
        if state is Health.DEAD:
            self._dead.add(record.name)
        event = SupervisorEvent(now, record.name, state, previous, reason)
        self.events.append(event)
        log.info("component_state", component=record.name, state=state.value, previous=previous.value,
                 reason=reason, sim_time=round(now, 3))
        if state is Health.DEAD and record.critical and self.gate is not None:
            self.gate.emergency_stop(f"{record.name} dead")
        for listener in tuple(self._listeners):
            listener(event)

    # -- queries (non-blocking; condition nodes call these every tick) ---------------------------
    def health(self, name: str) -> Health:
        """Current health; a component whose timeout just expired reads FAILED immediately."""
        record = self.components.get(name)
        if record is None:
            return Health.UNKNOWN
        if record.state is Health.OK and record.last_seen is not None and record.watched:
            if self.clock() - record.last_seen > record.timeout:
                return Health.FAILED
        return record.state

    def is_healthy(self, name: str) -> bool:
        return self.health(name) is Health.OK

    def all_healthy(self, names: list[str] | None = None) -> bool:
        return all(self.health(n) is Health.OK for n in (names or self.components))

    def failed_among(self, names: list[str] | None = None) -> list[str]:
        """The components of ``names`` (every one but the tree when None) that are FAILED,
        RESTARTING or DEAD, or whose timeout just expired: one pass for condition nodes that
        ask about many components on every tick."""
        now = self.clock()
        records = self.components
        out = []
        for name in (names if names is not None else records):
            record = records.get(name)
            if record is None or (names is None and name == "tree"):
                continue
            state = record.state
            if state is Health.OK:
                seen = record.last_seen
                if record.watched and seen is not None and now - seen > record.timeout:
                    out.append(name)
            elif state is not Health.UNKNOWN:
                out.append(name)
        return out

    def not_ok_among(self, names: list[str] | None = None) -> list[str]:
        """The components of ``names`` (every one but the tree when None) that are not OK:
        as ``failed_among``, plus those not heard from yet (UNKNOWN) and names the supervisor
        does not watch. UNKNOWN is not OK: a condition that lets it pass lets a goal start
        before localization or the planner has spoken.

        Asked on every tick, so the answer is kept until something can change it: a state or
        watch change (``_version``), or the earliest time an OK component's timeout can expire
        (messages only push that later). The list returned is shared: do not modify it."""
        now = self.clock()
        key = None if names is None else tuple(names)
        cached = self._not_ok_cache.get(key)
        if cached is not None and cached[0] == self._version and now <= cached[1]:
            return cached[2]
        records = self.components
        out = []
        valid_until = float("inf")
        for name in (names if names is not None else records):
            record = records.get(name)
            if record is None:
                out.append(name)
                continue
            if names is None and name == "tree":
                continue
            if record.state is Health.OK:
                seen = record.last_seen
                if record.watched and seen is not None:
                    expiry = seen + record.timeout
                    if now > expiry:  # the watchdog has not failed it yet: a message may revive it
                        out.append(name)
                        valid_until = -float("inf")
                    elif expiry < valid_until:
                        valid_until = expiry
            else:
                out.append(name)
        self._not_ok_cache[key] = (self._version, valid_until, out)
        return out

    def any_dead(self, names: list[str] | None = None) -> bool:
        """Is one of ``names`` (any component when None) DEAD? (cheap: a DEAD state is stored)."""
        if not self._dead:
            return False
        return names is None or any(n in self._dead for n in names)

    def is_failed(self, name: str) -> bool:
        """FAILED, RESTARTING or DEAD: not merely unknown (start-up grace)."""
        return self.health(name) in (Health.FAILED, Health.RESTARTING, Health.DEAD)

    def failed_dependencies(self, name: str) -> list[str]:
        """The components ``name`` depends on that are not OK, or recovered less than
        ``dependency_grace`` s ago (the dependent usually comes back by itself then)."""
        record = self.components.get(name)
        if record is None:
            return []
        now = self.clock()
        grace = self.config.dependency_grace
        blocking = []
        for dep in record.depends_on:
            dep_record = self.components.get(dep)
            if dep_record is None:
                continue
            if self.health(dep) is not Health.OK or now - dep_record.state_since < grace:
                blocking.append(dep)
        return blocking

    def unhealthy(self) -> list[str]:
        return [n for n in self.components if self.health(n) is not Health.OK]

    def dead(self) -> list[str]:
        return [n for n, r in self.components.items() if r.state is Health.DEAD]

    def age(self, name: str) -> float | None:
        record = self.components.get(name)
        if record is None or record.last_seen is None:
            return None
        return self.clock() - record.last_seen

    def failed_restarts(self, name: str) -> int:
        record = self.components.get(name)
        return record.failed_restarts if record else 0

    def restarting(self, name: str) -> bool:
        record = self.components.get(name)
        return record is not None and record.restart_task is not None and not record.restart_task.done()

    def events_of(self, name: str) -> list[SupervisorEvent]:
        return [e for e in self.events if e.component == name]

    def summary(self) -> dict[str, str]:
        return {n: self.health(n).value for n in self.components}

    # -- bring-up of lifecycle nodes (runtime/bringup.py) ----------------------------------------
    async def bring_up(self) -> BringupReport:
        """Configure and activate the driver's lifecycle nodes in order (nav2_lifecycle_manager's
        startup). Components being brought up are not judged until their node is active; a
        node that fails is an event (FAILED, with the reason) and its component is FAILED, as
        are those the aborted bring-up left inactive; ``goals_refused()`` then says why."""
        plan_of = getattr(self.driver, "bringup_plan", None)
        plan = plan_of() if callable(plan_of) else None
        if plan is None:
            return self.bringup
        held = {c for c in plan.components.values() if c in self.components}
        for name in held:
            self.components[name].watched = False
        self._version += 1

        def resume(name: str | None) -> ComponentRecord | None:
            record = self.components.get(name) if name in held else None
            if record is not None:
                held.discard(name)
                record.watched = True
                self._version += 1
                record.state_since = max(record.state_since, self.clock())  # its grace starts now
            return record

        def on_node(outcome: NodeOutcome, phase: str) -> None:
            record = resume(outcome.component)
            if phase != "failed":
                return
            reason = f"bring-up failed at {outcome.node}: {outcome.error}"
            if record is not None:
                self._fail(record, reason)
            else:  # a lifecycle node the supervisor does not watch: still an event
                self._event(outcome.node, Health.FAILED, Health.UNKNOWN, reason)

        try:
            await bring_up(self.driver, plan, self.clock, on_node, self.bringup)
        except Exception as exc:  # a driver error is a failed bring-up, never a crash of the runtime
            log.exception("bringup_error")
            self.bringup.status, self.bringup.reason = "failed", f"internal error: {exc!r}"
        finally:
            report = self.bringup
            for name in list(held):  # left inactive by an aborted bring-up (or cancelled)
                record = resume(name)
                if record is not None and report.failed:
                    self._fail(record, f"not activated: bring-up stopped at {report.failed_node}")
        return report

    def goals_refused(self) -> str | None:
        """Why goals cannot be taken (a bring-up that failed and a node still not active), else None."""
        report = self.bringup
        if not report.failed:
            return None
        waiting = [n.node for n in report.nodes if n.state != "active"
                   and not (n.component in self.components and self.health(n.component) is Health.OK)]
        if not waiting:
            return None
        return f"{report.describe()} (not active: {', '.join(waiting)})"

    def _event(self, component: str, state: Health, previous: Health, reason: str) -> None:
        """An event about something that has no record (e.g. a lifecycle node nobody watches)."""
        event = SupervisorEvent(self.clock(), component, state, previous, reason)
        self.events.append(event)
        log.warning("component_state", component=component, state=state.value, previous=previous.value,
                    reason=reason, sim_time=round(event.t, 3))
        for listener in tuple(self._listeners):
            listener(event)

    # -- restarts ------------------------------------------------------------------------------
    def request_restart(self, name: str) -> asyncio.Task | None:
        """Start restarting ``name`` in the background (non-blocking); joins a running restart."""
        record = self.components.get(name)
        if record is None or not record.restartable or record.state is Health.DEAD:
            return None
        blocked = self.failed_dependencies(name)
        if blocked:  # restarting it cannot help while what it needs is down: restart that
            tasks = [self.request_restart(d) for d in blocked if self.health(d) is Health.FAILED]
            return next((t for t in tasks if t is not None), None)
        if record.restart_task is not None and not record.restart_task.done():
            return record.restart_task
        record.restart_task = asyncio.get_running_loop().create_task(self.restart(name),
                                                                     name=f"restart:{name}")
        return record.restart_task

    async def restart(self, name: str) -> bool:
        """Restart ``name`` and confirm its data flows again. Counts failures; DEAD after the
        configured number of failed restarts."""
        record = self.components[name]
        if record.state is Health.DEAD:
            return False
        if record.state is Health.OK and self.health(name) is Health.FAILED:
            # its timeout expired but the watchdog has not run yet: record the failure first
            record.failures += 1
            self._set_state(record, Health.FAILED, self._silence_reason(record, self.clock()))
        cfg = self.config
        record.restarts += 1
        started = self.clock()
        self._set_state(record, Health.RESTARTING, f"restart #{record.restarts} requested")
        try:
            if record.restart_fn is not None:
                ok = await asyncio.wait_for(record.restart_fn(), cfg.restart_timeout)
            else:
                ok = await asyncio.wait_for(self.driver.restart(name), cfg.restart_timeout)
        except TimeoutError:
            ok = False
        except Exception as exc:  # a driver error is a failed restart, not a crash
            log.warning("restart_error", component=name, error=repr(exc))
            ok = False
        if ok:
            ok = await self._data_resumed(record, started)
        if ok:
            record.failed_restarts = 0
            self._set_state(record, Health.OK, "restarted, data flowing")
            return True
        if self.failed_dependencies(name):  # not its fault: what it needs is down
            self._set_state(record, Health.FAILED, f"restart waited for {', '.join(self.failed_dependencies(name))}")
            return False
        record.failed_restarts += 1
        if record.failed_restarts >= cfg.max_failed_restarts:
            self._set_state(record, Health.DEAD, f"{record.failed_restarts} failed restarts")
        else:
            self._set_state(record, Health.FAILED, f"restart failed ({record.failed_restarts} of "
                                                   f"{cfg.max_failed_restarts})")
        return False

    async def _data_resumed(self, record: ComponentRecord, since: float) -> bool:
        deadline = self.clock() + self.config.recovery_timeout
        while self.clock() < deadline:
            if record.last_seen is not None and record.last_seen >= since:
                return True
            await asyncio.sleep(0.01)
        return record.last_seen is not None and record.last_seen >= since
