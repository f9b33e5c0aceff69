"""The Ray backend: every run a Ray task on a local Ray with 2 CPUs. Same seeds and verdicts as
the local backend, run by run; a worker that dies is retried and its run counted once; and the
local Ray leaves no process behind."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

from sim.scenarios.backends import LocalBackend
from sim.scenarios.campaign import run_campaign
from sim.scenarios.runspec import plan_runs
from sim.scenarios.spec import load_scenario

from .campaign_support import by_key, cheap_plan

pytest.importorskip("ray")


def _processes() -> dict[int, tuple[int, str]]:
    """Every live process: pid -> (parent pid, state)."""
    out = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[int(stat.parent.name)] = (int(fields[1]), fields[0])
    return out


def _descendants(pid: int) -> set[int]:
    procs = _processes()
    children: dict[int, list[int]] = {}
    for child, (parent, _) in procs.items():
        children.setdefault(parent, []).append(child)
    out, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.add(child)
            todo.append(child)
    return out


def _alive(pids: set[int]) -> set[int]:
    """Those still running, wherever they were re-parented (zombies count as gone)."""
    procs = _processes()
    return {p for p in pids if p in procs and procs[p][1] != "Z"}


def _is_ray(pid: int) -> bool:
    try:
        return b"ray" in (Path("/proc") / str(pid) / "cmdline").read_bytes()
    except OSError:
        return False


@pytest.fixture(scope="module")
def ray_backend():
    from sim.scenarios.ray_backend import RayBackend

    backend = RayBackend(num_cpus=2)
    yield backend
    started = {p for p in _descendants(os.getpid()) if _is_ray(p)}  # Ray's daemons and its workers
    assert len(started) >= 3, "a local Ray runs in processes of its own (GCS, raylet, workers)"
    backend.close()
    deadline = time.monotonic() + 15
    while (left := _alive(started)) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not left, f"Ray processes left after shutdown: {sorted(left)}"


def test_ray_backend_reports_the_local_rays_cpus(ray_backend):
    assert ray_backend.cpus == 2


def test_ray_gives_the_same_runs_as_local(ray_backend):
    report = {"trajectory": {}}  # what --report needs back from every run
    plan = cheap_plan(runs=2, artifacts=report) + plan_runs([load_scenario("Lidar_1")], 1, 5, ("with",),
                                                            artifacts=report)
    local = run_campaign(plan, LocalBackend(jobs=1))
    on_ray = run_campaign(plan, ray_backend)
    assert on_ray.backend == "ray"
    assert [r["key"] for r in on_ray.results] == [r.key for r in plan]  # each once, in plan order
    assert by_key(on_ray.results) == by_key(local.results)
    assert any(r["success"] for r in on_ray.results) and not all(r["success"] for r in on_ray.results)
    assert on_ray.trajectories.keys() == local.trajectories.keys() and len(local.trajectories) == len(plan)
    for key, drawn in local.trajectories.items():
        assert (on_ray.trajectories[key]["trajectory"] == drawn["trajectory"]).all()


def test_a_dying_worker_is_retried_and_its_run_counted_once(ray_backend, tmp_path):
    maker = "tests.scenarios.worker_faults:die_once"
    plan = cheap_plan(runs=1, artifacts={maker: {"marker_dir": str(tmp_path)}})
    result = run_campaign(plan, ray_backend)
    assert [r["key"] for r in result.results] == [r.key for r in plan]
    assert all(r["artifacts"] == {maker: "survived a retry"} for r in result.results)
    assert len(list(tmp_path.iterdir())) == len(plan)  # every run's first worker died


def test_the_cli_runs_a_campaign_on_ray_and_streams_its_results(ray_backend, tmp_path, capsys):
    from bt_runtime.__main__ import main

    results, out = tmp_path / "runs.jsonl", tmp_path / "campaign.json"
    args = ["scenarios", "--backend", "ray", "--only", "Lidar_1", "--mode", "without", "--runs", "2", "--seed", "5"]
    assert main([*args, "--results", str(results), "--json", str(out)]) == 0
    assert "on 2 CPUs" in capsys.readouterr().err  # the progress line names the cluster's CPUs
    keys = [json.loads(line)["key"] for line in results.read_text().splitlines() if '"type":"run"' in line]
    assert sorted(keys) == ["Lidar_1/without/0", "Lidar_1/without/1"]
    meta = json.loads(out.read_text())["meta"]
    assert (meta["backend"], meta["jobs"], meta["runs"]) == ("ray", 2, 2)
