"""Cost of the gate's safety zones (bt_runtime/runtime/safety_zones.py): per scan and per command.

A scan is turned into base-frame points and counted against every static zone once
(``on_scan``); a command then costs a lookup plus, for an approach zone, one vectorised forward
simulation of the points within reach (cached per scan and command, so the gate's 100 Hz
republishing of an unchanged command is a dictionary hit). Scans are synthetic rooms (walls
0.3-2 m away, seeded); commands sweep speeds and turn rates so the cache cannot help, and a
second figure repeats one command as the gate does between scans.

Figures are CPU time (time.process_time), median of --repeat repetitions with the range.
For scale: Nav2's collision_monitor publishes ~4-5 ms per cycle for a 360-beam scan (C++).

Run: python bench/safety_zones.py [--repeat N] [--robot burger|rosbot2]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from bt_runtime.logging_setup import configure_logging
from bt_runtime.runtime.messages import LaserScan, RobotInfo, Twist
from bt_runtime.runtime.safety_zones import SafetyZones
from bt_runtime.runtime.safety_zones_config import default_config

ROBOTS = {"burger": RobotInfo(), "rosbot2": RobotInfo(radius=0.155, max_linear=0.9, max_angular=3.0,
                                                      max_angular_accel=4.0, lidar_x=0.02)}


def room_scan(rng: np.random.Generator, beams: int, stamp: float) -> LaserScan:
    """A box room around the robot (each wall 0.3-2 m away), some beams NaN or beyond range."""
    angles = 2 * math.pi * np.arange(beams) / beams
    walls = rng.uniform(0.3, 2.0, 4)  # +x, +y, -x, -y
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, walls[0] / c, np.where(c < 0, -walls[2] / c, np.inf))
        ty = np.where(s > 0, walls[1] / s, np.where(s < 0, -walls[3] / s, np.inf))
    ranges = np.minimum(tx, ty) + rng.normal(0, 0.01, beams)
    ranges[rng.random(beams) < 0.05] = np.nan
    return LaserScan(stamp, 0.0, 2 * math.pi / beams, 0.12, 3.5, ranges)


def per_call(fn, calls: int, repeat: int) -> tuple[float, float, float]:
    """(median, min, max) microseconds of CPU per call of ``fn(i)``."""
    samples = []
    for _ in range(repeat):
        t0 = time.process_time()
        for i in range(calls):
            fn(i)
        samples.append((time.process_time() - t0) / calls * 1e6)
    return statistics.median(samples), min(samples), max(samples)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--robot", default="rosbot2", choices=sorted(ROBOTS))
    args = ap.parse_args()
    robot = ROBOTS[args.robot]
    configure_logging(json=False, stream=sys.stderr, level="warning")  # zone changes log at info
    rng = np.random.default_rng(2026)
    print(f"safety zones (defaults for {args.robot}: stop ring, slowdown box, approach footprint "
          f"{default_config(robot).zones['FootprintApproach'].time_before_collision:g} s / 0.05 s steps)")
    print(f"{'':34s}{'median us':>10s}  {'range':>15s}")
    for beams in (360, 720):
        zones = SafetyZones.for_robot(robot, default_config(robot), clock=lambda: 0.0)
        scans = [room_scan(rng, beams, 0.0) for _ in range(50)]
        speeds = rng.uniform(-0.3, robot.max_linear, 997)
        turns = rng.uniform(-1.5, 1.5, 997)

        def scan_once(i, zones=zones, scans=scans):
            zones.on_scan(scans[i % len(scans)])

        def fresh_command(i, zones=zones, scans=scans, speeds=speeds, turns=turns):
            if i % 10 == 0:
                zones.on_scan(scans[(i // 10) % len(scans)])  # a new scan every 10 commands
            zones.filter(Twist(float(speeds[i % 997]), float(turns[i % 997])), 0.0)

        def same_command(i, zones=zones):
            zones.filter(Twist(0.25, 0.1), 0.0)

        zones.on_scan(scans[0])
        rows = [(f"{beams} beams: per scan (on_scan)", per_call(scan_once, 500, args.repeat)),
                (f"{beams} beams: per new command", per_call(fresh_command, 2000, args.repeat)),
                (f"{beams} beams: per repeated command", per_call(same_command, 5000, args.repeat))]
        for label, (med, lo, hi) in rows:
            print(f"{label:34s}{med:10.1f}  {lo:7.1f}-{hi:7.1f}")
        if beams == 360:
            scan_us, cmd_us = rows[0][1][0], rows[1][1][0]
    # a 10 Hz lidar and a gate publishing at 100 Hz, every command a new one (the worst case)
    share = (10 * scan_us + 100 * cmd_us) / 1e6 * 100
    print(f"360 beams at 10 Hz + 100 new commands/s: {share:.2f} % of one core (worst case)")

if __name__ == "__main__":
    main()
