"""A campaign killed midway (SIGKILL, pool workers included) and resumed from its results file
ends with the same runs and counts as one that was never interrupted, each run counted once."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

from bt_runtime.__main__ import main
from sim.scenarios.backends import LocalBackend
from sim.scenarios.campaign import run_campaign
from tests.paths import ROOT

from .campaign_support import CHEAP, by_key, cheap_plan

RUNS, SEED = 4, 5
ARGS = ["scenarios", "--only", ",".join(CHEAP), "--mode", "without", "--runs", str(RUNS), "--seed", str(SEED),
        "--jobs", "2"]


def _run_lines(path) -> list[dict]:
    if not path.exists():
        return []
    lines = path.read_text(encoding="utf-8").split("\n")[:-1]
    return [json.loads(raw) for raw in lines if '"type":"run"' in raw]


def test_a_killed_campaign_resumes_to_the_same_counts(tmp_path):
    results = tmp_path / "runs.jsonl"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "bt_runtime", *ARGS, "--results", str(results)], cwd=ROOT,
                            env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while len(_run_lines(results)) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)  # the campaign and its pool workers, mid-run
    proc.wait()
    before = _run_lines(results)
    planned = len(CHEAP) * RUNS
    assert 2 <= len(before) < planned, "the campaign was not killed midway"
    with results.open("a", encoding="utf-8") as f:
        f.write('{"type":"run","key":"Lidar_1/with')  # and a line cut off by the kill

    out = tmp_path / "resumed.json"
    assert main([*ARGS, "--resume", str(results), "--json", str(out)]) == 0
    after = _run_lines(results)
    assert [r["key"] for r in after[:len(before)]] == [r["key"] for r in before]  # kept, not run again
    assert sorted(r["key"] for r in after) == sorted(r.key for r in cheap_plan(RUNS, SEED))  # each once
    resumed = json.loads(out.read_text())
    assert resumed["meta"]["resumed_runs"] == len(before)

    whole = run_campaign(cheap_plan(RUNS, SEED), LocalBackend(jobs=2))
    assert by_key(after) == by_key(whole.results)
    for name in CHEAP:
        mode = resumed["scenarios"][name]["without"]
        assert mode["runs"] == RUNS
        assert mode["success_rate"] == whole.success_rate(name, "without")
        assert mode["failure_reasons"] == whole.to_dict()["scenarios"][name]["without"]["failure_reasons"]
