"""World files and robot profiles: validation, the shipped worlds, the converter."""

from __future__ import annotations

import math
from collections import deque
from pathlib import Path

import numpy as np
import pytest
import yaml

from sim.robot import SHIPPED_PROFILES, ProfileError, load_profile
from sim.world import SHIPPED_WORLDS, WorldError, load_world, world_from_dict
from sim.worlds.build_worlds import build_apartment, build_round_obstacles, dump, find_shared
from tests.paths import ROOT

SHARED = find_shared()
needs_shared = pytest.mark.skipif(SHARED is None, reason="../shared (reference data) is absent")


def small_world(**over):
    data = {
        "name": "box",
        "bounds": {"xmin": -3, "ymin": -3, "xmax": 3, "ymax": 3},
        "spawn": {"x": 0, "y": 0},
        "obstacles": [
            {"type": "polygon", "points": [[2, -2], [2.2, -2], [2.2, 2], [2, 2]]},
            {"type": "segment", "a": [-2, -2], "b": [-2, 2], "thickness": 0.1},
            {"type": "circle", "center": [0, 1.5], "radius": 0.2},
            {"type": "circle", "center": [0, -1.5], "radius": 0.2},
        ],
    }
    data.update(over)
    return data


def test_small_world_loads():
    w = world_from_dict(small_world())
    assert len(w.obstacles) == 4
    assert w.clearance(0, 0) == pytest.approx(1.3)


def test_error_names_file_and_field(tmp_path: Path):
    data = small_world()
    data["obstacles"][3]["radius"] = 0
    p = tmp_path / "x.yaml"
    p.write_text(yaml.safe_dump(data))
    with pytest.raises(WorldError) as ei:
        load_world(p)
    assert f"{p}: obstacles.3.radius: Input should be greater than 0" in str(ei.value)


@pytest.mark.parametrize("mutate, expected", [
    (lambda d: d["obstacles"].append({"type": "blob"}), "obstacles.4"),
    (lambda d: d["obstacles"][0].update(points=[[0, 0], [1, 0]]), "obstacles.0.points"),
    (lambda d: d["obstacles"][0].update(points=[[0, 0], [2, 0], [1, 0.2], [1, 2]]), "convex"),
    (lambda d: d["obstacles"][1].update(b=[-2, -2]), "obstacles.1"),
    (lambda d: d["obstacles"][1].update(thickness=-1), "obstacles.1.thickness"),
    (lambda d: d.update(spawn={"x": 10, "y": 0}), "outside the bounds"),
    (lambda d: d.update(bounds={"xmin": 1, "ymin": 0, "xmax": 0, "ymax": 1}), "bounds"),
    (lambda d: d["obstacles"][2].update(colour="red"), "obstacles.2.colour"),
    (lambda d: d.pop("spawn"), "spawn: Field required"),
])
def test_validation_messages(mutate, expected):
    data = small_world()
    mutate(data)
    with pytest.raises(WorldError) as ei:
        world_from_dict(data, "worlds/t.yaml")
    assert str(ei.value).startswith("worlds/t.yaml: ")
    assert expected in str(ei.value)


