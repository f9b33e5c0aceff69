"""``python -m bt_runtime scenarios``: the paper's 14 failure scenarios, with and without the
autonomy layer, many seeded runs in parallel, and a Table IV-style summary.

  --runs N        runs per scenario and mode (default 20)
  --paper-runs    the paper's numbers of runs (5 / 20 / 10 per scenario, 270 runs in all)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("scenarios", help="run the paper's failure scenarios and print Table IV",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    count = p.add_mutually_exclusive_group()
    count.add_argument("--runs", type=int, default=None, metavar="N", help="runs per scenario and mode (20)")
    count.add_argument("--paper-runs", action="store_true", help="the paper's runs per scenario (Table IV)")
    p.add_argument("--seed", type=int, default=0, help="base seed (each run's seed derives from it)")
    p.add_argument("--jobs", type=int, default=None, metavar="J", help="parallel processes (default: CPUs)")
    p.add_argument("--json", type=Path, default=None, metavar="FILE", help="write every run and verdict as JSON")
    p.add_argument("--report", type=Path, default=None, metavar="DIR", help="PNG per scenario + summary.md")
    p.add_argument("--only", action="append", default=[], metavar="NAME",
                   help="run only these scenarios (repeatable, or comma separated)")
    p.add_argument("--mode", choices=["both", "with", "without"], default="both")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from sim.scenarios.campaign import Progress, format_failures, format_table, plan, run_campaign
    from sim.scenarios.report import write_report
    from sim.scenarios.spec import ScenarioError, load_scenario, scenario_names

    from ..logging_setup import quiet_logging

    quiet_logging("error")
    names = [n for item in args.only for n in item.split(",") if n] or scenario_names()
    try:
        for name in names:
            load_scenario(name)
    except ScenarioError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if args.runs is not None and args.runs < 1:
        print("error: --runs must be at least 1", file=sys.stderr)
        return EXIT_USAGE
    runs = None if args.paper_runs else (args.runs or 20)
    modes = ("with", "without") if args.mode == "both" else (args.mode,)
    total = len(plan(names, runs, args.seed, modes))
    progress = Progress(total)
    result = run_campaign(names, runs=runs, seed=args.seed, jobs=args.jobs, keep_trajectories=args.report is not None,
                          modes=modes, on_result=lambda r: progress.update(r["success"]))
    print(format_table(result))
    failures = format_failures(result)
    if failures:
        print("\nfailed runs, by reason:")
        print(failures)
    meta = result.to_dict()["meta"]
    print(f"\n{meta['runs']} runs in {meta['wall_time_s']} s wall on {meta['jobs']} process(es); "
          f"{meta['sim_time_s']} s robot time, mean real-time factor per process x{meta['mean_real_time_factor']}")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result.to_dict(), indent=1), encoding="utf-8")
        print(f"results: {args.json}")
    if args.report is not None:
        files = write_report(result, args.report)
        print(f"report: {len(files)} files in {args.report}")
    with_failed = any(not r["success"] for r in result.results if r["mode"] == "with")
    return EXIT_FAILED if with_failed else EXIT_OK
