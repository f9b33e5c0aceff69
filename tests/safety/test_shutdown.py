"""Every way a run can end leaves the base at zero, within a bounded time: SIGTERM, SIGINT and
SIGHUP to a driving ``run``, KeyboardInterrupt/SystemExit raised in a node, an exception out
of the program, and an async node that ignores cancellation (abandoned, named in a warning)."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import signal
import subprocess
import sys
import time

import pytest
import structlog

from bt_runtime.node import AsyncActionNode
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import run as run_loop
from bt_runtime.runtime.config import RuntimeConfig
from bt_runtime.status import SUCCESS
from sim.driver import SimDriver
from tests.helpers import tree_xml
from tests.paths import ROOT
from tests.safety.support import BaseRecorder, register_fault_nodes

SHUTDOWN_BOUND = 5.0  # s from the signal to the process exit (runtime.stop itself takes ms; the rest is teardown)


def start_run(tmp_path, body: str, *extra: str) -> tuple[subprocess.Popen, os.PathLike, os.PathLike]:
    tree = tmp_path / "tree.xml"
    tree.write_text(tree_xml(body), encoding="utf-8")
    base_log, log_file = tmp_path / "base.json", tmp_path / "events.jsonl"
    env = dict(os.environ, PYTHONPATH=str(ROOT), SAFETY_BASE_LOG=str(base_log))
    proc = subprocess.Popen([sys.executable, "-m", "bt_runtime", "run", str(tree), "--realtime", "--no-progress",
                             "--register", "tests.safety.recording:register", "--log-file", str(log_file), *extra],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return proc, base_log, log_file


def driving(log_file) -> bool:
    """The gate has switched to the tree's command (the run is past its start-up wait)."""
    if not log_file.exists():
        return False
    for line in log_file.read_text(encoding="utf-8").splitlines():
        with contextlib.suppress(ValueError):
            event = json.loads(line)
            if event.get("event") == "gate_source" and event.get("source") == "tree":
                return True
    return False


def wait_started(proc, log_file, timeout=30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if driving(log_file):
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    proc.kill()
    raise AssertionError("run did not start")


def received(base_log) -> list[tuple[float, float, float]]:
    return [tuple(row) for row in json.loads(base_log.read_text(encoding="utf-8"))]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_signal_to_a_driving_run_ends_at_zero(tmp_path, signum):
    proc, base_log, log_file = start_run(tmp_path, '<Drive linear="0.15"/>')
    try:
        wait_started(proc, log_file)
        time.sleep(0.4)  # ramping up to 0.15 m/s
        sent = time.monotonic()
        proc.send_signal(signum)
        _, stderr = proc.communicate(timeout=SHUTDOWN_BOUND + 5)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
    rows = received(base_log)
    zero_after = next((w for w, v, a in rows if w >= sent and v == 0.0 and a == 0.0), None)
    assert zero_after is not None
    print(f"{signal.Signals(signum).name}: zero {1e3 * (zero_after - sent):.1f} ms after the signal, "
          f"exit {took:.2f} s after it")
    assert took <= SHUTDOWN_BOUND
    assert "Traceback" not in stderr
    assert any(v > 0.1 for _, v, _ in rows), "the robot was driving"
    assert rows[-1][1:] == (0.0, 0.0), "the last command to the base is zero"
    assert max(v for _, v, _ in rows) <= 0.15


@pytest.mark.parametrize("error", ["KeyboardInterrupt", "SystemExit"])
def test_interrupt_raised_in_a_node_ends_at_zero(tmp_path, error):
    proc, base_log, log_file = start_run(tmp_path, f'<RaiseIn after="60" error="{error}"/>')
    try:
        _, stderr = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    rows = received(base_log)
    assert any(v > 0.1 for _, v, _ in rows), "the robot was driving"
    assert rows[-1][1:] == (0.0, 0.0)
    assert "tick_interrupted" in log_file.read_text(encoding="utf-8")


class IgnoresCancel(AsyncActionNode):
    async def run(self):
        while True:
            with contextlib.suppress(asyncio.CancelledError):  # a careless node
                await asyncio.sleep(1.0)
        return SUCCESS


def test_exception_out_of_the_program_and_a_node_ignoring_cancellation_end_at_zero():
    """The program fails while driving with a node that swallows CancelledError: the base
    ends at zero, the node is named in a warning, the exit is bounded."""
    box = {}

    async def main():
        driver = SimDriver("apartment", "burger", seed=0)
        config = RuntimeConfig(shutdown_timeout=0.5)
        rt = AutonomyRuntime(driver, config, register=[register_fault_nodes,
                                                       lambda f: f.register_node_type(IgnoresCancel)])
        rt.load_tree(tree_xml('<Parallel success_count="-1"><Drive linear="0.15"/>'
                              '<IgnoresCancel name="stubborn"/></Parallel>'))
        box["base"] = BaseRecorder(driver.sim)
        await rt.start()
        try:
            await asyncio.sleep(0.5)
            raise RuntimeError("the program failed")
        finally:
            t0 = time.monotonic()
            await rt.stop()
            box["stop_s"] = time.monotonic() - t0

    with structlog.testing.capture_logs() as logs, pytest.raises(RuntimeError, match="program failed"):
        run_loop(main, virtual=False)
    base = box["base"]
    assert any(r.linear > 0.1 for r in base.received) and base.received[-1].is_zero
    abandoned = [e for e in logs if e["event"] == "task_abandoned"]
    assert abandoned and "stubborn" in abandoned[0]["who"]
    print(f"stop with a node ignoring cancellation: {box['stop_s']:.2f} s (timeout 0.5 s)")
    assert box["stop_s"] < 0.5 * 2 + 0.5
