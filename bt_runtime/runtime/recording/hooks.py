"""What a driver-specific wiring (the simulator's) adds to a recording, without this package
knowing the simulator: extra driver streams, a map source and the laser's mounting."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(slots=True, frozen=True)
class MapSnapshot:
    """An occupancy grid as ROS's map_server publishes it (int8, -1 unknown, 0..100)."""

    data: np.ndarray  # (H, W) int8, row 0 at origin y
    resolution: float
    origin: tuple[float, float, float]


@dataclass(slots=True, frozen=True)
class StreamSpec:
    """Record driver stream ``stream`` on ``topic``.

    ``kind``: 'odometry' (anything with ``stamp``, ``pose`` Pose2D and ``twist``; written as
    nav_msgs/msg/Odometry in the map frame) or 'event' (anything with ``t``, ``kind``, ``data``;
    written as rcl_interfaces/msg/Log). ``select`` filters messages (None: all). ``source``
    subscribes to streams that are not the robot's (the simulator's ground truth and events,
    which the driver interface does not carry); None: the driver. ``pose_topic`` (odometry
    only): the same pose also as geometry_msgs/msg/PoseStamped there, which Foxglove's 3D panel
    draws (it does not draw Odometry); empty: none.
    """

    stream: str
    topic: str
    kind: str
    select: Callable[[Any], bool] | None = None
    source: Callable[[str, Callable[[Any], None]], Callable[[], None]] | None = None
    pose_topic: str = ""


@dataclass
class RecordingHooks:
    streams: list[StreamSpec] = field(default_factory=list)
    # returns (version, snapshot); called on the loop every map_check_period_s, snapshot only
    # taken (copied) when the version changed
    map_source: Callable[[], tuple[int, Callable[[], MapSnapshot]]] | None = None
    laser_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y, yaw in base_link
