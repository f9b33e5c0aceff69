"""Global planner: cost-aware 8-connected search on the global costmap (Smac2D / NavFn-like).

Edge cost between neighbouring cells u, v: ``L * (w_u + w_v) / 2`` with L = 1 or sqrt(2) cells
and ``w = 1 + cost_penalty * cost / 252``; cells with cost >= 253 (inscribed or lethal) are
blocked; unknown cells (255) cost like free ones when ``allow_unknown``, else are blocked.

Why it is fast enough for 1 Hz replanning inside a >= 100x real-time simulation:

1. Per goal (and per version of the static, ``add_obstacle`` and phantom layers) a compiled
   Dijkstra (``scipy.sparse.csgraph``) computes the exact cost-to-goal over a *relaxed*
   costmap: those layers only, unknown as free. Every master cost is >= its relaxed cost (the
   obstacle layer only adds lethal cells), so this field is an admissible, consistent heuristic.
2. A replan first traces the relaxed-optimal path P from the field (a few hundred steps). No path
   can cost less than P's relaxed cost, so if P's master cost is within
   ``suboptimality_tolerance`` (1 %) of it, P is returned without any search ("cached"): optimal
   when sensing changed nothing along it, at most 1 % worse than optimal otherwise (LiDAR noise
   next to walls shifts inflation costs by a few units; a real obstacle near the path does not
   fit in 1 %).
3. If P is still passable but costs along it changed (sensed obstacles near it), a Python A*
   with that near-perfect heuristic finds the optimum expanding little more than the path
   ("astar").
4. If P is blocked (a sensed obstacle across it): a connected-components check answers
   NO_VALID_PATH in ~1 ms when the goal is cut off; otherwise, if an earlier detour to this goal
   left a master cost-to-goal field, A* is guided by it ("learned": near-optimal, possibly not
   optimal if costs dropped since); else, or if that fails, a compiled Dijkstra on the master
   costmap gives the optimum ("dijkstra") and leaves its field for the next replans.
Searches never read the clock: the same inputs always give the same path.
"""

from __future__ import annotations

import heapq
import math
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from bt_runtime.runtime.messages import NavErrorCode, Pose2D

from .costmap import INSCRIBED, LETHAL, NO_INFORMATION, GlobalCostmap, inflation_cost
from .params import PlannerParams

SQRT2 = math.sqrt(2.0)
_OFFSETS = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))


@dataclass(slots=True)
class PlanResult:
    error_code: NavErrorCode
    points: np.ndarray | None = None  # (N, 3): x, y, yaw in the map frame
    cost: float = math.nan  # path cost in cell units (sum of edge costs)
    message: str = ""
    method: str = ""  # "cached" | "astar" | "learned" | "dijkstra" | "trivial" | "components"
    expansions: int = 0
    stats: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.error_code is NavErrorCode.NONE


_GRAPHS: OrderedDict[tuple[int, int], csr_matrix] = OrderedDict()  # (Hp, Wp) -> a template graph


def _grid_graph(hp: int, wp: int, offs) -> csr_matrix:
    """The fixed CSR structure of the padded 8-connected grid (border rows point to themselves).
    Its index arrays depend only on the grid's size: built once per process per size (~10 ms
    of every run's setup) and shared, read-only; each planner gets its own matrix over them
    (searches replace its ``data``, never the indices)."""
    key = (hp, wp)
    tpl = _GRAPHS.get(key)
    if tpl is None:
        n = hp * wp
        p = np.arange(n, dtype=np.int64)
        cols = np.empty((n, 8), np.int32)
        for k, (off, _L) in enumerate(offs):
            q = p + off
            cols[:, k] = np.where((q >= 0) & (q < n), q, p)
        tpl = csr_matrix((np.ones(n * 8), cols.ravel(), np.arange(0, n * 8 + 1, 8, dtype=np.int64)),
                         shape=(n, n))
        for arr in (tpl.data, tpl.indices, tpl.indptr):
            arr.setflags(write=False)
        _GRAPHS[key] = tpl
        if len(_GRAPHS) > 8:
            _GRAPHS.popitem(last=False)
    return csr_matrix((tpl.data, tpl.indices, tpl.indptr), shape=tpl.shape, copy=False)


