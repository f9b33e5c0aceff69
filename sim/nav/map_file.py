"""Reading a ROS map_server map (YAML + PGM/PNG): the one reader behind both uses of a map file,
the navigation stand-in's grid (``OccupancyGrid.load``) and a simulator world made from a map
(``sim/map_world.py``), so both accept the same files and fail with the same errors.

Keys are read as nav2_map_server reads them: ``image``, ``resolution``, ``origin`` [x, y, yaw],
``negate``, ``occupied_thresh``, ``free_thresh`` and ``mode`` (trinary | scale | raw). With
p = (255 - pixel)/255 (pixel/255 when ``negate``), p >= occupied_thresh is occupied, p <=
free_thresh free, anything else unknown (trinary) or scaled to 0..100 (scale); a colour picture
is averaged over its channels. The picture's top row is the map's top, so rows are flipped on
the way in. Every error names the file and the field. The picture must lie in the YAML's folder;
if it is missing, a picture named like the YAML (``room.yaml`` -> ``room.pgm``) is used with a
warning, which covers the common renamed-map case.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import structlog
import yaml
from PIL import Image, UnidentifiedImageError

from bt_runtime.yaml_files import safe_load

log = structlog.get_logger("sim.nav.map_file")

FREE = 0
OCCUPIED = 100
UNKNOWN = -1
MAP_KEYS = ("image", "resolution", "origin", "occupied_thresh", "free_thresh")
MODES = ("trinary", "scale", "raw")
MAX_CELLS = 25_000_000  # 5 000 x 5 000 cells: 250 m x 250 m at 5 cm


class MapFileError(ValueError):
    """A map file that cannot be used; the message names the file and the field."""

    def __init__(self, path: Path, field_name: str, message: str):
        super().__init__(f"{path}: {field_name}: {message}")
        self.path = path
        self.field = field_name


@dataclass(frozen=True, slots=True)
class MapFile:
    """A map as read: occupancy values with row 0 at the origin (the picture's bottom)."""

    data: np.ndarray  # int8: 0 free, 100 occupied, -1 unknown, 1..99 in scale mode
    resolution: float
    origin: tuple[float, float, float]
    mode: str
    meta: dict[str, Any] = field(default_factory=dict)  # the YAML, for keys map_server ignores

    def occupied(self) -> np.ndarray:
        """Cells a planner treats as lethal (raw maps: 65 and above, as map_server's default)."""
        return self.data >= (65 if self.mode == "raw" else OCCUPIED)


def looks_like_map(data: Any) -> bool:
    """A parsed YAML document that is a map_server map description."""
    return isinstance(data, dict) and "image" in data and "resolution" in data


def read_map(yaml_path: str | Path, meta: dict | None = None) -> MapFile:
    """Read a map_server map; ``meta`` is the already parsed YAML, if the caller has it."""
    yaml_path = Path(yaml_path)
    if meta is None:
        try:
            meta = safe_load(yaml_path.read_text())
        except (OSError, yaml.YAMLError) as err:
            raise MapFileError(yaml_path, "(file)", f"not a readable map YAML: {err}") from None
    if not isinstance(meta, dict):
        raise MapFileError(yaml_path, "(top level)", "a map_server map is a mapping with " + ", ".join(MAP_KEYS))
    for key in MAP_KEYS:
        if key not in meta:
            raise MapFileError(yaml_path, key, "missing (a map_server map needs " + ", ".join(MAP_KEYS) + ")")
    resolution = _number(yaml_path, meta, "resolution")
    if resolution <= 0:
        raise MapFileError(yaml_path, "resolution", f"must be a positive number, got {meta['resolution']!r}")
    origin = meta["origin"]
    try:
        origin = tuple(float(v) for v in origin)
    except (TypeError, ValueError):
        origin = ()
    if len(origin) != 3 or not all(np.isfinite(origin)):
        raise MapFileError(yaml_path, "origin", f"must be [x, y, yaw] with finite numbers, got {meta['origin']!r}")
    occupied_thresh = _number(yaml_path, meta, "occupied_thresh")
    free_thresh = _number(yaml_path, meta, "free_thresh")
    if not 0.0 <= free_thresh < occupied_thresh <= 1.0:
        raise MapFileError(yaml_path, "free_thresh/occupied_thresh",
                           "need 0 <= free_thresh < occupied_thresh <= 1")
    try:
        negate = bool(int(meta.get("negate", 0)))
    except (TypeError, ValueError):
        raise MapFileError(yaml_path, "negate", f"must be 0 or 1, got {meta.get('negate')!r}") from None
    mode = str(meta.get("mode", "trinary")).lower()
    if mode not in MODES:
        raise MapFileError(yaml_path, "mode", f"must be trinary, scale or raw, got {mode!r}")
    pixels = _read_image(_image_path(yaml_path, meta), yaml_path)
    data = pixels_to_occupancy(pixels, negate=negate, occupied_thresh=occupied_thresh,
                               free_thresh=free_thresh, mode=mode)[::-1].copy()
    return MapFile(data, resolution, origin, mode, meta)


def _number(path: Path, meta: dict, key: str) -> float:
    try:
        value = float(meta[key])
    except (TypeError, ValueError):
        value = float("nan")
    if not np.isfinite(value):
        raise MapFileError(path, key, f"must be a finite number, got {meta[key]!r}")
    return value


def _image_path(yaml_path: Path, meta: dict) -> Path:
    folder = yaml_path.resolve().parent
    wanted = Path(str(meta["image"]))
    image = (folder / wanted).resolve() if not wanted.is_absolute() else wanted.resolve()
    if not image.is_relative_to(folder):  # a map file must not point the loader elsewhere
        raise MapFileError(yaml_path, "image", f"{meta['image']!r} lies outside the map file's folder {folder}")
    if image.exists():
        return image
    alt = yaml_path.resolve().with_suffix(image.suffix or ".pgm")
    if not alt.exists():
        raise MapFileError(yaml_path, "image", f"{image} not found")
    log.warning("map_image_fallback", wanted=str(image), using=str(alt))
    return alt


def _read_image(path: Path, yaml_path: Path) -> np.ndarray:
    """Picture rows (top first) as uint8 0..255: PGM by our reader (any maxval), other formats
    through Pillow, colour averaged over the channels (alpha ignored)."""
    try:
        if path.suffix.lower() == ".pgm":
            pixels = read_pgm(path)
        else:
            with Image.open(path) as img:
                if img.width * img.height > MAX_CELLS:
                    raise MapFileError(yaml_path, "image",
                                       f"{img.width} x {img.height} pixels is more than {MAX_CELLS} cells")
                if img.mode in ("I;16", "I;16B", "I"):
                    arr = np.asarray(img, dtype=np.float64) * (255.0 / 65535.0)
                else:
                    arr = np.asarray(img.convert("RGBA" if "A" in img.mode else "RGB"), dtype=np.float64)[..., :3]
                    arr = arr.mean(axis=2)
                pixels = np.rint(np.clip(arr, 0, 255)).astype(np.uint8)
    except MapFileError:
        raise
    except (UnidentifiedImageError, OSError, ValueError) as err:
        raise MapFileError(yaml_path, "image", f"cannot read {path}: {err}") from None
    return pixels


def pixels_to_occupancy(pixels: np.ndarray, *, negate: bool, occupied_thresh: float,
                        free_thresh: float, mode: str = "trinary") -> np.ndarray:
    """Picture rows (top first) to occupancy values, as nav2_map_server does."""
    if mode == "raw":
        out = pixels.astype(np.int16)
        out[(out < 0) | (out > 100)] = UNKNOWN
        return out.astype(np.int8)
    if mode not in ("trinary", "scale"):
        raise ValueError(f"unknown map mode {mode!r} (trinary, scale or raw)")
    p = pixels.astype(np.float32) / 255.0
    if not negate:
        p = 1.0 - p
    out = np.full(pixels.shape, UNKNOWN, np.int8)
    if mode == "scale":
        between = (p > free_thresh) & (p < occupied_thresh)
        scaled = np.rint((p - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        out[between] = scaled[between].astype(np.int8)
    out[p >= occupied_thresh] = OCCUPIED
    out[p <= free_thresh] = FREE
    return out


def read_pgm(path: str | Path) -> np.ndarray:
    """Read a binary (P5) or ASCII (P2) PGM into a uint8 array (rows top first)."""
    raw = Path(path).read_bytes()
    tokens: list[bytes] = []
    i, n = 0, len(raw)
    while len(tokens) < 4:
        while i < n and raw[i:i + 1].isspace():
            i += 1
        if i >= n:
            raise ValueError(f"{path}: truncated PGM header")
        if raw[i:i + 1] == b"#":
            while i < n and raw[i:i + 1] not in (b"\n", b"\r"):
                i += 1
            continue
        j = i
        while j < n and not raw[j:j + 1].isspace():
            j += 1
        tokens.append(raw[i:j])
        i = j
    magic, w, h, maxval = tokens[0], int(tokens[1]), int(tokens[2]), int(tokens[3])
    if w * h > MAX_CELLS:
        raise ValueError(f"{path}: {w} x {h} pixels is more than {MAX_CELLS} cells")
    if magic == b"P5":
        i += 1  # exactly one whitespace byte after maxval
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        arr = np.frombuffer(raw, dtype=dtype, count=w * h, offset=i).reshape(h, w)
    elif magic == b"P2":
        arr = np.array(raw[i:].split()[: w * h], dtype=np.int64).reshape(h, w)
    else:
        raise ValueError(f"{path}: not a PGM (magic {magic!r}); only P5/P2 are supported")
    if maxval != 255:
        arr = np.rint(arr.astype(np.float64) * (255.0 / maxval))
    return arr.astype(np.uint8)
