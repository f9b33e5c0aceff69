"""Share of a campaign run spent setting it up: world and simulator, runtime, tree load, start.

Runs scenarios the way a campaign worker does (one process, runs back to back; the caches a
forked worker inherits from the pool's parent are filled first, as sim/scenarios/warm.py does,
unless --cold) and splits each run's CPU time (time.process_time) into:

  driver      building the simulated robot: world file (cached per process), map, physics,
              sensors, the Nav2 stand-in
  runtime     AutonomyRuntime(...): factory, node registration, supervisor, gate, backup
  tree        load_tree: parse and build the run's tree
  start       rt.start(): tasks, first readings
  judge       judging the recorded run
  run         everything else: the simulated minutes themselves

Target (issue #14): setup (driver + runtime + tree + start) <= 5 % of a run.
Run: python bench/run_setup.py [--only Collision_1,Lidar_2] [--seeds 2] [--modes with,without]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bt_runtime.logging_setup import quiet_logging  # noqa: E402
from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from sim.scenarios import runner  # noqa: E402
from sim.scenarios.runspec import plan_runs  # noqa: E402
from sim.scenarios.spec import load_scenario, scenario_names  # noqa: E402
from sim.scenarios.warm import warm_caches  # noqa: E402

PHASES = ("driver", "runtime", "tree", "start", "judge")
_spent: dict[str, float] = {}


def _timed(phase: str, fn):
    def wrapper(*args, **kwargs):
        t0 = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            _spent[phase] = _spent.get(phase, 0.0) + time.process_time() - t0
    return wrapper


def _timed_async(phase: str, fn):
    async def wrapper(*args, **kwargs):
        t0 = time.process_time()
        try:
            return await fn(*args, **kwargs)
        finally:
            _spent[phase] = _spent.get(phase, 0.0) + time.process_time() - t0
    return wrapper


def instrument() -> None:
    runner.ScenarioRun._build_driver = _timed("driver", runner.ScenarioRun._build_driver)
    init = AutonomyRuntime.__init__
    AutonomyRuntime.__init__ = _timed("runtime", init)  # type: ignore[method-assign]
    AutonomyRuntime.load_tree = _timed("tree", AutonomyRuntime.load_tree)  # type: ignore[method-assign]
    AutonomyRuntime.start = _timed_async("start", AutonomyRuntime.start)  # type: ignore[method-assign]
    runner.judge = _timed("judge", runner.judge)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", default="Collision_1,Lidar_2,NoPathFound_1,Battery_1")
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--modes", default="with,without")
    parser.add_argument("--cold", action="store_true", help="no warm-up: the first run fills the caches")
    args = parser.parse_args()
    quiet_logging("error")
    instrument()
    names = args.only.split(",") if args.only else scenario_names()
    if not args.cold:
        specs = [load_scenario(name) for name in names]
        warm_caches(plan_runs(specs, 1, 0, args.modes.split(",")))
        _spent.clear()
    print(f"{'run':<34}{'CPU s':>8}" + "".join(f"{p:>9}" for p in PHASES) + f"{'setup %':>9}")
    shares = []
    for name in names:
        spec = load_scenario(name)
        for mode in args.modes.split(","):
            for seed in range(args.seeds):
                _spent.clear()
                t0 = time.process_time()
                runner.run_scenario(spec, mode, seed, keep_record=False)
                total = time.process_time() - t0
                setup = sum(_spent.get(p, 0.0) for p in PHASES[:4])
                shares.append(setup / total)
                print(f"{f'{name} {mode} seed {seed}':<34}{total:>8.2f}"
                      + "".join(f"{_spent.get(p, 0.0) * 1e3:>7.0f}ms" for p in PHASES)
                      + f"{100 * setup / total:>8.1f}%")
    print(f"\nsetup share of a run: median {100 * statistics.median(shares):.1f} %, "
          f"range {100 * min(shares):.1f}-{100 * max(shares):.1f} % over {len(shares)} runs "
          + ("(the first run of the process pays the world parse and imports)" if args.cold
             else "(caches filled before the first run, as a forked pool worker inherits them)"))


if __name__ == "__main__":
    main()
