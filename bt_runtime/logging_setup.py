"""structlog configuration for every log line: key-value events, JSON when not on a terminal.

Processes call ``configure_logging`` once at start-up (the CLI does). Library code only calls
``structlog.get_logger(name)`` and logs events with keys; simulation-time keys (``sim_time``)
are added by the components themselves, so lines from different parts line up in time. They
read the runtime's loop clock; where the driver knows the robot's own clock (ROS time on a ROS 2
robot), ``use_robot_time`` makes every ``sim_time`` the robot's time, so log lines line up with
the robot's logs and bags.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from pathlib import Path
from typing import IO

import structlog

_LEVELS = {"debug": logging.DEBUG, "info": logging.INFO, "warning": logging.WARNING,
           "error": logging.ERROR, "critical": logging.CRITICAL}


_robot_time: Callable[[float], float | None] | None = None


def use_robot_time(translate: Callable[[float], float | None] | None) -> None:
    """Log ``sim_time`` values (loop-clock times) as ``translate(t)``; None switches it off."""
    global _robot_time
    _robot_time = translate


def _sim_time_as_robot_time(_logger: object, _method: str, event: dict) -> dict:
    translate = _robot_time
    if translate is not None:
        t = event.get("sim_time")
        if isinstance(t, float | int):
            robot = translate(t)
            if robot is not None:
                event["sim_time"] = round(robot, 3)
    return event


class _SafeStream:
    """A log stream that never raises: a closed pipe (``| head``) turns it into a no-op, so
    logging inside simulation callbacks can never crash the event loop."""

    def __init__(self, stream: IO[str]):
        self._stream = stream
        self._broken = False

    def write(self, text: str) -> int:
        if self._broken:
            return len(text)
        try:
            return self._stream.write(text)
        except (BrokenPipeError, ValueError, OSError):
            self._broken = True
            return len(text)

    def flush(self) -> None:
        if not self._broken:
            try:
                self._stream.flush()
            except (BrokenPipeError, ValueError, OSError):
                self._broken = True

    def isatty(self) -> bool:
        return hasattr(self._stream, "isatty") and self._stream.isatty()


def configure_logging(*, json: bool | None = None, file: str | Path | None = None, level: str = "info",
                      stream: IO[str] | None = None) -> IO[str] | None:
    """Send events to ``file`` (JSON lines) or ``stream`` (default stderr).

    ``json=None`` means JSON unless the stream is a terminal. Returns the opened file, if any,
    so the caller can close it.
    """
    opened: IO[str] | None = None
    if file is not None:
        opened = open(file, "a", encoding="utf-8")  # noqa: SIM115 - closed by the caller
        out = opened
        json = True if json is None else json
    else:
        out = stream or sys.stderr
        if json is None:
            json = not (hasattr(out, "isatty") and out.isatty())
    renderer = structlog.processors.JSONRenderer() if json else structlog.dev.ConsoleRenderer(colors=False)
    structlog.configure(
        processors=[_sim_time_as_robot_time,
                    structlog.processors.add_log_level,
                    structlog.processors.TimeStamper(fmt="iso", utc=True),
                    structlog.processors.format_exc_info,
                    renderer],
        wrapper_class=structlog.make_filtering_bound_logger(_LEVELS.get(level, logging.INFO)),
        logger_factory=structlog.PrintLoggerFactory(file=_SafeStream(out)),
        cache_logger_on_first_use=False,
    )
    return opened


def quiet_logging(level: str = "warning") -> None:
    """Only warnings and errors, on stderr (the default for tests and benchmarks)."""
    configure_logging(level=level, stream=sys.stderr, json=False)
