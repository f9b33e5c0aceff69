"""``python -m bt_runtime scenarios``: the paper's 14 failure scenarios, with and without the
autonomy layer, many seeded runs in parallel, and a Table IV-style summary.

  --runs N        runs per scenario and mode (default 20)
  --paper-runs    the paper's numbers of runs (5 / 20 / 10 per scenario, 270 runs in all)
  --backend ray   every run a Ray task (a local Ray, or a cluster with --ray-address)
  --results FILE  stream every finished run to FILE (JSON lines); --resume FILE continues it
  --shard K/N     only the K-th of N deterministic slices (combine with `scenarios merge`)
  --file PATH     your own scenario file (or a folder of them), validated like the shipped ones

  scenarios merge FILES...   the table from several results files (shards, resumed parts)
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
    p.add_argument("--jobs", type=int, default=None, metavar="J",
                   help="parallel processes (default: CPUs); with --backend ray: the local Ray's CPUs")
    p.add_argument("--json", type=Path, default=None, metavar="FILE", help="write every run and verdict as JSON")
    p.add_argument("--report", type=Path, default=None, metavar="DIR", help="PNG per scenario + summary.md")
    p.add_argument("--only", action="append", default=[], metavar="NAME",
                   help="run only these scenarios (repeatable, or comma separated)")
    p.add_argument("--mode", choices=["both", "with", "without"], default="both")
    p.add_argument("--record", type=Path, default=None, metavar="DIR",
                   help="a rosbag2 bag (MCAP) per run in DIR, named SCENARIO_MODE_seedSEED")
    p.add_argument("--record-failures", action="store_true", help="with --record: keep only failed runs' bags")
    p.add_argument("--file", action="append", default=[], type=Path, metavar="PATH",
                   help="run your own scenario file, or every *.yaml in a folder (repeatable); "
                        "with --only, the named shipped scenarios run too")
    p.add_argument("--variants", type=int, default=None, metavar="N",
                   help="N randomized variants of the failure families instead, with the layer unless --mode "
                        "says otherwise; --only picks families (docs/scenarios.md)")
    _add_campaign_flags(p)
    p.set_defaults(func=run)
    return p


def _add_campaign_flags(p: argparse.ArgumentParser) -> None:
    """Where runs execute and where results go (docs/cluster.md)."""
    g = p.add_argument_group("backends, results files and shards")
    g.add_argument("--backend", choices=["local", "ray"], default="local",
                   help="local: a process pool on this machine; ray: every run a Ray task")
    g.add_argument("--ray-address", default=None, metavar="ADDR",
                   help="a running Ray cluster (e.g. auto, ray://head:10001); default: start a local Ray")
    files = g.add_mutually_exclusive_group()
    files.add_argument("--results", type=Path, default=None, metavar="FILE",
                       help="append every run's verdicts to FILE (JSON lines) as it finishes")
    files.add_argument("--resume", type=Path, default=None, metavar="FILE",
                       help="continue the campaign recorded in FILE: skip its runs, append the rest")
    g.add_argument("--shard", default=None, metavar="K/N", help="run only the K-th of N slices of the campaign")
    actions = p.add_subparsers(dest="scenarios_action", metavar="{merge}")
    merge = actions.add_parser("merge", help="print the table from several results files",
                               description="Combine results files (shards, resumed parts) into one table; "
                                           "a run in several files counts once.")
    merge.add_argument("files", nargs="+", type=Path, metavar="FILE")
    merge.add_argument("--json", type=Path, default=None, metavar="FILE", help="write every run as JSON")
    merge.set_defaults(func=run_merge)


def _scenario_specs(args: argparse.Namespace) -> list:
    """The scenarios to run, validated (a bad one raises ScenarioError naming file and field)."""
    from sim.scenarios.spec import load_scenario, load_scenario_files, scenario_names

    files = getattr(args, "file", None) or []
    named = [n for item in args.only for n in item.split(",") if n]
    if not named and not files:
        named = scenario_names()
    return [load_scenario(name) for name in named] + load_scenario_files(files)


def _artifacts(args: argparse.Namespace) -> dict[str, dict]:
    """What each run hands back besides its verdicts: maker -> its options (sim/scenarios/artifacts.py)."""
    artifacts: dict[str, dict] = {}
    if args.report is not None:
        artifacts["trajectory"] = {}
    return artifacts


def _run_options(args: argparse.Namespace) -> dict:
    """Extra keyword arguments for every run_scenario call."""
    options: dict = {}
    if args.record is not None:
        options.update(record_dir=str(args.record.resolve()), record_failures=args.record_failures)
    return options


def run(args: argparse.Namespace) -> int:
    from sim.scenarios.backends import make_backend
    from sim.scenarios.campaign import Progress, format_failures, format_table, run_campaign
    from sim.scenarios.report import write_report
    from sim.scenarios.results import ResultsError, ResultsLog
    from sim.scenarios.runspec import parse_shard, plan_runs, shard_runs
    from sim.scenarios.spec import ScenarioError

    from ..logging_setup import quiet_logging

    quiet_logging("error")
    if args.runs is not None and args.runs < 1:
        return _usage("--runs must be at least 1")
    if args.ray_address is not None and args.backend != "ray":
        return _usage("--ray-address needs --backend ray")
    if args.record_failures and args.record is None:
        return _usage("--record-failures needs --record DIR")
    runs = None if args.paper_runs else (args.runs or 20)
    modes = ("with", "without") if args.mode == "both" else (args.mode,)
    log = None
    try:
        if args.variants is not None:
            from sim.scenarios.variant_runs import variant_campaign

            specs, plan, format_table, format_failures = variant_campaign(args, _artifacts(args), _run_options(args))
        else:
            specs = _scenario_specs(args)
            plan = plan_runs(specs, runs, args.seed, modes, artifacts=_artifacts(args), options=_run_options(args))
        if args.shard is not None:
            plan = shard_runs(plan, *parse_shard(args.shard))
        if args.results is not None or args.resume is not None:
            log = ResultsLog(args.resume or args.results, specs, resume=args.resume is not None)
            log.check_seeds(plan)
    except (ScenarioError, ResultsError, ValueError) as exc:
        if log is not None:
            log.close()
        return _usage(str(exc))
    recorded = {r.key: log.recorded.runs[r.key] for r in plan if log and r.key in log.recorded.runs}
    if recorded:
        print(f"resuming {args.resume}: {len(recorded)} of {len(plan)} runs already recorded", file=sys.stderr)
    try:
        backend = make_backend(args.backend, jobs=args.jobs, ray_address=args.ray_address)
    except RuntimeError as exc:
        if log is not None:
            log.close()
        return _usage(str(exc))
    progress = Progress(len(plan) - len(recorded), cpus=backend.cpus)

    def on_result(line: dict) -> None:
        if log is not None:
            log.append(line)
        progress.update(line["success"])

    try:
        result = run_campaign(plan, backend, specs=specs, recorded=recorded, on_result=on_result)
    finally:
        backend.close()
        if log is not None:
            log.close()
    _print_result(result, format_table, format_failures)
    if args.json is not None:
        _write_json(args.json, result.to_dict())
    if args.report is not None:
        files = write_report(result, args.report)
        drawn = f" (draws the {len(result.trajectories)} runs made now)" if result.resumed else ""
        print(f"report: {len(files)} files in {args.report}{drawn}")
    if args.record is not None:
        bags = sorted(p for p in args.record.iterdir() if (p / "metadata.yaml").is_file()) \
            if args.record.is_dir() else []
        which = " (failed runs only)" if args.record_failures else ""
        print(f"recording: {len(bags)} bag{'' if len(bags) == 1 else 's'} in {args.record}{which}")
    return _exit_code(result.results)


def run_merge(args: argparse.Namespace) -> int:
    from sim.scenarios.campaign import format_failures, format_table, from_recorded
    from sim.scenarios.results import ResultsError, read_results

    try:
        result = from_recorded(read_results(args.files))
    except ResultsError as exc:
        return _usage(str(exc))
    if result.specs and all(_is_variant(name) for name in result.specs):  # files of --variants campaigns
        from sim.scenarios.variant_runs import format_families, format_variant_failures

        format_table, format_failures = format_families, format_variant_failures
    _print_result(result, format_table, format_failures)
    if args.json is not None:
        _write_json(args.json, result.to_dict())
    return _exit_code(result.results)


def _is_variant(name: str) -> bool:
    from sim.scenarios.variants import FAMILIES, family_of

    return family_of(name) in FAMILIES and name != family_of(name)


def _print_result(result, format_table, format_failures) -> None:
    print(format_table(result))
    failures = format_failures(result)
    if failures:
        print("\nfailed runs, by reason:")
        print(failures)
    meta = result.to_dict()["meta"]
    if result.backend == "merge":
        print(f"\n{meta['runs']} runs; {meta['sim_time_s']} s robot time, "
              f"mean real-time factor per process x{meta['mean_real_time_factor']}")
        return
    resumed = f" ({result.resumed} of them from the resumed file)" if result.resumed else ""
    print(f"\n{meta['runs']} runs{resumed} in {meta['wall_time_s']} s wall on {meta['jobs']} CPU(s) "
          f"({result.backend}); {meta['sim_time_s']} s robot time, mean real-time factor per process "
          f"x{meta['mean_real_time_factor']}")


def _write_json(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    print(f"results: {path}")


def _exit_code(results: list[dict]) -> int:
    with_failed = any(not r["success"] for r in results if r["mode"] == "with")
    return EXIT_FAILED if with_failed else EXIT_OK


def _usage(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return EXIT_USAGE
