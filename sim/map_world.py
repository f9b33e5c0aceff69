"""A ROS map_server map (YAML + PGM/PNG) as a simulator world: occupied cells become walls.

map_server's keys are read as map_server reads them: ``image``, ``resolution``, ``origin``,
``negate``, ``occupied_thresh``, ``free_thresh`` and ``mode`` (trinary, scale or raw); the
picture is averaged over its colour channels, as map_server does. Occupied cells become
axis-aligned boxes (runs of cells merged into rectangles, so a wall is a few shapes rather than
hundreds); free and unknown cells are open space. A map carries no spawn pose: the optional keys
``spawn``, ``goals`` and ``dock`` (which map_server ignores) give them; without ``spawn`` the
robot starts on the free cell with the most clearance nearest the map's centre.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image, UnidentifiedImageError
from pydantic import ValidationError
from scipy import ndimage

from .nav.occupancy import OCCUPIED, pixels_to_occupancy
from .world import PolygonObstacle, World, WorldError, format_validation_error

MAP_KEYS = ("image", "resolution", "origin", "occupied_thresh", "free_thresh")
_MAX_CELLS = 25_000_000  # 5 000 x 5 000 cells: 250 m x 250 m at 5 cm
_SPAWN_CLEARANCE = 0.35  # m from the nearest wall, if the map has room for it


def looks_like_map(data: Any) -> bool:
    """A parsed YAML document that is a map_server map description."""
    return isinstance(data, dict) and "image" in data and "resolution" in data


def _error(path: Path, field: str, message: str) -> WorldError:
    return WorldError(f"{path}: {field}: {message}")


def _read_image(path: Path, yaml_path: Path) -> np.ndarray:
    """Picture rows (top first) as 0..255, the mean of the colour channels (alpha ignored)."""
    try:
        with Image.open(path) as img:
            if img.width * img.height > _MAX_CELLS:
                raise _error(yaml_path, "image", f"{img.width} x {img.height} pixels is more than "
                                                 f"{_MAX_CELLS} cells")
            mode = img.mode
            if mode in ("I;16", "I;16B", "I"):
                arr = np.asarray(img, dtype=np.float64)
                return np.clip(arr / (arr.max() or 1) * 255.0, 0, 255)
            rgb = img.convert("RGBA" if "A" in mode else "RGB")
            arr = np.asarray(rgb, dtype=np.float64)[..., :3]
            return arr.mean(axis=2)
    except (FileNotFoundError, UnidentifiedImageError, OSError) as err:
        if isinstance(err, WorldError):
            raise
        raise _error(yaml_path, "image", f"cannot read {path}: {err}") from None


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
    if meta is None:
        try:
            meta = yaml.safe_load(yaml_path.read_text())
        except (OSError, yaml.YAMLError) as err:
            raise WorldError(f"{yaml_path}: not a readable map YAML: {err}") from None
    if not looks_like_map(meta):
        raise WorldError(f"{yaml_path}: (top level): a map_server map needs 'image' and 'resolution'")
    for key in MAP_KEYS:
        if key not in meta:
            raise _error(yaml_path, key, "missing (a map_server map needs " + ", ".join(MAP_KEYS) + ")")
    try:
        resolution = float(meta["resolution"])
        origin = [float(v) for v in meta["origin"]]
        occupied_thresh, free_thresh = float(meta["occupied_thresh"]), float(meta["free_thresh"])
        negate = bool(int(meta.get("negate", 0)))
    except (TypeError, ValueError) as err:
        raise WorldError(f"{yaml_path}: resolution/origin/thresholds/negate: not numbers ({err})") from None
    if not np.isfinite(resolution) or resolution <= 0:
        raise _error(yaml_path, "resolution", f"must be a positive number, got {meta['resolution']!r}")
    if len(origin) != 3 or not all(np.isfinite(origin)):
        raise _error(yaml_path, "origin", f"must be [x, y, yaw] with finite numbers, got {meta['origin']!r}")
    if not 0.0 <= free_thresh < occupied_thresh <= 1.0:
        raise _error(yaml_path, "free_thresh/occupied_thresh", "need 0 <= free_thresh < occupied_thresh <= 1")
    mode = str(meta.get("mode", "trinary")).lower()
    if mode not in ("trinary", "scale", "raw"):
        raise _error(yaml_path, "mode", f"must be trinary, scale or raw, got {mode!r}")
    image = Path(str(meta["image"]))
    folder = yaml_path.resolve().parent
    image = (folder / image).resolve() if not image.is_absolute() else image.resolve()
    if not image.is_relative_to(folder):
        raise _error(yaml_path, "image", f"{meta['image']!r} lies outside the map file's folder")
    pixels = _read_image(image, yaml_path)
    grid = pixels_to_occupancy(np.rint(pixels).astype(np.uint8), negate=negate, occupied_thresh=occupied_thresh,
                               free_thresh=free_thresh, mode=mode)[::-1]  # row 0 at the origin's y
    occupied = grid >= OCCUPIED if mode != "raw" else grid >= 65
    ox, oy = origin[0], origin[1]
    obstacles = []
    for r0, c0, r1, c1 in _boxes(occupied):
        x0, y0, x1, y1 = ox + c0 * resolution, oy + r0 * resolution, ox + c1 * resolution, oy + r1 * resolution
        obstacles.append(PolygonObstacle(name=f"map_{r0}_{c0}", points=[(x0, y0), (x1, y0), (x1, y1), (x0, y1)]))
    rows, cols = grid.shape
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
        raise _error(yaml_path, "spawn", str(err)) from None
    return world
