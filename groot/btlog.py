"""Record a run as a ``.btlog`` file, BT.CPP's ``FileLogger2`` format, which Groot2 replays.

    logger = BTLogger(tree, "run.btlog")   # header + FULLTREE XML + start time written now
    ...                                    # every status change is recorded
    logger.close()                         # drains and closes (also: ``with BTLogger(...)``)

Layout (little-endian): ``"BTCPP4-FileLogger2"``, a version byte (1), ``i32`` XML length, the
FULLTREE XML (``write_tree_to_xml``), ``i64`` start time in microseconds since the epoch, then
9-byte records: ``u48`` microseconds since the start time, ``u16`` node uid, ``u8`` new status
(0-4, transitions to IDLE included).

**Crash safety.** Records are buffered in memory and written in whole records, at the latest
every ``flush_interval`` seconds (tree clock) or every ``flush_records`` records, with one
``os.write`` per flush, and every ``flush_interval`` of wall time by a background task when an
event loop is running. If the process is killed, the file is valid up to the last flush (the
kernel keeps what was written). ``fsync=True`` also survives a power loss, at a cost.

**Time.** The start time is the wall clock (epoch) when the logger is created. Transition
offsets are measured on the **tree's clock** from that moment: in real time they are wall-clock
offsets; in simulation on a virtual-time loop they are simulated seconds, so a replay in
Groot2 plays simulated time (``start + clock offset``). Offsets never decrease (a clock swap,
e.g. ``tree.set_clock(loop.time)`` after the logger was created, re-anchors the offsets).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import struct
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_runtime.xml.writer import write_tree_to_xml

if TYPE_CHECKING:
    from bt_runtime.node import TreeNode
    from bt_runtime.status import NodeStatus
    from bt_runtime.tree import Tree

MAGIC = b"BTCPP4-FileLogger2"
VERSION = 1
_U48 = (1 << 48) - 1


class BTLogger:
    """FileLogger2-compatible recorder. Create it after the tree, close it at shutdown."""

    def __init__(self, tree: Tree, path: str | Path, *, flush_interval: float = 0.5,
                 flush_records: int = 4096, fsync: bool = False):
        path = Path(path)
        if path.suffix != ".btlog":
            raise ValueError("BTLogger: the file extension must be [.btlog]")
        self.tree = tree
        self.path = path
        self.flush_interval = flush_interval
        self.flush_records = flush_records
        self.fsync = fsync
        self.records_written = 0
        self._pending: list[tuple[float, int, int]] = []
        self._fd: int | None = None
        self._task: asyncio.Task | None = None
        xml = write_tree_to_xml(tree).encode("utf-8")
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            self._write_all(fd, MAGIC + bytes((VERSION,)) + struct.pack("<i", len(xml)) + xml)
            # BT.CPP takes the start time after the XML is written.
            self.start_usec = time.time_ns() // 1000
            self._clock = tree.clock
            self._clock0 = self._clock()
            self._wall0 = time.monotonic()
            self._write_all(fd, struct.pack("<q", self.start_usec))
            if fsync:
                os.fsync(fd)
        except BaseException:
            os.close(fd)
            raise
        self._fd = fd
        self._last_usec = 0
        self._next_flush = self._clock0 + flush_interval
        self._remove = tree.add_status_observer(self._on_change)
        with contextlib.suppress(RuntimeError):
            loop = asyncio.get_running_loop()
            self._task = loop.create_task(self._periodic_flush(), name="btlog:flush")

    # -- recording -------------------------------------------------------------------------------
    def _on_change(self, stamp: float, node: TreeNode, prev: NodeStatus, new: NodeStatus) -> None:
        pending = self._pending
        pending.append((stamp, node.config.uid, new))
        if len(pending) >= self.flush_records or stamp >= self._next_flush:
            self.flush()

    async def _periodic_flush(self) -> None:
        while True:
            await asyncio.sleep(self.flush_interval)
            self.flush()

    def flush(self) -> None:
        """Write every pending record (whole records, one write) and hand them to the kernel."""
        fd = self._fd
        if fd is None:
            return
        self._reanchor_if_clock_changed()
        self._next_flush = self._clock() + self.flush_interval
        pending = self._pending
        if not pending:
            return
        self._pending = []
        clock0 = self._clock0
        last = self._last_usec
        out = bytearray()
        for stamp, uid, status in pending:
            usec = int((stamp - clock0) * 1e6)
            if usec < last:
                usec = last
            last = usec
            out += (usec & _U48).to_bytes(6, "little")
            out += uid.to_bytes(2, "little")
            out.append(status)
        self._last_usec = last
        self._write_all(fd, bytes(out))
        if self.fsync:
            os.fsync(fd)
        self.records_written += len(pending)

    def _reanchor_if_clock_changed(self) -> None:
        clock = self.tree.clock
        if clock is not self._clock:
            # The tree now stamps with another clock: anchor it so that "now" keeps the offset
            # elapsed on the wall clock since the logger started.
            self._clock = clock
            self._clock0 = clock() - (time.monotonic() - self._wall0)

    @staticmethod
    def _write_all(fd: int, data: bytes) -> None:
        view = memoryview(data)
        while view:
            n = os.write(fd, view)
            view = view[n:]

    # -- shutdown --------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop recording, write what is pending (BT.CPP #1198: drain), close the file."""
        if self._remove is not None:
            self._remove()
            self._remove = None
        if self._task is not None:
            self._task.cancel()
            self._task = None
        if self._fd is not None:
            try:
                self.flush()
                if self.fsync:
                    os.fsync(self._fd)
            finally:
                os.close(self._fd)
                self._fd = None

    def __enter__(self) -> BTLogger:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()


def read_btlog(path: str | Path) -> tuple[str, int, list[tuple[int, int, int]]]:
    """(XML, start epoch µs, [(µs offset, uid, status)]) of a .btlog; a partial record at the
    end is ignored."""
    data = Path(path).read_bytes()
    if data[:len(MAGIC)] != MAGIC:
        raise ValueError("not a BTCPP4-FileLogger2 file")
    (xml_len,) = struct.unpack_from("<i", data, len(MAGIC) + 1)
    start = len(MAGIC) + 5
    xml = data[start:start + xml_len].decode("utf-8")
    (t0,) = struct.unpack_from("<q", data, start + xml_len)
    body = data[start + xml_len + 8:]
    from .protocol import unpack_transitions

    return xml, t0, unpack_transitions(body)
