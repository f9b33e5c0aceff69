"""What Groot2 monitoring costs the tick: tick cost with and without a client polling STATUS.

The tree ticks on an asyncio loop at --rate Hz (100 by default, the runtime's rate) for
--seconds per configuration; a separate process polls STATUS at --poll-hz (20 by default) like
Groot2 does. Each tick is timed with perf_counter; configurations are interleaved (--rounds) so
that drift affects them alike. Configurations:

  baseline        no server
  sampled+poll    GrootServer (default status mode), client polling STATUS
  exact+poll      GrootServer(status_mode="exact"), client polling STATUS
  btlog           BTLogger recording every transition to a .btlog file (no server)

Prints, per configuration, the robust mean (the slowest 0.2 % of ticks dropped: OS and VM
hiccups, while the sampled mode's one observed tick per second, 1 % of ticks, is kept) and the
median in microseconds per tick, the ratio of robust means to the baseline of the same round
(median over rounds, with the min-max range), and the process CPU per second of run (the
server's work between ticks shows up there).
A shared or busy machine makes those 100 Hz figures noisy, so the script first measures the
deterministic part on a hot loop (median of batches): the tick cost without and with a status
observer on every node (what exact mode, recording and .btlog pay on every tick, and what the
sampled mode pays on its one observed tick per second), and derives the sampled mode's expected
overhead at --rate: (observed/plain - 1) / (rate x observe_period).

Run: python bench/groot.py [--seconds 4] [--rounds 2] [--trees demo31,autonomy52]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
# This file is named like the groot package: take its folder off the path, put the root on it.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE]
sys.path.insert(0, str(HERE.parent))

from bt_runtime import BehaviorTreeFactory, NodeStatus  # noqa: E402
from groot import BTLogger, GrootServer  # noqa: E402
from groot.testing import demo_tree  # noqa: E402

POLLER = """
import sys, time
sys.path.insert(0, {root!r})
from groot.testing import GrootClient
port, hz, seconds = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
n = 0
with GrootClient(port) as c:
    c.fulltree()
    print("ready", flush=True)
    end = time.monotonic() + seconds
    nxt = time.monotonic()
    while time.monotonic() < end:
        c.status_bytes(); n += 1
        nxt += 1.0 / hz
        time.sleep(max(0.0, nxt - time.monotonic()))
