"""A ROS map_server map (YAML + PGM/PNG) as a simulator world: occupied cells become walls.

The map file is read by ``nav/map_file.py`` (the same reader as the navigation stand-in's
``OccupancyGrid.load``: map_server's keys, PGM or PNG, errors naming the file and field). Occupied cells become
axis-aligned boxes (runs of cells merged into rectangles, so a wall is a few shapes rather than
hundreds); free and unknown cells are open space. A map carries no spawn pose: the optional keys
``spawn``, ``goals`` and ``dock`` (which map_server ignores) give them; without ``spawn`` the
robot starts on the free cell with the most clearance nearest the map's centre.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydantic import ValidationError
from scipy import ndimage

from .nav.map_file import MapFileError, looks_like_map, read_map
from .world import PolygonObstacle, World, WorldError, format_validation_error

__all__ = ["looks_like_map", "world_from_map"]

_SPAWN_CLEARANCE = 0.35  # m from the nearest wall, if the map has room for it


def _boxes(occupied: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Cover the True cells with rectangles (row0, col0, row1, col1), end-exclusive: runs along
    each row, then runs with the same columns in consecutive rows merged."""
    open_runs: dict[tuple[int, int], int] = {}  # (col0, col1) -> first row
    boxes: list[tuple[int, int, int, int]] = []
    rows = occupied.shape[0]
    for r in range(rows + 1):
        runs: set[tuple[int, int]] = set()
        if r < rows:
            line = occupied[r].astype(np.int8)
            edges = np.flatnonzero(np.diff(np.concatenate(([0], line, [0]))))
            runs = {(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])}
        for run in [run for run in open_runs if run not in runs]:
            boxes.append((open_runs.pop(run), run[0], r, run[1]))
        for run in runs:
            open_runs.setdefault(run, r)
    return boxes


def _spawn(free: np.ndarray, resolution: float, origin: tuple[float, float]) -> dict[str, float]:
    clearance = (ndimage.distance_transform_edt(free) - 0.5) * resolution  # to the wall cell's edge
    if not free.any():
        raise ValueError("the map has no free cell to spawn the robot on")
    rows, cols = free.shape
    rr, cc = np.mgrid[0:rows, 0:cols]
    centre = ((rows - 1) / 2.0, (cols - 1) / 2.0)
    dist = np.hypot(rr - centre[0], cc - centre[1])
    roomy = clearance >= min(_SPAWN_CLEARANCE, float(clearance.max()))
    r, c = np.unravel_index(np.argmin(np.where(roomy, dist, np.inf)), free.shape)
    return {"x": origin[0] + (c + 0.5) * resolution, "y": origin[1] + (r + 0.5) * resolution, "yaw": 0.0}


def world_from_map(yaml_path: str | Path, meta: dict | None = None) -> World:
    """Build a World from a map_server YAML; errors name the file and the field."""
    yaml_path = Path(yaml_path)
    try:
        m = read_map(yaml_path, meta)
    except MapFileError as err:
        raise WorldError(str(err)) from None
    meta, resolution = m.meta, m.resolution
    occupied = m.occupied()
    ox, oy = m.origin[0], m.origin[1]
    obstacles = []
    for r0, c0, r1, c1 in _boxes(occupied):
        x0, y0, x1, y1 = ox + c0 * resolution, oy + r0 * resolution, ox + c1 * resolution, oy + r1 * resolution
        obstacles.append(PolygonObstacle(name=f"map_{r0}_{c0}", points=[(x0, y0), (x1, y0), (x1, y1), (x0, y1)]))
    rows, cols = occupied.shape
    data = {
        "name": yaml_path.stem,
        "description": f"map_server map {yaml_path.name} ({cols} x {rows} cells at {resolution} m)",
        "source": str(yaml_path),
        "bounds": {"xmin": ox, "ymin": oy, "xmax": ox + cols * resolution, "ymax": oy + rows * resolution},
        "goals": meta.get("goals") or {},
        "obstacles": obstacles,
    }
    if meta.get("dock") is not None:
        data["dock"] = meta["dock"]
    try:
        data["spawn"] = meta.get("spawn") or _spawn(~occupied, resolution, (ox, oy))
        world = World.model_validate(data)
    except ValidationError as err:
        raise WorldError(format_validation_error(str(yaml_path), err)) from None
    except ValueError as err:
        raise WorldError(f"{yaml_path}: spawn: {err}") from None
    return world
