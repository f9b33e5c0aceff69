"""Tick lateness and CPU use of the 100 Hz autonomy layer in real time, per pacing and per shape.

Two shapes, each printed under its own heading:

  ros2  the real deployment: the runtime with the ROS 2 driver in this process, the robot
        (``python -m bt_runtime sim-robot``: simulator, sensors, Nav2 stand-in) in another
        process on DDS (loopback). CPU % is THIS process only: what the autonomy layer costs
        a robot's computer (tick task, gate, supervisor, backup, watchdog, DDS receive and
        conversion of the sensor streams).
  sim   everything in one process: the runtime against the in-process simulator (100 Hz
        physics, lidar ray casts, Nav2 stand-in). CPU % is the whole process, simulator
        included: what a simulated run costs, not what the layer costs on a robot.

Each shape runs once idle (the tree ticks, the robot stands) and once while navigation drives
the robot, every pacing in turn in the same process:

  efficient   bt_runtime's default: a plain sleep to each deadline on its real-time loop
              (select(): microsecond timers)
  precise     opt-in: the same loop, sleeping to 3.5 ms before each deadline and yielding
              until it
  asyncio     the peer: stock asyncio loop (epoll, timeouts rounded up to 1 ms), plain sleep
  uvloop      the peer, if installed: uvloop's loop, plain sleep

Printed per pacing: ticks, overruns, lateness p50/p99/p99.9, tick cost, and CPU use as a
share of one core (time.process_time over wall time, after a warm-up of --warmup s), then the
same split by thread (Linux): the event loop's, the watchdog's, and the others (DDS receive
threads, in 10 ms clock ticks, so coarse).

Targets (issue #14): the default uses <= 5 % of a core at 100 Hz with an idle tree while
keeping lateness p99 <= 1 ms on an idle machine.
Run: python bench/loop.py [--seconds 10] [--shapes ros2,sim] [--histogram]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the repo, ahead of bench/ (bench/sim.py)
import asyncio  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402

from bt_runtime.logging_setup import quiet_logging  # noqa: E402
from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.clock import new_realtime_loop  # noqa: E402
from bt_runtime.runtime.config import RuntimeConfig, TickConfig  # noqa: E402
from bt_runtime.runtime.messages import Pose2D  # noqa: E402
from bt_runtime.runtime.tick_loop import TickStats  # noqa: E402

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <KeepRunningUntilFailure><ReactiveSequence>
    <ScriptCondition code="battery := 80; battery &gt; 20"/>
    <Fallback><ScriptCondition code="healthy := true; healthy"/><AlwaysFailure/></Fallback>
    <Fallback><ScriptCondition code="a := 1; a == 1"/><AlwaysFailure/></Fallback>
    <Fallback><ScriptCondition code="b := 2; b == 2"/><AlwaysFailure/></Fallback>
    <AlwaysSuccess/>
  </ReactiveSequence></KeepRunningUntilFailure>
</BehaviorTree></root>"""

GOAL = Pose2D(3.0, 1.0)


def thread_cpu() -> dict[str, float]:
    """CPU seconds per thread of this process, by thread name (Linux /proc; {} elsewhere)."""
    ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    out: dict[str, float] = {}
    tasks = Path("/proc/self/task")
    if not tasks.is_dir():
        return out
    for task in tasks.iterdir():
        try:
            name = (task / "comm").read_text().strip()
            fields = (task / "stat").read_text().rpartition(")")[2].split()
        except OSError:
            continue
        key = "main" if task.name == str(os.getpid()) else ("watchdog" if "watchdog" in name else "other")
        out[key] = out.get(key, 0.0) + (int(fields[11]) + int(fields[12])) / ticks
    return out


class RobotProcess:
    """``sim-robot`` on loopback DDS in its own process (the ros2 shape)."""

    def __init__(self, domain: int):
        self.domain = domain
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "bt_runtime", "sim-robot", "--loopback", "--nav-autostart", "--domain",
             str(domain), "--duration", "3600"], cwd=ROOT, env=env, stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL, text=True)
        line = self.proc.stdout.readline()
        if "sim-robot ready" not in line:
            self.stop()
            raise SystemExit(f"sim-robot did not start: {line!r}")

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()


def make_driver(shape: str, robot: RobotProcess | None):
    if shape == "ros2":
        from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver

        return Ros2Driver(Ros2Config(domain_id=robot.domain))
    from sim.driver import SimDriver

    return SimDriver("apartment", "burger", seed=1)