def test_missing_and_broken_files(tmp_path: Path):
    with pytest.raises(WorldError, match="no such world"):
        load_world(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed")
    with pytest.raises(WorldError, match="not valid YAML"):
        load_world(bad)


def test_polygon_orientation_normalised():
    w = world_from_dict(small_world(obstacles=[{"type": "polygon", "points": [[0, 0], [0, 1], [1, 1], [1, 0]]}],
                                    spawn={"x": 2, "y": 2}))
    pts = w.obstacles[0].polygon()
    x, y = pts[:, 0], pts[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) > 0  # CCW


def _reachable(world, radius: float, start, targets) -> dict[str, bool]:
    raster = world.rasterize(0.05, layer="body", inflate=radius)
    free = raster.data == 0
    r0, c0 = raster.world_to_cell(start.x, start.y)
    assert free[r0, c0]
    seen = np.zeros_like(free)
    seen[r0, c0] = True
    q = deque([(r0, c0)])
    H, W = free.shape
    while q:
        r, c = q.popleft()
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            rr, cc = r + dr, c + dc
            if 0 <= rr < H and 0 <= cc < W and free[rr, cc] and not seen[rr, cc]:
                seen[rr, cc] = True
                q.append((rr, cc))
    out = {}
    for name, p in targets.items():
        r, c = raster.world_to_cell(p.x, p.y)
        out[name] = bool(seen[r, c])
    return out


@pytest.mark.parametrize("name", SHIPPED_WORLDS)
def test_shipped_worlds_clear_and_reachable(name):
    w = load_world(name)
    poses = {"spawn": w.spawn, **w.goals}
    if w.dock:
        poses["dock"] = w.dock
    for label, p in poses.items():
        assert w.clearance(p.x, p.y) >= 0.3, f"{name}: {label} too close to an obstacle"
        assert w.clearance(p.x, p.y, body=False, lidar=True) >= 0.3, label
    assert len(w.goals) >= 5
    # every goal and the dock can be reached by the default robot from the spawn pose
    reach = _reachable(w, load_profile("burger").radius + 0.02, w.spawn, poses)
    assert all(reach.values()), {k: v for k, v in reach.items() if not v}


def test_apartment_is_closed():
    """The robot cannot leave the apartment: the bounds' border is unreachable."""
    w = load_world("apartment")
    raster = w.rasterize(0.05, layer="body", inflate=0.105)
    free = raster.data == 0
    r0, c0 = raster.world_to_cell(w.spawn.x, w.spawn.y)
    seen = np.zeros_like(free)
    seen[r0, c0] = True
    q = deque([(r0, c0)])
    H, W = free.shape
    while q:
        r, c = q.popleft()
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            rr, cc = r + dr, c + dc
            if 0 <= rr < H and 0 <= cc < W and free[rr, cc] and not seen[rr, cc]:
                seen[rr, cc] = True
                q.append((rr, cc))
    assert not (seen[0].any() or seen[-1].any() or seen[:, 0].any() or seen[:, -1].any())
    assert seen.sum() * 0.05 ** 2 > 60  # a big connected free area (m^2)


def test_apartment_has_undetected_obstacles():
    w = load_world("apartment")
    body_only = w.obstacles_where(lidar=False, body=True)
    assert {o.name.split("/")[0] for o in body_only} >= {"cafe_table", "cabinet", "bookshelf"}


def test_round_obstacles_layout():
    w = load_world("round_obstacles")
    pillars = [o for o in w.obstacles if o.type == "circle"]
    assert len(pillars) == 9 and all(o.radius == pytest.approx(0.15) for o in pillars)
    # the arena border: the inner hexagon's vertex on -x at 2.933 m
    assert w.clearance(-2.9, 0.0) < 0.05
    assert w.clearance(-2.5, 0.0) == pytest.approx(0.4329 * math.sin(math.pi / 3), abs=0.002)


def read_pgm(path: Path) -> np.ndarray:
    """A binary (P5) PGM with optional comment lines."""
    raw = path.read_bytes()
    fields: list[bytes] = []
    pos = 0
    while len(fields) < 4:
        while raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = pos
        while not raw[end:end + 1].isspace():
            end += 1
        fields.append(raw[pos:end])
        pos = end
    assert fields[0] == b"P5"
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(raw[pos + 1: pos + 1 + w * h], dtype=np.uint8).reshape(h, w)


@needs_shared
def test_committed_worlds_match_the_converter():
    ref = SHARED / "reference" / "worlds"
    for builder, csv_name, model, out in [
        (build_apartment, "turtlebot3_house_2d_obstacles.csv", "turtlebot3_house", "apartment.yaml"),
        (build_round_obstacles, "turtlebot3_world_2d_obstacles.csv", "turtlebot3_world", "round_obstacles.yaml"),
    ]:
        text = dump(builder(ref / csv_name), csv_name, model)
        committed = (ROOT / "sim" / "worlds" / out).read_text()
        assert text == committed, f"{out} is stale: run python -m sim.worlds.build_worlds"
        assert "Apache-2.0" in committed.splitlines()[1]


@needs_shared
def test_apartment_matches_reference_raster():
    """Our rasterized apartment agrees with the reference raster (all shapes below 0.2 m)
    except for the front-yard closure we added."""
    ref = SHARED / "reference" / "worlds"
    meta = yaml.safe_load((ref / "turtlebot3_house_2d_rasterized.yaml").read_text())
    img = read_pgm(ref / meta["image"])[::-1]  # row 0 = ymin
    ref_occ = img < 128
    w = load_world("apartment")
    ours = w.rasterize(meta["resolution"], layer="any").data.astype(bool)
    assert ours.shape == ref_occ.shape
    closure = np.zeros_like(ours)
    closure[: int((-5.0 - meta["origin"][1]) / 0.05), :] = True  # y < -5.0 (south wall)
    closure[:, : int((-5.0 - meta["origin"][0]) / 0.05)] |= True  # x < -5.0 (west wall, west wing)
    diff = (ours != ref_occ) & ~closure
    assert diff.mean() < 0.01, diff.mean()


@pytest.mark.parametrize("name", SHIPPED_PROFILES)
def test_profiles_load(name):
    p = load_profile(name)
    assert p.name == name
    assert p.lidar.range_min < p.lidar.range_max
    assert p.battery.voltage(100) == p.battery.voltage_full


def test_burger_values_and_the_025_decision():
    b = load_profile("burger")
    assert (b.radius, b.wheel_separation, b.max_linear, b.max_angular) == (0.105, 0.160, 0.22, 2.84)
    assert b.lidar.samples == 360 and b.lidar.range_min == 0.12 and b.lidar.range_max == 3.5
    assert b.lidar.rate_hz == 5 and b.lidar.noise_sigma == 0.01
    assert b.max_linear < 0.25 <= load_profile("rosbot2").max_linear
    assert load_profile("waffle").max_linear >= 0.25


def test_profile_errors_and_overrides(tmp_path: Path):
    p = load_profile("burger", **{"battery.initial_soc": 40, "lidar": {"rate_hz": 10}})
    assert p.battery.initial_soc == 40 and p.lidar.rate_hz == 10 and p.lidar.samples == 360
    with pytest.raises(ProfileError, match=r"burger.yaml: battery.initial_soc: Input should be less than or equal to 100"):
        load_profile("burger", **{"battery.initial_soc": 140})
    with pytest.raises(ProfileError, match="no such robot profile"):
        load_profile(tmp_path / "none.yaml")


def test_rasterize_thin_features():
    w = world_from_dict(small_world(obstacles=[
        {"type": "circle", "center": [1.0, 1.0], "radius": 0.02},
        {"type": "segment", "a": [-1, -1], "b": [-1, 1], "thickness": 0},
    ]))
    r = w.rasterize(0.05)
    assert r.data[r.world_to_cell(1.0, 1.0)] == 1
    assert r.data[r.world_to_cell(-1.0, 0.3)] == 1
    assert r.data.sum() < 100
    assert math.isclose(r.cell_center(*r.world_to_cell(0.01, 0.01))[0], 0.025)
