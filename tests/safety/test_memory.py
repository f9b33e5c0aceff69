"""Long-lived processes keep bounded memory: the simulator's ground-truth trajectory."""

from __future__ import annotations

import asyncio

import pytest

from sim.simulator import Simulator

pytestmark = pytest.mark.virtual_time


async def test_ground_truth_trajectory_is_a_bounded_buffer():
    sim = Simulator("apartment", "burger", seed=0, trajectory_hz=100.0, trajectory_keep=50)
    await sim.start()
    sim.command(0.1, 0.0)
    await asyncio.sleep(2.0)  # 200 samples recorded, the latest 50 kept
    await sim.stop()
    traj = sim.trajectory()
    assert traj.shape == (50, 7)
    assert traj[-1, 0] == pytest.approx(sim.now, abs=0.011) and traj[0, 0] > 1.0
