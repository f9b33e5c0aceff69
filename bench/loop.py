"""Tick lateness and CPU use of the 100 Hz tick task in real time, with everything else running.

The runtime (supervisor, backup, gate, tick task) runs against the simulator for --seconds of
wall time, once idle (the tree ticks, the robot stands) and once while the Nav2 stand-in
drives the robot. Each pacing runs in turn, in the same process:

  efficient   bt_runtime's default: a plain sleep to each deadline on its real-time loop
              (select(): microsecond timers)
  precise     opt-in: the same loop, sleeping to 3.5 ms before each deadline and yielding
              until it
  asyncio     the peer: stock asyncio loop (epoll, timeouts rounded up to 1 ms), plain sleep
  uvloop      the peer, if installed: uvloop's loop, plain sleep

Printed per pacing: ticks, overruns, lateness p50/p99/p99.9, tick cost, and CPU use of the
whole process as a share of one core (time.process_time over wall time).

Targets (issue #14): the default uses <= 5 % of a core at 100 Hz with an idle tree while
keeping lateness p99 <= 1 ms on an idle machine.
Run: python bench/loop.py [--seconds 10] [--histogram]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repo, ahead of bench/ (bench/sim.py)
import asyncio
import time

from bt_runtime.logging_setup import quiet_logging
from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import new_realtime_loop
from bt_runtime.runtime.config import RuntimeConfig, TickConfig
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


async def measure(seconds: float, pacing: str, drive: bool) -> dict:
    driver = SimDriver("apartment", "burger", seed=1)
    config = RuntimeConfig(tick=TickConfig(pacing="precise" if pacing == "precise" else "efficient"))
    rt = AutonomyRuntime(driver, config, realtime=True)
    rt.load_tree(TREE)
    await rt.start()
    nav = driver.navigation.navigate_to_pose(Pose2D(3.0, 1.0)) if drive else None
    cpu0, wall0 = time.process_time(), time.perf_counter()
    await asyncio.sleep(seconds)
    cpu = (time.process_time() - cpu0) / (time.perf_counter() - wall0)
    if nav is not None:
        nav.cancel()
    stats = rt.tick_loop.stats
    await rt.stop()
    return {"stats": stats, "cpu": cpu}


def _loop_factory(pacing: str):
    if pacing in ("efficient", "precise"):
        return new_realtime_loop
    if pacing == "uvloop":
        import uvloop

        return uvloop.new_event_loop
    return asyncio.new_event_loop


def run_one(seconds: float, pacing: str, drive: bool) -> dict:
    with asyncio.Runner(loop_factory=_loop_factory(pacing)) as runner:
        return runner.run(measure(seconds, pacing, drive))


def report(name: str, result: dict, histogram: bool) -> None:
    stats = result["stats"]
    pct = stats.lateness_percentiles((50, 99, 99.9))
    print(f"{name:<22}{stats.count:>7}{stats.overruns:>6}" + "".join(f"{v * 1e3:>10.3f}" for v in pct.values())
          + f"{stats.cost_mean * 1e6:>11.1f}{result['cpu'] * 100:>9.1f}")
    if histogram:
        total = max(1, min(stats.count, stats.keep))
        for label, count in stats.histogram():
            print(f"  {label:>14}: {count:7d} {'#' * int(50 * count / total)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--histogram", action="store_true")
    args = parser.parse_args()
    quiet_logging("error")
    pacings = ["efficient", "precise", "asyncio"]
    try:
        import uvloop  # noqa: F401

        pacings.append("uvloop")
    except ImportError:
        print("(uvloop not installed: pip install uvloop to include it)")
    for drive in (False, True):
        print(f"\n{'driving' if drive else 'idle tree, robot standing'}, {args.seconds:g} s each")
        print(f"{'pacing':<22}{'ticks':>7}{'over':>6}{'p50 ms':>10}{'p99 ms':>10}{'p99.9 ms':>10}"
              f"{'cost us':>11}{'CPU %':>9}")
        for pacing in pacings:
            report(pacing, run_one(args.seconds, pacing, drive), args.histogram)
    print("\nCPU % is the whole process (simulator, runtime, tick task) as a share of one core.")


if __name__ == "__main__":
    main()
