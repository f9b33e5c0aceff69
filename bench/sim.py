"""Simulator speed: real-time factor of a drive across the apartment on virtual time.

    python bench/sim.py [--seconds 60] [--robot burger] [--seed 0] [--json]

Drives the robot from the front yard through the front door, the east room and the study
(and back, and again, until the time is up) with the Nav2 stand-in (planner replanning at
1 Hz, Regulated Pure Pursuit at 20 Hz, costmaps from the scans), physics at 100 Hz and every
sensor at its profile rate, and prints the real-time factor with a breakdown from
perf_counter accounting: physics (pymunk), lidar (ray casting + noise), other sim work
(drivers, IMU/odom/battery integration, contacts, recording), planning, control, and the rest
(event loop, costmap updates, subscribers). ``--scripted`` drives with a waypoint follower on
ground truth instead (the simulator's own share). Also prints micro-benchmarks: lidar ms/scan
and physics µs/step. Target (issue #3): >= 100x real time on one core.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bt_runtime.runtime.clock import run  # noqa: E402
from sim import Simulator  # noqa: E402
from sim.scripted import WaypointFollower  # noqa: E402

# yard -> east of the mailbox -> front door -> corridor -> east room -> study door -> study
APARTMENT_ROUTE = [(1.3, -1.2), (1.3, 0.4), (3.2, 0.4), (3.2, 4.6), (1.1, 4.6), (1.1, 2.0)]


class Patrol:
    """Follow the route, then back, and so on, until the time is up."""

    def __init__(self, sim: Simulator, route, speed: float) -> None:
        self.sim = sim
        self.route = list(route)
        self.speed = speed

    async def run(self, timeout: float) -> None:
        loop = asyncio.get_running_loop()
        end = loop.time() + timeout
        back = [(self.sim.spawn.x, self.sim.spawn.y), *self.route[:-1]][::-1]
        legs = [self.route, back]
        i = 0
        while loop.time() < end - 1e-9:
            follower = WaypointFollower(self.sim, legs[i % 2], speed=self.speed)
            await follower.run(timeout=end - loop.time())
            i += 1


def scripted(sim: Simulator):
    return Patrol(sim, APARTMENT_ROUTE, speed=min(sim.profile.max_linear, 0.3))


class NavPatrol:
    """The Nav2 stand-in drives the route (planner at 1 Hz while following, controller at
    20 Hz); its commands go straight to the base, as in a plain Nav2 setup."""

    def __init__(self, sim: Simulator, route) -> None:
        from sim.driver import occupancy_from_world, robot_params_for
        from sim.nav import NavStack

        self.sim = sim
        self.route = list(route)
        self.nav = NavStack(sim.bus, occupancy_from_world(sim), robot=robot_params_for(sim))
        sim.subscribe("nav_cmd_vel", lambda t: sim.command(t.linear, t.angular))
        self.timing = {"planning": 0.0, "control": 0.0}
        _time_calls(self.nav.planner, "plan", self.timing, "planning")
        _time_calls(self.nav.controller, "compute", self.timing, "control")

    async def run(self, timeout: float) -> None:
        from bt_runtime.runtime.messages import Pose2D

        loop = asyncio.get_running_loop()
        end = loop.time() + timeout
        await self.nav.start()
        while self.sim.bus.latest("pose") is None:  # as Nav2 waits for AMCL's first pose
            await asyncio.sleep(0.05)
        back = [(self.sim.spawn.x, self.sim.spawn.y), *self.route[:-1]][::-1]
        legs = [self.route, back]
        i = 0
        while loop.time() < end - 1e-9:
            for x, y in legs[i % 2]:
                handle = self.nav.navigate_to_pose(Pose2D(x, y))
                try:
                    await asyncio.wait_for(asyncio.shield(asyncio.ensure_future(handle._wait())),
                                           max(0.0, end - loop.time()))
                except TimeoutError:
                    handle.cancel()
                    break
                if not handle.result().succeeded:
                    await asyncio.sleep(0.5)  # never spin on a leg that fails at once
            i += 1
        await self.nav.stop()


def _time_calls(obj, name: str, timing: dict, key: str) -> None:
    inner = getattr(obj, name)

    def timed(*args, **kwargs):
        t = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            timing[key] += time.perf_counter() - t

    setattr(obj, name, timed)


def navigated(sim: Simulator):
    return NavPatrol(sim, APARTMENT_ROUTE)


def drive(seconds: float, *, robot: str = "burger", seed: int = 0, world: str = "apartment",
          make_driver=navigated) -> dict:
    sim = Simulator(world, robot, seed=seed)
    counts: dict[str, int] = {}
    for topic in ("scan", "imu", "odom", "pose", "battery", "bumper", "ground_truth"):
        sim.subscribe(topic, lambda m, t=topic: counts.__setitem__(t, counts.get(t, 0) + 1))

    driver = make_driver(sim)

    cpu = [0.0]  # this thread's CPU seconds for the drive (the wall time also counts other processes')

    async def main() -> tuple[float, float]:
        await sim.start()
        t0, c0 = time.perf_counter(), time.thread_time()
        await driver.run(timeout=seconds)
        wall = time.perf_counter() - t0
        cpu[0] = time.thread_time() - c0
        elapsed = sim.now - sim.t0
        await sim.stop()
        return wall, elapsed

    wall, seconds = run(main, virtual=True)
    tr = sim.trajectory()
    dist = float(sum(math.hypot(*d) for d in zip(tr[1:, 1] - tr[:-1, 1], tr[1:, 2] - tr[:-1, 2])))
    step_s = sim.perf["step_s"]
    physics_s = sim.perf["physics_s"]
    lidar_s = sim.lidar.cast_time
    return {
        "world": world, "robot": robot, "seed": seed, "sim_seconds": seconds, "wall_seconds": wall,
        "rtf": seconds / wall, "cpu_rtf": seconds / max(cpu[0], 1e-9), "distance_m": dist, "collisions": len(sim.events_of("collision")),
        "steps": sim.perf["steps"], "scans": sim.lidar.casts, "messages": counts,
        "breakdown_s": {"physics": physics_s, "lidar": lidar_s, "other_sim": step_s - physics_s - lidar_s,
                        **getattr(driver, "timing", {}),
                        "loop_and_rest": wall - step_s - sum(getattr(driver, "timing", {}).values())},
        "physics_us_per_step": physics_s / max(sim.perf["steps"], 1) * 1e6,
        "lidar_ms_per_scan": lidar_s / max(sim.lidar.casts, 1) * 1e3,
        "sim_share_rtf": seconds / step_s,
    }


def lidar_microbench(world: str = "apartment", robot: str = "burger", n: int = 400) -> dict:
    """ms per scan (cast + noise) at poses spread over the world's free space."""
    sim = Simulator(world, robot, seed=0)
    poses = [sim.world.spawn, *sim.world.goals.values()]
    times = []
    for p in poses:
        sim.physics.teleport(p.x, p.y, p.yaw)
        sim.lidar.sample(0.0)  # warm
        t = time.perf_counter()
        for _ in range(n // len(poses) + 1):
            sim.lidar.sample(0.0)
        times.append((time.perf_counter() - t) / (n // len(poses) + 1))
    return {"mean_ms": 1e3 * sum(times) / len(times), "max_ms": 1e3 * max(times)}


def physics_microbench(robot: str = "burger", steps: int = 20000) -> float:
    sim = Simulator("apartment", robot, seed=0)
    phys = sim.physics
    t = time.perf_counter()
    for _ in range(steps):  # circles of 0.67 m radius around the spawn pose: free space
        phys.step(0.2, 0.3, 0.01)
    return (time.perf_counter() - t) / steps * 1e6


def main(argv: list[str] | None = None) -> None:
    from bt_runtime.logging_setup import quiet_logging

    quiet_logging("error")
    ap = argparse.ArgumentParser(description="simulator real-time factor")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--robot", default="burger")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3, help="best of N runs")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--scripted", action="store_true",
                    help="drive with the scripted waypoint follower instead of the Nav2 stand-in "
                         "(the simulator's own share)")
    args = ap.parse_args(argv)
    make = scripted if args.scripted else navigated
    runs = [drive(args.seconds, robot=args.robot, seed=args.seed, make_driver=make) for _ in range(args.repeat)]
    best = min(runs, key=lambda r: r["wall_seconds"])
    best["lidar_microbench"] = {w: lidar_microbench(w, args.robot) for w in ("apartment", "round_obstacles")}
    best["physics_microbench_us_per_step"] = physics_microbench(args.robot)
    if args.json:
        print(json.dumps(best, indent=2))
        return
    b = best["breakdown_s"]
    wall = best["wall_seconds"]
    print(f"{args.seconds:.0f} s drive across the apartment ({args.robot}, seed {args.seed}), "
          f"best of {args.repeat}: {wall * 1e3:.1f} ms wall -> real-time factor {best['rtf']:.0f}x")
    print(f"  driven {best['distance_m']:.2f} m, {best['collisions']} collisions, "
          f"{best['steps']} physics steps, {best['scans']} scans, messages {best['messages']}")
    for k, v in b.items():
        print(f"  {k:16s} {v * 1e3:8.1f} ms  {100 * v / wall:5.1f} %")
    print(f"  simulator alone (physics + sensors + recording): {best['sim_share_rtf']:.0f}x real time")
    print(f"  physics {best['physics_us_per_step']:.1f} us/step in the run, "
          f"{best['physics_microbench_us_per_step']:.1f} us/step alone")
    for w, m in best["lidar_microbench"].items():
        print(f"  lidar {w}: {m['mean_ms']:.3f} ms/scan mean, {m['max_ms']:.3f} max "
              f"(in the run {best['lidar_ms_per_scan']:.3f})")


if __name__ == "__main__":
    main()
