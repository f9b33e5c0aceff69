"""Wiring Groot2 monitoring and recording into a command line (``python -m bt_runtime run``).

    from groot.cli import add_arguments, Monitoring
    add_arguments(run_parser)                 # --groot [PORT], --groot-host, --groot-status, --btlog
    ...
    tree.set_clock(loop.time)                 # first, so recorded times use the loop's clock
    monitoring = Monitoring.from_args(tree, args)
    await monitoring.start()                  # binds the server, opens the .btlog
    ...                                       # tick as usual: nothing to call per tick
    await monitoring.stop()                   # releases hooks, closes sockets, drains the log

Nothing here is needed per tick: the server answers requests from its own task on the same
loop, and the logger records through a status observer.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .server import DEFAULT_PORT

if TYPE_CHECKING:
    from bt_runtime.tree import Tree

    from .btlog import BTLogger
    from .server import GrootServer


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("Groot2")
    group.add_argument("--groot", nargs="?", type=int, const=DEFAULT_PORT, default=None, metavar="PORT",
                       help=f"serve the tree to Groot2 on PORT (default {DEFAULT_PORT}) and PORT+1")
    group.add_argument("--groot-host", default="127.0.0.1", metavar="HOST",
                       help="address to bind the Groot2 server to (default 127.0.0.1; 0.0.0.0 for all)")
    group.add_argument("--groot-status", choices=("sampled", "exact"), default="sampled",
                       help="STATUS bookkeeping: sampled (near-free, default) or exact (BT.CPP-identical, "
                            "a callback per status change)")
    group.add_argument("--btlog", default=None, metavar="FILE.btlog",
                       help="record every status change to a .btlog file Groot2 can replay")


class MonitoringError(ValueError):
    """A bad --btlog path or a Groot2 port that cannot be bound (reported without a traceback)."""


def check_btlog_path(path: str) -> None:
    target = Path(path)
    if target.suffix != ".btlog":
        raise MonitoringError(f"--btlog {path}: the file name must end in .btlog (Groot2 replays only those)")
    if not target.parent.is_dir():
        raise MonitoringError(f"--btlog {path}: folder {target.parent} does not exist")
    if target.exists() and not target.is_file():
        raise MonitoringError(f"--btlog {path}: exists and is not a regular file")


@dataclass
class Monitoring:
    """The Groot2 server and/or .btlog logger of one tree."""

    tree: Tree
    port: int | None = None
    host: str = "127.0.0.1"
    status_mode: str = "sampled"
    btlog: str | None = None
    server: GrootServer | None = None
    logger: BTLogger | None = None

    @classmethod
    def from_args(cls, tree: Tree, args: Any) -> Monitoring:
        return cls(tree, port=getattr(args, "groot", None), host=getattr(args, "groot_host", "127.0.0.1"),
                   status_mode=getattr(args, "groot_status", "sampled"), btlog=getattr(args, "btlog", None))

    async def start(self) -> Monitoring:
        from .btlog import BTLogger
        from .server import GrootServer

        if self.btlog and self.logger is None:
            check_btlog_path(self.btlog)
            try:
                self.logger = BTLogger(self.tree, self.btlog)
            except OSError as exc:
                raise MonitoringError(f"--btlog {self.btlog}: {exc.strerror or exc}") from None
        if self.port is not None and self.server is None:
            self.server = GrootServer(self.tree, port=self.port, host=self.host, status_mode=self.status_mode)
            try:
                await self.server.start()
            except BaseException as exc:
                self.server = None
                await self.stop()
                if isinstance(exc, OSError):  # a port in use (or a host we cannot bind)
                    raise MonitoringError(f"--groot {self.port}: {exc} (is another run or Groot2 "
                                          "server using it? pick another port)") from None
                raise
        return self

    async def stop(self) -> None:
        if self.server is not None:
            await self.server.stop()
            self.server = None
        if self.logger is not None:
            self.logger.close()
            self.logger = None

    async def __aenter__(self) -> Monitoring:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()
