"""Campaign throughput: the local process pool against a local Ray on this machine, in the same
run, interleaved, and the projected time of a 10 000-run campaign on N cores.

    python bench/campaign.py [--runs 1] [--rounds 2] [--cpus 2] [--only A,B] [--json]

Each round runs the same plan (every scenario, both modes, ``--runs`` seeded runs each) on the
pool and then on Ray (the next round in the other order), and reports per backend: runs/min
(wall), CPU seconds per run of the whole process tree (driver, pool or Ray workers, Ray's own
daemons), the overhead (that CPU over the runs' own CPU time), and the efficiency (the
runs' own wall time / (wall x CPUs): how busy the backend keeps its CPUs). Ray's start-up is
timed apart (a campaign pays it once). The projection weights each scenario's CPU time per
run (measured inside the run, so it does not depend on how busy this machine is) by the
paper's number of runs (the mix of --paper-runs), multiplies by the backend's overhead and
spreads it over N dedicated cores at the measured efficiency.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sim.scenarios.backends import LocalBackend  # noqa: E402
from sim.scenarios.campaign import CampaignResult, run_campaign  # noqa: E402
from sim.scenarios.runspec import plan_runs  # noqa: E402
from sim.scenarios.spec import load_scenario, scenario_names  # noqa: E402

TICKS = os.sysconf("SC_CLK_TCK")


def tree_cpu(pid: int | None = None) -> float:
    """CPU seconds of a process and every live descendant (reaped children included)."""
    pid = pid or os.getpid()
    stats: dict[int, tuple[int, list[int]]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        stats[int(stat.parent.name)] = (int(fields[1]), [int(x) for x in fields[11:15]])
    children: dict[int, list[int]] = {}
    for p, (ppid, _) in stats.items():
        children.setdefault(ppid, []).append(p)
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        if p in stats:
            total += sum(stats[p][1])
        todo += children.get(p, [])
    return total / TICKS


def measure(name: str, backend, plan) -> dict:
    cpu0, t0 = tree_cpu(), time.perf_counter()
    result: CampaignResult = run_campaign(plan, backend)
    wall, cpu = time.perf_counter() - t0, tree_cpu() - cpu0
    run_time = sum(r["wall_time"] for r in result.results)
    run_cpu = sum(r["cpu_time"] for r in result.results)
    return {"backend": name, "runs": len(result.results), "wall_s": wall, "runs_per_min": 60 * len(plan) / wall,
            "cpu_s_per_run": cpu / len(plan), "overhead": cpu / run_cpu, "efficiency": run_time / (wall * backend.cpus),
            "cpu_by_scenario": _by_scenario(result)}


def _by_scenario(result: CampaignResult) -> dict[str, float]:
    """Mean CPU seconds of one run (both modes averaged) per scenario, measured inside the run."""
    times: dict[str, list[float]] = {}
    for r in result.results:
        times.setdefault(r["scenario"], []).append(r["cpu_time"])
    return {k: statistics.fmean(v) for k, v in times.items()}


def project(rows: list[dict], names: list[str], cores: list[int], total: int = 10_000) -> dict[str, dict]:
    """Hours for ``total`` runs in the paper's mix on N dedicated cores, per backend: the runs' CPU
    time, times the backend's overhead (its process tree's CPU over the runs' own), spread over
    the cores at the efficiency measured here (independent of how busy this machine was)."""
    weights = {n: load_scenario(n).paper.runs for n in names}
    out: dict[str, dict] = {}
    for backend in ("local", "ray"):
        mine = [r for r in rows if r["backend"] == backend]
        per_scenario = {n: statistics.fmean(r["cpu_by_scenario"][n] for r in mine) for n in names}
        mean_cpu = sum(per_scenario[n] * w for n, w in weights.items()) / sum(weights.values())
        overhead = statistics.fmean(r["overhead"] for r in mine)
        efficiency = statistics.fmean(r["efficiency"] for r in mine)
        core_hours = total * mean_cpu * overhead / 3600
        out[backend] = {"mean_run_cpu_s": mean_cpu, "core_hours": core_hours,
                        "hours": {n: core_hours / (n * efficiency) for n in cores}}
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=1, help="runs per scenario and mode in each campaign")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--cpus", type=int, default=os.cpu_count() or 1, help="pool processes and Ray CPUs")
    parser.add_argument("--only", default=None, help="comma-separated scenarios (default: all 14)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    from bt_runtime.logging_setup import quiet_logging

    quiet_logging("critical")
    names = args.only.split(",") if args.only else scenario_names()
    plan = plan_runs([load_scenario(n) for n in names], args.runs, 0)
    from sim.scenarios.ray_backend import RayBackend

    t0 = time.perf_counter()
    ray = RayBackend(num_cpus=args.cpus)
    ray_start = time.perf_counter() - t0
    pool = LocalBackend(jobs=args.cpus)
    rows = []
    try:
        for i in range(args.rounds):
            order = [("local", pool), ("ray", ray)]
            for name, backend in (order if i % 2 == 0 else order[::-1]):
                rows.append(measure(name, backend, plan))
                print(f"round {i + 1} {name:>5}: {rows[-1]['runs_per_min']:6.1f} runs/min", file=sys.stderr)
    finally:
        ray.close()
    cores = [2, 8, 32, 128]
    projection = project(rows, names, cores)
    if args.json:
        print(json.dumps({"ray_start_s": ray_start, "rows": rows, "projection_h": projection}, indent=1))
        return 0
    print(f"{len(plan)} runs per campaign ({len(names)} scenarios x 2 modes x {args.runs}), {args.cpus} CPUs, "
          f"{args.rounds} rounds interleaved; Ray start-up {ray_start:.1f} s (once per campaign)")
    print(f"{'backend':<8}{'runs/min':>10}{'(range)':>16}{'CPU s/run':>11}{'overhead':>10}{'efficiency':>12}")
    for backend in ("local", "ray"):
        mine = [r for r in rows if r["backend"] == backend]
        rates = [r["runs_per_min"] for r in mine]
        print(f"{backend:<8}{statistics.median(rates):>10.1f}{f'{min(rates):.1f}-{max(rates):.1f}':>16}"
              f"{statistics.median(r['cpu_s_per_run'] for r in mine):>11.2f}"
              f"{statistics.median(r['overhead'] for r in mine):>10.2f}"
              f"{statistics.median(r['efficiency'] for r in mine):>12.2f}")
    print("\n10 000 runs in the paper's mix on N dedicated cores (hours):")
    print(f"{'backend':<8}{'CPU s/run':>10}{'core-h':>8}" + "".join(f"{f'{n} cores':>11}" for n in cores))
    for backend, p in projection.items():
        print(f"{backend:<8}{p['mean_run_cpu_s']:>10.2f}{p['core_hours']:>8.1f}"
              + "".join(f"{p['hours'][n]:>11.2f}" for n in cores))
    return 0


if __name__ == "__main__":
    sys.exit(main())
