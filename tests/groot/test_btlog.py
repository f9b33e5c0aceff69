"""groot.btlog: the FileLogger2 layout, btlog_check --strict, BT.CPP's own transition sequence,
crash safety (a SIGKILLed writer leaves a valid file), clocks."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bt_runtime import NodeStatus
from bt_runtime.xml.writer import write_tree_to_xml
from groot import BTLogger
from groot.btlog import read_btlog
from groot.testing import DEMO_XML as XML
from groot.testing import demo_tree as our_tree
from groot.testing import groot2_tools
from tests.paths import ROOT

TOOLS = groot2_tools()
needs_tools = pytest.mark.skipif(TOOLS is None, reason="shared/tools/groot2 (checkers) is absent")


def btlog_check(path: Path, *extra: str) -> dict:
    proc = subprocess.run([sys.executable, str(TOOLS / "btlog_check.py"), str(path), "--strict", *extra],
                          capture_output=True, text=True, timeout=60)
    report = json.loads(proc.stdout)
    assert proc.returncode == (0 if report["passed"] else 1)
    return report


def test_layout_and_contents(tmp_path: Path) -> None:
    tree = our_tree()
    before = time.time_ns() // 1000
    with BTLogger(tree, tmp_path / "run.btlog") as logger:
        for _ in range(10):
            tree.tick_once()
    data = (tmp_path / "run.btlog").read_bytes()
    xml = write_tree_to_xml(tree)
    assert data[:19] == b"BTCPP4-FileLogger2\x01"
    assert int.from_bytes(data[19:23], "little") == len(xml.encode())
    assert data[23:23 + len(xml.encode())].decode() == xml
    got_xml, t0, records = read_btlog(tmp_path / "run.btlog")
    assert got_xml == xml and before <= t0 <= time.time_ns() // 1000
    assert len(records) == logger.records_written > 50 and (len(data) - 31 - len(xml)) == 9 * len(records)
    assert records[0][1:] == (1, NodeStatus.RUNNING)
    assert [r[0] for r in records] == sorted(r[0] for r in records)
    with pytest.raises(ValueError, match=r"\.btlog"):
        BTLogger(tree, tmp_path / "run.log")


@needs_tools
def test_btlog_check_strict(tmp_path: Path) -> None:
    tree = our_tree()
    with BTLogger(tree, tmp_path / "run.btlog"):
        for _ in range(20):
            tree.tick_once()
    report = btlog_check(tmp_path / "run.btlog", "--expect-nodes", str(sum(len(r.nodes) for r in tree.subtrees)))
    assert report["passed"], (report["required_failed"], report["advisory_failed"])


@pytest.mark.oracle
def test_same_transitions_as_btcpp_filelogger2(tmp_path: Path) -> None:
    bt = pytest.importorskip("behaviortreepy")
    from tests.groot.reference import reference_tree

    ref_tree, _ = reference_tree()
    ref_logger = bt.FileLogger(ref_tree, str(tmp_path / "ref.btlog"))
    ours = our_tree()
    logger = BTLogger(ours, tmp_path / "ours.btlog")
    for _ in range(14):
        assert ref_tree.tick_once().name == ours.tick_once().name
    ref_tree.halt_tree()
    ours.halt_tree()
    ref_logger.flush()
    del ref_logger
    logger.close()
    ref_xml, _, ref_records = read_btlog(tmp_path / "ref.btlog")
    our_xml, _, our_records = read_btlog(tmp_path / "ours.btlog")
    assert [r[1:] for r in our_records] == [r[1:] for r in ref_records]
    assert ref_xml.split("<TreeNodesModel>")[0].count("\n") == our_xml.split("<TreeNodesModel>")[0].count("\n")
    assert XML  # the same tree document for both


WRITER = """
import sys, time
sys.path.insert(0, {root!r})
from groot.testing import demo_tree as our_tree
from groot import BTLogger
tree = our_tree()
logger = BTLogger(tree, sys.argv[1], flush_interval=0.05)
print("ready", flush=True)
while True:
    tree.tick_once()
    time.sleep(0.001)
"""


@needs_tools
def test_killed_writer_leaves_a_valid_file(tmp_path: Path) -> None:
    path = tmp_path / "killed.btlog"
    proc = subprocess.Popen([sys.executable, "-c", WRITER.format(root=str(ROOT)), str(path)],
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        deadline = time.monotonic() + 10
        while path.stat().st_size < 31 + 9 * 2000 + 12000 and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL
    # Linux checks for a fatal signal between the pages of a write(): a SIGKILL that lands while
    # a flush is being written can cut it at a page boundary, leaving part of one record at the
    # end (nothing user space can prevent). Every whole record must pass --strict, and a cut
    # record is the only thing allowed to fail.
    report = btlog_check(path, "--allow-truncated")
    assert not report["required_failed"], report["required_failed"]
    assert set(report["advisory_failed"]) <= {"records_are_whole_9_byte_units"}, report["advisory_failed"]
    assert report["summary"]["transitions"]["count"] >= 2000


async def test_virtual_and_swapped_clocks(tmp_path: Path) -> None:
    """Offsets follow the tree's clock; a clock swapped after the logger started re-anchors."""
    tree = our_tree()
    fake = {"t": 1000.0}
    tree.set_clock(lambda: fake["t"])
    logger = BTLogger(tree, tmp_path / "v.btlog", flush_records=10**9)
    tree.tick_once()
    fake["t"] += 2.5  # 2.5 s of simulated time pass instantly
    tree.tick_once()
    logger.flush()
    tree.set_clock(asyncio.get_running_loop().time)
    tree.tick_once()
    logger.close()
    _, _, records = read_btlog(tmp_path / "v.btlog")
    stamps = [r[0] for r in records]
    assert stamps[0] == 0 and 2_500_000 in stamps
    assert stamps == sorted(stamps)  # never decreasing, whatever the clock did
    assert os.path.getsize(tmp_path / "v.btlog") > 0
