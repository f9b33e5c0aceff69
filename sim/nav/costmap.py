"""Costmaps with Nav2's cost values and layers (static, obstacle, inflation, plus two extras).

Cost values (``nav2_costmap_2d/cost_values.hpp``): 0 free, 1..252 graded, 253 inscribed
(the robot's centre here means a collision), 254 lethal, 255 no information.

Layers, combined in this order into the master grid (Nav2's ``combination_method`` 1 = max,
where an observed cell overrides "no information"):
  * static    the map: occupancy >= ``lethal_cost_threshold`` -> 254, unknown -> 255 (or free
              when not tracking unknown space), anything else 0 (trinary, as Nav2 defaults)
  * updates   ``add_obstacle`` marks: lethal discs that persist across clears (what the
              autonomy layer writes after a collision). Shared by both costmaps.
  * obstacle  from LaserScans: raytrace clearing along each beam, then marking of the hits
              within ``obstacle_max_range``; robot footprint cleared. Dropped by ``clear()``.
  * phantom   fault injection: lethal regions that look like sensed obstacles but are not
              raytraced away; dropped by ``clear()`` (ClearEntireCostmap).
  * inflation ``cost = 252 * exp(-k (d - r_inscribed))`` for r_inscribed < d <= inflation
              radius, 253 within the inscribed radius, d measured between cell centres as
              Nav2 does. Vectorised with an exact Euclidean distance transform (scipy).

``GlobalCostmap`` covers the whole map and re-inflates only the window a scan changed.
``LocalCostmap`` is a rolling window (3 x 3 m by default) around the robot, aligned to the map's
cells, with no static layer (as in the TurtleBot3 parameters).
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np
from scipy import ndimage

from bt_runtime.runtime.messages import LaserScan, Pose2D

from .occupancy import OccupancyGrid
from .params import CostmapParams, LocalCostmapParams

FREE_SPACE = 0
MAX_NON_OBSTACLE = 252
INSCRIBED = 253
LETHAL = 254
NO_INFORMATION = 255


def inflation_cost(distance_m: np.ndarray | float, inscribed_radius: float, inflation_radius: float,
                   cost_scaling_factor: float, resolution: float):
    """Nav2's InflationLayer::computeCost for a distance (metres, between cell centres) to the
    nearest lethal cell; cells beyond the inflation radius get 0."""
    d = np.asarray(distance_m, dtype=float)
    factor = np.exp(-cost_scaling_factor * (d - inscribed_radius))
    cost = np.floor(MAX_NON_OBSTACLE * factor)
    cost = np.where(d <= inscribed_radius, INSCRIBED, cost)
    cost = np.where(d <= 0.0, LETHAL, cost)
    max_cells = math.ceil(inflation_radius / resolution - 1e-9)
    cost = np.where(d > max_cells * resolution + 1e-9, FREE_SPACE, cost)
    out = cost.astype(np.uint8)
    return int(out) if out.ndim == 0 else out


class Inflator:
    """Turns a lethal mask into inflated costs via a lookup table on squared cell distance."""

    def __init__(self, resolution: float, inscribed_radius: float, inflation_radius: float,
                 cost_scaling_factor: float):
        self.resolution = resolution
        self.inscribed_radius = inscribed_radius
        self.inflation_radius = inflation_radius
        self.cost_scaling_factor = cost_scaling_factor
        self.cells = math.ceil(inflation_radius / resolution - 1e-9)
        self.max_d2 = self.cells * self.cells
        d = np.sqrt(np.arange(self.max_d2 + 1, dtype=float)) * resolution
        lut = inflation_cost(d, inscribed_radius, inflation_radius, cost_scaling_factor, resolution)
        self.lut = np.append(lut, np.uint8(FREE_SPACE))  # index max_d2 + 1 = beyond the radius

    def distances(self, lethal: np.ndarray) -> np.ndarray:
        """Euclidean distance in cells from each cell to the nearest lethal cell (inf if none)."""
        if not lethal.any():
            return np.full(lethal.shape, np.inf)
        return ndimage.distance_transform_edt(~lethal)

    def costs_from_distances(self, dist_cells: np.ndarray) -> np.ndarray:
        d2 = np.minimum(dist_cells * dist_cells, self.max_d2 + 1.0)
        idx = np.rint(d2).astype(np.intp)
        return self.lut[np.minimum(idx, self.max_d2 + 1)]

    def costs(self, lethal: np.ndarray) -> np.ndarray:
        return self.costs_from_distances(self.distances(lethal))


def combine_unknown(inflated: np.ndarray, unknown: np.ndarray) -> np.ndarray:
    """Nav2: an unknown cell takes the inflated cost only if it is >= inscribed."""
    if not unknown.any():
        return inflated
    return np.where(unknown & (inflated < INSCRIBED), np.uint8(NO_INFORMATION), inflated)


_INFLATED: OrderedDict[tuple, np.ndarray] = OrderedDict()  # (layers' bytes, shape, inflator) -> costs
_INFLATED_MAX = 16


def _inflated_master(inflator: Inflator, base: np.ndarray) -> np.ndarray:
    """The whole map's inflated costs from its combined layers (a new array).

    A campaign worker builds a costmap of the same map for every run, and every "clear entire
    costmap" recomputes it from the static layer alone: the result depends only on the layers'
    values and the inflation parameters, so it is kept per process (keyed by the values
    themselves) and each caller gets a copy."""
    key = (base.tobytes(), base.shape, inflator.resolution, inflator.inscribed_radius,
           inflator.inflation_radius, inflator.cost_scaling_factor)
    costs = _INFLATED.get(key)
    if costs is None:
        costs = combine_unknown(inflator.costs(base == LETHAL), base == NO_INFORMATION)
        _INFLATED[key] = costs
        if len(_INFLATED) > _INFLATED_MAX:
            _INFLATED.popitem(last=False)
    else:
        _INFLATED.move_to_end(key)
    return costs.copy()


class _Rays:
    """Vectorised beam sampling shared by both costmaps."""

    def __init__(self) -> None:
        self._key: tuple | None = None
        self._angles: np.ndarray | None = None

    def angles(self, scan: LaserScan) -> np.ndarray:
        key = (scan.angle_min, scan.angle_increment, len(scan.ranges))
        if key != self._key:
            self._key = key
            self._angles = scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
        return self._angles


def _finite(pose: Pose2D) -> bool:
    """A pose a scan can be placed with (a corrupt localization gives NaN)."""
    return math.isfinite(pose.x) and math.isfinite(pose.y) and math.isfinite(pose.yaw)


def _scan_geometry(scan: LaserScan, pose: Pose2D, laser_offset, params: CostmapParams, rays: _Rays):
    """World-frame origin, beam directions, clearing lengths and marking mask of a scan."""
    ox_l, oy_l, oyaw_l = laser_offset
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    x0 = pose.x + c * ox_l - s * oy_l
    y0 = pose.y + s * ox_l + c * oy_l
    ang = rays.angles(scan) + (pose.yaw + oyaw_l)
    cos, sin = np.cos(ang), np.sin(ang)
    r = np.asarray(scan.ranges, dtype=float)
    with np.errstate(invalid="ignore"):
        valid_hit = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
        no_hit = ~np.isnan(r) & ~valid_hit & ((r >= scan.range_max) | np.isposinf(r))
    clear_len = np.where(valid_hit, r, 0.0)
    if params.inf_is_valid:
        clear_len = np.where(no_hit, scan.range_max, clear_len)
    clear_len = np.minimum(clear_len, params.raytrace_max_range)
    with np.errstate(invalid="ignore"):
        mark = valid_hit & (r <= params.obstacle_max_range) & (r >= params.obstacle_min_range)
    return x0, y0, cos, sin, r, clear_len, mark


class Costmap2D:
    """A cost grid (uint8, row 0 at the origin's y) with world<->cell helpers."""

    def __init__(self, width: int, height: int, resolution: float, origin_x: float,
                 origin_y: float, robot_radius: float, params: CostmapParams):
        self.width = int(width)
        self.height = int(height)
        self.resolution = float(resolution)
        self.origin_x = float(origin_x)
        self.origin_y = float(origin_y)
        # cell indices are computed against a fixed base (the map's origin) minus an integer
        # offset, so a rolling window agrees exactly with the global grid on cell boundaries
        self._bx, self._by = self.origin_x, self.origin_y
        self._or = self._oc = 0
        self.params = params
        self.robot_radius = float(robot_radius)
        self.inscribed_radius = robot_radius + params.footprint_padding
        self.inflator = Inflator(resolution, self.inscribed_radius, params.inflation_radius,
                                 params.cost_scaling_factor)
        self.cost = np.zeros((self.height, self.width), np.uint8)
        self.version = 0
        self._rays = _Rays()
        self._fp_offsets = self._disc_offsets(self.robot_radius)

    # -- geometry ---------------------------------------------------------------------------
    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        return (math.floor((y - self._by) / self.resolution) - self._or,
                math.floor((x - self._bx) / self.resolution) - self._oc)

    def cell_to_world(self, row, col):
        x = self.origin_x + (np.asarray(col, dtype=float) + 0.5) * self.resolution
        y = self.origin_y + (np.asarray(row, dtype=float) + 0.5) * self.resolution
        if x.ndim == 0:
            return float(x), float(y)
        return x, y

    def in_bounds(self, row: int, col: int) -> bool:
        return 0 <= row < self.height and 0 <= col < self.width

    def cost_at(self, x: float, y: float) -> int:
        """Cost at a world point; NO_INFORMATION outside the grid."""
        r, c = self.world_to_cell(x, y)
        if 0 <= r < self.height and 0 <= c < self.width:
            return int(self.cost[r, c])
        return NO_INFORMATION

    def costs_at(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        r = np.floor((np.asarray(ys) - self._by) / self.resolution).astype(np.intp) - self._or
        c = np.floor((np.asarray(xs) - self._bx) / self.resolution).astype(np.intp) - self._oc
        inside = (r >= 0) & (r < self.height) & (c >= 0) & (c < self.width)
        out = np.full(r.shape, NO_INFORMATION, np.uint8)
        out[inside] = self.cost[r[inside], c[inside]]
        return out

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return (self.origin_x, self.origin_y, self.origin_x + self.width * self.resolution,
                self.origin_y + self.height * self.resolution)

    def _disc_offsets(self, radius: float) -> tuple[np.ndarray, np.ndarray]:
        n = math.ceil(radius / self.resolution)
        dr, dc = np.mgrid[-n:n + 1, -n:n + 1]
        keep = (dr * dr + dc * dc) * self.resolution ** 2 <= radius * radius
        return dr[keep], dc[keep]

    def _disc_cells(self, x: float, y: float, radius: float, offsets=None):
        """In-bounds (rows, cols) of the cells whose centres lie within ``radius`` of (x, y)
        (always including the cell under (x, y))."""
        r0, c0 = self.world_to_cell(x, y)
        dr, dc = offsets if offsets is not None else self._disc_offsets(radius)
        rows, cols = r0 + dr, c0 + dc
        keep = (rows >= 0) & (rows < self.height) & (cols >= 0) & (cols < self.width)
        return rows[keep], cols[keep]

    def _ray_cells(self, x0: float, y0: float, cos: np.ndarray, sin: np.ndarray,
                   lengths: np.ndarray, min_len: float = 0.0):
        """Flat indices of the in-bounds cells sampled along each beam from ``min_len`` up to
        (not including) its length, every resolution. Beams are first clipped where they leave
        the grid, so only samples inside it are generated."""
        res = self.resolution
        # clip each beam at the grid's border (slab method; the origin may be outside)
        x_lo = self._bx + self._oc * res
        y_lo = self._by + self._or * res
        x_hi, y_hi = x_lo + self.width * res, y_lo + self.height * res
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(cos > 0, (x_hi - x0) / cos, np.where(cos < 0, (x_lo - x0) / cos, np.inf))
            ty = np.where(sin > 0, (y_hi - y0) / sin, np.where(sin < 0, (y_lo - y0) / sin, np.inf))
        lengths = np.minimum(lengths, np.minimum(tx, ty))
        counts = np.ceil((lengths - min_len) / res).astype(np.intp)
        np.maximum(counts, 0, out=counts)
        total = int(counts.sum())
        if total == 0:
            return np.empty(0, np.intp)
        beam = np.repeat(np.arange(len(counts)), counts)
        starts = np.cumsum(counts) - counts
        t = (np.arange(total) - np.repeat(starts, counts)) * res + min_len
        inv = 1.0 / res
        c = np.floor((x0 - self._bx) * inv + cos[beam] * (t * inv)).astype(np.intp) - self._oc
        r = np.floor((y0 - self._by) * inv + sin[beam] * (t * inv)).astype(np.intp) - self._or
        inside = (r >= 0) & (r < self.height) & (c >= 0) & (c < self.width)
        return r[inside] * self.width + c[inside]

    def _hit_cells(self, x0: float, y0: float, cos: np.ndarray, sin: np.ndarray,
                   r: np.ndarray, mark: np.ndarray):
        rr = r[mark]
        hx = x0 + cos[mark] * rr
        hy = y0 + sin[mark] * rr
        rows = np.floor((hy - self._by) / self.resolution).astype(np.intp) - self._or
        cols = np.floor((hx - self._bx) / self.resolution).astype(np.intp) - self._oc
        inside = (rows >= 0) & (rows < self.height) & (cols >= 0) & (cols < self.width)
        return rows[inside] * self.width + cols[inside]


class GlobalCostmap(Costmap2D):
    """The whole map: static + updates + obstacle + phantom layers, inflated."""

    def __init__(self, grid: OccupancyGrid, robot_radius: float,
                 params: CostmapParams | None = None, laser_offset=(0.0, 0.0, 0.0)):
        params = params or CostmapParams()
        super().__init__(grid.width, grid.height, grid.resolution, grid.origin[0], grid.origin[1],
                         robot_radius, params)
        self.grid = grid
        self.laser_offset = laser_offset
        static = np.zeros(grid.data.shape, np.uint8)
        if params.use_static_layer:
            static[grid.data >= params.lethal_cost_threshold] = LETHAL
            if params.track_unknown_space:
                static[grid.data < 0] = NO_INFORMATION
        self.static = static
        self.updates = np.zeros(grid.data.shape, bool)  # add_obstacle marks (persistent)
        self.phantom = np.zeros(grid.data.shape, bool)  # fault injection (cleared by clear())
        fill = NO_INFORMATION if params.track_unknown_space else FREE_SPACE
        self._obstacle_fill = fill
        self.obstacle = np.full(grid.data.shape, fill, np.uint8)
        self.base_version = 0  # bumps when static/updates/phantom change (planner heuristic cache)
        self.last_update_time = -math.inf
        self._relaxed: np.ndarray | None = None
        self._relaxed_version = -1
        self._dist_cache: tuple[int, np.ndarray] | None = None
        self._recompute_all()

    # -- layer composition ---------------------------------------------------------------
    def _base(self, sl) -> np.ndarray:
        """Uncombined-with-inflation master values (0 / 254 / 255) in a slice."""
        base = self.static[sl].copy()
        base[self.updates[sl]] = LETHAL
        if self.params.use_obstacle_layer:
            obs = self.obstacle[sl]
            seen = obs != NO_INFORMATION
            if seen.any():
                merged = np.where(base == NO_INFORMATION, obs, np.maximum(base, obs))
                base = np.where(seen, merged, base)
        base[self.phantom[sl]] = LETHAL
        return base

    def _recompute_all(self) -> None:
        full = (slice(0, self.height), slice(0, self.width))
        new = _inflated_master(self.inflator, self._base(full))
        if not np.array_equal(new, self.cost):
            self.cost = new
            self.version += 1
        self._dist_cache = None

    def _recompute_window(self, r0: int, r1: int, c0: int, c1: int) -> bool:
        """Re-inflate after a change confined to rows r0:r1, cols c0:c1."""
        n = self.inflator.cells + 1
        ir0, ir1 = max(r0 - n, 0), min(r1 + n, self.height)  # cells whose cost may change
        ic0, ic1 = max(c0 - n, 0), min(c1 + n, self.width)
        er0, er1 = max(ir0 - n, 0), min(ir1 + n, self.height)  # lethal cells that matter
        ec0, ec1 = max(ic0 - n, 0), min(ic1 + n, self.width)
        base = self._base((slice(er0, er1), slice(ec0, ec1)))
        costs = combine_unknown(self.inflator.costs(base == LETHAL), base == NO_INFORMATION)
        inner = costs[ir0 - er0:ir1 - er0, ic0 - ec0:ic1 - ec0]
        old = self.cost[ir0:ir1, ic0:ic1]
        if np.array_equal(inner, old):
            return False
        self.cost[ir0:ir1, ic0:ic1] = inner
        self.version += 1
        self._dist_cache = None
        return True

    # -- sensor updates ------------------------------------------------------------------
    def update_due(self, now: float) -> bool:
        return now - self.last_update_time >= 1.0 / self.params.update_frequency - 1e-9

    def update_from_scan(self, scan: LaserScan, pose: Pose2D, now: float | None = None) -> bool:
        """Raytrace-clear and mark one scan taken at ``pose`` (map frame). Returns True if the
        master costmap changed."""
        if now is not None:
            self.last_update_time = now
        if not self.params.use_obstacle_layer:
            return False
        if not _finite(pose):
            return False  # no valid transform for this scan (a corrupt localization): as Nav2, skip it
        x0, y0, cos, sin, r, clear_len, mark = _scan_geometry(
            scan, pose, self.laser_offset, self.params, self._rays)
        flat = self.obstacle.reshape(-1)
        clear = self._ray_cells(x0, y0, cos, sin, clear_len, self.params.raytrace_min_range)
        hits = self._hit_cells(x0, y0, cos, sin, r, mark)
        if self.params.footprint_clearing_enabled:
            fr, fc = self._disc_cells(pose.x, pose.y, self.robot_radius, self._fp_offsets)
            fp = fr * self.width + fc
        else:
            fp = np.empty(0, np.intp)
        touched = np.concatenate([clear, hits, fp])
        if touched.size == 0:
            return False
        rows, cols = np.divmod(touched, self.width)
        r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
        before = self.obstacle[r0:r1, c0:c1].copy()
        flat[clear] = FREE_SPACE
        flat[hits] = LETHAL
        flat[fp] = FREE_SPACE
        changed = before != self.obstacle[r0:r1, c0:c1]
        if not changed.any():
            return False
        rr, cc = np.nonzero(changed)
        return self._recompute_window(int(r0 + rr.min()), int(r0 + rr.max() + 1),
                                      int(c0 + cc.min()), int(c0 + cc.max() + 1))

    # -- services ------------------------------------------------------------------------
    def clear(self) -> None:
        """ClearEntireCostmap: drop the obstacle and phantom layers (static and updates stay)."""
        self.obstacle.fill(self._obstacle_fill)
        if self.phantom.any():
            self.phantom.fill(False)
            self.base_version += 1
        self._recompute_all()

    def _mark_disc(self, layer: np.ndarray, x: float, y: float, radius: float) -> None:
        rows, cols = self._disc_cells(x, y, max(radius, 0.0))
        if rows.size == 0:
            return
        layer[rows, cols] = True
        self._recompute_window(int(rows.min()), int(rows.max()) + 1, int(cols.min()),
                               int(cols.max()) + 1)

    def add_obstacle(self, x: float, y: float, radius: float = 0.1) -> None:
        """A persistent lethal disc (the "map update" layer)."""
        self._mark_disc(self.updates, x, y, radius)
        self.base_version += 1

    def clear_updates(self) -> None:
        """Drop every ``add_obstacle`` disc (they are marked again, smaller, by the caller)."""
        if self.updates.any():
            self.updates.fill(False)
            self.base_version += 1
            self._recompute_all()

    def add_phantom(self, x: float, y: float, radius: float) -> None:
        """A fault-injected lethal disc, gone after ``clear()``."""
        self._mark_disc(self.phantom, x, y, radius)
        self.base_version += 1

    # -- queries -------------------------------------------------------------------------
    def relaxed_cost(self) -> np.ndarray:
        """Inflated static + updates + phantom layers with unknown as free: a cell-wise lower
        bound of the master costs (the obstacle layer only adds lethal cells), used for the
        planner's heuristic. Changes only with ``base_version``."""
        if self._relaxed is None or self._relaxed_version != self.base_version:
            lethal = (self.static == LETHAL) | self.updates | self.phantom
            relaxed = self.inflator.costs(lethal)
            # a cell the master may still report unknown (planned as free) must not cost more
            relaxed[(self.static == NO_INFORMATION) & (relaxed < INSCRIBED)] = FREE_SPACE
            self._relaxed = relaxed
            self._relaxed_version = self.base_version
        return self._relaxed

    def distance_field(self) -> np.ndarray:
        """Metres from each cell centre to the nearest lethal cell centre (cached per version)."""
        if self._dist_cache is None or self._dist_cache[0] != self.version:
            lethal = self.cost == LETHAL
            self._dist_cache = (self.version, self.inflator.distances(lethal) * self.resolution)
        return self._dist_cache[1]


class LocalCostmap(Costmap2D):
    """A rolling window around the robot, aligned to the global map's cells."""

    def __init__(self, global_costmap: GlobalCostmap, robot_radius: float,
                 params: LocalCostmapParams | None = None, laser_offset=(0.0, 0.0, 0.0)):
        params = params or LocalCostmapParams()
        res = global_costmap.resolution
        w = max(int(round(params.width / res)), 3)
        h = max(int(round(params.height / res)), 3)
        super().__init__(w, h, res, 0.0, 0.0, robot_radius, params)
        self.map = global_costmap
        self.laser_offset = laser_offset
        self._gi = 0  # window origin as global cell indices (row, col)
        self._gj = 0
        self._placed = False
        self.follow_slack_cells = 4  # between scans, re-centre only after 0.2 m of drift
        self.obstacle = np.zeros((h, w), bool)  # lethal marks (track_unknown_space false)
        self.phantom = np.zeros_like(global_costmap.phantom)  # full-map grid, like updates
        self.dist = np.full((h, w), np.inf)  # metres to the nearest lethal cell
        self.last_update_time = -math.inf
        self._cost_bytes = self.cost.tobytes()

    # -- window --------------------------------------------------------------------------
    def follow(self, pose: Pose2D) -> None:
        """Keep the window centred on the robot between scans (recomposes only on a move)."""
        if self._place(pose.x, pose.y, slack=self.follow_slack_cells):
            self.recompose()

    def _place(self, x: float, y: float, slack: int = 0) -> bool:
        m = self.map
        gi = math.floor((y - m.origin_y) / self.resolution) - self.height // 2
        gj = math.floor((x - m.origin_x) / self.resolution) - self.width // 2
        if self._placed and abs(gi - self._gi) <= slack and abs(gj - self._gj) <= slack:
            return False
        if self._placed:
            di, dj = gi - self._gi, gj - self._gj
            shifted = np.zeros_like(self.obstacle)
            h, w = self.height, self.width
            if abs(di) < h and abs(dj) < w:
                src = self.obstacle[max(di, 0):h + min(di, 0), max(dj, 0):w + min(dj, 0)]
                shifted[max(-di, 0):h + min(-di, 0), max(-dj, 0):w + min(-dj, 0)] = src
            self.obstacle = shifted
        self._gi, self._gj, self._placed = gi, gj, True
        self.origin_x = m.origin_x + gj * self.resolution
        self.origin_y = m.origin_y + gi * self.resolution
        self._bx, self._by, self._or, self._oc = m.origin_x, m.origin_y, gi, gj
        return True

    def _map_slice(self, layer: np.ndarray) -> np.ndarray:
        """The window's view of a full-map layer (False outside the map)."""
        out = np.zeros((self.height, self.width), layer.dtype)
        H, W = layer.shape
        r0, c0 = self._gi, self._gj
        a0, a1 = max(r0, 0), min(r0 + self.height, H)
        b0, b1 = max(c0, 0), min(c0 + self.width, W)
        if a0 < a1 and b0 < b1:
            out[a0 - r0:a1 - r0, b0 - c0:b1 - c0] = layer[a0:a1, b0:b1]
        return out

    # -- updates -------------------------------------------------------------------------
    def update_due(self, now: float) -> bool:
        return now - self.last_update_time >= 1.0 / self.params.update_frequency - 1e-9

    def update(self, pose: Pose2D, scan: LaserScan | None = None, now: float | None = None) -> None:
        """Move the window to ``pose``, apply ``scan`` (if any), recompose and re-inflate."""
        if now is not None:
            self.last_update_time = now
        if not _finite(pose):
            return  # no valid transform (a corrupt localization): the window stays where it was
        self._place(pose.x, pose.y)
        if scan is not None and self.params.use_obstacle_layer:
            x0, y0, cos, sin, r, clear_len, mark = _scan_geometry(
                scan, pose, self.laser_offset, self.params, self._rays)
            flat = self.obstacle.reshape(-1)
            flat[self._ray_cells(x0, y0, cos, sin, clear_len, self.params.raytrace_min_range)] = False
            flat[self._hit_cells(x0, y0, cos, sin, r, mark)] = True
        if self.params.footprint_clearing_enabled:
            fr, fc = self._disc_cells(pose.x, pose.y, self.robot_radius, self._fp_offsets)
            self.obstacle[fr, fc] = False
        self.recompose()

    def recompose(self) -> None:
        lethal = self.obstacle | self._map_slice(self.map.updates) | self._map_slice(self.phantom)
        if self.params.use_static_layer:
            lethal |= self._map_slice(self.map.static) == LETHAL
        d = self.inflator.distances(lethal)
        new = self.inflator.costs_from_distances(d)
        self.dist = d * self.resolution
        if not np.array_equal(new, self.cost):
            self.cost = new
            self.version += 1
        self._cost_bytes = self.cost.tobytes()

    # -- services ------------------------------------------------------------------------
    def clear(self) -> None:
        self.obstacle.fill(False)
        self.phantom.fill(False)
        if self._placed:
            self.recompose()

    def add_phantom(self, x: float, y: float, radius: float) -> None:
        rows, cols = self.map._disc_cells(x, y, max(radius, 0.0))
        self.phantom[rows, cols] = True
        if self._placed:
            self.recompose()

    # -- fast scalar queries (controller hot path) ---------------------------------------
    def cost_at(self, x: float, y: float) -> int:
        c = math.floor((x - self._bx) / self.resolution) - self._oc
        r = math.floor((y - self._by) / self.resolution) - self._or
        if 0 <= r < self.height and 0 <= c < self.width:
            return self._cost_bytes[r * self.width + c]
        return NO_INFORMATION

    def distance_at(self, x: float, y: float) -> float:
        """Metres to the nearest lethal cell (inf outside the window or with none)."""
        c = math.floor((x - self._bx) / self.resolution) - self._oc
        r = math.floor((y - self._by) / self.resolution) - self._or
        if 0 <= r < self.height and 0 <= c < self.width:
            return float(self.dist[r, c])
        return math.inf

    def in_collision(self, x: float, y: float) -> bool:
        """The circular footprint at (x, y) overlaps a lethal cell (cost >= inscribed)."""
        cost = self.cost_at(x, y)
        return INSCRIBED <= cost < NO_INFORMATION
