"""The drawn trajectory lands where the robot was: pixels checked against the map-to-pixel layout.

Campaign records keep (t, x, y) columns; a renderer that read them as (x, y) drew every path
through walls. These tests draw known paths and look at the pixels."""

from __future__ import annotations

import numpy as np
from PIL import Image

from sim.render import render_png
from sim.render_layout import Layout
from sim.scenarios.campaign import CampaignResult
from sim.scenarios.report import WITH, WITHOUT, write_report
from sim.scenarios.spec import load_scenario
from sim.world import load_world

INK = (1, 2, 250)  # a colour nothing else in the picture uses


def _l_path() -> np.ndarray:
    """(t, x, y): 2 m east from (-2, -2), then 1.5 m north, 10 Hz; t never looks like a coordinate."""
    east = [(-2.0 + 0.05 * i, -2.0) for i in range(41)]
    north = [(0.0, -2.0 + 0.05 * i) for i in range(1, 31)]
    xy = np.array(east + north)
    t = 100.0 + 0.1 * np.arange(len(xy))
    return np.column_stack([t, xy])


def _ink_pixels(path) -> np.ndarray:
    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    mask = (np.abs(img - np.array(INK)).sum(axis=-1) <= 6)
    rows, cols = np.nonzero(mask)
    return np.column_stack([cols, rows])


def _assert_on_path(ink: np.ndarray, layout: Layout, xy: np.ndarray) -> None:
    expected = np.array([layout.px(x, y) for x, y in xy])
    # every sample of the path has ink within 2 px ...
    for ex, ey in expected:
        assert np.min(np.hypot(ink[:, 0] - ex, ink[:, 1] - ey)) <= 2.0, (ex, ey)
    # ... and no ink lies more than 7 px (the end markers) from the path
    dense = np.concatenate([np.linspace(a, b, 20) for a, b in zip(expected[:-1], expected[1:])])
    far = [p for p in ink if np.min(np.hypot(dense[:, 0] - p[0], dense[:, 1] - p[1])) > 7.0]
    assert not far, f"{len(far)} pixels drawn away from the trajectory, e.g. {far[:3]}"


def test_a_t_x_y_trajectory_is_drawn_at_its_x_y(tmp_path):
    world = load_world("apartment")
    traj = _l_path()
    out = render_png(tmp_path / "l.png", world, trajectories=[(traj, INK)], goals={}, scale=40)
    ink = _ink_pixels(out)
    assert len(ink) > 100
    _assert_on_path(ink, Layout.of(world.bounds, 40), traj[:, 1:3])


def test_report_pictures_draw_each_run_where_it_went(tmp_path):
    """write_report on a campaign's own (t, x, y) records: pixels of the 'with' colour sit on
    the run's path, the 'without' run on its own; the picture has a legend and axes."""
    spec = load_scenario("Collision_1")
    traj = _l_path()
    other = traj.copy()
    other[:, 2] += 2.5  # the 'without' run, 2.5 m further north (the paths never cross)
    result = CampaignResult(
        specs={"Collision_1": spec},
        results=[{"scenario": "Collision_1", "mode": "with", "success": True, "sim_time": 7.0, "verdicts": []},
                 {"scenario": "Collision_1", "mode": "without", "success": False, "sim_time": 7.0,
                  "verdicts": []}],
        wall_time=1.0, jobs=1,
        trajectories={("Collision_1", "with", 0): {"trajectory": traj, "marks": [], "faults": [],
                                                   "goals": [(0.0, -0.5)]},
                      ("Collision_1", "without", 0): {"trajectory": other, "marks": [], "faults": [(101.0, "x")],
                                                      "goals": [(0.0, -0.5)], "collisions": [(-1.0, -1.0)]}})
    png = next(p for p in write_report(result, tmp_path) if p.suffix == ".png")
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    layout = Layout.of(load_world(spec.world).bounds, 40.0)
    for xy, colour in ((traj[:, 1:3], WITH), (other[:, 1:3], WITHOUT)):
        for x, y in xy[15:-5:5]:  # clear of the fault marker (sample 10) and the end markers
            c, r = (int(round(v)) for v in layout.px(x, y))
            patch = img[r - 1:r + 2, c - 1:c + 2].reshape(-1, 3)
            assert any((abs(p - np.array(colour)).sum() < 10) for p in patch), (x, y, colour)
    # the fault was placed where the 'without' run was at t = 101 s: an orange triangle there
    fx, fy = (int(round(v)) for v in layout.px(*other[10, 1:3]))
    assert (np.abs(img[fy - 3:fy + 4, fx - 3:fx + 4] - np.array((250, 170, 60))).sum(axis=-1) < 10).any()
    # the legend sits right of the map and names both modes' colours
    legend = img[:, layout.left + layout.map_w + 15:]
    for colour in (WITH, WITHOUT):
        assert (np.abs(legend - np.array(colour)).sum(axis=-1) < 10).any()
