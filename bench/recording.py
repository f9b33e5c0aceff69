"""What recording and the live view cost a run: CPU and wall time with and without them.

Each configuration is a whole ``python -m bt_runtime run trees/autonomy.xml --goal yard_east``
process (the simulator on virtual time, --duration robot seconds), so the CPU figure is the
run's CPU as a user pays it: start-up, the tick, the simulator, and for recording the imports,
the writer thread and the file writes. Configurations are interleaved (--rounds) so machine
drift affects them alike:

  baseline     no recording
  record       --record DIR (rosbag2 bag, MCAP segments)
  foxglove     --foxglove 0 (live server, no client connected)
  both         --record DIR --foxglove 0

Prints per configuration the median CPU (user+sys of the process) and wall time over rounds,
the CPU ratio to the baseline of the same round (median, min-max), the writer thread's own CPU,
the messages written and dropped. A second part runs --realtime pairs (baseline, record) and
prints the tick lateness p50/p99 of each, to show recording does not delay ticks. A third part
(--inprocess) measures the run phase alone, in one process: CPU (all threads) from
``runtime.start()`` to the bag closed, baseline and record interleaved, so start-up (imports)
is left out: the steady-state cost per robot second.

Run: python bench/recording.py [--duration 40] [--rounds 3] [--realtime-seconds 15] [--inprocess]
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if sys.path and Path(sys.path[0]).resolve() == ROOT / "bench":  # bench/sim.py would shadow the sim package
    sys.path[0] = str(ROOT)
CONFIGS = {"baseline": [], "record": ["--record", "{dir}/bag"], "foxglove": ["--foxglove", "0"],
           "both": ["--record", "{dir}/bag", "--foxglove", "0"]}


def run_once(extra: list[str], duration: float, realtime: bool = False) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        summary = Path(tmp) / "summary.json"
        args = [sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--goal", "yard_east",
                "--duration", str(duration), "--no-progress", "--summary-json", str(summary),
                *[a.format(dir=tmp) for a in extra]]
        if realtime:
            args.append("--realtime")
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(args, cwd=ROOT, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        data = json.loads(summary.read_text())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rec = data.get("recording") or {}
    return {"cpu": cpu, "wall": wall, "writer_cpu": rec.get("writer_cpu_s", 0.0),
            "messages": rec.get("message_count", 0), "dropped": sum((rec.get("dropped") or {}).values()),
            "lateness_p99_us": data.get("lateness_p99_ms", 0.0) * 1e3,
            "lateness_p50_us": data.get("lateness_p50_ms", 0.0) * 1e3, "sim_time": data.get("sim_time", 0.0)}


def inprocess(duration: float, rounds: int) -> None:
    import asyncio
    import shutil

    from bt_runtime.cli.registration import registrations
    from bt_runtime.logging_setup import quiet_logging
    from bt_runtime.runtime.app import AutonomyRuntime
    from bt_runtime.runtime.clock import run as run_loop
    from bt_runtime.runtime.messages import Pose2D
    from bt_runtime.runtime.recording.cli import Recording
    from sim.driver import SimDriver
    from sim.recording import recording_hooks

    quiet_logging("error")
    regs = registrations(argparse.Namespace(register=[], no_nodes=False))

    async def one(record: bool, folder: Path) -> tuple[float, int]:
        driver = SimDriver("apartment", "burger", seed=0)
        rt = AutonomyRuntime(driver, register=regs)
        rt.load_tree(ROOT / "trees" / "autonomy.xml")
        g = driver.sim.world.goal("yard_east")
        bb = rt.tree.root_blackboard
        bb.set("goal", Pose2D(g.x, g.y, 0.0))
        bb.set("goal_status", "PENDING")
        rec = Recording(bag=folder) if record else None
        c0 = time.process_time()
        if rec is not None:
            rec.start(rt, recording_hooks(driver))
        await rt.start()
        await asyncio.sleep(duration)
        await rt.stop()
        report = rec.stop() if rec is not None else {}
        return time.process_time() - c0, report.get("message_count", 0)

    rows: dict[str, list[float]] = {"baseline": [], "record": []}
    n = 0
    with tempfile.TemporaryDirectory() as tmp:
        run_loop(one(True, Path(tmp) / "warm"), virtual=True)  # imports and serializer code generation
        for r in range(rounds):
            for name in rows:
                folder = Path(tmp) / f"{name}{r}"
                cpu, msgs = run_loop(one(name == "record", folder), virtual=True)
                rows[name].append(cpu)
                n = max(n, msgs)
                shutil.rmtree(folder, ignore_errors=True)
    base, rec = statistics.median(rows["baseline"]), statistics.median(rows["record"])
    ratios = [b2 / b1 - 1 for b1, b2 in zip(rows["baseline"], rows["record"])]
    print(f"\nrun phase only (in process, {duration:g} s robot time, {rounds} rounds): CPU baseline {base:.3f} s, "
          f"record {rec:.3f} s: {statistics.median(ratios):+.1%} ({min(ratios):+.1%}..{max(ratios):+.1%}); "
          f"{n} messages, {(rec - base) / max(n, 1) * 1e6:.0f} us CPU a message; "
          f"{base / duration * 1e3:.1f} vs {rec / duration * 1e3:.1f} ms CPU per robot second")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=40.0, help="robot seconds per run (virtual time)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--configs", default="baseline,record,foxglove,both")
    ap.add_argument("--realtime-seconds", type=float, default=15.0, help="0: skip the real-time part")
    ap.add_argument("--inprocess", action="store_true", help="also measure the run phase alone, in process")
    ap.add_argument("--skip-processes", action="store_true", help="only the in-process part")
    args = ap.parse_args()
    if args.inprocess:
        inprocess(args.duration, args.rounds)
    if args.skip_processes:
        return
    names = [n for n in args.configs.split(",") if n]
    results: dict[str, list[dict]] = {n: [] for n in names}
    for r in range(args.rounds):
        for name in names:
            results[name].append(run_once(CONFIGS[name], args.duration))
        print(f"round {r + 1}/{args.rounds}: " + "  ".join(
            f"{n} {results[n][-1]['cpu']:.2f}s" for n in names), file=sys.stderr, flush=True)
    print(f"\nrun: trees/autonomy.xml to yard_east, {args.duration:g} s robot time (virtual), "
          f"{args.rounds} interleaved rounds; medians")
    print(f"{'config':<10} {'CPU s':>7} {'wall s':>7} {'CPU vs base':>22} {'writer CPU s':>13} "
          f"{'messages':>9} {'dropped':>8}")
    base = results.get("baseline")
    for name in names:
        rows = results[name]
        cpu = statistics.median(x["cpu"] for x in rows)
        wall = statistics.median(x["wall"] for x in rows)
        if base and name != "baseline":
            ratios = [x["cpu"] / b["cpu"] - 1 for x, b in zip(rows, base)]
            rel = f"{statistics.median(ratios):+.1%} ({min(ratios):+.1%}..{max(ratios):+.1%})"
        else:
            rel = "-"
        print(f"{name:<10} {cpu:7.2f} {wall:7.2f} {rel:>22} {statistics.median(x['writer_cpu'] for x in rows):13.3f} "
              f"{statistics.median(x['messages'] for x in rows):9.0f} {max(x['dropped'] for x in rows):8d}")
    if args.realtime_seconds > 0:
        print(f"\nreal time, {args.realtime_seconds:g} s: tick lateness p99 (us)")
        for name in ("baseline", "record"):
            row = run_once(CONFIGS[name], args.realtime_seconds, realtime=True)
            print(f"{name:<10} p50 {row['lateness_p50_us']:8.1f}  p99 {row['lateness_p99_us']:8.1f}  "
                  f"CPU {row['cpu']:.2f} s  dropped {row['dropped']}")


if __name__ == "__main__":
    main()
