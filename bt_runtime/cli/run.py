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
from pathlib import Path
from typing import Any

from ..errors import BehaviorTreeException
from ..runtime.messages import Pose2D
from .progress import ProgressLine, SharedConsole
from .registration import RegistrationError, add_registration_arguments
from .registration import registrations as node_registrations
from .run_goals import mark_unfinished, outcomes_for, send_goals, uses_goal_handoff
from .summary import EXIT_INTERRUPTED, EXIT_USAGE, format_summary, summary_dict, verdict
from .summary import EXIT_OK as EXIT_OK  # re-exported for callers

EXIT_TREE_FAILED = 1  # see summary.verdict: a goal not reached, FAILURE, or ticks that raised


class UsageError(Exception):
    """A bad command line or input file, reported without a traceback."""


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("run", help="run a tree with the autonomy layer (simulator by default)",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("tree", help="BehaviorTree.CPP v4 XML file")
    p.add_argument("--world", default="apartment", help="apartment | round_obstacles | a world YAML file")
    p.add_argument("--robot", default="burger", help="burger | waffle | rosbot2 | a profile YAML file")
    p.add_argument("--goal", action="append", default=[], metavar="X,Y[,YAW]",
                   help="goal pose in metres, YAW in radians (repeatable; write --goal=-1,2 for negative x) "
                        "or a goal name of the world; goals are handed to the tree one after the other")
    p.add_argument("--tree", dest="tree_id", default=None, metavar="ID",
                   help="the BehaviorTree ID to run (default: main_tree_to_execute, or the only tree)")
    p.add_argument("--png", type=Path, default=None, metavar="FILE",
                   help="draw the run at the end: map, trajectory, goals, collisions, faults, marks")
    p.add_argument("--ready-timeout", type=float, default=10.0, metavar="S",
                   help="wait up to S s (robot time) for every component to report before the tree "
                        "starts and gets its goals (default 10)")
    p.add_argument("--duration", type=positive_seconds, default=None, metavar="S",
                   help="stop after S seconds of robot time (default: when the tree completes)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--realtime", action="store_true", help="pace the simulation to the wall clock")
    p.add_argument("--driver", default="sim", choices=["sim", "ros2"])
    p.add_argument("--config", type=Path, default=None,
                   help="runtime configuration (YAML; `python -m bt_runtime config` prints every setting)")
    p.add_argument("--twist-mux", type=Path, default=None, metavar="FILE",
                   help="the gate's inputs and locks from a twist_mux parameter file (docs/twist_mux.example.yaml)")
    p.add_argument("--ros2-config", type=Path, default=None, metavar="FILE",
                   help="--driver ros2: topics, QoS, domain, Nav2 names, components (YAML, see docs/ros2.md)")
    p.add_argument("--loopback", action="store_true",
                   help="--driver ros2: DDS on 127.0.0.1 only, to reach a `sim-robot --loopback` on this machine")
    add_registration_arguments(p)
    p.add_argument("--collision-monitor", default=None, metavar="FILE|off",
                   help="safety zones from a Nav2 collision_monitor parameter file; 'off': none (default: "
                        "zones sized for the robot, docs/safety_zones.md)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="set a root blackboard entry before the first tick (repeatable)")
    p.add_argument("--log-json", action="store_true", help="structlog events as JSON lines on stdout")
    p.add_argument("--log-file", type=Path, default=None, help="structlog events (JSON lines) to this file")
    p.add_argument("--log-level", default="info", choices=["debug", "info", "warning", "error"])
    p.add_argument("--no-progress", action="store_true", help="no live progress line")
    p.add_argument("--summary-json", type=Path, default=None, help="write the run summary as JSON")
    from groot.cli import add_arguments as add_groot_arguments

    add_groot_arguments(p)
    from .recording import add_arguments as add_recording_arguments

    add_recording_arguments(p)
    p.set_defaults(func=run)
    return p


# ---------------------------------------------------------------------------------------------
# argument checking (clear errors, no tracebacks)
# ---------------------------------------------------------------------------------------------

def positive_seconds(text: str) -> float:
    """argparse type for durations: a finite number > 0 (nan, inf and -5 are refused)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


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


def load_config(path: Path | None, twist_mux: Path | None = None):
    from pydantic import ValidationError

    from ..runtime.config_file import ConfigError, load_runtime_config, plain_errors

    try:
        config = load_runtime_config(path)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    if twist_mux is not None:
        try:
            config.gate = config.gate.with_twist_mux(twist_mux)
        except ValueError as exc:  # TwistMuxFileError, or a ValidationError of the gate's settings
            if not isinstance(exc, ValidationError):
                raise UsageError(f"--twist-mux: {exc}") from None
            raise UsageError(f"--twist-mux {twist_mux}: "
                             + "; ".join(p.removeprefix("'(top level)': ") for p in plain_errors(exc))) from None
    return config


def with_collision_monitor(config, choice: str | None):
    """``config`` with ``--collision-monitor`` applied; the zones file is read now, so a bad one
    is a usage error naming the file and field rather than a failure at start."""
    from ..runtime.safety_zones_config import SafetyZonesConfigError, load_collision_monitor

    if choice is not None:
        update = {"enabled": False} if choice == "off" else {"enabled": True, "file": choice}
        config = config.model_copy(update={"safety_zones": config.safety_zones.model_copy(update=update)})
    zones = config.safety_zones
    if zones.enabled and zones.file is not None:
        try:
            load_collision_monitor(zones.file)
        except SafetyZonesConfigError as exc:
            raise UsageError(str(exc)) from None
    return config


def _profile(robot: str):
    """The robot profile named on the command line, or None if it cannot be read (then the
    ROS 2 config's own components and robot section stay as they are)."""
    try:
        from sim.robot import load_profile

        return load_profile(robot)
    except Exception:
        return None


def _robot_section(p) -> dict:
    """The ROS 2 config's ``robot:`` section (size, limits, power model, lidar mount) from a profile."""
    b = p.battery
    return {"radius": p.radius, "max_linear": p.max_linear, "max_angular": p.max_angular,
            "max_linear_accel": p.max_linear_accel, "max_angular_accel": p.max_angular_accel,
            "capacity_ah": b.capacity_ah, "voltage_nominal": (b.voltage_full + b.voltage_empty) / 2,
            "idle_power_w": b.idle_power_w, "k_linear": b.k_linear, "k_angular": b.k_angular,
            "lidar_x": p.lidar.x, "lidar_y": p.lidar.y}


def make_driver(args: argparse.Namespace):
    if args.driver == "ros2":
        try:
            from ..runtime.ros2 import Ros2Config, Ros2Driver  # provided by the [ros2] extra
            from ..runtime.ros2.config import RobotConfig
        except ImportError as exc:
            raise UsageError(f"--driver ros2 needs the [ros2] extra (pip install -e '.[ros2]'): {exc}") from None
        path = getattr(args, "ros2_config", None)
        try:
            config = Ros2Config.load(path) if path else Ros2Config()
        except ValueError as exc:  # names the file and field; no traceback
            raise UsageError(str(exc)) from None
        if getattr(args, "loopback", False):
            config.loopback_only = True
        profile = _profile(getattr(args, "robot", "burger"))
        if profile is not None and profile.bumper is None:
            config = config.without_components("bumper")  # e.g. the ROSbot 2.0 senses contacts by IMU
        if profile is not None and "robot" not in config.model_fields_set:
            # --robot sizes the layer (limits, footprint, zones) unless the file does
            config = config.model_copy(update={"robot": RobotConfig(**_robot_section(profile))})
        return Ros2Driver(config.with_environment())
    from sim.driver import SimDriver

    try:
        return SimDriver(args.world, args.robot, seed=args.seed)
    except (FileNotFoundError, KeyError, ValueError) as exc:
        raise UsageError(f"cannot build the simulator: {exc}") from None


# ---------------------------------------------------------------------------------------------
# the run
# ---------------------------------------------------------------------------------------------

async def _run_async(args: argparse.Namespace, tree_path: Path, config: Any, registrations: list,
                     console: SharedConsole | None, held: dict[str, Any]) -> None:
    """The run itself; everything the summary needs goes into ``held`` as it becomes known
    (so an interrupted run still reports what it did)."""
    from ..runtime.app import AutonomyRuntime
    from ..runtime.explain import FailureWitness
    from ..runtime.readiness import wait_until_reported

    driver = make_driver(args)
    runtime = AutonomyRuntime(driver, config, realtime=args.realtime or None, register=registrations)
    try:
        runtime.load_tree(tree_path, tree_id=args.tree_id)
    except BehaviorTreeException as exc:
        trees = runtime.factory.registered_behavior_trees()
        hint = (f"; pick the tree to run with --tree ID (trees: {', '.join(trees)})"
                if len(trees) > 1 and ("main_tree_to_execute" in str(exc) or args.tree_id) else "")
        raise UsageError(f"{exc}{hint}") from None
    world = getattr(getattr(driver, "sim", None), "world", None)
    goals = [parse_goal(g, world) for g in args.goal]
    bb = runtime.tree.root_blackboard
    dock = getattr(getattr(driver, "sim", None), "dock", None)
    if dock is not None:  # the simulated world's dock (configuration, as opennav_docking's dock database)
        bb.set("dock_pose", dock)
    for assignment in args.set:
        key, value = parse_assignment(assignment)
        bb.set(key, value)
    handoff = uses_goal_handoff(runtime.tree)
    outcomes = outcomes_for(goals)
    witness = FailureWitness.attach(runtime)
    picture = None
    if args.png is not None:
        from .run_picture import RunPicture

        picture = RunPicture.attach(runtime, args.world)
    held.update(runtime=runtime, goals=outcomes, witness=witness, handoff=handoff, picture=picture,
                notes=[], goal_poses=goals)
    progress = ProgressLine(runtime, console) if console is not None else None
    from .recording import RecordingError, start_recording

    try:
        recording = start_recording(args, runtime, driver)
    except RecordingError as exc:
        raise UsageError(str(exc)) from None
    from groot.cli import Monitoring, MonitoringError

    try:
        monitoring = await Monitoring.from_args(runtime.tree, args).start()
    except MonitoringError as exc:  # --btlog folder/extension, --groot port in use
        raise UsageError(str(exc)) from None
    await runtime.start(tick=False)
    progress_task = asyncio.get_running_loop().create_task(progress.run()) if progress else None
    t0 = runtime.clock()

    async def body() -> None:
        bringup = await asyncio.shield(runtime.bringup_task)  # Nav2's lifecycle nodes (--driver ros2)
        if bringup.failed:  # goals are refused (REJECTED, naming the node); the summary says why
            held["notes"].append(bringup.describe())
            _say(console, f"error: {bringup.describe()}")
        ready = (await wait_until_reported(runtime.supervisor, runtime.clock, args.ready_timeout)
                 if not bringup.failed else None)
        if ready is not None and not ready.ready:
            note = f"start-up: {ready.describe()} after {ready.waited:.1f} s; starting anyway"
            held["notes"].append(note)
            _say(console, f"warning: {note}")
        if goals:
            await send_goals(runtime, goals, outcomes, witness)
            return
        runtime.restart_tree()
        if handoff:
            hint = ("the tree is waiting for a goal: pass --goal X,Y[,YAW] (metres, radians)"
                    + (f" or a goal name ({', '.join(sorted(world.goals))})" if world is not None and world.goals
                       else ""))
            hint += _goal_serving_hint(runtime.driver)
            held["notes"].append(hint)
            _say(console, hint)
        await asyncio.shield(runtime.completed)

    try:
        remaining = None if args.duration is None else max(0.0, args.duration - (runtime.clock() - t0))
        await asyncio.wait_for(body(), remaining)
    except TimeoutError:
        pass
    finally:
        mark_unfinished(outcomes, runtime, witness, args.duration)
        client_notes = client_goal_notes(runtime.goals)
        if client_notes:  # goals from ROS clients: the summary says what became of them, not "waiting"
            held["notes"][:] = [n for n in held["notes"] if not n.startswith("the tree is waiting for a goal")]
            held["notes"].extend(client_notes)
        if progress_task is not None:
            progress_task.cancel()
            progress.maybe_print()
            progress.finish()
        held["summary"] = runtime.summary()
        await runtime.stop()
        witness.detach()
        await monitoring.stop()
        if recording.enabled:
            held["summary"].recording = recording.stop()


def client_goal_notes(intake) -> list[str]:
    """One line per goal from a ROS client (the NavigateToPose action, the goal topic) with its
    outcome; --goal's goals (``runtime.send_goal``, source "api") have summary lines of their own."""
    handles = [*intake.finished, *([intake.current] if intake.current is not None else []), *intake.queue]
    lines = []
    for h in sorted((h for h in handles if h.source != "api"), key=lambda h: h.id):
        r = h.result
        outcome = "not finished" if r is None else r.outcome + (f": {r.error_msg}" if r.error_msg else "")
        lines.append(f"goal from {h.source} ({h.pose.x:.2f}, {h.pose.y:.2f}, yaw {h.pose.yaw:.2f} rad): {outcome}")
    return lines


def _goal_serving_hint(driver) -> str:
    """Where a ROS 2 client can send goals (--driver ros2), for the waiting-for-a-goal hint."""
    goals = getattr(getattr(driver, "config", None), "goals", None)
    if goals is None or not goals.enabled:
        return ""
    ns = driver.config.namespace.strip("/")
    names = [f"{name} ({kind})" for name, kind in ((goals.action, "NavigateToPose action"),
                                                   (goals.topic, "PoseStamped, RViz's 2D Goal Pose")) if name]
    return "; or send one to " + " or ".join(n if n.startswith("/") else f"/{ns + '/' if ns else ''}{n}"
                                             for n in names)


def _say(console: SharedConsole | None, text: str) -> None:
    """A message for the person at the terminal (never over the progress line)."""
    (console or sys.stderr).write(text + "\n")


def _last_error(runtime: Any) -> str | None:
    """The error of the tick loop's last tick, if that tick raised (with the node's path)."""
    loop = runtime.tick_loop
    exc = getattr(loop, "last_error", None) if loop is not None else None
    if exc is None or loop.status.name != "IDLE":
        return None
    path = getattr(exc, "node_path", None)
    return f"{type(exc).__name__} in {path}: {exc}" if path else f"{type(exc).__name__}: {exc}"


def run(args: argparse.Namespace) -> int:
    from ..logging_setup import configure_logging
    from ..runtime.clock import run as run_loop

    tree_path = Path(args.tree)
    if not tree_path.is_file():
        print(f"error: tree file not found: {tree_path}", file=sys.stderr)
        return EXIT_USAGE
    log_file = None
    show_progress = not args.no_progress and not args.log_json and sys.stderr.isatty()
    console = SharedConsole(sys.stderr) if show_progress else None
    held: dict[str, Any] = {}
    interrupted = False
    try:
        if args.log_json:
            configure_logging(json=True, stream=sys.stdout, level=args.log_level)
        elif args.log_file is not None:
            log_file = configure_logging(file=args.log_file, level=args.log_level)
        else:
            configure_logging(json=False, stream=console or sys.stderr, level="warning")
        config = with_collision_monitor(load_config(args.config, getattr(args, "twist_mux", None)),
                                        args.collision_monitor)
        try:
            registrations = node_registrations(args)
        except RegistrationError as exc:
            raise UsageError(str(exc)) from None
        virtual = args.driver == "sim" and not args.realtime
        try:
            run_loop(_run_async(args, tree_path, config, registrations, console, held), virtual=virtual,
                     signals=True)  # SIGTERM/SIGINT/SIGHUP end like Ctrl-C: through runtime.stop()
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            if "summary" not in held:
                return EXIT_INTERRUPTED
            interrupted = True
    except UsageError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    finally:
        if log_file is not None:
            log_file.close()
    return report(args, held, interrupted)


def notes_to_print(notes: list[str], result) -> list[str]:
    """The run's notes less those the result line already says (a refused bring-up was
    printed on the result line and again as a note)."""
    return [n for n in notes if n not in result.reasons]


def report(args: argparse.Namespace, held: dict[str, Any], interrupted: bool) -> int:
    """Print the summary, write --summary-json and --png; the exit code."""
    runtime, summary, goals = held["runtime"], held["summary"], held["goals"]
    last_error = _last_error(runtime)
    result = verdict(summary, goals, last_error, interrupted)
    summary.goal_outcomes = [g.outcome for g in goals]
    extra = notes_to_print(held["notes"], result)
    if summary.tick_errors:
        why = held["witness"]
        extra.append(f"tick errors: {summary.tick_errors}"
                     + (f"; last: {last_error}" if last_error else "")
                     + (f"; last failing node {why.last_node_failure().path}" if why.last_node_failure() else ""))
    if held.get("picture") is not None:
        title = f"{Path(args.tree).name} on {args.world}: " + (", ".join(
            f"goal {i} {g.outcome}" for i, g in enumerate(goals)) or "no goal")
        try:
            png = held["picture"].write(args.png, held["goal_poses"], title)
            extra.append(f"picture: {png}")
        except Exception as exc:  # a picture that cannot be drawn must not hide the summary
            extra.append(f"picture not written: {exc}")
    if getattr(summary, "recording", None):
        from .recording import format_report

        extra.append(format_report(summary.recording))
    out = sys.stderr if args.log_json else sys.stdout
    with contextlib.suppress(BrokenPipeError):
        print(format_summary(summary, runtime, goals, result, uses_goal_handoff=held["handoff"], extra=extra),
              file=out)
    if args.summary_json is not None:
        data = summary_dict(summary, goals, result, notes=held["notes"], last_error=last_error)
        args.summary_json.write_text(json.dumps(data, indent=2, default=str), encoding="utf-8")
    return result.code
