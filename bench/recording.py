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
prints the tick lateness p99 of each, to show recording does not delay ticks.

Run: python bench/recording.py [--duration 40] [--rounds 3] [--realtime-seconds 15]
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
            "lateness_p99_us": data.get("lateness_p99_ms", 0.0) * 1e3, "sim_time": data.get("sim_time", 0.0)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=40.0, help="robot seconds per run (virtual time)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--configs", default="baseline,record,foxglove,both")
    ap.add_argument("--realtime-seconds", type=float, default=15.0, help="0: skip the real-time part")
    args = ap.parse_args()
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
            print(f"{name:<10} p99 {row['lateness_p99_us']:8.1f}  CPU {row['cpu']:.2f} s  dropped {row['dropped']}")


if __name__ == "__main__":
    main()
