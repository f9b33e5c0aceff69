"""ROS map_server maps as worlds: walls where the picture is occupied, map_server's keys read as
map_server reads them, clear errors for bad files, and the robot drives in one."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sim.nav.occupancy import OccupancyGrid
from sim.world import WorldError, load_world
from tests.paths import ROOT

EXAMPLE = ROOT / "sim" / "worlds" / "maps" / "apartment_map.yaml"


def _inside_any(world, x: float, y: float) -> bool:
    return any(o.distance(x, y) <= 0 for o in world.obstacles)


def _write_map(folder: Path, pixels: np.ndarray, *, name: str = "room", **keys) -> Path:
    Image.fromarray(pixels).save(folder / f"{name}.png")
    meta = {"image": f"{name}.png", "resolution": 0.1, "origin": [-1.0, -2.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196} | keys
    lines = [f"{k}: {v}" for k, v in meta.items()]
    path = folder / f"{name}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _room(rgb: bool = False) -> np.ndarray:
    """40 x 30 cells (4 x 3 m): white floor, a black 1-cell frame and a black 5 x 5 block whose
    lower-left cell is column 20, row 10 counted from the bottom."""
    img = np.full((30, 40), 254, np.uint8)
    img[0, :] = img[-1, :] = 0
    img[:, 0] = img[:, -1] = 0
    img[30 - 15:30 - 10, 20:25] = 0  # picture rows are top first
    return np.stack([img] * 3, axis=2) if rgb else img


@pytest.mark.parametrize("rgb", [False, True])
def test_occupied_cells_become_walls_at_their_map_coordinates(tmp_path: Path, rgb: bool) -> None:
    world = load_world(_write_map(tmp_path, _room(rgb), spawn="{x: 0.5, y: -1.0, yaw: 0.0}"))
    assert (world.bounds.xmin, world.bounds.ymin, world.bounds.xmax, world.bounds.ymax) == (-1.0, -2.0, 3.0, 1.0)
    # block: columns 20..24 -> x in [1.0, 1.5]; rows 10..14 from the bottom -> y in [-1.0, -0.5]
    assert _inside_any(world, 1.25, -0.75)
    assert not _inside_any(world, 0.9, -0.75) and not _inside_any(world, 1.25, -1.1)
    assert _inside_any(world, -0.95, 0.0) and _inside_any(world, 2.95, 0.0)  # the frame
    assert len(world.obstacles) <= 8  # runs merged into rectangles, not one box per cell


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    world = load_world(_write_map(tmp_path, 254 - _room(), negate=1, spawn="{x: 0.5, y: -1.0, yaw: 0}"))
    assert _inside_any(world, 1.25, -0.75) and not _inside_any(world, 0.5, -1.0)


def test_without_a_spawn_the_robot_starts_in_open_space(tmp_path: Path) -> None:
    world = load_world(_write_map(tmp_path, _room()))
    assert not _inside_any(world, world.spawn.x, world.spawn.y)
    assert min(o.distance(world.spawn.x, world.spawn.y) for o in world.obstacles) >= 0.3


@pytest.mark.parametrize(("keys", "field"), [
    ({"resolution": -0.05}, "resolution"),
    ({"origin": "[1.0, 2.0]"}, "origin"),
    ({"mode": "fancy"}, "mode"),
    ({"image": "../elsewhere.png"}, "image"),
    ({"image": "missing.pgm"}, "image"),  # no room.pgm beside room.yaml to fall back on either
    ({"negate": "maybe"}, "negate"),
    ({"occupied_thresh": ".nan"}, "occupied_thresh"),
    ({"free_thresh": 0.9}, "free_thresh/occupied_thresh"),
])
def test_bad_map_files_name_the_file_and_field(tmp_path: Path, keys: dict, field: str) -> None:
    path = _write_map(tmp_path, _room(), **keys)
    with pytest.raises(WorldError) as err:
        load_world(path)
    assert str(path) in str(err.value) and field in str(err.value)


def test_a_renamed_picture_falls_back_to_the_one_named_like_the_map(tmp_path: Path) -> None:
    """One reader for worlds and the navigation grid: both accept the same files."""
    path = _write_map(tmp_path, _room(), image="old_name.png", spawn="{x: 0.5, y: -1.0, yaw: 0}")
    world = load_world(path)
    grid = OccupancyGrid.load(path)
    assert _inside_any(world, 1.25, -0.75) and grid.value_at(1.25, -0.75) == 100
    assert grid.value_at(0.5, -1.0) == 0


def test_the_shipped_map_matches_the_apartment() -> None:
    world, apartment = load_world(EXAMPLE), load_world("apartment")
    assert world.bounds == apartment.bounds and world.spawn == apartment.spawn
    assert set(world.goals) == set(apartment.goals)
    for goal in apartment.goals.values():
        assert not _inside_any(world, goal.x, goal.y)


def test_run_reaches_a_goal_in_a_map_server_map() -> None:
    result = subprocess.run([sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--world", str(EXAMPLE),
                             "--goal", "yard_east", "--duration", "120"],
                            cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert "SUCCEEDED" in result.stdout
