"""Tick lateness of the 100 Hz tick task in real-time mode, with everything else running.

The runtime (supervisor, backup, gate, tick task) runs on the stock asyncio loop against the
simulator while the Nav2 stand-in drives the robot across the apartment, for --seconds of
wall time. Printed: the lateness histogram and percentiles for our tick task (sleep to just
before the deadline, then yield until it), the same for a plain ``asyncio.sleep`` pacing as
the peer, mean/p99 tick cost and overruns.

Target (issue #4): lateness p50 <= 0.1 ms and p99 <= 0.5 ms.
Run: python bench/loop.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repo, ahead of bench/ (bench/sim.py)
import asyncio

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import run
from bt_runtime.runtime.messages import Pose2D
from sim.driver import SimDriver

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <KeepRunningUntilFailure><ReactiveSequence>
    <ScriptCondition code="battery := 80; battery &gt; 20"/>
    <Fallback><ScriptCondition code="healthy := true; healthy"/><AlwaysFailure/></Fallback>
    <Fallback><ScriptCondition code="a := 1; a == 1"/><AlwaysFailure/></Fallback>
    <Fallback><ScriptCondition code="b := 2; b == 2"/><AlwaysFailure/></Fallback>
    <AlwaysSuccess/>
  </ReactiveSequence></KeepRunningUntilFailure>
</BehaviorTree></root>"""


async def measure(seconds: float, precise: bool) -> dict:
    driver = SimDriver("apartment", "burger", seed=1)
    rt = AutonomyRuntime(driver, realtime=precise)
    rt.load_tree(TREE)
    await rt.start()
    nav = driver.navigation.navigate_to_pose(Pose2D(3.0, 1.0))
    await asyncio.sleep(seconds)
    nav.cancel()
    stats = rt.tick_loop.stats
    await rt.stop()
    return {"stats": stats, "summary": rt.summary()}


def report(name: str, stats) -> None:
    pct = stats.lateness_percentiles((50, 90, 99, 99.9))
    cost = stats.cost_percentiles((50, 99))
    print(f"\n{name}: {stats.count} ticks, overruns {stats.overruns}, errors {stats.errors}")
    print("  lateness " + "  ".join(f"{k}={v * 1e3:.3f} ms" for k, v in pct.items()))
    print(f"  tick cost mean={stats.cost_mean * 1e6:.1f} us  p50={cost['p50'] * 1e6:.1f} us  "
          f"p99={cost['p99'] * 1e6:.1f} us  max={stats.cost_max * 1e6:.1f} us")
    total = max(1, min(stats.count, stats.keep))
    for label, count in stats.histogram():
        print(f"  {label:>14}: {count:7d} {'#' * int(50 * count / total)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    quiet_logging("error")
    ours = run(measure(args.seconds, precise=True), virtual=False)
    peer = run(measure(args.seconds, precise=False), virtual=False)
    report("bt_runtime tick task (sleep + yield-until-deadline)", ours["stats"])
    report("peer: plain asyncio.sleep to each deadline", peer["stats"])
    o = ours["stats"].lateness_percentiles((50, 99))
    p = peer["stats"].lateness_percentiles((50, 99))
    print(f"\nratio ours/peer: p50 {o['p50'] / p['p50']:.3f}, p99 {o['p99'] / p['p99']:.3f}")
    ok = o["p50"] <= 1e-4 and o["p99"] <= 5e-4
    print(f"target p50 <= 0.1 ms and p99 <= 0.5 ms: {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
