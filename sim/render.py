"""Render a world (and optionally a map, a path, a scan, events, goals) to a PNG with Pillow.

    render_png("out/run.png", sim.world, occupancy=raster, trajectory=sim.trajectory(),
               scan=(scan, pose), events=sim.events, obstacles=sim.dynamic_obstacles.values())

The map is framed by axes in metres (light grid, tick labels, a scale bar) and a legend lists
what is drawn. Colours: lidar-blocking obstacles dark slate; body-only ("undetected")
obstacles orange with a dark-orange outline; lidar-only shapes (rare) light blue outline.
Obstacles added at run time are drawn like the others, outlined in magenta. Occupied map
cells are grey, unknown cells pale yellow; the path is blue (green start circle, red end
dot); scan hits are red dots; collisions are red crosses, faults orange triangles, other
events small grey dots; goals are green ringed dots with their names, the spawn pose a blue
arrow, the dock a purple square. ``sim.render_layout.Layout`` maps metres to pixels.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from bt_runtime.runtime.messages import LaserScan, Pose2D

from .render_layout import PAD, Layout, font, tick_step
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
    """The image and the drawing helpers, on a ``Layout`` (map metres -> pixels)."""

    def __init__(self, world: World, scale: float) -> None:
        self.layout = Layout.of(world.bounds, scale)
        self.scale = scale
        self.img = Image.new("RGBA", (self.layout.width, self.layout.height), (255, 255, 255, 255))
        self.draw = ImageDraw.Draw(self.img, "RGBA")
        self.legend: dict[str, tuple[str, tuple[int, int, int]]] = {}  # label -> (marker kind, colour)

    def px(self, x: float, y: float) -> tuple[float, float]:
        return self.layout.px(x, y)

    def poly(self, pts, fill=None, outline=None, width=1) -> None:
        self.draw.polygon([self.px(*p) for p in pts], fill=fill, outline=outline, width=width)

    def circle(self, x, y, r_m=None, r_px=None, fill=None, outline=None, width=1) -> None:
        cx, cy = self.px(x, y)
        r = r_px if r_px is not None else max(1.0, r_m * self.scale)
        self.draw.ellipse([cx - r, cy - r, cx + r, cy + r], fill=fill, outline=outline, width=width)

    def note(self, label: str, kind: str, colour: tuple[int, int, int]) -> None:
        """Add a legend entry (once per label)."""
        self.legend.setdefault(label, (kind, colour))


def _marker(draw: ImageDraw.ImageDraw, kind: str, x: float, y: float, colour) -> None:
    """The shapes shared by the map and the legend."""
    if kind == "line":
        draw.line([(x - 9, y), (x + 9, y)], fill=colour, width=3)
    elif kind == "start":
        draw.ellipse([x - 5, y - 5, x + 5, y + 5], outline=colour, width=2)
    elif kind == "end":
        draw.ellipse([x - 4, y - 4, x + 4, y + 4], fill=colour)
    elif kind == "goal":
        draw.ellipse([x - 7, y - 7, x + 7, y + 7], outline=colour, width=2)
        draw.ellipse([x - 2, y - 2, x + 2, y + 2], fill=colour)
    elif kind == "fault":
        draw.polygon([(x, y - 8), (x - 7, y + 5), (x + 7, y + 5)], fill=ORANGE, outline=DARK_ORANGE)
    elif kind == "collision":
        draw.line([(x - 6, y - 6), (x + 6, y + 6)], fill=colour, width=3)
        draw.line([(x - 6, y + 6), (x + 6, y - 6)], fill=colour, width=3)
    elif kind == "mark":
        draw.rectangle([x - 4, y - 4, x + 4, y + 4], outline=colour, width=2)
    elif kind == "spawn":
        draw.ellipse([x - 3, y - 3, x + 3, y + 3], fill=colour)
        draw.line([(x, y), (x + 10, y)], fill=colour, width=2)
    elif kind == "dock":
        draw.rectangle([x - 5, y - 5, x + 5, y + 5], outline=colour, width=2)
    elif kind == "block":
        draw.rectangle([x - 8, y - 5, x + 8, y + 5], fill=colour)
    elif kind == "outline":
        draw.rectangle([x - 8, y - 5, x + 8, y + 5], outline=colour, width=2)
    else:
        draw.ellipse([x - 3, y - 3, x + 3, y + 3], fill=colour)


def _draw_axes(c: _Canvas) -> None:
    """Frame, light grid and tick labels in metres, axis names, and a scale bar."""
    lay, d, f = c.layout, c.draw, font(13)
    x0, y0 = lay.px(lay.xmin, lay.ymax)
    x1, y1 = lay.px(lay.xmax, lay.ymin)
    for tx in lay.ticks(lay.xmin, lay.xmax):
        px_, _ = lay.px(tx, 0)
        d.line([(px_, y0), (px_, y1)], fill=(228, 228, 228))
        d.line([(px_, y1), (px_, y1 + 5)], fill=(0, 0, 0), width=1)
        d.text((px_, y1 + 7), f"{tx:g}", fill=(0, 0, 0), font=f, anchor="mt")
    for ty in lay.ticks(lay.ymin, lay.ymax):
        _, py_ = lay.px(0, ty)
        d.line([(x0, py_), (x1, py_)], fill=(228, 228, 228))
        d.line([(x0 - 5, py_), (x0, py_)], fill=(0, 0, 0), width=1)
        d.text((x0 - 8, py_), f"{ty:g}", fill=(0, 0, 0), font=f, anchor="rm")
    d.rectangle([x0, y0, x1, y1], outline=(0, 0, 0), width=1)
    d.text(((x0 + x1) / 2, y1 + 26), "x [m]", fill=(0, 0, 0), font=f, anchor="mt")
    d.text((x0 - 40, (y0 + y1) / 2), "y [m]", fill=(0, 0, 0), font=f, anchor="mm")
    bar_m = tick_step(lay.xmax - lay.xmin, lay.scale)
    bx1, by = x1, y1 + 34
    bx0 = bx1 - bar_m * lay.scale
    d.rectangle([bx0, by - 3, bx1, by + 3], fill=(0, 0, 0))
    d.text((bx0 - 6, by), f"{bar_m:g} m", fill=(0, 0, 0), font=f, anchor="rm")


def _draw_legend(c: _Canvas) -> None:
    lay, d, f = c.layout, c.draw, font(13)
    x = lay.left + lay.map_w + PAD + 8
    y = lay.top + 4
    d.text((x, y), "legend", fill=(0, 0, 0), font=font(14))
    y += 24
    for label, (kind, colour) in c.legend.items():
        _marker(d, kind, x + 10, y + 8, colour)
        for line in _wrap(label, 24):
            d.text((x + 26, y), line, fill=(0, 0, 0), font=f)
            y += 16
        y += 4


def _wrap(text: str, width: int) -> list[str]:
    words, lines, line = text.split(), [], ""
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}" if line else w
    return lines + [line] if line else lines or [""]


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
    """The (x, y) columns of a trajectory: (N, 2) is x, y; three or more columns are
    t, x, y[, yaw, ...] (``Simulator.trajectory()``, the campaign's (t, x, y) records)."""
    tr = np.asarray(trajectory, dtype=float)
    if tr.ndim != 2 or len(tr) == 0 or tr.shape[1] < 2:
        return np.empty((0, 2))
    xy = tr[:, 1:3] if tr.shape[1] >= 3 else tr[:, :2]
    return xy[np.isfinite(xy).all(axis=1)]


def _event_xy(ev: Any, trajectory: Any) -> tuple[float, float] | None:
    data = ev.data if hasattr(ev, "data") else ev.get("data", ev)
    for key in ("point", "center"):
        p = data.get(key) if isinstance(data, Mapping) else None
        if p is not None and len(p) == 2 and all(map(math.isfinite, p)):
            return float(p[0]), float(p[1])
    if isinstance(data, Mapping) and "x" in data and "y" in data and data["x"] is not None:
        return float(data["x"]), float(data["y"])
    t = ev.t if hasattr(ev, "t") else ev.get("t")
    return position_at(trajectory, t) if trajectory is not None and t is not None else None


def position_at(trajectory: Any, t: float) -> tuple[float, float] | None:
    """Where a (t, x, y, ...) trajectory was at time ``t`` (the first sample at or after it)."""
    tr = np.asarray(trajectory, dtype=float)
    if tr.ndim != 2 or tr.shape[1] < 3 or len(tr) == 0:
        return None
    i = int(np.clip(np.searchsorted(tr[:, 0], t), 0, len(tr) - 1))
    return float(tr[i, 1]), float(tr[i, 2])


def render_png(path: str | Path, world: World, *, occupancy: Any = None, trajectory: Any = None,
               scan: LaserScan | tuple[LaserScan, Pose2D] | None = None, scan_pose: Pose2D | None = None,
               events: Iterable[Any] | None = None, goals: Mapping[str, Any] | Iterable[Any] | None = None,
               obstacles: Iterable[Any] | None = None, robot: Pose2D | None = None, robot_radius: float = 0.105,
               scale: float = 50.0, title: str | None = None,
               trajectories: Iterable[tuple[Any, tuple[int, int, int]]] = (),
               marks: Iterable[tuple[float, float, tuple[int, int, int], str]] = (),
               legend: Mapping[str, tuple[int, int, int]] | None = None) -> Path:
    """Draw the world and the optional layers to ``path`` (PNG); returns the path.

    The map is framed by axes in metres with a scale bar; a legend names every kind of mark
    drawn. ``occupancy``: a Raster-like grid (see ``_occupancy_parts``). ``trajectory``:
    (N, 2) x, y, or (N, >=3) t, x, y, ... (``Simulator.trajectory()``); drawn blue from a
    start circle to an end dot. ``scan``: a LaserScan with ``scan_pose`` (the robot's
    map-frame pose when it was taken; the lidar mounting offset is ignored), or a (scan,
    pose) pair. ``events``: SimEvents (or dicts with t/kind/data; data may hold x, y):
    collisions are red crosses, faults orange triangles. ``goals``: name -> pose mapping, or
    poses; default: the world's goals. ``obstacles``: extra (run-time) obstacles. ``robot``:
    draw the robot's body at this pose. ``trajectories``: more paths as (trajectory, rgb)
    pairs (e.g. many runs of one scenario), named in the legend by ``legend`` (label -> rgb).
    ``marks``: (x, y, rgb, label) squares (e.g. obstacles the autonomy layer added).
    """
    c = _Canvas(world, scale)
    _draw_axes(c)
    if occupancy is not None:
        data, res, origin = _occupancy_parts(occupancy)
        rgba = _occupancy_rgb(np.asarray(data))[::-1]  # row 0 = ymin -> bottom of the image
        layer = Image.fromarray(np.ascontiguousarray(rgba), "RGBA")
        w_px = max(1, int(round(data.shape[1] * res * scale)))
        h_px = max(1, int(round(data.shape[0] * res * scale)))
        layer = layer.resize((w_px, h_px), Image.NEAREST)
        x0, y1 = c.px(origin[0], origin[1] + data.shape[0] * res)
        c.img.alpha_composite(layer, (int(round(x0)), int(round(y1))))
        c.note("occupied map cell", "block", (110, 110, 110))
    for ob in world.obstacles:
        _draw_obstacle(c, ob)
    if any(ob.blocks_lidar and ob.blocks_body for ob in world.obstacles):
        c.note("wall / obstacle", "block", SLATE)
    if any(ob.blocks_body and not ob.blocks_lidar for ob in world.obstacles):
        c.note("obstacle the lidar cannot see", "block", ORANGE)
    extra_obstacles = list(obstacles or ())
    for ob in extra_obstacles:
        _draw_obstacle(c, ob, dynamic=True)
    if extra_obstacles:
        c.note("obstacle added at run time", "outline", MAGENTA)

    goal_items: list[tuple[str, Any]]
    if goals is None:
        goal_items = list(world.goals.items())
    elif isinstance(goals, Mapping):
        goal_items = list(goals.items())
    else:
        goal_items = [("", g) for g in goals]
    label_font = font(13)
    for name, g in goal_items:
        gx, gy = (g.x, g.y) if hasattr(g, "x") else (g[0], g[1])
        x, y = c.px(gx, gy)
        _marker(c.draw, "goal", x, y, GREEN)
        if name:
            c.draw.text((x + 9, y - 8), name, fill=GREEN, font=label_font)
        c.note("goal", "goal", GREEN)
    sp = world.spawn
    x, y = c.px(sp.x, sp.y)
    c.draw.line([(x, y), c.px(sp.x + 0.3 * math.cos(sp.yaw), sp.y + 0.3 * math.sin(sp.yaw))], fill=PATH, width=2)
    c.circle(sp.x, sp.y, r_px=3, fill=PATH)
    c.note("world spawn pose", "spawn", PATH)
    if world.dock is not None:
        x, y = c.px(world.dock.x, world.dock.y)
        _marker(c.draw, "dock", x, y, PURPLE)
        c.note("dock", "dock", PURPLE)

    for label, colour in (legend or {}).items():
        c.note(label, "line", colour)
    for extra, colour in trajectories:
        xy = _traj_xy(extra)
        if len(xy) > 1:
            c.draw.line([c.px(px, py) for px, py in xy], fill=colour, width=2)
        if len(xy):
            _marker(c.draw, "start", *c.px(*xy[0]), colour)
            _marker(c.draw, "end", *c.px(*xy[-1]), colour)
            c.note("start of a run (circle), end (dot)", "start", (0, 0, 0))

    if trajectory is not None:
        xy = _traj_xy(trajectory)
        if len(xy) > 1:
            c.draw.line([c.px(px, py) for px, py in xy], fill=PATH, width=3)
            c.note("trajectory (ground truth)", "line", PATH)
        if len(xy):
            _marker(c.draw, "start", *c.px(*xy[0]), GREEN)
            _marker(c.draw, "end", *c.px(*xy[-1]), RED)
            c.note("start", "start", GREEN)
            c.note("end", "end", RED)

    for mx, my, colour, label in marks:
        x, y = c.px(mx, my)
        _marker(c.draw, "mark", x, y, colour)
        if label:  # named in the legend: many marks share one label
            c.note(label, "mark", colour)

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
        c.note("lidar hits", "dot", RED)

    for ev in events or ():
        kind = ev.kind if hasattr(ev, "kind") else ev.get("kind", "")
        if kind in ("sim_started", "sim_stopped", "component_state"):
            continue
        p = _event_xy(ev, trajectory)
        if p is None:
            continue
        x, y = c.px(*p)
        if kind == "collision":
            _marker(c.draw, "collision", x, y, RED)
            c.note("collision", "collision", RED)
        elif kind == "fault":
            _marker(c.draw, "fault", x, y, ORANGE)
            c.note("fault injected", "fault", ORANGE)
        else:
            c.circle(*p, r_px=2.5, fill=GREY)
            c.note("other event", "dot", GREY)

    if robot is not None:
        c.circle(robot.x, robot.y, r_m=robot_radius, outline=PATH, width=2)
        c.draw.line([c.px(robot.x, robot.y),
                     c.px(robot.x + robot_radius * math.cos(robot.yaw),
                          robot.y + robot_radius * math.sin(robot.yaw))], fill=PATH, width=2)
        c.note("robot", "start", PATH)

    _draw_legend(c)
    title_lines = _wrap(title or f"{world.name}", max(40, int(c.layout.width / 9)))[:2]
    for i, line in enumerate(title_lines):
        c.draw.text((PAD, 6 + 20 * i), line, fill=(0, 0, 0), font=font(16))
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    c.img.convert("RGB").save(out, "PNG")
    return out
