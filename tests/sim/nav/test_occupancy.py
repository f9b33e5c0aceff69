"""sim.nav.occupancy: rasterization, map_server load/save, ray casting."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.nav.occupancy import OccupancyGrid, pixels_to_occupancy, read_pgm
from tests.sim.nav.fixtures import REFERENCE, small_world

REFERENCE_MAPS = sorted(REFERENCE.glob("*.yaml")) if REFERENCE.is_dir() else []


def test_geometry_round_trip():
    g = OccupancyGrid(np.zeros((20, 30), np.int8), 0.05, (-1.0, 2.0, 0.0))
    assert (g.width, g.height) == (30, 20)
    assert g.bounds == pytest.approx((-1.0, 2.0, 0.5, 3.0))
    r, c = g.world_to_cell(-0.72, 2.31)
    assert (r, c) == (6, 5)
    x, y = g.cell_to_world(r, c)
    assert (x, y) == pytest.approx((-0.725, 2.325))
    assert g.value_at(5.0, 5.0) == -1  # outside


def test_from_shapes_marks_what_the_shapes_cover():
    g = OccupancyGrid.from_shapes(
        polygons=[np.array([[2.0, 2.0], [3.0, 2.0], [3.0, 2.5], [2.0, 2.5]])],
        circles=[(1.0, 1.0, 0.2)],
        segments=[(0.0, 3.0, 4.0, 3.0, 0.1)],
        bounds=(0.0, 0.0, 4.0, 4.0), resolution=0.05)
    assert g.data.shape == (80, 80)
    occ = lambda x, y: g.value_at(x, y) == 100  # noqa: E731
    assert occ(1.0, 1.0) and occ(1.18, 1.0) and not occ(1.3, 1.0)
    assert occ(2.5, 2.25) and occ(2.01, 2.01) and not occ(3.2, 2.25) and not occ(2.5, 1.9)
    assert occ(0.5, 3.0) and occ(3.9, 3.04) and not occ(2.0, 3.2)
    assert g.value_at(0.3, 0.3) == 0
    # a circle's area is covered to within a cell ring
    n = int((g.data == 100)[: 40, : 40].sum())
    area_cells = math.pi * 0.2 ** 2 / 0.05 ** 2
    assert area_cells <= n <= math.pi * (0.2 + 0.05 * 1.5) ** 2 / 0.05 ** 2


def test_conservative_rasterization_is_a_superset():
    shapes = dict(polygons=[np.array([[0.33, 0.41], [1.27, 0.52], [0.8, 1.33]])],
                  circles=[(2.02, 2.03, 0.17)], segments=[(0.1, 2.5, 1.7, 3.6, 0.08)])
    loose = OccupancyGrid.from_shapes(**shapes, bounds=(0, 0, 4, 4), conservative=False)
    tight = OccupancyGrid.from_shapes(**shapes, bounds=(0, 0, 4, 4), conservative=True)
    a, b = loose.data == 100, tight.data == 100
    assert a.sum() > 0 and (b | a).sum() == b.sum() and b.sum() > a.sum()


def test_save_load_round_trip(tmp_path):
    data = np.zeros((30, 40), np.int8)
    data[5:8, 10:30] = 100
    data[20:, :5] = -1
    data[0, 0] = 100  # bottom-left corner: row 0 is the map's bottom
    g = OccupancyGrid(data, 0.05, (-2.0, -1.5, 0.0))
    path = g.save(tmp_path / "room.yaml")
    text = path.read_text()
    for key in ("image: room.pgm", "resolution: 0.05", "negate: 0", "occupied_thresh: 0.65",
                "free_thresh: 0.196", "mode: trinary"):
        assert key in text
    pixels = read_pgm(tmp_path / "room.pgm")
    assert pixels[-1, 0] == 0 and pixels[0, 0] == 205 and pixels[-1, 5] == 254
    back = OccupancyGrid.load(path)
    np.testing.assert_array_equal(back.data, g.data)
    assert back.resolution == g.resolution and back.origin == g.origin


def test_map_server_thresholds():
    px = np.array([[0, 80, 150, 205, 254]], np.uint8)
    # p = (255 - px) / 255 = 1, .69, .41, .19608 (just above free_thresh: unknown), .004
    tri = pixels_to_occupancy(px, negate=False, occupied_thresh=0.65, free_thresh=0.196)
    assert tri.tolist() == [[100, 100, -1, -1, 0]]
    neg = pixels_to_occupancy(px, negate=True, occupied_thresh=0.65, free_thresh=0.196)
    assert neg.tolist() == [[0, -1, -1, 100, 100]]
    scale = pixels_to_occupancy(px, negate=False, occupied_thresh=0.65, free_thresh=0.196,
                                mode="scale")
    assert scale.tolist() == [[100, 100, 48, 0, 0]]
    raw = pixels_to_occupancy(np.array([[0, 50, 100, 101, 255]], np.uint8), negate=False,
                              occupied_thresh=0.65, free_thresh=0.196, mode="raw")
    assert raw.tolist() == [[0, 50, 100, -1, -1]]


def test_read_ascii_pgm(tmp_path):
    p = tmp_path / "a.pgm"
    p.write_text("P2\n# comment\n3 2\n15\n0 15 7\n15 0 15\n")
    px = read_pgm(p)
    assert px.tolist() == [[0, 255, 119], [255, 0, 255]]


@pytest.mark.skipif(not REFERENCE_MAPS, reason="shared/reference/worlds not available")
@pytest.mark.parametrize("yaml_path", REFERENCE_MAPS, ids=lambda p: p.stem)
def test_load_reference_maps(yaml_path):
    g = OccupancyGrid.load(yaml_path)
    assert g.resolution == pytest.approx(0.05)
    values = set(np.unique(g.data).tolist())
    assert values <= {-1, 0, 100} and 100 in values and 0 in values
    if "house" in yaml_path.stem:
        assert g.origin[:2] == (-8.0, -6.0) and g.data.shape == (240, 320)
        assert g.value_at(-0.05, 3.1) == 100  # Wall_101
        assert g.value_at(-4.0, 3.5) == 0  # a room


def test_raycast_hits_walls():
    g = small_world()
    # from (1, 1) towards -x the outer wall (x = 0, 0.1 thick) is ~0.95 m away
    r = g.raycast(1.0, 1.0, np.array([math.pi, -math.pi / 2, 0.0]), 3.5)
    assert r[0] == pytest.approx(0.95, abs=0.06)
    assert r[1] == pytest.approx(0.95, abs=0.06)
    assert r[2] == pytest.approx(2.95, abs=0.06)  # dividing wall at x = 4
    far = g.raycast(1.0, 1.0, np.array([0.0]), 1.0)
    assert np.isinf(far[0])
