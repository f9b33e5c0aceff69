"""Plain 2D geometry on numpy arrays: obstacle outlines, distances, rasterizing, ray casting.

Conventions: polygons are counter-clockwise (interior on the left of each edge), so the
outward normal of edge a->b is (dy, -dx). An *edge array* has shape (N, 4): ax, ay, bx, by,
each edge one-sided (it is seen only from outside). A *circle array* has shape (M, 3): cx, cy, r.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_runtime.runtime.messages import wrap_angle as wrap_angle  # the one definition, re-exported here

TWO_PI = 2.0 * math.pi


def polygon_area(points: np.ndarray) -> float:
    """Signed area (positive when counter-clockwise)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def is_convex(points: np.ndarray) -> bool:
    """True for a convex polygon (either orientation; collinear vertices allowed)."""
    d = np.roll(points, -1, axis=0) - points
    cross = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
    eps = 1e-12
    return bool(np.all(cross >= -eps) or np.all(cross <= eps))


def rectangle_around_segment(a: tuple[float, float], b: tuple[float, float],
                             thickness: float) -> np.ndarray:
    """The CCW rectangle of a thick segment (square ends flush with the end points)."""
    ax, ay = a
    bx, by = b
    L = math.hypot(bx - ax, by - ay)
    nx, ny = -(by - ay) / L * thickness / 2, (bx - ax) / L * thickness / 2
    return np.array([[ax - nx, ay - ny], [bx - nx, by - ny], [bx + nx, by + ny], [ax + nx, ay + ny]])


def polygon_edges(points: np.ndarray) -> np.ndarray:
    """Edges (N, 4) of a CCW polygon."""
    nxt = np.roll(points, -1, axis=0)
    return np.hstack([points, nxt])


def segment_edges(a: tuple[float, float], b: tuple[float, float]) -> np.ndarray:
    """A zero-thickness segment is seen from both sides: two opposite one-sided edges."""
    return np.array([[a[0], a[1], b[0], b[1]], [b[0], b[1], a[0], a[1]]], dtype=float)


def point_segment_distance(px: np.ndarray | float, py: np.ndarray | float,
                           edges: np.ndarray) -> np.ndarray:
    """Distance from each point (broadcast against edges) to each edge: shape (P, N) or (N,)."""
    ax, ay, bx, by = edges[:, 0], edges[:, 1], edges[:, 2], edges[:, 3]
    px = np.asarray(px, dtype=float)[..., None]
    py = np.asarray(py, dtype=float)[..., None]
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    L2 = np.where(L2 == 0, 1e-300, L2)
    t = np.clip(((px - ax) * dx + (py - ay) * dy) / L2, 0.0, 1.0)
    return np.hypot(px - (ax + t * dx), py - (ay + t * dy))


