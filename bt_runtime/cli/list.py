"""``python -m bt_runtime list worlds|goals|robots|trees``: what ships, to pick ``run``'s arguments.

``goals`` lists the named goals of ``--world`` (default: the apartment), usable as
``run --goal NAME``. Distances in metres, angles in radians, speeds in m/s and rad/s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

KINDS = ("worlds", "goals", "robots", "trees")


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser("list", help="list the shipped worlds, a world's goals, robots, trees",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("kind", choices=KINDS)
    p.add_argument("--world", default="apartment", help="for 'goals': a world name or YAML file")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if args.kind == "worlds":
        from sim.world import WORLDS_DIR, load_world

        for path in sorted(WORLDS_DIR.glob("*.yaml")):
            world = load_world(path.stem)
            b = world.bounds
            print(f"{path.stem:<16} {b.width:.0f} x {b.height:.0f} m, {len(world.goals)} goals: "
                  f"{getattr(world, 'description', '') or ''}".rstrip())
    elif args.kind == "goals":
        from sim.world import load_world

        try:
            world = load_world(args.world)
        except (FileNotFoundError, KeyError, ValueError) as exc:
            print(f"error: --world {args.world}: {exc}")
            return 2
        print(f"spawn            x={world.spawn.x:+.2f} y={world.spawn.y:+.2f} yaw={world.spawn.yaw:+.2f} rad")
        for name, g in world.goals.items():
            print(f"{name:<16} x={g.x:+.2f} y={g.y:+.2f} yaw={g.yaw:+.2f} rad")
    elif args.kind == "robots":
        from sim.robot import SHIPPED_PROFILES, load_profile

        for name in SHIPPED_PROFILES:
            p = load_profile(name)
            print(f"{name:<10} radius {p.radius:.3f} m, max {p.max_linear:.2f} m/s, {p.max_angular:.2f} rad/s: "
                  f"{p.description}".rstrip())
    else:
        trees = Path(__file__).resolve().parents[2] / "trees"
        for path in sorted(trees.glob("*.xml")):
            print(path.relative_to(trees.parent))
    return 0
