"""Render a world (and optionally a map, a path, a scan, events, goals) to a PNG with Pillow.

    render_png("out/run.png", sim.world, occupancy=raster, trajectory=sim.trajectory(),
               scan=(scan, pose), events=sim.events, obstacles=sim.dynamic_obstacles.values())

Colours: lidar-blocking obstacles dark slate; body-only ("undetected") obstacles orange with a
dark-orange outline; lidar-only shapes (rare) light blue outline. Obstacles added at run time
are drawn like the others, outlined in magenta. Occupied map cells are grey, unknown cells pale
yellow; the path is blue (green start, red end); scan hits are red dots; collisions are red
crosses, faults orange triangles, other events small grey dots; goals are green circles with
their names, the spawn pose a blue arrow, the dock a purple square.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from bt_runtime.runtime.messages import LaserScan, Pose2D

from .world import World

SLATE = (60, 66, 80)
ORANGE = (250, 170, 60)
DARK_ORANGE = (190, 100, 0)
LIGHT_BLUE = (120, 170, 230)
MAGENTA = (200, 0, 160)
PATH = (30, 90, 220)
RED = (220, 30, 30)
GREEN = (20, 150, 60)
PURPLE = (120, 40, 170)
GREY = (150, 150, 150)


def _occupancy_parts(occ: Any) -> tuple[np.ndarray, float, tuple[float, float]]:
    """(data, resolution, origin) from a Raster-like object (``data``/``grid``/``cells``,
    ``resolution``, ``origin``) or a (data, resolution, origin) tuple."""
    if isinstance(occ, tuple):
        data, res, origin = occ
    else:
        data = next(getattr(occ, n) for n in ("data", "grid", "cells", "array") if hasattr(occ, n))
        res = occ.resolution
        origin = occ.origin
    if hasattr(origin, "x"):
        origin = (origin.x, origin.y)
    return np.asarray(data), float(res), (float(origin[0]), float(origin[1]))


def _occupancy_rgb(data: np.ndarray) -> np.ndarray:
    """Colour cells: occupied grey, unknown pale yellow, free transparent (alpha 0).

    Accepts 0/1 (or bool) rasters, ROS OccupancyGrid values (-1 unknown, 0..100) and Nav2
    costmap values (0..252 graded, 253/254 lethal, 255 unknown)."""
    d = data.astype(np.int32)
    rgba = np.zeros(d.shape + (4,), dtype=np.uint8)
    if d.max(initial=0) <= 1 and d.min(initial=0) >= 0:
        occ = d > 0
        unknown = np.zeros_like(occ)
        cost = np.zeros(d.shape)
    elif d.max(initial=0) <= 100:
        occ = d >= 65
        unknown = d < 0
        cost = np.clip(d, 0, 100) / 100.0
    else:
        occ = (d >= 253) & (d != 255)
        unknown = d == 255
        cost = np.where(occ | unknown, 0, np.clip(d, 0, 252)) / 252.0
    graded = (cost > 0) & ~occ
    rgba[graded] = np.stack([np.full(graded.sum(), 200), np.full(graded.sum(), 120),
                             np.full(graded.sum(), 220), (cost[graded] * 150).astype(np.uint8)], axis=-1)
    rgba[occ] = (110, 110, 110, 255)
    rgba[unknown] = (250, 240, 190, 255)
    return rgba


class _Canvas:
    def __init__(self, world: World, scale: float, margin: int = 10) -> None:
        b = world.bounds
        self.b = b
        self.scale = scale
        self.margin = margin
        self.w = int(math.ceil(b.width * scale)) + 2 * margin
        self.h = int(math.ceil(b.height * scale)) + 2 * margin + 16
        self.img = Image.new("RGBA", (self.w, self.h), (255, 255, 255, 255))
        self.draw = ImageDraw.Draw(self.img, "RGBA")

    def px(self, x: float, y: float) -> tuple[float, float]:
        return (self.margin + (x - self.b.xmin) * self.scale,
                16 + self.margin + (self.b.ymax - y) * self.scale)

    def poly(self, pts, fill=None, outline=None, width=1) -> None:
        self.draw.polygon([self.px(*p) for p in pts], fill=fill, outline=outline, width=width)

    def circle(self, x, y, r_m=None, r_px=None, fill=None, outline=None, width=1) -> None:
        cx, cy = self.px(x, y)
        r = r_px if r_px is not None else max(1.0, r_m * self.scale)
        self.draw.ellipse([cx - r, cy - r, cx + r, cy + r], fill=fill, outline=outline, width=width)


def _draw_obstacle(c: _Canvas, ob, dynamic: bool = False) -> None:
    if ob.blocks_lidar and ob.blocks_body:
        fill, outline = SLATE, SLATE
    elif ob.blocks_body:
        fill, outline = ORANGE, DARK_ORANGE
    else:
        fill, outline = None, LIGHT_BLUE
    if dynamic:
        outline = MAGENTA
    poly = ob.polygon()
    circle = ob.circle()
    width = 2 if dynamic else 1
    if poly is not None:
        c.poly(poly.tolist(), fill=fill, outline=outline, width=width)
    elif circle is not None:
        c.circle(circle[0], circle[1], r_m=circle[2], fill=fill, outline=outline, width=width)
    else:  # a zero-thickness segment
        c.draw.line([c.px(*ob.a), c.px(*ob.b)], fill=outline, width=max(width, 2))


def _traj_xy(trajectory: Any) -> np.ndarray:
    tr = np.asarray(trajectory, dtype=float)
    if tr.ndim != 2 or len(tr) == 0:
        return np.empty((0, 2))
    if tr.shape[1] >= 4:  # Simulator.trajectory(): t, x, y, yaw, ...
        return tr[:, 1:3]
    return tr[:, :2]


def _event_xy(ev: Any, trajectory: Any) -> tuple[float, float] | None:
    data = ev.data if hasattr(ev, "data") else ev.get("data", ev)
    for key in ("point", "center"):
        p = data.get(key) if isinstance(data, Mapping) else None
        if p is not None and len(p) == 2 and all(map(math.isfinite, p)):
            return float(p[0]), float(p[1])
    if isinstance(data, Mapping) and "x" in data and "y" in data and data["x"] is not None:
        return float(data["x"]), float(data["y"])
    t = ev.t if hasattr(ev, "t") else ev.get("t")
    if trajectory is None or t is None:
        return None
    tr = np.asarray(trajectory, dtype=float)
    if tr.ndim != 2 or tr.shape[1] < 4 or len(tr) == 0:
        return None
    i = int(np.clip(np.searchsorted(tr[:, 0], t), 0, len(tr) - 1))
    return float(tr[i, 1]), float(tr[i, 2])


def render_png(path: str | Path, world: World, *, occupancy: Any = None, trajectory: Any = None,
               scan: LaserScan | tuple[LaserScan, Pose2D] | None = None, scan_pose: Pose2D | None = None,
               events: Iterable[Any] | None = None, goals: Mapping[str, Any] | Iterable[Any] | None = None,
               obstacles: Iterable[Any] | None = None, robot: Pose2D | None = None, robot_radius: float = 0.105,
               scale: float = 50.0, title: str | None = None,
               trajectories: Iterable[tuple[Any, tuple[int, int, int]]] = (),
               marks: Iterable[tuple[float, float, tuple[int, int, int], str]] = ()) -> Path:
    """Draw the world and the optional layers to ``path`` (PNG); returns the path.

    ``occupancy``: a Raster-like grid (see ``_occupancy_parts``). ``trajectory``: (N, 2) x, y,
    or ``Simulator.trajectory()``. ``scan``: a LaserScan with ``scan_pose`` (the robot's
    map-frame pose when it was taken; the lidar mounting offset is ignored), or a
    (scan, pose) pair. ``events``: SimEvents (or dicts with t/kind/data). ``goals``: name ->
    pose mapping, or poses; default: the world's goals. ``obstacles``: extra (run-time)
    obstacles. ``robot``: draw the robot's body at this pose. ``trajectories``: more paths as
    (trajectory, rgb) pairs (e.g. many runs of one scenario). ``marks``: (x, y, rgb, label)
    points (e.g. where a fault or a recovery happened).
    """
    c = _Canvas(world, scale)
    if occupancy is not None:
        data, res, origin = _occupancy_parts(occupancy)
        rgba = _occupancy_rgb(np.asarray(data))[::-1]  # row 0 = ymin -> bottom of the image
        layer = Image.fromarray(np.ascontiguousarray(rgba), "RGBA")
        w_px = max(1, int(round(data.shape[1] * res * scale)))
        h_px = max(1, int(round(data.shape[0] * res * scale)))
        layer = layer.resize((w_px, h_px), Image.NEAREST)
        x0, y1 = c.px(origin[0], origin[1] + data.shape[0] * res)
        c.img.alpha_composite(layer, (int(round(x0)), int(round(y1))))
    for ob in world.obstacles:
        _draw_obstacle(c, ob)
    for ob in obstacles or ():
        _draw_obstacle(c, ob, dynamic=True)

    goal_items: list[tuple[str, Any]]
    if goals is None:
        goal_items = list(world.goals.items())
    elif isinstance(goals, Mapping):
        goal_items = list(goals.items())
    else:
        goal_items = [("", g) for g in goals]
    for name, g in goal_items:
        gx, gy = (g.x, g.y) if hasattr(g, "x") else (g[0], g[1])
        c.circle(gx, gy, r_px=4, outline=GREEN, width=2)
        if name:
            x, y = c.px(gx, gy)
            c.draw.text((x + 5, y - 6), name, fill=GREEN)
    sp = world.spawn
    x, y = c.px(sp.x, sp.y)
    c.draw.line([(x, y), c.px(sp.x + 0.3 * math.cos(sp.yaw), sp.y + 0.3 * math.sin(sp.yaw))], fill=PATH, width=2)
    c.circle(sp.x, sp.y, r_px=3, fill=PATH)
    if world.dock is not None:
        x, y = c.px(world.dock.x, world.dock.y)
        c.draw.rectangle([x - 4, y - 4, x + 4, y + 4], outline=PURPLE, width=2)

    if trajectory is not None:
        xy = _traj_xy(trajectory)
        if len(xy) > 1:
            c.draw.line([c.px(px, py) for px, py in xy], fill=PATH, width=2)
        if len(xy):
            c.circle(*xy[0], r_px=4, fill=GREEN)
            c.circle(*xy[-1], r_px=4, fill=RED)

    for extra, colour in trajectories:
        xy = _traj_xy(extra)
        if len(xy) > 1:
            c.draw.line([c.px(px, py) for px, py in xy], fill=colour, width=1)
        if len(xy):
            c.circle(*xy[-1], r_px=2.5, fill=colour)

    for mx, my, colour, label in marks:
        x, y = c.px(mx, my)
        c.draw.rectangle([x - 3, y - 3, x + 3, y + 3], outline=colour, width=2)
        if label:
            c.draw.text((x + 5, y + 2), label, fill=colour)

    if scan is not None:
        if isinstance(scan, tuple):
            scan, scan_pose = scan
        if scan_pose is None:
            raise ValueError("a scan needs the pose it was taken from (scan_pose=...)")
        r = np.asarray(scan.ranges, dtype=float)
        a = scan.angle_min + scan.angle_increment * np.arange(len(r)) + scan_pose.yaw
        ok = np.isfinite(r)
        hx = scan_pose.x + r[ok] * np.cos(a[ok])
        hy = scan_pose.y + r[ok] * np.sin(a[ok])
        for px_, py_ in zip(hx, hy):
            c.circle(px_, py_, r_px=1.5, fill=RED)

    for ev in events or ():
        kind = ev.kind if hasattr(ev, "kind") else ev.get("kind", "")
        if kind in ("sim_started", "sim_stopped", "component_state"):
            continue
        p = _event_xy(ev, trajectory)
        if p is None:
            continue
        x, y = c.px(*p)
        if kind == "collision":
            c.draw.line([(x - 6, y - 6), (x + 6, y + 6)], fill=RED, width=3)
            c.draw.line([(x - 6, y + 6), (x + 6, y - 6)], fill=RED, width=3)
        elif kind == "fault":
            c.draw.polygon([(x, y - 7), (x - 6, y + 5), (x + 6, y + 5)], fill=ORANGE, outline=DARK_ORANGE)
        else:
            c.circle(*p, r_px=2.5, fill=GREY)

    if robot is not None:
        c.circle(robot.x, robot.y, r_m=robot_radius, outline=PATH, width=2)
        c.draw.line([c.px(robot.x, robot.y),
                     c.px(robot.x + robot_radius * math.cos(robot.yaw),
                          robot.y + robot_radius * math.sin(robot.yaw))], fill=PATH, width=2)

    c.draw.text((c.margin, 3), title or f"{world.name}  (1 m = {scale:g} px; slate: lidar+body, "
                "orange: body only, magenta outline: added at run time)", fill=(0, 0, 0))
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    c.img.convert("RGB").save(out, "PNG")
    return out
