"""Lidar: the vectorised ray caster against brute force and against known geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim import Simulator
from sim.geometry import RayCaster
from sim.robot import load_profile
from sim.testing import Recorder, run_virtual
from sim.world import lidar_geometry, load_world, world_from_dict


def brute_force(edges, circles, ox, oy, angles, max_range):
    out = np.full(len(angles), np.inf)
    for i, a in enumerate(angles):
        ux, uy = math.cos(a), math.sin(a)
        best = np.inf
        for ax, ay, bx, by in edges:
            dx, dy = bx - ax, by - ay
            # one-sided: only edges whose front (right side) faces the sensor
            if dx * (oy - ay) - dy * (ox - ax) >= 0:
                continue
            den = ux * dy - uy * dx
            if abs(den) < 1e-12:
                continue
            t = ((ax - ox) * dy - (ay - oy) * dx) / den
            s = ((ax - ox) * uy - (ay - oy) * ux) / den
            if t >= 0 and -1e-9 <= s <= 1 + 1e-9:
                best = min(best, t)
        for cx, cy, r in circles:
            vx, vy = cx - ox, cy - oy
            b = vx * ux + vy * uy
            disc = r * r - (vx * vx + vy * vy - b * b)
            if disc >= 0 and b - math.sqrt(disc) >= 0:
                best = min(best, b - math.sqrt(disc))
        out[i] = best if best <= max_range else np.inf
    return out


def world(obstacles, spawn=(0.0, 0.0, 0.0)):
    return world_from_dict({
        "name": "t", "bounds": {"xmin": -10, "ymin": -10, "xmax": 10, "ymax": 10},
        "spawn": {"x": spawn[0], "y": spawn[1], "yaw": spawn[2]}, "obstacles": obstacles})


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.integers(0, 10_000), st.floats(-math.pi, math.pi))
def test_raycaster_matches_brute_force(seed, yaw):
    rng = np.random.default_rng(seed)
    obs = []
    for _ in range(rng.integers(1, 6)):
        cx, cy = rng.uniform(-4, 4, 2)
        if np.hypot(cx, cy) < 1.2:
            cx += 2.5
        kind = rng.integers(0, 3)
        if kind == 0:
            w, h, a = rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0), rng.uniform(0, math.pi)
            c, s = math.cos(a), math.sin(a)
            pts = [[cx + c * dx - s * dy, cy + s * dx + c * dy]
                   for dx, dy in ((-w, -h), (w, -h), (w, h), (-w, h))]
            obs.append({"type": "polygon", "points": pts})
        elif kind == 1:
            b = [cx + rng.uniform(-1, 1), cy + rng.uniform(-1, 1)]
            obs.append({"type": "segment", "a": [cx, cy], "b": b, "thickness": float(rng.choice([0.0, 0.1]))})
        else:
            obs.append({"type": "circle", "center": [cx, cy], "radius": float(rng.uniform(0.05, 0.6))})
    w = world(obs)
    edges, circles = lidar_geometry(w.obstacles)
    ox, oy = 0.0, 0.0
    if any(o.distance(ox, oy) <= 0 for o in w.obstacles):
        return
    rc = RayCaster(edges, circles)
    n, inc = 360, 2 * math.pi / 360
    got = rc.cast(ox, oy, yaw, n, 0.0, inc, 6.0)
    want = brute_force(edges, circles, ox, oy, yaw + inc * np.arange(n), 6.0)
    assert np.array_equal(np.isinf(got), np.isinf(want))
    both = np.isfinite(got)
    assert np.allclose(got[both], want[both], rtol=0, atol=1e-9)


def _scan_sim(obstacles, *, spawn=(0.0, 0.0, 0.0), seed=3, **lidar):
    profile = load_profile("burger", lidar={"x": 0.0, **lidar})
    return Simulator(world(obstacles, spawn), profile, seed=seed)


def _first_scan(sim):
    async def main():
        rec = Recorder(sim, ["scan"])
        await sim.start()
        await __import__("asyncio").sleep(0.45)
        await sim.stop()
        return rec["scan"]

    return run_virtual(main)


WALL_X2 = {"type": "polygon", "points": [[2, -5], [2.3, -5], [2.3, 5], [2, 5]]}


def test_beam_at_known_wall_reads_range_within_noise():
    sim = _scan_sim([WALL_X2])
    scans = _first_scan(sim)
    assert len(scans) == 2  # 5 Hz
    for scan in scans:
        assert scan.range_min == 0.12 and scan.range_max == 3.5 and len(scan.ranges) == 360
        assert abs(scan.ranges[0] - 2.0) < 4 * 0.01
        # beam k hits the wall at 2 / cos(k deg) while within range
        k = np.arange(-40, 41)
        expect = 2.0 / np.cos(np.radians(k))
        got = scan.ranges[k % 360]
        assert np.all(np.abs(got - expect) < 4 * 0.01)
        # behind the robot nothing is within 3.5 m: +inf
        assert np.all(np.isinf(scan.ranges[100:260])) and np.all(scan.ranges[100:260] > 0)
    assert scans[0].ranges[0] != scans[1].ranges[0]  # noise differs per scan


def test_noise_statistics():
    sim = _scan_sim([WALL_X2])
    sim.lidar.spec = sim.lidar.spec.model_copy(update={"noise_sigma": 0.01})
    errs = []
    for _ in range(30):
        r = sim.lidar.sample(0.0).ranges
        errs.append(r[0] - 2.0)
    assert 0.005 < np.std(errs) < 0.015 and abs(np.mean(errs)) < 0.006


def test_out_of_range_is_inf_and_too_close_is_neg_inf():
    far = {"type": "polygon", "points": [[3.6, -5], [3.9, -5], [3.9, 5], [3.6, 5]]}
    near = {"type": "circle", "center": [0, 0.21], "radius": 0.1}  # 0.11 m from the sensor
    sim = _scan_sim([far, near], seed=5)
    r = sim.lidar.sample(0.0).ranges
    assert np.isinf(r[0]) and r[0] > 0
    assert r[90] == -np.inf


@pytest.mark.parametrize("ob, beam, expect", [
    ({"type": "circle", "center": [0, 1.5], "radius": 0.25}, 90, 1.25),
    ({"type": "polygon", "points": [[-1, -2.2], [1, -2.2], [1, -1.8], [-1, -1.8]]}, 270, 1.8),
    ({"type": "segment", "a": [-1.5, -1], "b": [-1.5, 1], "thickness": 0.0}, 180, 1.5),
    ({"type": "segment", "a": [-1.5, -1], "b": [-1.5, 1], "thickness": 0.2}, 180, 1.4),
])
def test_beams_see_each_shape_kind(ob, beam, expect):
    sim = _scan_sim([ob])
    r = sim.lidar.sample(0.0).ranges
    assert abs(r[beam] - expect) < 0.04
    assert np.isfinite(r).sum() < 120


def test_body_only_obstacle_is_invisible_to_lidar():
    low = {"type": "polygon", "points": [[1, -0.5], [1.2, -0.5], [1.2, 0.5], [1, 0.5]],
           "blocks_lidar": False, "blocks_body": True}
    sim = _scan_sim([low, WALL_X2])
    r = sim.lidar.sample(0.0).ranges
    assert abs(r[0] - 2.0) < 0.04  # sees the wall behind the low plate


def test_lidar_offset_and_robot_yaw():
    # sensor 0.1 m ahead of the centre, robot facing +y: beam 0 travels along +y
    profile = load_profile("burger", lidar={"x": 0.1, "noise_sigma": 0.0})
    wall_y = {"type": "polygon", "points": [[-5, 2], [5, 2], [5, 2.3], [-5, 2.3]]}
    sim = Simulator(world([wall_y], spawn=(0, 0, math.pi / 2)), profile, seed=0)
    r = sim.lidar.true_ranges()
    assert r[0] == pytest.approx(1.9, abs=1e-9)
    assert r[180] == np.inf


def test_scan_in_the_apartment_is_fast_and_sane():
    sim = Simulator("apartment", "burger", seed=0)
    r = sim.lidar.true_ranges()
    assert np.isfinite(r).mean() > 0.5
    assert np.nanmin(r[np.isfinite(r)]) > 0.3  # spawn clearance
    import time

    t = time.perf_counter()
    for _ in range(50):
        sim.lidar.sample(0.0)
    per_scan = (time.perf_counter() - t) / 50
    assert per_scan < 0.003  # budget 0.3 ms; loose bound for slow CI machines


def test_dynamic_obstacles_update_the_raycaster():
    sim = Simulator(load_world("round_obstacles"), "burger", seed=0)
    before = sim.lidar.true_ranges()[0]
    name = sim.faults.block_corridor((-1.5, -1.0), (-1.5, 0.0), thickness=0.1)
    after = sim.lidar.true_ranges()[0]
    assert after < before and after == pytest.approx(0.45 + 0.032, abs=1e-6)
    sim.faults.remove_obstacle(name)
    assert sim.lidar.true_ranges()[0] == pytest.approx(before)
