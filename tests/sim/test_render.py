"""Rendering: a PNG with the world, an occupancy grid, a path, a scan and events."""

from __future__ import annotations

import asyncio

import numpy as np
from PIL import Image

from sim import Simulator
from sim.geometry import Raster
from sim.render import render_png
from sim.render_layout import Layout
from sim.testing import run_virtual


def test_render_everything(tmp_path):
    sim = Simulator("round_obstacles", "burger", seed=0)

    async def main():
        await sim.start()
        sim.faults.invisible_obstacle(ahead=0.2)
        for _ in range(30):
            sim.command(0.2, 0.0)
            await asyncio.sleep(0.1)
        await sim.stop()

    run_virtual(main)
    raster = sim.rasterize(0.05, layer="lidar", inflate=0.2)
    out = render_png(tmp_path / "a" / "run.png", sim.world, occupancy=raster, trajectory=sim.trajectory(),
                     scan=(sim.bus.latest("scan"), sim.pose), events=sim.events,
                     obstacles=sim.dynamic_obstacles.values(), robot=sim.pose, scale=40)
    img = np.asarray(Image.open(out).convert("RGB"))
    b = sim.world.bounds
    assert img.shape[1] == Layout.of(b, 40).width and Layout.of(b, 40).map_w == int(np.ceil(b.width * 40))
    colours = {tuple(c) for c in img.reshape(-1, 3)[::7]}
    assert (60, 66, 80) in colours  # lidar + body obstacles
    assert (250, 170, 60) in colours  # the body-only obstacle
    assert (110, 110, 110) in colours  # inflated occupancy around the obstacles
    assert any(c[2] > 150 and c[0] < 80 for c in colours)  # the path (blue)
    assert sim.events_of("collision")


def test_render_costmap_and_ros_grids(tmp_path):
    sim = Simulator("round_obstacles", "burger", seed=0)
    raster = sim.rasterize(0.1)
    cost = np.where(raster.data > 0, 254, 0).astype(np.uint8)
    cost[:5, :5] = 255
    cost[10:20, 10:20] = 120
    render_png(tmp_path / "cost.png", sim.world, occupancy=(cost, 0.1, raster.origin), goals=[(0.0, 1.9)])
    grid = np.where(raster.data > 0, 100, 0).astype(np.int8)
    grid[:3] = -1
    render_png(tmp_path / "grid.png", sim.world, occupancy=Raster(grid, 0.1, raster.origin), goals={})
    assert (tmp_path / "cost.png").stat().st_size > 1000 and (tmp_path / "grid.png").exists()