class GridPlanner:
    def __init__(self, costmap: GlobalCostmap, params: PlannerParams | None = None):
        self.costmap = costmap
        self.params = params or PlannerParams()
        H, W = costmap.height, costmap.width
        self.H, self.W = H, W
        self.Hp, self.Wp = H + 2, W + 2  # padded with a blocked border: no bounds checks
        self.Np = self.Hp * self.Wp
        wp = self.Wp
        self._offs = tuple((dr * wp + dc, SQRT2 if dr and dc else 1.0) for dr, dc in _OFFSETS)
        self._graph = _grid_graph(self.Hp, self.Wp, self._offs)
        self._edge_len = np.array([L for _, L in self._offs])
        self._heuristics: OrderedDict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self._master_cache: tuple[int, bool, np.ndarray] | None = None
        self._learned: OrderedDict[int, np.ndarray] = OrderedDict()  # goal -> master field
        self._labels: tuple[tuple[int, bool], np.ndarray] | None = None
        self._relaxed_w: tuple[int, np.ndarray, np.ndarray] | None = None
        self.last: PlanResult | None = None
        self._halo: tuple[int, np.ndarray | None] | None = None
        inf = costmap.inflator  # the cost of a cell pinch_margin beyond the inscribed radius
        self._pinch_cost = int(inflation_cost(inf.inscribed_radius + self.params.pinch_margin,
                                              inf.inscribed_radius, inf.inflation_radius,
                                              inf.cost_scaling_factor, costmap.resolution)) or 1

    # -- weights -------------------------------------------------------------------------
    def _weights(self, cost: np.ndarray, allow_unknown: bool) -> np.ndarray:
        """Padded flat per-cell weights (inf = blocked)."""
        c = cost.astype(np.float64)
        w = 1.0 + self.params.cost_penalty * c / 252.0
        if self.params.pinch_penalty > 0 and self.params.pinch_margin > 0:
            w[(cost >= self._pinch_cost) & (cost < INSCRIBED)] += self.params.pinch_penalty
        halo = self._mark_halo()
        if halo is not None:
            w += halo
        w[(cost == INSCRIBED) | (cost == LETHAL)] = np.inf
        unknown = cost == NO_INFORMATION
        w[unknown] = 1.0 if allow_unknown else np.inf
        out = np.full((self.Hp, self.Wp), np.inf)
        out[1:-1, 1:-1] = w
        return out.ravel()

    def _mark_halo(self) -> np.ndarray | None:
        """Extra weight near the map-update layer (``add_obstacle``: the collision marks), falling
        from ``mark_penalty`` at the inscribed radius to 0 at ``mark_halo`` m beyond it; None
        without marks. A mark is where a touch was sensed, not the obstacle's outline: a plan that
        can keep a wider berth does, so it does not touch the unsensed rest of the obstacle."""
        p, cm = self.params, self.costmap
        if p.mark_penalty <= 0 or p.mark_halo <= 0:
            return None
        key = cm.base_version
        if self._halo is None or self._halo[0] != key:
            extra = None
            if cm.updates.any():
                d = ndimage.distance_transform_edt(~cm.updates) * cm.resolution - cm.inscribed_radius
                extra = np.clip(1.0 - d / p.mark_halo, 0.0, 1.0) * p.mark_penalty
            self._halo = (key, extra)
        return self._halo[1]

    def _master_weights(self) -> np.ndarray:
        cm = self.costmap
        key = (cm.version, self.params.allow_unknown)
        if self._master_cache is None or self._master_cache[:2] != key:
            self._master_cache = (*key, self._weights(cm.cost, self.params.allow_unknown))
        return self._master_cache[2]

    def _relaxed_weights(self) -> np.ndarray:
        cm = self.costmap
        if self._relaxed_w is None or self._relaxed_w[0] != cm.base_version:
            w = self._weights(cm.relaxed_cost(), True)
            self._relaxed_w = (cm.base_version, w, self._edge_data(w))
            self._heuristics.clear()
        return self._relaxed_w[1]

    def _edge_data(self, w: np.ndarray) -> np.ndarray:
        data = np.empty((self.Np, 8))
        n = self.Np
        for k, (off, L) in enumerate(self._offs):
            shifted = np.full(n, np.inf)
            if off >= 0:
                shifted[:n - off] = w[off:]
            else:
                shifted[-off:] = w[:n + off]
            data[:, k] = (0.5 * L) * (w + shifted)
        return data.ravel()

    def _dijkstra(self, data: np.ndarray, source: int):
        self._graph.data = data
        return dijkstra(self._graph, directed=True, indices=source, return_predecessors=True)

    def _heuristic(self, goal: int) -> tuple[np.ndarray, np.ndarray]:
        self._relaxed_weights()
        key = (self.costmap.base_version, goal)
        entry = self._heuristics.get(key)
        if entry is None:
            dist, pred = self._dijkstra(self._relaxed_w[2], goal)
            entry = (dist, pred)
            self._heuristics[key] = entry
            while len(self._heuristics) > self.params.heuristic_cache_size:
                self._heuristics.popitem(last=False)
        else:
            self._heuristics.move_to_end(key)
        return entry

    # -- indices -------------------------------------------------------------------------
    def _cell(self, x: float, y: float) -> tuple[int, int] | None:
        r, c = self.costmap.world_to_cell(x, y)
        if 0 <= r < self.H and 0 <= c < self.W:
            return r, c
        return None

    def _flat(self, rc: tuple[int, int]) -> int:
        return (rc[0] + 1) * self.Wp + rc[1] + 1

    def _unflat(self, p: np.ndarray):
        r, c = np.divmod(np.asarray(p), self.Wp)
        return r - 1, c - 1

    def _blocked(self, cost: int) -> bool:
        if cost == NO_INFORMATION:
            return not self.params.allow_unknown
        return cost >= INSCRIBED

    # -- planning ------------------------------------------------------------------------
    def plan(self, start: Pose2D, goal: Pose2D) -> PlanResult:
        res = self._plan(start, goal)
        self.last = res
        return res

    def _plan(self, start: Pose2D, goal: Pose2D) -> PlanResult:
        E = NavErrorCode
        cm = self.costmap
        s_rc = self._cell(start.x, start.y)
        if s_rc is None:
            return PlanResult(E.START_OUTSIDE_MAP, message=f"start ({start.x:.2f}, {start.y:.2f}) is outside the map")
        g_rc = self._cell(goal.x, goal.y)
        if g_rc is None:
            return PlanResult(E.GOAL_OUTSIDE_MAP, message=f"goal ({goal.x:.2f}, {goal.y:.2f}) is outside the map")
        s_cost = int(cm.cost[s_rc])
        if s_cost == LETHAL:
            return PlanResult(E.START_OCCUPIED, message="start is in a lethal cell")
        g_cost = int(cm.cost[g_rc])
        if self._blocked(g_cost):
            g_rc = self._goal_within_tolerance(g_rc)
            if g_rc is None:
                return PlanResult(E.GOAL_OCCUPIED, message=f"goal is occupied (cost {g_cost})")
            # as NavFn: the plan ends at the nearest plannable point, not inside the obstacle
            gx, gy = self.costmap.cell_to_world(np.array([g_rc[0]]), np.array([g_rc[1]]))
            goal = Pose2D(float(gx[0]), float(gy[0]), goal.yaw)
        s, g = self._flat(s_rc), self._flat(g_rc)
        if s == g:
            pts = np.array([[start.x, start.y], [goal.x, goal.y]])
            return PlanResult(E.NONE, self._finish(pts, goal, smooth=False), 0.0, method="trivial")

        w = self._master_weights()
        h, pred = self._heuristic(g)
        budget = min(self.params.max_python_expansions, self.params.max_iterations)
        escape = self._blocked(s_cost)
        if escape:  # start inside the inscribed band: let the search leave through it
            w, h = self._escape(w, h, s_rc)
            p_passable = True
        else:
            if math.isinf(h[s]):
                return PlanResult(E.NO_VALID_PATH, message="start and goal are not connected in the map")
            path = self._trace(pred, s, g)
            idx = np.asarray(path)
            wp = w[idx]
            p_passable = bool(np.isfinite(wp).all())
            if p_passable:
                cost = self._path_cost(path, wp)
                if cost <= float(h[s]) * (1.0 + self.params.suboptimality_tolerance) + 1e-9:
                    return self._result(path, cost, "cached", 0, start, goal)
        if p_passable:
            found, path, cost, n = self._astar(w, h, s, g, budget, prune_inf=True)
            if found:
                return self._result(path, cost, "astar", n, start, goal)
            if path is None and n <= budget:
                return PlanResult(E.NO_VALID_PATH, message="no path: the goal is cut off",
                                  expansions=n, method="astar")
        else:
            if not self._connected(w, s, g, escape):
                return PlanResult(E.NO_VALID_PATH, message="no path: the goal is cut off",
                                  method="components")
            learned = self._learned.get(g)
            if learned is not None:
                found, path, cost, n = self._astar(w, learned, s, g, budget, prune_inf=False)
                if found:
                    return self._result(path, cost, "learned", n, start, goal)
        if self.params.max_iterations < self.Np:
            return PlanResult(E.PLANNER_TIMEOUT, message="search exceeded max_iterations",
                              expansions=self.params.max_iterations)
        dist, pred = self._dijkstra(self._edge_data(w), g)
        settled = int(np.isfinite(dist).sum())
        if math.isinf(dist[s]):
            return PlanResult(E.NO_VALID_PATH, message="no path between start and goal",
                              method="dijkstra", expansions=settled)
        if not escape:
            self._learned[g] = dist
            while len(self._learned) > self.params.heuristic_cache_size:
                self._learned.popitem(last=False)
        path = self._trace(pred, s, g)
        return self._result(path, float(dist[s]), "dijkstra", settled, start, goal)

    def _path_cost(self, path: list[int], wp: np.ndarray) -> float:
        steps = np.abs(np.diff(np.asarray(path)))
        lengths = np.where((steps == 1) | (steps == self.Wp), 1.0, SQRT2)
        return float((0.5 * lengths * (wp[:-1] + wp[1:])).sum())

    def _connected(self, w: np.ndarray, s: int, g: int, escape: bool) -> bool:
        """Are start and goal in one 8-connected component of passable cells? (cached per
        costmap version)"""
        key = (self.costmap.version, self.params.allow_unknown)
        if escape or self._labels is None or self._labels[0] != key:
            passable = np.isfinite(w).reshape(self.Hp, self.Wp)
            labels, _n = ndimage.label(passable, structure=np.ones((3, 3), bool))
            labels = labels.ravel()
            if escape:
                return bool(labels[s] == labels[g] and labels[s] != 0)
            self._labels = (key, labels)
        labels = self._labels[1]
        return bool(labels[s] == labels[g] and labels[s] != 0)

    def _goal_within_tolerance(self, g_rc):
        """NavFn's tolerance: the nearest free cell in the square of half-side ``tolerance``
        around the goal (None if there is none, or the tolerance is 0)."""
        tol = self.params.tolerance
        if tol <= 0:
            return None
        cm = self.costmap
        n = math.ceil(tol / cm.resolution)
        r0, c0 = g_rc
        best, best_d = None, math.inf
        for dr in range(-n, n + 1):
            for dc in range(-n, n + 1):
                d = math.hypot(dr, dc) * cm.resolution
                r, c = r0 + dr, c0 + dc
                if d >= best_d or not (0 <= r < self.H and 0 <= c < self.W):
                    continue
                if not self._blocked(int(cm.cost[r, c])):
                    best, best_d = (r, c), d
        return best

    def _escape(self, w: np.ndarray, h: np.ndarray, s_rc):
        """Make inscribed (not lethal) cells near the start passable at the highest cost, with
        an admissible heuristic of 0 where the relaxed field has none."""
        cm = self.costmap
        w = w.copy()
        h = h.copy()
        n = math.ceil(cm.inscribed_radius / cm.resolution) + 1
        r0, r1 = max(s_rc[0] - n, 0), min(s_rc[0] + n + 1, self.H)
        c0, c1 = max(s_rc[1] - n, 0), min(s_rc[1] + n + 1, self.W)
        esc = cm.cost[r0:r1, c0:c1] == INSCRIBED
        wv = w.reshape(self.Hp, self.Wp)[r0 + 1:r1 + 1, c0 + 1:c1 + 1]
        wv[esc] = 1.0 + self.params.cost_penalty * INSCRIBED / 252.0
        hv = h.reshape(self.Hp, self.Wp)[r0 + 1:r1 + 1, c0 + 1:c1 + 1]
        hv[esc & np.isinf(hv)] = 0.0
        return w, h

    def _trace(self, pred: np.ndarray, s: int, g: int) -> list[int] | None:
        path = [s]
        p = s
        limit = self.Np
        while p != g:
            p = int(pred[p])
            if p < 0 or len(path) > limit:
                return None
            path.append(p)
        return path

    def _astar(self, w_arr: np.ndarray, h_arr: np.ndarray, s: int, g: int, budget: int,
               prune_inf: bool = True):
        """A*. Returns (found, path, cost, expansions); (False, None, ...) = the open list ran
        dry, which proves "no path" only with an admissible heuristic (``prune_inf``: a cell
        with an infinite heuristic cannot reach the goal and is skipped)."""
        w = memoryview(w_arr)
        h = memoryview(h_arr)
        inf = math.inf
        offs = self._offs
        gs = {s: 0.0}
        parent = {s: -1}
        closed = set()
        heap = [(h[s], 0.0, s)]
        push, pop = heapq.heappush, heapq.heappop
        n = 0
        while heap:
            _f, neg_g, u = pop(heap)
            if u in closed:
                continue
            if u == g:
                path = [u]
                while parent[path[-1]] != -1:
                    path.append(parent[path[-1]])
                path.reverse()
                return True, path, -neg_g, n
            closed.add(u)
            n += 1
            if n > budget:
                return False, [], inf, n
            gu = -neg_g
            wu = w[u]
            for off, L in offs:
                v = u + off
                wv = w[v]
                if wv == inf:
                    continue
                hv = h[v]
                if hv == inf:
                    if prune_inf:
                        continue
                    hv = 0.0
                ng = gu + L * 0.5 * (wu + wv)
                if ng < gs.get(v, inf):
                    gs[v] = ng
                    parent[v] = u
                    push(heap, (ng + hv, -ng, v))
        return False, None, inf, n

    def _result(self, path: list[int], cost: float, method: str, n: int, start: Pose2D,
                goal: Pose2D) -> PlanResult:
        rows, cols = self._unflat(path)
        xs, ys = self.costmap.cell_to_world(rows, cols)
        pts = np.column_stack([xs, ys])
        pts[0] = (start.x, start.y)
        pts[-1] = (goal.x, goal.y)
        return PlanResult(NavErrorCode.NONE, self._finish(pts, goal, self.params.smooth), cost,
                          method=method, expansions=n)

    def _finish(self, pts: np.ndarray, goal: Pose2D, smooth: bool) -> np.ndarray:
        if smooth and len(pts) > 3:
            sm = smooth_path(pts)
            if self._all_free(sm):
                pts = sm
        yaw = np.empty(len(pts))
        d = np.diff(pts, axis=0)
        yaw[:-1] = np.arctan2(d[:, 1], d[:, 0])
        yaw[-1] = goal.yaw
        return np.column_stack([pts, yaw])

    def _all_free(self, pts: np.ndarray) -> bool:
        costs = self.costmap.costs_at(pts[1:-1, 0], pts[1:-1, 1])
        blocked = (costs >= INSCRIBED) & (costs != NO_INFORMATION)
        if not self.params.allow_unknown:
            blocked |= costs == NO_INFORMATION
        return not bool(blocked.any())

    # -- path services -------------------------------------------------------------------
    def is_path_valid(self, points: np.ndarray, max_cost: int = 253, start_index: int = 0,
                      consider_unknown_as_obstacle: bool = False) -> bool:
        """Nav2 IsPathValid / ValidatePath: invalid if a pose from ``start_index`` on is outside
        the map or has cost >= ``max_cost`` (unknown cells only count as obstacles on request)."""
        pts = np.asarray(points, dtype=float)
        if len(pts) == 0:
            return False
        pts = pts[start_index:]
        if not np.isfinite(pts[:, :2]).all():  # a non-finite pose is nowhere on the map
            return False
        cm = self.costmap
        r = np.floor((pts[:, 1] - cm.origin_y) / cm.resolution).astype(np.intp)
        c = np.floor((pts[:, 0] - cm.origin_x) / cm.resolution).astype(np.intp)
        inside = (r >= 0) & (r < self.H) & (c >= 0) & (c < self.W)
        if not inside.all():
            return False
        costs = cm.cost[r, c]
        unknown = costs == NO_INFORMATION
        bad = (costs >= max_cost) & ~unknown
        if consider_unknown_as_obstacle:
            bad |= unknown
        return not bool(bad.any())

    def path_clearance(self, points: np.ndarray) -> float:
        """Smallest distance (m) from any path pose to a lethal cell (cell-centre distances);
        0 for a path with a non-finite pose (its clearance is unknown, so it is not safe)."""
        pts = np.asarray(points, dtype=float)
        if len(pts) == 0:
            return math.inf
        if not np.isfinite(pts[:, :2]).all():
            return 0.0
        cm = self.costmap
        dist = cm.distance_field()
        r = np.floor((pts[:, 1] - cm.origin_y) / cm.resolution).astype(np.intp)
        c = np.floor((pts[:, 0] - cm.origin_x) / cm.resolution).astype(np.intp)
        inside = (r >= 0) & (r < self.H) & (c >= 0) & (c < self.W)
        if not inside.any():
            return math.inf
        return float(dist[r[inside], c[inside]].min())


def smooth_path(pts: np.ndarray, w_data: float = 0.2, w_smooth: float = 0.3,
                iterations: int = 40) -> np.ndarray:
    """Nav2 SimpleSmoother-style gradient smoothing with fixed end points (vectorised)."""
    orig = np.asarray(pts, dtype=float)
    y = orig.copy()
    for _ in range(iterations):
        y[1:-1] += w_data * (orig[1:-1] - y[1:-1]) + w_smooth * (y[:-2] + y[2:] - 2.0 * y[1:-1])
    return y


def path_length(points: np.ndarray) -> float:
    pts = np.asarray(points)
    if len(pts) < 2:
        return 0.0
    d = np.diff(pts[:, :2], axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())
