"""Occupancy grids: rasterized from world geometry, or loaded/saved in ROS map_server format.

Conventions follow ROS ``nav_msgs/OccupancyGrid``: ``data[row, col]`` with row 0 at the map's
origin (the *bottom* of the picture), values 0 (free), 100 (occupied), -1 (unknown) and, in
"scale" mode, 1..99 in between. The cell ``(row, col)`` covers
``[ox + col*res, ox + (col+1)*res) x [oy + row*res, oy + (row+1)*res)``.

The map_server format (read by ``map_file.py``) is a picture plus a YAML file with ``image``, ``resolution``,
``origin`` [x, y, yaw], ``negate``, ``occupied_thresh``, ``free_thresh`` and optionally ``mode``
(trinary | scale | raw). Loading follows ``nav2_map_server/map_io.cpp``: with p = (255 - pixel)/255
(or pixel/255 when ``negate``), p >= occupied_thresh is occupied, p <= free_thresh is free,
anything else unknown (trinary) or scaled to 0..100 (scale). The picture's top row is the map's
top (largest y), so rows are flipped on the way in and out. Saving writes trinary PGMs the way
``map_saver`` does (254 free, 0 occupied, 205 unknown; thresholds 0.65 / 0.196).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import structlog
import yaml

from .map_file import FREE, OCCUPIED, UNKNOWN, pixels_to_occupancy, read_map, read_pgm

log = structlog.get_logger("sim.nav.occupancy")

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyGrid", "pixels_to_occupancy", "read_pgm", "write_pgm"]


@dataclass(slots=True)
class OccupancyGrid:
    data: np.ndarray  # int8 (H, W): 0 free .. 100 occupied, -1 unknown; row 0 at origin y
    resolution: float
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y, yaw of cell (0, 0)'s corner

    def __post_init__(self) -> None:
        self.data = np.ascontiguousarray(self.data, dtype=np.int8)
        if self.data.ndim != 2:
            raise ValueError(f"an occupancy grid is 2-D, got shape {self.data.shape}")
        if self.resolution <= 0:
            raise ValueError(f"resolution must be > 0, got {self.resolution}")
        ox, oy, *rest = self.origin
        self.origin = (float(ox), float(oy), float(rest[0]) if rest else 0.0)
        if abs(self.origin[2]) > 1e-9:
            log.warning("map_origin_yaw_ignored", yaw=self.origin[2],
                        note="costmaps are axis-aligned, as in Nav2")

    # -- geometry -------------------------------------------------------------------------
    @property
    def height(self) -> int:
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        ox, oy, _ = self.origin
        return (ox, oy, ox + self.width * self.resolution, oy + self.height * self.resolution)

    def world_to_cell(self, x, y):
        """(row, col) of the cell containing (x, y); works on scalars and arrays; may be out of
        bounds (check with ``in_bounds``)."""
        ox, oy, _ = self.origin
        r = np.floor((np.asarray(y, dtype=float) - oy) / self.resolution).astype(np.int64)
        c = np.floor((np.asarray(x, dtype=float) - ox) / self.resolution).astype(np.int64)
        if r.ndim == 0:
            return int(r), int(c)
        return r, c

    def cell_to_world(self, row, col):
        """World coordinates of a cell's centre."""
        ox, oy, _ = self.origin
        x = ox + (np.asarray(col, dtype=float) + 0.5) * self.resolution
        y = oy + (np.asarray(row, dtype=float) + 0.5) * self.resolution
        if x.ndim == 0:
            return float(x), float(y)
        return x, y

    def in_bounds(self, row, col):
        return (row >= 0) & (row < self.height) & (col >= 0) & (col < self.width)

    def value_at(self, x: float, y: float) -> int:
        """Occupancy at a world point; -1 (unknown) outside the map."""
        r, c = self.world_to_cell(x, y)
        if 0 <= r < self.height and 0 <= c < self.width:
            return int(self.data[r, c])
        return UNKNOWN

    def occupied_mask(self, threshold: int = 65) -> np.ndarray:
        return self.data >= threshold

    def unknown_mask(self) -> np.ndarray:
        return self.data < 0

    def copy(self) -> OccupancyGrid:
        return OccupancyGrid(self.data.copy(), self.resolution, self.origin)

    # -- rasterization --------------------------------------------------------------------
    @classmethod
    def from_shapes(cls, polygons: Iterable[np.ndarray] = (),
                    circles: Iterable[Sequence[float]] = (),
                    segments: Iterable[Sequence[float]] = (), *,
                    bounds: Sequence[float], resolution: float = 0.05,
                    conservative: bool = True) -> OccupancyGrid:
        """Rasterize obstacle geometry given as plain data.

        ``polygons``: (N, 2) vertex arrays (any winding, closed implicitly); ``circles``:
        (cx, cy, r); ``segments``: (x0, y0, x1, y1, thickness) thick lines with flat ends.
        ``bounds`` = (xmin, ymin, xmax, ymax) of the map. With ``conservative`` (default) a cell
        is occupied if the shape touches it at all (what a LiDAR hit on the surface would
        mark); otherwise only if the cell's centre is inside.
        """
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)
        if xmax <= xmin or ymax <= ymin:
            raise ValueError(f"empty bounds {bounds}")
        w = int(math.ceil((xmax - xmin) / resolution - 1e-9))
        h = int(math.ceil((ymax - ymin) / resolution - 1e-9))
        grid = cls(np.zeros((h, w), np.int8), resolution, (xmin, ymin, 0.0))
        occ = np.zeros((h, w), bool)
        half = resolution / 2.0 if conservative else 0.0
        for poly in polygons:
            grid._raster_polygon(occ, np.asarray(poly, dtype=float), conservative)
        for cx, cy, rad in circles:
            grid._raster_circle(occ, float(cx), float(cy), float(rad), conservative)
        for x0, y0, x1, y1, thick in segments:
            grid._raster_segment(occ, float(x0), float(y0), float(x1), float(y1),
                                 max(float(thick), 0.0) / 2.0, half)
        grid.data[occ] = OCCUPIED
        return grid

    def _window(self, xlo: float, ylo: float, xhi: float, yhi: float, margin: float):
        """Cell window covering a world box (clipped); returns (r0, r1, c0, c1, X, Y) with X, Y
        the cell-centre coordinates of the window, or None if empty."""
        r0, c0 = self.world_to_cell(xlo - margin, ylo - margin)
        r1, c1 = self.world_to_cell(xhi + margin, yhi + margin)
        r0, c0 = max(r0, 0), max(c0, 0)
        r1, c1 = min(r1 + 1, self.height), min(c1 + 1, self.width)
        if r0 >= r1 or c0 >= c1:
            return None
        xs, ys = self.cell_to_world(np.arange(r0, r1), np.arange(c0, c1))
        # cell_to_world(row, col) -> (x of col, y of row)
        return r0, r1, c0, c1, xs[None, :], ys[:, None]

    def _raster_circle(self, occ: np.ndarray, cx: float, cy: float, rad: float,
                       conservative: bool) -> None:
        win = self._window(cx - rad, cy - rad, cx + rad, cy + rad, self.resolution)
        if win is None:
            return
        r0, r1, c0, c1, X, Y = win
        if conservative:  # distance from the disc centre to the cell square
            half = self.resolution / 2.0
            dx = np.maximum(np.abs(X - cx) - half, 0.0)
            dy = np.maximum(np.abs(Y - cy) - half, 0.0)
        else:
            dx, dy = X - cx, Y - cy
        occ[r0:r1, c0:c1] |= dx * dx + dy * dy <= rad * rad

    def _raster_segment(self, occ: np.ndarray, x0: float, y0: float, x1: float, y1: float,
                        half_thick: float, margin: float) -> None:
        pad = half_thick + margin
        win = self._window(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1), pad + self.resolution)
        if win is None:
            return
        r0, r1, c0, c1, X, Y = win
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        if length < 1e-12:
            self._raster_circle(occ, x0, y0, half_thick, margin > 0)
            return
        ux, uy = dx / length, dy / length
        along = (X - x0) * ux + (Y - y0) * uy
        across = np.abs(-(X - x0) * uy + (Y - y0) * ux)
        # a cell square of half-size m reaches at most m*(|ux|+|uy|) along either axis
        m = margin * (abs(ux) + abs(uy))
        inside = (along >= -m) & (along <= length + m) & (across <= half_thick + m)
        occ[r0:r1, c0:c1] |= inside

    def _raster_polygon(self, occ: np.ndarray, poly: np.ndarray, conservative: bool) -> None:
        if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
            raise ValueError(f"a polygon is an (N>=3, 2) array, got shape {poly.shape}")
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        win = self._window(lo[0], lo[1], hi[0], hi[1], self.resolution)
        if win is None:
            return
        r0, r1, c0, c1, X, Y = win
        X = np.broadcast_to(X, (r1 - r0, c1 - c0))
        Y = np.broadcast_to(Y, (r1 - r0, c1 - c0))
        inside = np.zeros(X.shape, bool)
        xs, ys = poly[:, 0], poly[:, 1]
        for i in range(len(poly)):  # even-odd rule, vectorised over the cells
            xa, ya, xb, yb = xs[i - 1], ys[i - 1], xs[i], ys[i]
            if ya == yb:
                continue
            crosses = (ya > Y) != (yb > Y)
            xcross = xa + (Y - ya) * (xb - xa) / (yb - ya)
            inside ^= crosses & (xcross > X)
        occ[r0:r1, c0:c1] |= inside
        if conservative:  # plus every cell the outline passes through
            for i in range(len(poly)):
                self._raster_segment(occ, xs[i - 1], ys[i - 1], xs[i], ys[i], 0.0,
                                     self.resolution / 2.0)

    # -- ray casting (for test fixtures and simple sensors) -------------------------------
    def raycast(self, x: float, y: float, angles: np.ndarray, max_range: float,
                min_range: float = 0.0, step: float | None = None,
                occupied_threshold: int = 65) -> np.ndarray:
        """Range to the first occupied cell along each world-frame angle; ``inf`` when nothing
        is hit within ``max_range`` (leaving the map counts as nothing hit)."""
        step = step or self.resolution / 2.0
        t = np.arange(max(min_range, step), max_range + 1e-9, step)
        angles = np.asarray(angles, dtype=float)
        px = x + np.cos(angles)[:, None] * t[None, :]
        py = y + np.sin(angles)[:, None] * t[None, :]
        r, c = self.world_to_cell(px, py)
        inside = self.in_bounds(r, c)
        hit = np.zeros(px.shape, bool)
        occ = self.data >= occupied_threshold
        hit[inside] = occ[r[inside], c[inside]]
        any_hit = hit.any(axis=1)
        first = hit.argmax(axis=1)
        return np.where(any_hit, t[first], np.inf)

    # -- ROS map_server format ------------------------------------------------------------
    @classmethod
    def load(cls, yaml_path: str | Path) -> OccupancyGrid:
        """Load a map_server map (YAML + PGM/PNG); errors name the file and the field
        (``map_file.MapFileError``, a ValueError)."""
        m = read_map(yaml_path)
        return cls(m.data, m.resolution, m.origin)

    def save(self, yaml_path: str | Path, image: str | None = None) -> Path:
        """Save as map_server trinary PGM + YAML (like ``map_saver_cli``). Returns the YAML path."""
        yaml_path = Path(yaml_path)
        if yaml_path.suffix != ".yaml":
            yaml_path = yaml_path.with_suffix(".yaml")
        image_name = image or yaml_path.with_suffix(".pgm").name
        pixels = np.full(self.data.shape, 205, np.uint8)
        d = self.data.astype(np.int16)
        known = (d >= 0) & (d <= 100)
        pixels[known & (d <= 20)] = 254  # rint(0.196 * 100) = 20
        pixels[known & (d >= 65)] = 0
        write_pgm(yaml_path.parent / image_name, pixels[::-1],
                  comment=f"bt_runtime sim.nav {self.resolution:.3f} m/pix")
        meta = {
            "image": image_name,
            "mode": "trinary",
            "resolution": float(self.resolution),
            "origin": [float(self.origin[0]), float(self.origin[1]), float(self.origin[2])],
            "negate": 0,
            "occupied_thresh": 0.65,
            "free_thresh": 0.196,
        }
        yaml_path.write_text(yaml.safe_dump(meta, sort_keys=False, default_flow_style=None))
        return yaml_path


def write_pgm(path: str | Path, pixels: np.ndarray, comment: str = "") -> None:
    pixels = np.ascontiguousarray(pixels, dtype=np.uint8)
    h, w = pixels.shape
    header = b"P5\n" + (f"# {comment}\n".encode() if comment else b"") + f"{w} {h}\n255\n".encode()
    Path(path).write_bytes(header + pixels.tobytes())
