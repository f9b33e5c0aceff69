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
the CPU ratio to the baseline of the same round (median, min-max) and the ratio of the minima
(the run is deterministic, so the least CPU a configuration took is its cost with the least
interference from other processes), the writer's own CPU (its thread in real time; on virtual
time, as these runs are, the drains the recorder makes on the loop), the messages written and
dropped, and the load average before and after. A second part runs --realtime pairs (baseline,
record) and prints the tick lateness p50/p99 of each, to show recording does not delay ticks.
A third part (--inprocess) measures the run phase alone, in one process: CPU (all threads)
from the recording's start to its stop, baseline, record, live view without a client and live
view with a client (a Foxglove WebSocket client in another process, subscribed to every
channel before the run starts; it gets the high-rate streams at the viewing rate,
``live_rate_hz``), so start-up (imports) is left out: the steady-state cost per robot second.

Run: python bench/recording.py [--duration 40] [--rounds 3] [--realtime-seconds 15] [--inprocess]
"""

from __future__ import annotations

import argparse
import asyncio
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


def client(url: str) -> None:
    """A Foxglove WebSocket client in its own process: subscribes to every advertised channel,
    prints 'ready', and reads (and drops) messages until the server goes away."""
    import json

    from websockets.sync.client import connect

    with connect(url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"], max_size=None) as ws:
        subscribed = 0
        ready = False
        try:
            while True:
                frame = ws.recv(timeout=None if ready else 5)
                if isinstance(frame, str):
                    msg = json.loads(frame)
                    if msg.get("op") == "advertise":
                        subs = [{"id": subscribed + i + 1, "channelId": ch["id"]} for i, ch in enumerate(msg["channels"])]
                        subscribed += len(subs)
                        ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
        except TimeoutError:
            print(f"ready {subscribed}", flush=True)  # no more advertisements: everything is subscribed
            ready = True
            for _frame in ws:
                pass
        except Exception:
            pass


IN_PROCESS = ("baseline", "record", "foxglove", "foxglove+client")


async def run_phase(config: str, folder: Path, duration: float) -> dict:
    """One run of the autonomy tree to yard_east in this process (virtual or real time: the
    caller's loop); the recording's start to its stop is measured: CPU of all threads, the tick
    lateness, the recording's report."""
    import os

    from bt_runtime.cli.registration import registrations
    from bt_runtime.runtime.app import AutonomyRuntime
    from bt_runtime.runtime.messages import Pose2D
    from bt_runtime.runtime.recording.cli import Recording
    from sim.driver import SimDriver
    from sim.recording import recording_hooks

    regs = registrations(argparse.Namespace(register=[], no_nodes=False))
    driver = SimDriver("apartment", "burger", seed=0)
    rt = AutonomyRuntime(driver, register=regs)
    rt.load_tree(ROOT / "trees" / "autonomy.xml")
    g = driver.sim.world.goal("yard_east")
    bb = rt.tree.root_blackboard
    bb.set("goal", Pose2D(g.x, g.y, 0.0))
    bb.set("goal_status", "PENDING")
    bag_configs = ("record", "record-nice10")
    rec = None if config == "baseline" else Recording(bag=folder) if config in bag_configs else \
        Recording(foxglove_port=0)
    if config == "record-nice10":  # the writer thread at nice +10 (real time), as before
        from bt_runtime.runtime.recording.pipeline import RecordPipeline

        RecordPipeline.writer_nice = 10
    viewer = None
    c0 = time.process_time()
    if rec is not None:
        rec.start(rt, recording_hooks(driver))
    if config == "foxglove+client":
        viewer = subprocess.Popen([sys.executable, __file__, "--client", rec.live.url], stdout=subprocess.PIPE,
                                  text=True)
        if not viewer.stdout.readline().startswith("ready"):
            raise RuntimeError("the Foxglove client did not subscribe")
    await rt.start()
    await asyncio.sleep(duration)
    await rt.stop()
    report = rec.stop() if rec is not None else {}
    if config == "record-nice10":
        RecordPipeline.writer_nice = 0
    cpu = time.process_time() - c0
    if viewer is not None:
        viewer.wait(30)
    stats = rt.tick_loop.stats
    late = stats._window(stats.lateness)
    return {"cpu": cpu, "report": report, "lateness": late.copy(), "load": os.getloadavg()[0]}


def inprocess(duration: float, rounds: int, configs: tuple[str, ...] = IN_PROCESS) -> None:
    """The run phase alone, in this process: CPU of all threads (process_time) from the recording's
    start to its stop, so the interpreter's start-up and imports are left out."""
    import os
    import shutil

    from bt_runtime.logging_setup import quiet_logging
    from bt_runtime.runtime.clock import run as run_loop

    quiet_logging("error")
    rows: dict[str, list[float]] = {name: [] for name in configs}
    messages: dict[str, int] = {}
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        run_loop(run_phase("record", Path(tmp) / "warm", duration), virtual=True)  # imports, serializer code
        for r in range(rounds):
            for name in configs:
                folder = Path(tmp) / f"{name}{r}"
                out = run_loop(run_phase(name, folder, duration), virtual=True)
                rows[name].append(out["cpu"])
                messages[name] = max(messages.get(name, 0), out["report"].get("message_count", 0))
                shutil.rmtree(folder, ignore_errors=True)
    load1 = os.getloadavg()
    print(f"\nrun phase only (in process, {duration:g} s robot time, {rounds} interleaved rounds; load average "
          f"{load0[0]:.1f} -> {load1[0]:.1f}): CPU ms per robot second, min and median over rounds, and the "
          f"per-round ratio to the baseline (median, min..max)")
    base = rows[configs[0]]
    for name in configs:
        values = rows[name]
        ratios = [x / b - 1 for x, b in zip(values, base)]
        rel = (f"min {min(values) / min(base) - 1:+6.1%}  median {statistics.median(ratios):+6.1%} "
               f"({min(ratios):+.1%}..{max(ratios):+.1%})") if name != configs[0] else ""
        print(f"  {name:<16} {min(values) / duration * 1e3:6.2f} / {statistics.median(values) / duration * 1e3:6.2f} "
              f"ms  {rel}  {messages[name]} messages")


def realtime_inprocess(seconds: float, pairs: int, configs: tuple[str, ...] = ("baseline", "record")) -> None:
    """Tick lateness in real time with and without --record, interleaved (the order rotates
    each round): p50, p99 and max of every run, the ticks later than 5 ms, the CPU of the run phase
    (all threads) and the writer's, and the recording's longest segment-close step and drops. ``record-nice10``: --record with the writer thread
    at nice +10 (the loop's priority is the default)."""
    import shutil

    import numpy as np

    from bt_runtime.logging_setup import quiet_logging
    from bt_runtime.runtime.clock import run as run_loop

    quiet_logging("error")
    rows: dict[str, list[dict]] = {name: [] for name in configs}
    with tempfile.TemporaryDirectory() as tmp:
        run_loop(run_phase("record", Path(tmp) / "warm", 1.0), virtual=True)
        for r in range(pairs):
            k = r % len(configs)
            for name in configs[k:] + configs[:k]:
                folder = Path(tmp) / f"{name}{r}"
                out = run_loop(run_phase(name, folder, seconds), virtual=False)
                late = out["lateness"] * 1e3
                rep = out["report"]
                row = {"p50": float(np.percentile(late, 50)), "p99": float(np.percentile(late, 99)),
                       "max": float(late.max()), "over5": int((late > 5.0).sum()), "ticks": len(late),
                       "load": out["load"], "dropped": sum((rep.get("dropped") or {}).values()),
                       "flush_ms": rep.get("max_flush_step_ms", 0.0), "messages": rep.get("message_count", 0),
                       "cpu": out["cpu"] * 1e3, "writer": rep.get("writer_cpu_s", 0.0) * 1e3}
                rows[name].append(row)
                print(f"  pair {r + 1} {name:<9} p50 {row['p50']:6.3f} ms  p99 {row['p99']:6.2f} ms  max "
                      f"{row['max']:6.1f} ms  >5 ms {row['over5']:3d}/{row['ticks']}  load {row['load']:5.1f}"
                      + f"  CPU {row['cpu']:.0f} ms"
                      + (f" (writer {row['writer']:.0f})  {row['messages']} messages, dropped {row['dropped']}, "
                         f"longest close step {row['flush_ms']:.2f} ms" if name != "baseline" else ""), flush=True)
                shutil.rmtree(folder, ignore_errors=True)
    print(f"\nreal time, {seconds:g} s runs, {pairs} pairs (in process): median (min..max) over runs, ms")
    for name, got in rows.items():
        cells = "  ".join(f"{k} {statistics.median(x[k] for x in got):.3f} ({min(x[k] for x in got):.3f}.."
                          f"{max(x[k] for x in got):.3f})" for k in ("p50", "p99", "max", "cpu", "writer"))
        print(f"  {name:<9} {cells}  >5 ms {sum(x['over5'] for x in got)}/{sum(x['ticks'] for x in got)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=40.0, help="robot seconds per run (virtual time)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--configs", default="baseline,record,foxglove,both")
    ap.add_argument("--realtime-seconds", type=float, default=15.0, help="0: skip the real-time part")
    ap.add_argument("--inprocess", action="store_true", help="also measure the run phase alone, in process")
    ap.add_argument("--skip-processes", action="store_true", help="only the in-process part")
    ap.add_argument("--realtime-pairs", type=int, default=0, metavar="N",
                    help="also N interleaved in-process real-time pairs (no recording, --record) of "
                         "--realtime-seconds each: tick lateness p50/p99/max")
    ap.add_argument("--realtime-configs", default="baseline,record",
                    help="configurations of the real-time pairs (baseline, record, record-nice10, foxglove, "
                         "foxglove+client)")
    ap.add_argument("--client", metavar="URL", help=argparse.SUPPRESS)  # the subscribing viewer's process
    args = ap.parse_args()
    if args.client:
        client(args.client)
        return
    if args.inprocess:
        inprocess(args.duration, args.rounds)
    if args.realtime_pairs:
        realtime_inprocess(args.realtime_seconds, args.realtime_pairs, tuple(args.realtime_configs.split(",")))
    if args.skip_processes:
        return
    import os

    names = [n for n in args.configs.split(",") if n]
    results: dict[str, list[dict]] = {n: [] for n in names}
    load0 = os.getloadavg()
    for r in range(args.rounds):
        for name in names:
            results[name].append(run_once(CONFIGS[name], args.duration))
        print(f"round {r + 1}/{args.rounds}: " + "  ".join(
            f"{n} {results[n][-1]['cpu']:.2f}s" for n in names), file=sys.stderr, flush=True)
    load1 = os.getloadavg()
    print(f"\nwhole runs: trees/autonomy.xml to yard_east, {args.duration:g} s robot time (virtual), "
          f"{args.rounds} interleaved rounds, load average {load0[0]:.1f} -> {load1[0]:.1f}; medians, and the "
          f"CPU ratio to the baseline of the same round (median, min..max) and of the minima")
    print(f"{'config':<10} {'CPU s':>7} {'wall s':>7} {'CPU vs base':>34} {'writer CPU s':>13} "
          f"{'messages':>9} {'dropped':>8}")
    base = results.get("baseline")
    for name in names:
        rows = results[name]
        cpu = statistics.median(x["cpu"] for x in rows)
        wall = statistics.median(x["wall"] for x in rows)
        if base and name != "baseline":
            ratios = [x["cpu"] / b["cpu"] - 1 for x, b in zip(rows, base)]
            low = min(x["cpu"] for x in rows) / min(b["cpu"] for b in base) - 1
            rel = f"{statistics.median(ratios):+.1%} ({min(ratios):+.1%}..{max(ratios):+.1%}) min {low:+.1%}"
        else:
            rel = "-"
        print(f"{name:<10} {cpu:7.2f} {wall:7.2f} {rel:>34} {statistics.median(x['writer_cpu'] for x in rows):13.3f} "
              f"{statistics.median(x['messages'] for x in rows):9.0f} {max(x['dropped'] for x in rows):8d}")
    if args.realtime_seconds > 0:
        print(f"\nreal time, {args.realtime_seconds:g} s: tick lateness p99 (us)")
        for name in ("baseline", "record"):
            row = run_once(CONFIGS[name], args.realtime_seconds, realtime=True)
            print(f"{name:<10} p50 {row['lateness_p50_us']:8.1f}  p99 {row['lateness_p99_us']:8.1f}  "
                  f"CPU {row['cpu']:.2f} s  dropped {row['dropped']}")


if __name__ == "__main__":
    main()
