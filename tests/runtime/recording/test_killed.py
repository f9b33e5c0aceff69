"""A recording killed with SIGKILL is a readable bag up to its last flush (segment close)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
import yaml

from tests.paths import ROOT

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader
make_reader = pytest.importorskip("mcap.reader").make_reader


def _listed(bag) -> list[str]:
    try:
        info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    except (FileNotFoundError, yaml.YAMLError, TypeError):
        return []
    return info["relative_file_paths"]


def test_sigkilled_run_leaves_a_readable_bag(tmp_path):
    bag = tmp_path / "killed"
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--goal", "yard_east", "--realtime",
         "--duration", "120", "--record", str(bag), "--record-flush", "0.3", "--no-progress"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while len(_listed(bag)) < 3 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.1)
        assert len(_listed(bag)) >= 3, "three segments closed while the run was going"
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    listed = _listed(bag)
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    with AnyReader([bag]) as reader:
        topics = {c.topic for c in reader.connections}
        n = sum(1 for _ in reader.messages())
    assert n == info["message_count"] > 0
    assert {"/scan", "/odom", "/cmd_vel", "/tf"} <= topics
    decoded = 0
    for name in listed:
        with open(bag / name, "rb") as f:
            decoded += sum(1 for _ in make_reader(f).iter_messages())
    assert decoded == n