def convex_signed_distance(px: np.ndarray, py: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed distance to a CCW convex polygon: negative inside (approximate outside the
    corners' Voronoi regions: exact distance when outside, max of edge depths inside)."""
    edges = polygon_edges(points)
    ax, ay, bx, by = edges[:, 0], edges[:, 1], edges[:, 2], edges[:, 3]
    dx, dy = bx - ax, by - ay
    L = np.hypot(dx, dy)
    px = np.asarray(px, dtype=float)
    py = np.asarray(py, dtype=float)
    # outward normal (dy, -dx)/L; signed distance to each edge's line
    side = ((px[..., None] - ax) * dy - (py[..., None] - ay) * dx) / L
    inside_depth = side.max(axis=-1)
    outside = point_segment_distance(px, py, edges).min(axis=-1)
    return np.where(inside_depth <= 0, inside_depth, outside)


# ---------------------------------------------------------------------------------------------
# Raster
# ---------------------------------------------------------------------------------------------

@dataclass(slots=True)
class Raster:
    """An occupancy raster: ``data[row, col]`` (uint8, 1 = occupied), row 0 at ``origin[1]``
    (y grows with the row index, like a ROS OccupancyGrid; flip vertically to view it)."""

    data: np.ndarray
    resolution: float
    origin: tuple[float, float]

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    @property
    def height(self) -> int:
        return int(self.data.shape[0])

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding the point."""
        return (int(math.floor((y - self.origin[1]) / self.resolution)),
                int(math.floor((x - self.origin[0]) / self.resolution)))

    def cell_center(self, row: int, col: int) -> tuple[float, float]:
        return (self.origin[0] + (col + 0.5) * self.resolution,
                self.origin[1] + (row + 0.5) * self.resolution)


def rasterize(polygons: list[np.ndarray], circles: np.ndarray, edges: np.ndarray,
              origin: tuple[float, float], size: tuple[int, int], resolution: float,
              inflate: float = 0.0) -> Raster:
    """Mark every cell whose centre lies within ``resolution/2 + inflate`` of a shape.

    ``polygons``: CCW convex vertex arrays; ``circles``: (M, 3); ``edges``: (N, 4) thin
    segments. ``size`` = (width, height) in cells.
    """
    width, height = size
    data = np.zeros((height, width), dtype=np.uint8)
    margin = resolution / 2 + inflate
    ox, oy = origin

    def window(xmin: float, ymin: float, xmax: float, ymax: float):
        c0 = max(0, int(math.floor((xmin - margin - ox) / resolution)))
        c1 = min(width, int(math.ceil((xmax + margin - ox) / resolution)) + 1)
        r0 = max(0, int(math.floor((ymin - margin - oy) / resolution)))
        r1 = min(height, int(math.ceil((ymax + margin - oy) / resolution)) + 1)
        if c0 >= c1 or r0 >= r1:
            return None
        xs = ox + (np.arange(c0, c1) + 0.5) * resolution
        ys = oy + (np.arange(r0, r1) + 0.5) * resolution
        X, Y = np.meshgrid(xs, ys)
        return (slice(r0, r1), slice(c0, c1)), X, Y

    for pts in polygons:
        w = window(pts[:, 0].min(), pts[:, 1].min(), pts[:, 0].max(), pts[:, 1].max())
        if w is None:
            continue
        sl, X, Y = w
        d = convex_signed_distance(X, Y, pts)
        data[sl] |= (d <= margin).astype(np.uint8)
    for cx, cy, r in np.asarray(circles, dtype=float).reshape(-1, 3):
        w = window(cx - r, cy - r, cx + r, cy + r)
        if w is None:
            continue
        sl, X, Y = w
        data[sl] |= (np.hypot(X - cx, Y - cy) <= r + margin).astype(np.uint8)
    for e in np.asarray(edges, dtype=float).reshape(-1, 4):
        w = window(min(e[0], e[2]), min(e[1], e[3]), max(e[0], e[2]), max(e[1], e[3]))
        if w is None:
            continue
        sl, X, Y = w
        d = point_segment_distance(X, Y, e[None, :])[..., 0]
        data[sl] |= (d <= margin).astype(np.uint8)
    return Raster(data, resolution, (ox, oy))


# ---------------------------------------------------------------------------------------------
# Ray casting
# ---------------------------------------------------------------------------------------------

class RayCaster:
    """Vectorised 2D ray casting of a full (or partial) fan of beams against one-sided edges
    and circles.

    Instead of intersecting every beam with every shape, each front-facing edge (and each
    circle) in range is mapped to the interval of beam indices it subtends as seen from the
    sensor, and only those (beam, shape) pairs are intersected; ``np.minimum.at`` keeps the
    nearest hit per beam. The number of pairs is ~ beams x depth complexity, not beams x shapes.
    """

    def __init__(self, edges: np.ndarray, circles: np.ndarray) -> None:
        edges = np.asarray(edges, dtype=float).reshape(-1, 4)
        circles = np.asarray(circles, dtype=float).reshape(-1, 3)
        self.edges = edges
        self.circles = circles
        self._ax, self._ay = edges[:, 0].copy(), edges[:, 1].copy()
        self._dx, self._dy = edges[:, 2] - edges[:, 0], edges[:, 3] - edges[:, 1]
        self._xmin = np.minimum(edges[:, 0], edges[:, 2])
        self._xmax = np.maximum(edges[:, 0], edges[:, 2])
        self._ymin = np.minimum(edges[:, 1], edges[:, 3])
        self._ymax = np.maximum(edges[:, 1], edges[:, 3])
        self._cx, self._cy, self._cr = circles[:, 0].copy(), circles[:, 1].copy(), circles[:, 2].copy()
        self._trig_key: tuple[float, float, int] | None = None

    def _trig(self, angle_min: float, inc: float, n_full: int) -> tuple[np.ndarray, np.ndarray]:
        key = (angle_min, inc, n_full)
        if self._trig_key != key:
            a = angle_min + inc * np.arange(n_full)
            self._cos0, self._sin0 = np.cos(a), np.sin(a)
            self._trig_key = key
        return self._cos0, self._sin0

    def cast(self, ox: float, oy: float, yaw: float, n_beams: int, angle_min: float,
             angle_increment: float, max_range: float) -> np.ndarray:
        """True ranges (float64) of ``n_beams`` beams at ``yaw + angle_min + i*increment``
        from (ox, oy); ``inf`` where nothing lies within ``max_range``."""
        inc = angle_increment
        n_full = int(round(TWO_PI / inc))
        out = np.full(n_full, np.inf)
        base = yaw + angle_min
        # beam directions in the world frame: rotate the cached sensor-frame table by yaw
        c0, s0 = self._trig(0.0, inc, n_full)
        cy, sy = math.cos(base), math.sin(base)
        ux = c0 * cy - s0 * sy
        uy = s0 * cy + c0 * sy

        idx_parts: list[np.ndarray] = []
        t_parts: list[np.ndarray] = []
        if len(self._ax):
            # in range (bounding box) and front-facing: the sensor is right of a->b
            rx, ry = ox - self._ax, oy - self._ay
            sel = ((self._xmin - max_range <= ox) & (self._xmax + max_range >= ox)
                   & (self._ymin - max_range <= oy) & (self._ymax + max_range >= oy)
                   & (self._dx * ry - self._dy * rx < 0))
            k = np.flatnonzero(sel)
            if len(k):
                ax, ay, dx, dy = self._ax[k], self._ay[k], self._dx[k], self._dy[k]
                a0 = np.arctan2(ay - oy, ax - ox)
                a1 = np.arctan2(ay + dy - oy, ax + dx - ox)
                # an edge seen from its front goes clockwise (a1 < a0): span [a1, a0]
                start = ((a1 - base) % TWO_PI) / inc
                span = ((a0 - a1) % TWO_PI) / inc
                first = np.ceil(start - 1e-9)
                cnt = (np.floor(start + span + 1e-9) - first + 1).astype(np.intp)
                np.maximum(cnt, 0, out=cnt)
                total = int(cnt.sum())
                if total:
                    seg = np.repeat(np.arange(len(k)), cnt)
                    offs = np.cumsum(cnt) - cnt
                    beam = (first.astype(np.intp)[seg] + (np.arange(total) - offs[seg])) % n_full
                    bx, by = ux[beam], uy[beam]
                    ex, ey = dx[seg], dy[seg]
                    px, py = ax[seg] - ox, ay[seg] - oy
                    denom = bx * ey - by * ex
                    with np.errstate(divide="ignore", invalid="ignore"):
                        t = (px * ey - py * ex) / denom
                    good = (t >= 0) & np.isfinite(t)
                    idx_parts.append(beam[good])
                    t_parts.append(t[good])
        if len(self._cx):
            vx, vy = self._cx - ox, self._cy - oy
            d = np.hypot(vx, vy)
            sel = (d - self._cr <= max_range) & (d > self._cr)
            k = np.flatnonzero(sel)
            if len(k):
                vx, vy, d, r = vx[k], vy[k], d[k], self._cr[k]
                half = np.arcsin(r / d)
                centre = np.arctan2(vy, vx)
                start = ((centre - half - base) % TWO_PI) / inc
                span = 2 * half / inc
                first = np.ceil(start - 1e-9)
                cnt = (np.floor(start + span + 1e-9) - first + 1).astype(np.intp)
                np.maximum(cnt, 0, out=cnt)
                total = int(cnt.sum())
                if total:
                    ci = np.repeat(np.arange(len(k)), cnt)
                    offs = np.cumsum(cnt) - cnt
                    beam = (first.astype(np.intp)[ci] + (np.arange(total) - offs[ci])) % n_full
                    b = vx[ci] * ux[beam] + vy[ci] * uy[beam]
                    disc = r[ci] ** 2 - (d[ci] ** 2 - b * b)
                    good = disc >= 0
                    t = b[good] - np.sqrt(disc[good])
                    idx_parts.append(beam[good])
                    t_parts.append(t)
        if idx_parts:
            idx = np.concatenate(idx_parts) if len(idx_parts) > 1 else idx_parts[0]
            t = np.concatenate(t_parts) if len(t_parts) > 1 else t_parts[0]
            np.minimum.at(out, idx, t)
        out[out > max_range] = np.inf
        return out[:n_beams] if n_beams <= n_full else out
