"""``python -m bt_runtime run TREE.xml``: run a tree with the autonomy layer on a robot.

Defaults to the built-in simulator in the apartment, on virtual time (as fast as the CPU
allows); ``--realtime`` paces it to the wall clock. Shows a live progress line (on a
terminal) and a summary at the end; structlog events go to ``--log-file`` or, with
``--log-json``, to stdout as JSON lines.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

from ..errors import BehaviorTreeException
from ..runtime.messages import Pose2D
from .registration import RegistrationError, add_registration_arguments
from .registration import registrations as node_registrations

EXIT_OK, EXIT_TREE_FAILED, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """A bad command line or input file, reported without a traceback."""


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("run", help="run a tree with the autonomy layer (simulator by default)",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("tree", help="BehaviorTree.CPP v4 XML file")
    p.add_argument("--world", default="apartment", help="apartment | round_obstacles | a world YAML file")
    p.add_argument("--robot", default="burger", help="burger | waffle | rosbot2 | a profile YAML file")
    p.add_argument("--goal", action="append", default=[], metavar="X,Y[,YAW]",
                   help="goal pose (repeatable; write --goal=-1,2 for negative x) or a goal name of the "
                        "world; goals are handed to the tree one after the other")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="stop after S seconds of robot time (default: when the tree completes)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--realtime", action="store_true", help="pace the simulation to the wall clock")
    p.add_argument("--driver", default="sim", choices=["sim", "ros2"])
    p.add_argument("--config", type=Path, default=None, help="runtime configuration (YAML)")
    p.add_argument("--ros2-config", type=Path, default=None, metavar="FILE",
                   help="--driver ros2: topics, QoS, domain, Nav2 names, components (YAML, see docs/ros2.md)")
    add_registration_arguments(p)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="set a root blackboard entry before the first tick (repeatable)")
    p.add_argument("--log-json", action="store_true", help="structlog events as JSON lines on stdout")
    p.add_argument("--log-file", type=Path, default=None, help="structlog events (JSON lines) to this file")
    p.add_argument("--log-level", default="info", choices=["debug", "info", "warning", "error"])
    p.add_argument("--no-progress", action="store_true", help="no live progress line")
    p.add_argument("--summary-json", type=Path, default=None, help="write the run summary as JSON")
    from groot.cli import add_arguments as add_groot_arguments

    add_groot_arguments(p)
    p.set_defaults(func=run)
    return p


# ---------------------------------------------------------------------------------------------
# argument checking (clear errors, no tracebacks)
# ---------------------------------------------------------------------------------------------

def parse_goal(text: str, world: Any = None) -> Pose2D:
    parts = [p.strip() for p in text.replace(";", ",").split(",") if p.strip()]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) in (2, 3) and all(math.isfinite(v) for v in values):
        return Pose2D(*values)
    if world is not None and len(parts) == 1:
        try:
            g = world.goal(parts[0])
            return Pose2D(g.x, g.y, getattr(g, "yaw", 0.0))
        except Exception:
            names = ", ".join(sorted(getattr(world, "goals", {}) or {}))
            raise UsageError(f"--goal {text!r}: not X,Y[,YAW] and not a goal of this world "
                             f"(goals: {names or 'none'})") from None
    raise UsageError(f"--goal expects X,Y[,YAW] (numbers), got {text!r}")


def parse_assignment(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise UsageError(f"--set expects KEY=VALUE, got {text!r}")
    key, value = text.split("=", 1)
    for cast in (int, float):
        try:
            return key.strip(), cast(value)
        except ValueError:
            pass
    return key.strip(), value


def load_config(path: Path | None):
    from pydantic import ValidationError

    from ..runtime.config import RuntimeConfig

    if path is None:
        return RuntimeConfig()
    import yaml

    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        return RuntimeConfig.model_validate(data)
    except FileNotFoundError:
        raise UsageError(f"config file not found: {path}") from None
    except (yaml.YAMLError, ValidationError) as exc:
        raise UsageError(f"{path}: {exc}") from None


def make_driver(args: argparse.Namespace):
    if args.driver == "ros2":
        try:
            from ..runtime.ros2 import Ros2Config, Ros2Driver  # provided by the [ros2] extra
        except ImportError as exc:
            raise UsageError(f"--driver ros2 is not available: {exc}") from None
        path = getattr(args, "ros2_config", None)
        try:
            config = Ros2Config.load(path) if path else Ros2Config()
        except ValueError as exc:  # names the file and field; no traceback
            raise UsageError(str(exc)) from None
        return Ros2Driver(config.with_environment())
    from sim.driver import SimDriver

    try:
        return SimDriver(args.world, args.robot, seed=args.seed)
    except (FileNotFoundError, KeyError, ValueError) as exc:
        raise UsageError(f"cannot build the simulator: {exc}") from None


# ---------------------------------------------------------------------------------------------
# the run
# ---------------------------------------------------------------------------------------------

class ProgressLine:
    """One status line, refreshed at most every ``interval`` wall seconds."""

    def __init__(self, runtime: Any, stream=sys.stderr, interval: float = 0.25):
        self.runtime = runtime
        self.stream = stream
        self.interval = interval
        self._last = 0.0
        self._wall0 = time.perf_counter()
        self._sim0 = runtime.clock()
        self.printed = False

    def line(self) -> str:
        rt = self.runtime
        sim_t = rt.clock() - self._sim0
        wall = time.perf_counter() - self._wall0
        rtf = sim_t / wall if wall > 0 else 0.0
        pose = rt.backup.latest("pose")
        pose_txt = (f"({pose.pose.x:+.2f}, {pose.pose.y:+.2f}, {math.degrees(pose.pose.yaw):+4.0f}deg)"
                    if pose is not None else "(no pose)")
        bad = rt.supervisor.unhealthy()
        health = "OK" if not bad else "! " + ",".join(f"{n}:{rt.supervisor.health(n).value}" for n in bad)
        status = rt.tick_loop.status.name if rt.tick_loop else "-"
        return (f"t={sim_t:7.2f}s  x{rtf:6.1f}  pose={pose_txt}  tree={status:<8} gate={rt.gate.source:<7} "
                f"health={health}")

    def maybe_print(self) -> None:
        now = time.perf_counter()
        if now - self._last < self.interval:
            return
        self._last = now
        self.stream.write("\r" + self.line()[:160].ljust(160))
        self.stream.flush()
        self.printed = True

    async def run(self) -> None:
        while True:
            await asyncio.sleep(0.05)  # loop time: cheap when idle, frequent enough in real time
            self.maybe_print()

    def finish(self) -> None:
        if self.printed:
            self.stream.write("\n")
            self.stream.flush()


def format_summary(summary: Any, runtime: Any) -> str:
    s = summary
    pose = runtime.backup.latest("pose")
    lines = [
        f"tree: {s.status} ({'completed' if s.completed else 'not completed'})",
        f"time: {s.sim_time:.2f} s robot time in {s.wall_time:.2f} s wall (x{s.real_time_factor:.1f})",
        f"ticks: {s.ticks}  errors: {s.tick_errors}  overruns: {s.overruns}  "
        f"tick cost mean {s.tick_cost_mean_ms * 1e3:.1f} us, p99 {s.tick_cost_p99_ms * 1e3:.1f} us  "
        f"lateness p50 {s.lateness_p50_ms * 1e3:.1f} us, p99 {s.lateness_p99_ms * 1e3:.1f} us",
        "health: " + ", ".join(f"{k}={v}" for k, v in s.health.items()),
        f"supervisor events: {s.supervisor_events}  gate switches: {s.gate_switches}"
        + (f"  e-stop: {', '.join(s.estop_reasons)}" if s.estop_reasons else ""),
    ]
    if pose is not None:
        lines.append(f"final pose: x={pose.pose.x:.2f} y={pose.pose.y:.2f} yaw={math.degrees(pose.pose.yaw):.0f}deg")
    outcomes = getattr(s, "goal_outcomes", None)
    if outcomes:
        lines.append("goals: " + ", ".join(outcomes))
    return "\n".join(lines)


async def _run_async(args: argparse.Namespace, tree_path: Path, config: Any,
                     registrations: list, show_progress: bool, holder: dict[str, Any]) -> tuple[Any, int]:
    from ..runtime.app import AutonomyRuntime

    driver = make_driver(args)
    runtime = AutonomyRuntime(driver, config, realtime=args.realtime or None, register=registrations)
    try:
        runtime.load_tree(tree_path)
    except BehaviorTreeException as exc:
        raise UsageError(str(exc)) from None
    world = getattr(getattr(driver, "sim", None), "world", None)
    goals = [parse_goal(g, world) for g in args.goal]
    bb = runtime.tree.root_blackboard
    for assignment in args.set:
        key, value = parse_assignment(assignment)
        bb.set(key, value)
    progress = ProgressLine(runtime) if show_progress else None
    from groot.cli import Monitoring

    monitoring = await Monitoring.from_args(runtime.tree, args).start()
    await runtime.start()
    progress_task = asyncio.get_running_loop().create_task(progress.run()) if progress else None
    outcomes: list[str] = []
    try:
        if goals:
            await asyncio.wait_for(_send_goals(runtime, goals, outcomes), args.duration)
            summary = runtime.summary()
        else:
            summary = await runtime.run(duration=args.duration)
    except TimeoutError:
        summary = runtime.summary()
    finally:
        if progress_task is not None:
            progress_task.cancel()
            progress.maybe_print()
            progress.finish()
        holder["summary"], holder["runtime"] = runtime.summary(), runtime  # kept if interrupted
        await runtime.stop()
        await monitoring.stop()
    summary.goal_outcomes = outcomes
    failed = summary.status == "FAILURE" or any(o not in ("SUCCEEDED", "SUCCESS") for o in outcomes)
    return (summary, runtime), EXIT_TREE_FAILED if failed else EXIT_OK


HANDOFF_DONE = ("SUCCEEDED", "ABORTED", "REFUSED")


async def _send_goals(runtime: Any, goals: list[Pose2D], outcomes: list[str]) -> None:
    """Hand the goals to the tree one after the other.

    A tree that runs continuously and uses the goal hand-off (``{goal_status}``, like
    trees/autonomy.xml) gets each goal when the previous one is SUCCEEDED / ABORTED /
    REFUSED; a tree that completes per goal (like Nav2's, trees/navigation.xml) is run once
    per goal.
    """
    bb = runtime.tree.root_blackboard
    handoff = "goal_status" in _port_keys(runtime.tree)
    for goal in goals:
        bb.set("goal", goal)
        bb.set("goals", [goal])
        if handoff:
            bb.set("goal_status", "PENDING")
            while bb.get("goal_status", default="") not in HANDOFF_DONE:
                if runtime.completed.done():
                    outcomes.append(runtime.completed.result().name)
                    return
                await asyncio.sleep(0.05)
            outcomes.append(bb.get("goal_status"))
        else:
            done = runtime.completed if not runtime.completed.done() else runtime.restart_tree()
            outcomes.append((await done).name)
            if goal is not goals[-1]:
                runtime.restart_tree()


def _port_keys(tree: Any) -> set[str]:
    """Blackboard keys the tree's ports refer to (to see whether it uses the goal hand-off)."""
    from ..ports import blackboard_key

    keys = set()
    for node in tree.nodes():
        for name, raw in {**node.config.input_ports, **node.config.output_ports}.items():
            key = blackboard_key(raw, name) if isinstance(raw, str) else None
            if key:
                keys.add(key.lstrip("@"))
    return keys


def run(args: argparse.Namespace) -> int:
    from ..logging_setup import configure_logging
    from ..runtime.clock import run as run_loop

    tree_path = Path(args.tree)
    if not tree_path.is_file():
        print(f"error: tree file not found: {tree_path}", file=sys.stderr)
        return EXIT_USAGE
    log_file = None
    try:
        if args.log_json:
            configure_logging(json=True, stream=sys.stdout, level=args.log_level)
        elif args.log_file is not None:
            log_file = configure_logging(file=args.log_file, level=args.log_level)
        else:
            configure_logging(json=False, stream=sys.stderr, level="warning")
        config = load_config(args.config)
        try:
            registrations = node_registrations(args)
        except RegistrationError as exc:
            raise UsageError(str(exc)) from None
        show_progress = not args.no_progress and not args.log_json and sys.stderr.isatty()
        virtual = args.driver == "sim" and not args.realtime
        holder: dict[str, Any] = {}
        try:
            (summary, runtime), code = run_loop(
                _run_async(args, tree_path, config, registrations, show_progress, holder), virtual=virtual)
        except KeyboardInterrupt:
            if "summary" not in holder:
                print("interrupted", file=sys.stderr)
                return 130
            summary, runtime, code = holder["summary"], holder["runtime"], 130
            print("interrupted", file=sys.stderr)
    except UsageError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    finally:
        if log_file is not None:
            log_file.close()
    out = sys.stderr if args.log_json else sys.stdout
    with contextlib.suppress(BrokenPipeError):
        print(format_summary(summary, runtime), file=out)
    if args.summary_json is not None:
        args.summary_json.write_text(json.dumps(summary.__dict__, indent=2, default=str), encoding="utf-8")
    return code
