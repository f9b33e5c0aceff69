"""Ending a process safely: signals stop it through the same path as a normal end, and no
task can hold the exit hostage.

``run_main`` replaces ``asyncio.run`` for the CLI: SIGTERM, SIGINT and SIGHUP cancel the main
task (whose ``finally`` stops the runtime: the gate's last message is zero), then surface as
``ShutdownSignal`` (a KeyboardInterrupt, so callers that handle Ctrl-C handle all three). A
second signal zeroes every live runtime's base from the signal handler and interrupts at once.
Tasks still pending when the main task ends are cancelled and given ``timeout`` seconds; a task
that ignores cancellation is abandoned with a warning naming it (``bt:<node path>`` for an
AsyncActionNode), and the loop is closed anyway.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import threading
import time
import weakref
from collections.abc import Awaitable, Callable, Iterable
from typing import Any, TypeVar

import structlog

log = structlog.get_logger("bt_runtime.shutdown")

T = TypeVar("T")
SHUTDOWN_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
DEFAULT_TIMEOUT = 2.0

# runtimes that have started and not stopped: zeroed by a second signal or a crashed loop
_live: weakref.WeakSet = weakref.WeakSet()


class ShutdownSignal(KeyboardInterrupt):
    """The process was asked to stop by a signal; ``signum`` says which."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


def register_live(runtime: Any) -> None:
    _live.add(runtime)


def unregister_live(runtime: Any) -> None:
    _live.discard(runtime)


def zero_live_runtimes(reason: str) -> int:
    """Zero the base of every runtime still running, without the event loop (thread-safe
    driver path); returns how many."""
    count = 0
    for runtime in list(_live):
        zero = getattr(runtime.driver, "emergency_zero", None)
        if callable(zero):
            try:
                zero()
                count += 1
            except Exception as exc:
                log.error("emergency_zero_failed", reason=reason, error=repr(exc))
    if count:
        log.warning("emergency_zero", reason=reason, runtimes=count)
    return count


def task_label(task: asyncio.Task) -> str:
    name = task.get_name()
    return f"node {name[3:]}" if name.startswith("bt:") else f"task {name}"


async def settle(tasks: Iterable[asyncio.Task], timeout: float, *, what: str = "shutdown") -> list[asyncio.Task]:
    """Cancel ``tasks`` and wait for them up to ``timeout`` seconds (loop time and wall time,
    whichever comes first); returns (and logs) the ones that ignored the cancellation."""
    pending = {t for t in tasks if not t.done()}
    for task in pending:
        task.cancel()
    loop = asyncio.get_running_loop()
    wall_end, loop_end = time.monotonic() + timeout, loop.time() + timeout
    while pending and time.monotonic() < wall_end and loop.time() < loop_end:
        _, pending = await asyncio.wait(pending, timeout=min(0.05, max(0.0, loop_end - loop.time())))
    for task in pending:
        log.warning("task_abandoned", during=what, task=task.get_name(), who=task_label(task),
                    reason=f"ignored cancellation for {timeout:.1f} s")
    return sorted(pending, key=lambda t: t.get_name())


def _finish(loop: asyncio.AbstractEventLoop, timeout: float) -> None:
    """Cancel what is left, bounded; then close the loop even if something would not end."""
    current = asyncio.tasks.all_tasks(loop)
    stragglers: list[asyncio.Task] = []
    if current:
        stragglers = loop.run_until_complete(settle(current, timeout))
    if stragglers:  # never awaited again; keep asyncio from complaining when they are collected
        for task in stragglers:
            with contextlib.suppress(Exception):
                task._log_destroy_pending = False  # type: ignore[attr-defined]
    else:
        with contextlib.suppress(Exception):
            loop.run_until_complete(asyncio.wait_for(loop.shutdown_asyncgens(), timeout))
    with contextlib.suppress(Exception):
        loop.run_until_complete(asyncio.wait_for(loop.shutdown_default_executor(), timeout))


def run_main(main: Awaitable[T] | Callable[[], Awaitable[T]], *, loop_factory: Callable[[], asyncio.AbstractEventLoop],
             signals: bool = False, timeout: float = DEFAULT_TIMEOUT, debug: bool | None = None) -> T:
    """Run ``main`` on a fresh loop; see the module docstring."""
    loop = loop_factory()
    if debug is not None:
        loop.set_debug(debug)
    asyncio.set_event_loop(loop)
    coro = main() if callable(main) else main
    task = loop.create_task(coro, name="main")
    received: list[int] = []
    installed: list[int] = []

    def on_signal(signum: int) -> None:
        received.append(signum)
        if len(received) == 1:
            log.warning("shutdown_signal", signal=signal.Signals(signum).name)
            task.cancel()
        else:  # asked twice: stop the robot without the loop and interrupt now
            zero_live_runtimes(f"second signal {signal.Signals(signum).name}")
            raise ShutdownSignal(signum)

    if signals and threading.current_thread() is threading.main_thread():
        for signum in SHUTDOWN_SIGNALS:
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                loop.add_signal_handler(signum, on_signal, signum)
                installed.append(signum)
    try:
        try:
            return loop.run_until_complete(task)
        except asyncio.CancelledError:
            if received:
                raise ShutdownSignal(received[0]) from None
            raise
    finally:
        try:
            _finish(loop, timeout)
        finally:
            zero_live_runtimes("event loop ended with the runtime running")
            for signum in installed:
                with contextlib.suppress(Exception):
                    loop.remove_signal_handler(signum)
            asyncio.set_event_loop(None)
            loop.close()
