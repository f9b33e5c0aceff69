"""The low-rate converters (encoded from tuples by ``cdr_encoder``) give the bytes rosbags gives
for the same messages built as typestore objects, the way they were built before the encoder."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import BatteryState, Path
from bt_runtime.runtime.recording import convert as c
from bt_runtime.runtime.recording.hooks import MapSnapshot
from bt_runtime.runtime.recording.types import serialize


def _header(t: float, frame: str):
    return c.Header(stamp=c.stamp(t), frame_id=frame)


def _plan_by_objects(t: float, pts: np.ndarray) -> bytes:
    header = _header(t, "map")
    poses = []
    for i, row in enumerate(pts):
        if len(row) > 2:
            yaw = float(row[2])
        elif i + 1 < len(pts):
            yaw = math.atan2(pts[i + 1, 1] - row[1], pts[i + 1, 0] - row[0])
        else:
            yaw = poses[-1][2] if poses else 0.0
        poses.append((float(row[0]), float(row[1]), yaw))
    msg = c.Path(header=header, poses=[c.PoseStamped(header=header, pose=c.pose(*p)) for p in poses])
    return serialize(msg, "nav_msgs/msg/Path")


@pytest.mark.parametrize("columns,n", [(2, 0), (2, 1), (2, 37), (3, 1), (3, 12)])
def test_plan_bytes_match_the_object_built_message(columns, n):
    rng = np.random.default_rng(n * 10 + columns)
    pts = rng.uniform(-20, 20, (n, columns))
    (_, typename, data), = c.plan(c.ConvertState(), "/plan", 0.0, Path(12.345, pts))
    assert typename == "nav_msgs/msg/Path"
    assert data == _plan_by_objects(12.345, pts)


def test_battery_diagnostics_map_and_logs_match_the_object_built_messages():
    s = c.ConvertState()
    battery = BatteryState(3.5, 12.1, 61.0, current=1.25, capacity_ah=4.4)
    (_, _, data), = c.battery(s, "/battery_state", 3.5, battery)
    nan = math.nan
    expected = c.BatteryState(header=_header(3.5, "base_link"), voltage=12.1, temperature=nan, current=-1.25,
                              charge=nan, capacity=4.4, design_capacity=4.4, percentage=0.61,
                              power_supply_status=2, power_supply_health=0, power_supply_technology=0,
                              present=True, cell_voltage=c.EMPTY32, cell_temperature=c.EMPTY32, location="",
                              serial_number="")
    assert data == serialize(expected, "sensor_msgs/msg/BatteryState")

    rows = [("planner", "process", "ok", 0.25, 0, 1), ("lidar", "sensor", "dead", None, 3, 7)]
    (_, _, data), = c.diagnostics(s, "/diagnostics", 4.0, rows)
    status = [c.DiagnosticStatus(level=c.DIAG_LEVEL.get(state, 3), name=f"supervisor: {name}", message=state,
                                 hardware_id=kind,
                                 values=[c.KeyValue(key="last_seen_age_s", value="" if age is None else f"{age:.3f}"),
                                         c.KeyValue(key="restarts", value=str(restarts)),
                                         c.KeyValue(key="failures", value=str(failures))])
              for name, kind, state, age, restarts, failures in rows]
    expected = c.DiagnosticArray(header=_header(4.0, ""), status=status)
    assert data == serialize(expected, "diagnostic_msgs/msg/DiagnosticArray")

    grid = np.arange(-1, 59, dtype=np.int8).reshape(6, 10)
    (_, _, data), = c.occupancy(s, "/map", 5.5, MapSnapshot(grid, 0.05, (-1.0, 2.0, 0.3)))
    expected = c.OccupancyGrid(header=_header(5.5, "map"),
                               info=c.MapMetaData(map_load_time=c.stamp(5.5), resolution=0.05, width=10, height=6,
                                                  origin=c.pose(-1.0, 2.0, 0.3)),
                               data=grid.reshape(-1))
    assert data == serialize(expected, "nav_msgs/msg/OccupancyGrid")

    (_, _, data), = c.tf_static(s, "/tf_static", 0.5, (0.1, -0.02, 0.7))
    expected = c.TFMessage(transforms=[c.transform(c.stamp(0.5), "base_link", "laser", 0.1, -0.02, 0.7)])
    assert data == serialize(expected, "tf2_msgs/msg/TFMessage")

    data = c.log_line(s, 6.25, c.LOG_WARN, "gate", "nav -> estop: pressed")
    expected = c.Log(stamp=c.stamp(6.25), level=30, name="gate", msg="nav -> estop: pressed", file="", function="",
                     line=0)
    assert data == serialize(expected, "rcl_interfaces/msg/Log")
