"""The world as map_server serves it: ``nav_msgs/msg/OccupancyGrid`` on ``map``, latched.

map_server publishes its map once, reliable and transient local (depth 1), so a node that
starts later (RViz, AMCL, the costmaps) still receives it. ``sim-robot`` does the same: for a
map_server world (``--world map.yaml``) the file's own grid (its resolution, unknown cells -1),
for a built-in or YAML world the grid its Nav2 stand-in plans on (the walls rasterised at 5 cm).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bt_runtime.runtime.ros2 import idl
from bt_runtime.runtime.ros2.convert import quaternion_of

from .nav.occupancy import OccupancyGrid


def world_grid(world: Any, stand_in_map: OccupancyGrid) -> OccupancyGrid:
    """The grid to serve: the map_server file itself when ``world`` names one, else the stand-in's."""
    if isinstance(world, str | Path) and str(world).endswith((".yaml", ".yml")) and Path(world).is_file():
        import yaml

        from .map_world import looks_like_map

        try:
            data = yaml.safe_load(Path(world).read_text(encoding="utf-8"))
        except (OSError, yaml.YAMLError):
            data = None
        if looks_like_map(data):
            return OccupancyGrid.load(world)
    return stand_in_map


def occupancy_msg(grid: OccupancyGrid, frame_id: str = "map") -> idl.OccupancyGrid:
    """The grid as ``nav_msgs/msg/OccupancyGrid`` (row-major from the origin corner, as ROS)."""
    ox, oy, oyaw = grid.origin
    stamp = idl.Time.now()
    info = idl.MapMetaData(map_load_time=stamp, resolution=float(grid.resolution), width=grid.width,
                           height=grid.height,
                           origin=idl.Pose(position=idl.Point(ox, oy, 0.0), orientation=quaternion_of(oyaw)))
    data = np.clip(grid.data, -1, 100).astype(np.int8).ravel()
    return idl.OccupancyGrid(header=idl.Header(stamp=stamp, frame_id=frame_id), info=info, data=data.tolist())
