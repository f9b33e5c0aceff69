"""Benchmarks of the Nav2 stand-in (sim/nav): planning, costmap updates, control.

    python bench/nav.py            # uses shared/reference/worlds if present, else a synthetic map
    python bench/nav.py --quick    # fewer repetitions

Prints median / p95 wall times for
  * planning in the TurtleBot3 house (~16 x 12 m at 0.05 m, 77k cells): a new goal (builds the
    heuristic field), a replan to the same goal (cached), a replan after noisy scans have been
    integrated into the global costmap (A*), a replan around a blocking obstacle (detour), and
    the compiled whole-grid Dijkstra for comparison;
  * one scan (360 beams) integrated into the local (3 x 3 m) and the global costmap;
  * one Regulated Pure Pursuit step;
  * an end-to-end navigation with the kinematic test robot (sim seconds per wall second).
"""

from __future__ import annotations

import argparse
import asyncio
import math
import statistics
import sys
import time
from pathlib import Path as FsPath

import numpy as np

ROOT = FsPath(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from nav_fixture import HOUSE, KinematicRobot, small_world  # noqa: E402

from bt_runtime.runtime.clock import run  # noqa: E402
from bt_runtime.runtime.messages import LaserScan, Pose2D, Twist  # noqa: E402
from sim.bus import Bus  # noqa: E402
from sim.nav.controller import GoalChecker, NoValidControl, RegulatedPurePursuit  # noqa: E402
from sim.nav.costmap import GlobalCostmap, LocalCostmap  # noqa: E402
from sim.nav.occupancy import OccupancyGrid  # noqa: E402
from sim.nav.params import NavParams, RobotParams  # noqa: E402
from sim.nav.planner import GridPlanner  # noqa: E402
from sim.nav.stack import NavStack  # noqa: E402

# rooms of the TurtleBot3 house (map frame == Gazebo world frame)
HOUSE_POINTS = {
    "west_wing": (-6.3, -1.5), "nw_room": (-4.0, 3.5), "nw_corner": (-6.5, 2.2),
    "mid_room": (1.2, 3.0), "ne_room": (6.5, 1.0), "ne_shelf": (3.2, 4.5),
    "east_wing": (5.5, -4.3), "east_door": (6.2, -1.0), "yard": (-2.0, -0.5),
    "yard_south": (0.0, -3.0), "corridor": (-3.0, 0.4),
}
HOUSE_QUERIES = [("yard", "ne_room"), ("west_wing", "east_wing"), ("nw_room", "mid_room"),
                 ("mid_room", "east_door"), ("nw_corner", "yard_south"), ("ne_shelf", "west_wing"),
                 ("corridor", "ne_shelf"), ("east_wing", "nw_room")]


def stats(samples: list[float]) -> str:
    ms = sorted(s * 1e3 for s in samples)
    p95 = ms[min(len(ms) - 1, int(math.ceil(0.95 * len(ms))) - 1)]
    return f"median {statistics.median(ms):7.3f} ms   p95 {p95:7.3f} ms   (n={len(ms)})"


def timed(fn, *args):
    t = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - t, out


def scan_at(world: OccupancyGrid, pose: Pose2D, rng, noise: float = 0.01) -> LaserScan:
    angles = np.linspace(0.0, 2 * math.pi, 360, endpoint=False)
    r = world.raycast(pose.x, pose.y, angles + pose.yaw, 3.5, step=world.resolution / 2)
    r = r + rng.normal(0.0, noise, r.shape)
    return LaserScan(0.0, 0.0, 2 * math.pi / 360, 0.12, 3.5, r)


def bench_planner(world: OccupancyGrid, points: dict, queries: list, reps: int) -> None:
    rng = np.random.default_rng(0)
    cm = GlobalCostmap(world, 0.1)
    planner = GridPlanner(cm)
    P = {k: Pose2D(*v) for k, v in points.items() if cm.cost_at(*v) < 253}
    qs = [(P[a], P[b]) for a, b in queries if a in P and b in P]
    first, cached, noisy, detour, compiled = [], [], [], [], []
    methods = {"noisy": {}, "detour": {}}
    lengths = []
    for s, g in qs:
        planner._heuristics.clear()
        dt, res = timed(planner.plan, s, g)
        assert res.ok, res.message
        first.append(dt)
        lengths.append(float(np.hypot(*np.diff(res.points[:, :2], axis=0).T).sum()))
        for _ in range(reps):
            cached.append(timed(planner.plan, s, g)[0])
        # replans from along the path after scans along it were integrated (noise: 1 cm)
        pts = res.points
        for i in np.linspace(0, len(pts) - 1, min(reps, 10)).astype(int):
            pose = Pose2D(pts[i, 0], pts[i, 1], pts[i, 2])
            cm.update_from_scan(scan_at(world, pose, rng), pose)
            dt, r2 = timed(planner.plan, pose, g)
            noisy.append(dt)
            methods["noisy"][r2.method] = methods["noisy"].get(r2.method, 0) + 1
        # a sensed obstacle across the path (a box the map does not know): seen from ~1 m
        # before it, then replans from successive poses while driving on (detour)
        mid_i = len(pts) // 2
        mid = pts[mid_i]
        blocked_world = OccupancyGrid.from_shapes((), [(mid[0], mid[1], 0.45)], (),
                                                  bounds=world.bounds, resolution=world.resolution)
        blocked_world.data[:] = np.maximum(world.data, blocked_world.data)
        cm.clear()
        back = max(mid_i - 20, 0)
        for j in range(6):
            i = max(back - 3 * j, 0)
            pose = Pose2D(pts[i, 0], pts[i, 1], pts[i, 2])
            cm.update_from_scan(scan_at(blocked_world, pose, rng), pose)
            dt, r3 = timed(planner.plan, pose, g)
            detour.append(dt)
            key = r3.method or r3.error_code.name
            methods["detour"][key] = methods["detour"].get(key, 0) + 1
        saved = planner.params.max_python_expansions
        planner.params.max_python_expansions = 1
        planner._learned.clear()
        compiled.append(timed(planner.plan, s, g)[0])
        planner.params.max_python_expansions = saved
        cm.clear()
    print(f"planner ({world.width}x{world.height} cells, {len(qs)} queries, "
          f"path length {min(lengths):.1f}..{max(lengths):.1f} m)")
    print(f"  new goal (heuristic field)  {stats(first)}")
    print(f"  replan, same goal (cached)  {stats(cached)}")
    print(f"  replan after noisy scans    {stats(noisy)}   routes {methods['noisy']}")
    print(f"  replan around a sensed box  {stats(detour)}   routes {methods['detour']}")
    print(f"  compiled Dijkstra only      {stats(compiled)}")


def bench_costmaps(world: OccupancyGrid, points: dict, reps: int) -> None:
    rng = np.random.default_rng(1)
    cm = GlobalCostmap(world, 0.1)
    lc = LocalCostmap(cm, 0.1)
    poses = [Pose2D(x, y, 0.3 * i) for i, (x, y) in enumerate(points.values()) if cm.cost_at(x, y) < 253]
    scans = [(p, scan_at(world, p, rng)) for p in poses]
    loc, glob = [], []
    for _ in range(reps):
        for p, sc in scans:
            loc.append(timed(lc.update, p, sc)[0])
            glob.append(timed(cm.update_from_scan, sc, p)[0])
    print("costmap update per scan (360 beams, 1 cm noise)")
    print(f"  local 3x3 m (clear, mark, inflate)   {stats(loc)}")
    print(f"  global (clear, mark, re-inflate)     {stats(glob)}")
    t, _ = timed(cm.clear)
    print(f"  global clear (full re-inflation)     {t * 1e3:7.3f} ms")


def bench_controller(world: OccupancyGrid, points: dict, queries: list, reps: int) -> None:
    rng = np.random.default_rng(2)
    cm = GlobalCostmap(world, 0.1)
    lc = LocalCostmap(cm, 0.1)
    params = NavParams()
    rpp = RegulatedPurePursuit(params.controller, RobotParams(), lc)
    planner = GridPlanner(cm)
    a, b = queries[0]
    res = planner.plan(Pose2D(*points[a]), Pose2D(*points[b]))
    rpp.set_plan(res.points)
    gc = GoalChecker()
    samples = []
    collisions = 0
    pts = res.points
    for i in range(0, len(pts) - 1, max(1, len(pts) // (reps * 4))):
        pose = Pose2D(pts[i, 0] + 0.03, pts[i, 1] - 0.02, pts[i, 2] + 0.1)
        lc.update(pose, scan_at(world, pose, rng))
        for _ in range(5):
            t = time.perf_counter()
            try:
                rpp.compute(pose, Twist(0.25, 0.0), gc)
            except NoValidControl:  # the offset pose can aim at a door frame: still a step
                collisions += 1
            samples.append(time.perf_counter() - t)
    print(f"controller: Regulated Pure Pursuit step   {stats(samples)}   "
          f"({collisions} steps found a collision ahead)")


def bench_end_to_end(world: OccupancyGrid, start: Pose2D, goal: Pose2D) -> None:
    async def main():
        bus = Bus()
        robot = KinematicRobot(bus, world, start, scan_noise=0.01).start()
        nav = NavStack(bus, world)
        await nav.start()
        await asyncio.sleep(0.5)
        loop = asyncio.get_running_loop()
        t0, w0 = loop.time(), time.perf_counter()
        result = await nav.navigate_to_pose(goal)
        sim, wall = loop.time() - t0, time.perf_counter() - w0
        await nav.stop()
        await robot.stop()
        return result, sim, wall, robot.pose.distance_to(goal)

    async def robot_only(duration: float):
        bus = Bus()
        robot = KinematicRobot(bus, world, start, scan_noise=0.01).start()
        bus.subscribe("scan", lambda _m: None)
        loop = asyncio.get_running_loop()
        w0 = time.perf_counter()
        t_end = loop.time() + duration
        while loop.time() < t_end:  # a command stream like the controller's (20 Hz)
            bus.publish("nav_cmd_vel", Twist(0.0, 0.0))
            await asyncio.sleep(0.05)
        wall = time.perf_counter() - w0
        await robot.stop()
        return wall

    result, sim, wall, err = run(main())
    fixture = run(robot_only(sim))
    nav = max(wall - fixture, 1e-9)
    print(f"end to end: navigate_to_pose with the kinematic robot (100 Hz physics, 5 Hz scans): "
          f"{result.status.value}, {sim:.1f} sim s in {wall:.2f} wall s = {sim / wall:.0f}x real time, "
          f"final error {err:.2f} m")
    print(f"  of which the test robot alone takes {fixture:.2f} s: the navigation stack runs at "
          f"~{sim / nav:.0f}x real time ({nav / sim * 1e3:.1f} ms of CPU per simulated second)")


def main() -> None:
    from bt_runtime.logging_setup import quiet_logging

    quiet_logging("error")
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    reps = 5 if args.quick else 20
    if HOUSE.exists():
        world = OccupancyGrid.load(HOUSE)
        points, queries = HOUSE_POINTS, HOUSE_QUERIES
        e2e = (Pose2D(-6.3, -1.5, 0.0), Pose2D(5.5, -4.3, 0.0))
        print(f"map: {HOUSE.name}")
    else:
        world = small_world()
        points = {"a": (1.0, 1.0), "b": (7.0, 5.0), "c": (1.0, 5.0), "d": (7.0, 0.6), "e": (3.0, 2.0)}
        queries = [("a", "b"), ("c", "d"), ("e", "b"), ("b", "c")]
        e2e = (Pose2D(1.0, 1.0, 0.0), Pose2D(7.0, 5.0, 0.0))
        print("map: synthetic 8 x 6 m (shared/reference not found)")
    bench_planner(world, points, queries, reps)
    bench_costmaps(world, points, reps)
    bench_controller(world, points, queries, reps)
    bench_end_to_end(world, *e2e)


if __name__ == "__main__":
    main()
