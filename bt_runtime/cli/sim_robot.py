"""``python -m bt_runtime sim-robot``: the simulator as a ROS 2 robot on DDS.

Publishes the simulated robot's sensors (scan, imu, odom, amcl_pose, battery_state, bumper),
takes cmd_vel, serves Nav2's actions and costmap services from the Nav2 stand-in, lifecycle
services for its sensor drivers and Nav2 servers (the servers start unconfigured, as Nav2's do
before a lifecycle manager activates them, unless --nav-autostart) and the world on /map
(latched), on the wall clock, until interrupted. Drive it with
``python -m bt_runtime run TREE.xml --driver ros2`` or with your own ROS 2 stack (same
domain id). Needs the ``[ros2]`` extra (cyclonedds). See docs/ros2.md.
"""

from __future__ import annotations

import argparse
import sys

EXIT_OK, EXIT_USAGE = 0, 2


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("sim-robot", help="serve the simulator as a ROS 2 robot over DDS",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--world", default="apartment", help="apartment | round_obstacles | a world YAML file")
    p.add_argument("--robot", default="burger", help="burger | waffle | rosbot2 | a profile YAML file")
    p.add_argument("--domain", type=int, default=None, metavar="N",
                   help="DDS domain id (default: $ROS_DOMAIN_ID or 0)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--spawn", default=None, metavar="X,Y[,YAW]", help="start pose (default: the world's spawn)")
    p.add_argument("--namespace", default="", help="ROS namespace for every name")
    p.add_argument("--realtime", action="store_true",
                   help="accepted for symmetry with run: a DDS peer always runs on the wall clock")
    p.add_argument("--crash", action="append", default=[], metavar="COMPONENT@T",
                   help="crash a component T seconds after start (repeatable), e.g. lidar@3")
    p.add_argument("--cruise-speed", type=float, default=None, metavar="V",
                   help="the navigation stand-in's cruise speed (default 0.25 m/s)")
    p.add_argument("--goal-tolerance", type=float, default=None, metavar="M",
                   help="the navigator's xy goal tolerance (default 0.25 m, TurtleBot3's Nav2 file; "
                        "the project's scenarios use 0.1)")
    p.add_argument("--nav-autostart", action="store_true",
                   help="the Nav2 stand-in's lifecycle servers start active (as with nav2_lifecycle_manager "
                        "autostart); by default they start unconfigured and wait to be configured and activated")
    p.add_argument("--refuse-activate", action="append", default=[], metavar="NODE",
                   help="this lifecycle node's activation fails (it stays inactive; repeatable; for tests)")
    p.add_argument("--service-mapping", default="cyclonedds", choices=["cyclonedds", "rpc_basic"],
                   help="request ids of services/actions as rmw_cyclonedds_cpp (default) or DDS-RPC basic "
                        "(rmw_connextdds with RMW_CONNEXT_REQUEST_REPLY_MAPPING=basic); see docs/ros2.md")
    p.add_argument("--stamped-cmd-vel", action="store_true", help="cmd_vel is TwistStamped (Jazzy option)")
    p.add_argument("--loopback", action="store_true", help="DDS on 127.0.0.1 only (unless CYCLONEDDS_URI is set)")
    p.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds")
    p.add_argument("--log-level", default="warning", choices=["debug", "info", "warning", "error"])
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    import asyncio
    import os

    from ..logging_setup import configure_logging
    from ..runtime.messages import Pose2D

    try:
        from bt_runtime.runtime.ros2 import dds
        from sim.ros2_robot import SimRobot, parse_crash, run_sim_robot
    except ImportError as exc:
        print(f"error: sim-robot needs the [ros2] extra (pip install -e '.[ros2]'): {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        crashes = [parse_crash(c) for c in args.crash]
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    known = (*SimRobot.LIFECYCLE, *SimRobot.NAV_LIFECYCLE)
    unknown = [n for n in args.refuse_activate if n not in known]
    if unknown:
        print(f"error: --refuse-activate: no lifecycle node {', '.join(unknown)} (nodes: {', '.join(known)})",
              file=sys.stderr)
        return EXIT_USAGE
    spawn = None
    if args.spawn is not None:
        try:
            pose = Pose2D.from_string(args.spawn)
        except ValueError as exc:
            print(f"error: --spawn: {exc}", file=sys.stderr)
            return EXIT_USAGE
        spawn = (pose.x, pose.y, pose.yaw)
    domain = args.domain
    if domain is None:
        env = os.environ.get("ROS_DOMAIN_ID", "")
        domain = int(env) if env.isdigit() else 0
    if not 0 <= domain <= 232:
        print(f"error: --domain must be 0..232, got {domain}", file=sys.stderr)
        return EXIT_USAGE
    from sim.robot import ProfileError, load_profile
    from sim.world import WorldError, load_world

    try:  # a bad world or robot file is a usage error naming the file and field, not a traceback
        load_world(args.world)
        load_profile(args.robot)
    except (WorldError, ProfileError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    configure_logging(json=False, stream=sys.stderr, level=args.log_level)
    uri = dds.loopback_config() if args.loopback and not os.environ.get("CYCLONEDDS_URI") else None
    robot = SimRobot(args.world, args.robot, seed=args.seed, domain_id=domain, namespace=args.namespace,
                     crashes=crashes, cruise_speed=args.cruise_speed, stamped_cmd_vel=args.stamped_cmd_vel,
                     cyclonedds_uri=uri, goal_tolerance=args.goal_tolerance, nav_autostart=args.nav_autostart,
                     refuse_activate=args.refuse_activate, spawn=spawn, service_mapping=args.service_mapping)
    try:
        asyncio.run(run_sim_robot(robot, args.duration))
    except (FileNotFoundError, KeyError) as exc:
        print(f"error: cannot build the simulator: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        pass
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    """``python -m bt_runtime.cli.sim_robot`` (until the lead wires the subcommand)."""
    parser = argparse.ArgumentParser(prog="sim-robot")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    args = parser.parse_args(["sim-robot", *(sys.argv[1:] if argv is None else argv)])
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