async def measure(shape: str, robot: RobotProcess | None, seconds: float, warmup: float, pacing: str,
                  drive: bool) -> dict:
    driver = make_driver(shape, robot)
    config = RuntimeConfig(tick=TickConfig(pacing="precise" if pacing == "precise" else "efficient"))
    rt = AutonomyRuntime(driver, config, realtime=True)
    rt.load_tree(TREE)
    await rt.start()
    await asyncio.sleep(warmup)  # discovery (ros2), bring-up, first messages
    nav = driver.navigation.navigate_to_pose(GOAL) if drive else None
    rt.tick_loop.stats = TickStats()
    threads0, cpu0, wall0 = thread_cpu(), time.process_time(), time.perf_counter()
    await asyncio.sleep(seconds)
    wall = time.perf_counter() - wall0
    cpu = (time.process_time() - cpu0) / wall
    threads = {k: (v - threads0.get(k, 0.0)) / wall for k, v in thread_cpu().items()}
    stats = rt.tick_loop.stats
    if nav is not None:
        nav.cancel()
    await rt.stop()
    if drive and shape == "ros2":
        await asyncio.sleep(0.5)  # let the robot hear the cancel before the next run
    return {"stats": stats, "cpu": cpu, "threads": threads}


def _loop_factory(pacing: str):
    if pacing in ("efficient", "precise"):
        return new_realtime_loop
    if pacing == "uvloop":
        import uvloop

        return uvloop.new_event_loop
    return asyncio.new_event_loop


def run_one(shape: str, robot: RobotProcess | None, seconds: float, warmup: float, pacing: str,
            drive: bool) -> dict:
    with asyncio.Runner(loop_factory=_loop_factory(pacing)) as runner:
        return runner.run(measure(shape, robot, seconds, warmup, pacing, drive))


def report(name: str, result: dict, histogram: bool) -> None:
    stats = result["stats"]
    pct = stats.lateness_percentiles((50, 99, 99.9))
    print(f"{name:<22}{stats.count:>7}{stats.overruns:>6}" + "".join(f"{v * 1e3:>10.3f}" for v in pct.values())
          + f"{stats.cost_mean * 1e6:>11.1f}{result['cpu'] * 100:>9.1f}"
          + "".join(f"{result['threads'].get(k, 0.0) * 100:>9.1f}" for k in THREADS), flush=True)
    if histogram:
        total = max(1, min(stats.count, stats.keep))
        for label, count in stats.histogram():
            print(f"  {label:>14}: {count:7d} {'#' * int(50 * count / total)}")


THREADS = ("main", "watchdog", "other")  # CPU % by thread: the event loop, the dead-man, DDS/other
HEADINGS = {"ros2": "ros2: runtime + ROS 2 driver here, sim-robot in another process; CPU of this process only",
            "sim": "sim: runtime + in-process simulator; CPU of the whole process, simulator included"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--warmup", type=float, default=2.0, help="seconds after start before measuring")
    parser.add_argument("--shapes", default="ros2,sim", help="comma-separated: ros2, sim")
    parser.add_argument("--pacings", default="efficient,precise,asyncio,uvloop")
    parser.add_argument("--idle-only", action="store_true", help="skip the driving runs")
    parser.add_argument("--histogram", action="store_true")
    args = parser.parse_args()
    quiet_logging("error")
    pacings = args.pacings.split(",")
    if "uvloop" in pacings:
        try:
            import uvloop  # noqa: F401
        except ImportError:
            print("(uvloop not installed: pip install uvloop to include it)")
            pacings.remove("uvloop")
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for shape in args.shapes.split(","):
        robot = None
        if shape == "ros2":
            from bt_runtime.runtime.ros2 import dds

            os.environ.setdefault("CYCLONEDDS_URI", dds.loopback_config())
            robot = RobotProcess(domain=230 + os.getpid() % 3)  # apart from the tests' 10..229
        try:
            for drive in (False,) if args.idle_only else (False, True):
                print(f"\n{HEADINGS[shape]}\n{'driving' if drive else 'idle tree, robot standing'}, "
                      f"{args.seconds:g} s each")
                print(f"{'pacing':<22}{'ticks':>7}{'over':>6}{'p50 ms':>10}{'p99 ms':>10}{'p99.9 ms':>10}"
                      f"{'cost us':>11}{'CPU %':>9}" + "".join(f"{k:>9}" for k in THREADS))
                for pacing in pacings:
                    report(pacing, run_one(shape, robot, args.seconds, args.warmup, pacing, drive), args.histogram)
        finally:
            if robot is not None:
                robot.stop()
    print(f"\nload average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