print(n, flush=True)
"""


def autonomy52():
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_tick", HERE / "tick.py")
    tick = importlib.util.module_from_spec(spec)  # bench/tick.py: the same shape as its autonomy52
    spec.loader.exec_module(tick)

    f = BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda n: NodeStatus.SUCCESS)
    f.register_simple_condition("No", lambda n: NodeStatus.FAILURE)
    f.register_simple_action("Act", lambda n: NodeStatus.SUCCESS)
    f.register_simple_stateful_action("Run", lambda n: NodeStatus.RUNNING, lambda n: NodeStatus.RUNNING,
                                      lambda n: None)
    return f.create_tree_from_text(tick.autonomy52())


TREES = {"demo31": demo_tree, "autonomy52": autonomy52}


async def run_config(make_tree, config: str, seconds: float, rate: float, poll_hz: float) -> dict:
    tree = make_tree()
    loop = asyncio.get_running_loop()
    tree.set_clock(loop.time)
    server = poller = logger = None
    tmp = None
    if config in ("sampled+poll", "exact+poll"):
        server = GrootServer(tree, port=0, status_mode="exact" if config == "exact+poll" else "sampled")
        await server.start()
        poller = await asyncio.create_subprocess_exec(
            sys.executable, "-c", POLLER.format(root=str(HERE.parent)), str(server.port), str(poll_hz),
            str(seconds + 2.0), stdout=subprocess.PIPE)
        assert (await poller.stdout.readline()).strip() == b"ready"
    elif config == "btlog":
        tmp = tempfile.TemporaryDirectory()
        logger = BTLogger(tree, Path(tmp.name) / "bench.btlog")
    for _ in range(50):  # warm up
        tree.tick_once()
    durations = []
    period = 1.0 / rate
    cpu0, wall0 = time.process_time(), time.monotonic()
    next_tick = loop.time()
    end = next_tick + seconds
    perf = time.perf_counter
    while loop.time() < end:
        t0 = perf()
        tree.tick_once()
        durations.append(perf() - t0)
        next_tick += period
        await asyncio.sleep(max(0.0, next_tick - loop.time()))
    cpu = (time.process_time() - cpu0) / (time.monotonic() - wall0)
    polls = None
    if server is not None:
        polls = server.requests_served
        await server.stop()
        poller.kill()
        await poller.wait()
    if logger is not None:
        logger.close()
        tmp.cleanup()
    us = sorted(d * 1e6 for d in durations)
    kept = us[:max(1, len(us) - len(us) // 500)]
    return {"mean": statistics.fmean(kept), "median": statistics.median(us), "n": len(us), "cpu": cpu,
            "polls": polls}


def hot_loop(make_tree, observed: bool, batches: int = 15, inner: int = 400) -> float:
    """Median microseconds per tick over batches of back-to-back ticks."""
    tree = make_tree()
    if observed:
        tree.add_status_observer(lambda stamp, node, prev, new: None)
    for _ in range(inner):
        tree.tick_once()
    samples = []
    for _ in range(batches):
        t0 = time.perf_counter()
        for _ in range(inner):
            tree.tick_once()
        samples.append((time.perf_counter() - t0) / inner * 1e6)
    return statistics.median(samples)


async def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=4.0, help="run time per configuration and round")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--rate", type=float, default=100.0, help="tick rate, Hz")
    p.add_argument("--poll-hz", type=float, default=20.0, help="client STATUS polling rate")
    p.add_argument("--trees", default="demo31,autonomy52")
    p.add_argument("--configs", default="baseline,sampled+poll,exact+poll,btlog")
    args = p.parse_args()
    configs = args.configs.split(",")
    print("hot loop (back-to-back ticks, median of batches):")
    print(f"{'tree':<11} {'plain us':>9} {'observed us':>12} {'x':>6} {'sampled-mode overhead':>22}")
    for name in args.trees.split(","):
        plain, observed = hot_loop(TREES[name], False), hot_loop(TREES[name], True)
        overhead = (observed / plain - 1) / (args.rate * 1.0) * 100
        print(f"{name:<11} {plain:9.2f} {observed:12.2f} {observed / plain:6.2f} {overhead:21.2f}%")
    print()
    print(f"tick at {args.rate:g} Hz, STATUS polled at {args.poll_hz:g} Hz by another process, "
          f"{args.rounds} x {args.seconds:g} s per configuration")
    print(f"{'tree':<11} {'config':<13} {'mean us':>8} {'median':>8} {'ratio':>7} {'range':>13} {'cpu %':>6} "
          f"{'polls/s':>8}")
    for name in args.trees.split(","):
        make = TREES[name]
        results: dict[str, list[dict]] = {c: [] for c in configs}
        for _ in range(args.rounds):
            for config in configs:
                results[config].append(await run_config(make, config, args.seconds, args.rate, args.poll_hz))
        for config in configs:
            rs = results[config]
            mean = statistics.fmean(r["mean"] for r in rs)
            median = statistics.fmean(r["median"] for r in rs)
            cpu = statistics.fmean(r["cpu"] for r in rs) * 100
            polls = [r["polls"] for r in rs if r["polls"] is not None]
            rate = f"{sum(polls) / (args.seconds * len(polls)):.1f}" if polls else "-"
            if "baseline" in results:
                ratios = [r["mean"] / b["mean"] for r, b in zip(rs, results["baseline"])]
                ratio = f"{statistics.median(ratios):.3f}"
                spread = f"{min(ratios):.2f}-{max(ratios):.2f}"
            else:
                ratio = spread = "-"
            print(f"{name:<11} {config:<13} {mean:8.2f} {median:8.2f} {ratio:>7} {spread:>13} {cpu:6.1f} {rate:>8}")


if __name__ == "__main__":
    asyncio.run(main())
