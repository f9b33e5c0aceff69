"""Safety zones on a ROS 2 robot over DDS: ``sim-robot`` faces a wall, the runtime (Ros2Driver,
wall clock) runs a tree that drives straight at it; the gate's stop zone, fed by the scan that
came over DDS, halts the robot short of the wall. The simulator's ground truth (its
``sim/ground_truth`` topic) is read by the test only."""

import asyncio
import math

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.config import RuntimeConfig, SafetyZonesSettings  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from bt_runtime.runtime.safety_zones import STREAM  # noqa: E402
from sim.world import load_world  # noqa: E402
from tests.helpers import BLIND_TREE, STOP_ZONE_YAML, SimRobotProcess, dds_domain, register_blind_driving  # noqa: E402
from tests.helpers import wait_until as wait_for  # noqa: E402

BURGER_RADIUS = 0.105


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


async def test_a_stop_zone_halts_a_blind_tree_before_the_wall_over_dds(tmp_path):
    domain = dds_domain()
    zones_file = tmp_path / "cm.yaml"
    zones_file.write_text(STOP_ZONE_YAML)
    robot = SimRobotProcess(domain, "--robot", "burger", "--spawn=-2,-2,1.5708", duration=60.0)
    try:
        await robot.ready(timeout=90)  # a loaded machine takes its time to import and start
        driver = Ros2Driver(Ros2Config(domain_id=domain))  # the burger, lidar 0.032 m behind the centre
        config = RuntimeConfig(safety_zones=SafetyZonesSettings(file=str(zones_file)))
        runtime = AutonomyRuntime(driver, config, realtime=True, register=[register_blind_driving])
        runtime.load_tree(BLIND_TREE)
        truth: list[tuple[float, float]] = []
        states: list[tuple[int, str]] = []
        await runtime.start()
        try:
            driver.node.subscription("collision_monitor_state", idl.CollisionMonitorState, dds.DEFAULT,
                                     lambda s, now: states.extend((m.action_type, m.polygon_name) for m in s))
            driver.node.subscription("sim/ground_truth", idl.PoseStamped, dds.DEFAULT,
                                     lambda s, now: truth.extend((m.pose.position.x, m.pose.position.y) for m in s))
            await wait_for(lambda: truth and truth[-1][1] > -1.9, 40, "the robot to drive 0.1 m")
            # 1.75 m at 0.22 m/s: 8 s to the wall; the zone must have stopped it by then
            await wait_for(lambda: runtime.safety_zones.state.zone == "PolygonStop", 40, "the stop zone")
            stopped_at = truth[-1]
            await asyncio.sleep(2.0)  # it stays stopped while the tree keeps commanding
            bb = runtime.tree.root_blackboard
            read = (bb.get("zone", default=""), bb.get("action", default=""))
            recorded = [m for _, m in runtime.backup.buffer(STREAM)]
        finally:
            await runtime.stop()
    finally:
        robot.stop()
    world = load_world("apartment")
    x, y = truth[-1]
    gap = world.clearance(x, y) - BURGER_RADIUS
    assert gap > 0.01, f"the robot ended {gap:.3f} m from the wall (ground truth)"
    assert math.hypot(x - stopped_at[0], y - stopped_at[1]) < 0.05  # and did not creep on
    assert read == ("PolygonStop", "stop")  # the tree read the zone
    assert any((m.action, m.zone, m.source) == ("stop", "PolygonStop", "tree") for m in recorded)
    assert (1, "PolygonStop") in states  # nav2_msgs/CollisionMonitorState STOP, as collision_monitor
