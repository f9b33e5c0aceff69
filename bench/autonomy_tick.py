"""CPU per tick of the autonomy tree in the running system (issue #12: mean <= 0.1 ms).

Runs what ``python -m bt_runtime run trees/autonomy.xml --robot R --goal G`` runs (the CLI's
own ``run``: virtual time, the in-process simulator), in this process, and wraps
``Tree.tick_once`` to record the thread CPU (time.thread_time_ns) of every tick. Prints per
robot the tick count, mean, median, p90, p99 and max, and the ticks' share of the run phase's
CPU (process time from the end of ``runtime.start()`` to ``runtime.stop()``: the simulator,
supervisor, gate and backup share the process).

    python bench/autonomy_tick.py                              # rosbot2, burger, waffle; yard_east
    python bench/autonomy_tick.py --robot rosbot2 --goal 1,2
    python bench/autonomy_tick.py --other /path/to/checkout --rounds 7

``--other PATH`` runs this checkout's code and PATH's (e.g. a worktree of main) in alternating
subprocesses (order swapped each round), and prints per round the ratio this/other of the mean
and median, then the median ratio and range per robot; absolute figures move with the load,
the ratios of interleaved runs are what to read. The same run in both codes should make the
same decisions: each run's tick count and final pose are printed to compare.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


def measure(robot: str, goal: str, code: Path) -> dict:
    """One CLI run of the autonomy tree on ``code`` (a checkout root), tick CPU recorded."""
    sys.path.insert(0, str(code))
    os.chdir(code)
    from bt_runtime.__main__ import build_parser
    from bt_runtime.cli import run as cli_run
    from bt_runtime.runtime.app import AutonomyRuntime
    from bt_runtime.tree import Tree

    costs: list[int] = []
    phase: dict[str, float] = {}
    held: dict = {}
    tick_once = Tree.tick_once
    start, stop, report = AutonomyRuntime.start, AutonomyRuntime.stop, cli_run.report

    def timed_tick(self, *args, **kwargs):
        t0 = time.thread_time_ns()
        try:
            return tick_once(self, *args, **kwargs)
        finally:
            costs.append(time.thread_time_ns() - t0)

    async def timed_start(self, *args, **kwargs):
        result = await start(self, *args, **kwargs)
        phase["t0"] = time.process_time()
        return result

    async def timed_stop(self):
        phase.setdefault("t1", time.process_time())
        return await stop(self)

    def quiet_report(args, run_held, interrupted):
        held.update(run_held)
        with contextlib.redirect_stdout(io.StringIO()) as text:
            code = report(args, run_held, interrupted)
        held["text"] = text.getvalue()
        return code

    Tree.tick_once = timed_tick  # type: ignore[method-assign]
    AutonomyRuntime.start = timed_start  # type: ignore[method-assign]
    AutonomyRuntime.stop = timed_stop  # type: ignore[method-assign]
    cli_run.report = quiet_report
    args = build_parser().parse_args(["run", "trees/autonomy.xml", "--robot", robot, "--goal", goal,
                                      "--no-progress"])
    exit_code = args.func(args)
    runtime = held["runtime"]
    sim = getattr(runtime.driver, "sim", None)
    pose = None if sim is None else sim.pose  # the true end pose: a fingerprint of the run's decisions
    costs_us = sorted(c / 1e3 for c in costs)
    n = len(costs_us)
    run_cpu = phase.get("t1", phase.get("t0", 0.0)) - phase.get("t0", 0.0)
    return {"robot": robot, "goal": goal, "code": str(code), "exit": exit_code, "ticks": n,
            "mean": statistics.fmean(costs_us), "median": costs_us[n // 2],
            "p90": costs_us[int(0.9 * (n - 1))], "p99": costs_us[int(0.99 * (n - 1))], "max": costs_us[-1],
            "share": sum(costs_us) / 1e6 / run_cpu if run_cpu > 0 else float("nan"),
            "outcomes": [g.outcome for g in held["goals"]],
            "pose": None if pose is None else [round(pose.x, 6), round(pose.y, 6), round(pose.yaw, 6)]}


def line(r: dict) -> str:
    return (f"{r['robot']:<8} ticks {r['ticks']:>5}  mean {r['mean']:6.1f}  median {r['median']:6.1f}  "
            f"p90 {r['p90']:6.1f}  p99 {r['p99']:6.1f}  max {r['max']:7.1f} us  "
            f"share of run CPU {100 * r['share']:4.1f} %  {','.join(r['outcomes'])} pose {r['pose']}")


def in_subprocess(robot: str, goal: str, code: Path) -> dict:
    out = subprocess.run([sys.executable, __file__, "--robot", robot, "--goal", goal, "--code", str(code),
                          "--json"], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def compare(robots: list[str], goal: str, other: Path, rounds: int) -> None:
    ratios: dict[str, dict[str, list[float]]] = {r: {"mean": [], "median": []} for r in robots}
    print(f"this: {HERE}\nother: {other}\nratio = this / other, CPU per tick (thread time), {rounds} rounds")
    for k in range(rounds):
        for robot in robots:
            order = [HERE, other] if (k % 2 == 0) else [other, HERE]
            got = {code: in_subprocess(robot, goal, code) for code in order}
            a, b = got[HERE], got[other]
            for key in ("mean", "median"):
                ratios[robot][key].append(a[key] / b[key])
            same = "same" if (a["ticks"], a["pose"], a["outcomes"]) == (b["ticks"], b["pose"], b["outcomes"]) \
                else "DIFFERENT run"
            print(f"round {k + 1} {robot:<8} mean {a['mean']:6.1f} / {b['mean']:6.1f} = {a['mean'] / b['mean']:.3f}  "
                  f"median {a['median']:6.1f} / {b['median']:6.1f} = {a['median'] / b['median']:.3f}  "
                  f"p99 {a['p99']:6.1f} / {b['p99']:6.1f}  ({same}: ticks {a['ticks']}/{b['ticks']})  "
                  f"load {os.getloadavg()[0]:.2f}", flush=True)
    print()
    for robot in robots:
        m, md = ratios[robot]["mean"], ratios[robot]["median"]
        print(f"{robot:<8} mean ratio median {statistics.median(m):.3f} ({min(m):.3f}-{max(m):.3f})  "
              f"median ratio median {statistics.median(md):.3f} ({min(md):.3f}-{max(md):.3f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robot", default="rosbot2,burger,waffle", help="robots, comma separated")
    parser.add_argument("--goal", default="yard_east", help="a goal name of the world or X,Y[,YAW]")
    parser.add_argument("--other", type=Path, default=None, metavar="PATH",
                        help="another checkout: both run interleaved in subprocesses, ratios printed")
    parser.add_argument("--rounds", type=int, default=7, help="with --other: rounds (default 7)")
    parser.add_argument("--code", type=Path, default=HERE, help=argparse.SUPPRESS)
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    robots = [r for r in args.robot.split(",") if r]
    if args.other is not None:
        compare(robots, args.goal, args.other.resolve(), args.rounds)
        return
    if args.json:  # one robot, in a subprocess of compare()
        print(json.dumps(measure(robots[0], args.goal, args.code.resolve())))
        return
    print(f"load average {os.getloadavg()[0]:.2f}; CPU per tick of trees/autonomy.xml, goal {args.goal}")
    for robot in robots:
        print(line(in_subprocess(robot, args.goal, args.code.resolve())), flush=True)


if __name__ == "__main__":
    main()
