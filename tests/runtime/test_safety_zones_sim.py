"""Safety zones in the simulator (virtual time): a tree that ignores obstacles drives at a wall;
the gate's zones stop it short, and the tree can read which zone acted. Ground truth is read
only here, by the test."""

from __future__ import annotations

import asyncio
import math

from bt_runtime.runtime.config import RuntimeConfig, SafetyZonesSettings
from bt_runtime.runtime.safety_zones import STREAM
from tests.helpers import BLIND_TREE, STOP_ZONE_YAML, register_blind_driving

SPAWN = (-2.0, -2.0, math.pi / 2)  # the apartment: a wall 1.75 m ahead



def clearance(rt) -> float:
    """Ground truth: metres between the robot's body and the nearest wall."""
    sim = rt.driver.sim
    return sim.world.clearance(sim.physics.x, sim.physics.y) - sim.profile.radius


async def drive(runtime, settings: SafetyZonesSettings, seconds=14.0):
    rt = await runtime(BLIND_TREE, register=[register_blind_driving],
                       config=RuntimeConfig(safety_zones=settings), spawn=SPAWN)
    try:
        await asyncio.sleep(seconds)  # 1.75 m at 0.22 m/s: the wall is reached after ~7 s
        return rt, clearance(rt), rt.tree.root_blackboard
    finally:
        await rt.stop()


async def test_a_stop_zone_halts_a_blind_tree_before_the_wall(runtime, tmp_path):
    path = tmp_path / "stop.yaml"
    path.write_text(STOP_ZONE_YAML)
    rt, gap, bb = await drive(runtime, SafetyZonesSettings(file=str(path)))
    assert gap > 0.02, f"the robot ended {gap:.3f} m from the wall"
    assert rt.safety_zones.state.zone == "PolygonStop"
    states = [m for _, m in rt.backup.buffer(STREAM) if m.triggered and m.zone != "invalid source"]
    assert (states[0].action, states[0].zone, states[0].source) == ("stop", "PolygonStop", "tree")
    assert (bb.get("zone"), bb.get("action")) == ("PolygonStop", "stop")


async def test_the_default_zones_brake_it_in_time_and_without_zones_it_hits(runtime):
    rt, gap, _ = await drive(runtime, SafetyZonesSettings())
    assert gap > 0.005, f"the robot ended {gap:.3f} m from the wall"
    assert any(m.zone == "FootprintApproach" for _, m in rt.backup.buffer(STREAM))
    _, gap_off, _ = await drive(runtime, SafetyZonesSettings(enabled=False), seconds=10.0)
    assert gap_off < 0.005  # the same tree without zones drives into the wall
