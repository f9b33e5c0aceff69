"""``scenarios --record DIR --record-failures``: a bag per failed run, named by scenario, mode
and seed, holding the injected fault; the passing run's bag is gone."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.paths import ROOT

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader


def test_only_the_failed_run_keeps_its_bag(tmp_path):
    out = tmp_path / "bags"
    result = subprocess.run(
        [sys.executable, "-m", "bt_runtime", "scenarios", "--only", "Lidar_1", "--runs", "1", "--jobs", "1",
         "--record", str(out), "--record-failures"],
        cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert result.returncode in (0, 1), result.stderr
    bags = sorted(p.name for p in out.iterdir())
    # the baseline (navigation alone) fails Lidar_1, the autonomy layer passes it (Table IV)
    assert len(bags) == 1 and bags[0].startswith("Lidar_1_without_seed"), bags
    assert f"recording: 1 bag in {out} (failed runs only)" in result.stdout, result.stdout[-500:]
    with AnyReader([out / bags[0]]) as reader:
        topics = {c.topic for c in reader.connections}
        faults = [c for c in reader.connections if c.topic == "/sim/faults"]
        texts = [reader.deserialize(raw, c.msgtype).msg for c, _t, raw in reader.messages(faults)]
    assert {"/scan", "/cmd_vel", "/sim/ground_truth", "/map"} <= topics
    assert any('"fault": "crash"' in t and '"component": "lidar"' in t for t in texts), texts


def test_scenarios_refuses_record_failures_without_a_folder():
    result = subprocess.run([sys.executable, "-m", "bt_runtime", "scenarios", "--record-failures"],
                            cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "--record-failures needs --record" in result.stderr
