"""The layer's energy model learns this unit's consumption from noisy state of charge."""

from __future__ import annotations

import asyncio

import pytest

from bt_runtime.runtime.messages import BatteryState, RobotInfo, Twist
from nodes.energy import EnergyModel
from sim import Simulator
from sim.driver import SimDriver
from sim.robot import load_profile
from sim.testing import run_virtual


def _learn(seed: int, seconds: float) -> tuple[EnergyModel, float]:
    """Drive a ROSbot (small battery, so the state of charge moves) in slow circles while the
    model listens to the battery and the commands; return the model and the true ratio of this
    unit's consumption to the nominal model's for the same motion."""
    driver = SimDriver("apartment", load_profile("rosbot2", **{"battery.capacity_ah": 0.3}), seed=seed)
    sim: Simulator = driver.sim
    model = EnergyModel(driver.robot_info())

    async def main():
        loop = asyncio.get_running_loop()
        sim.subscribe("battery", lambda m: model.on_battery(m, loop.time()))
        sim.subscribe("cmd_vel_out", lambda m: model.on_command(m, loop.time()))
        await sim.start()
        end = loop.time() + seconds
        while loop.time() < end:
            sim.command(0.2, 0.4)
            await asyncio.sleep(0.1)
        await sim.stop()

    run_virtual(main)
    b, nominal = sim.battery, driver.robot_info()
    truth = b.idle_power_w + b.k_linear * 0.2 + b.k_angular * 0.4
    return model, truth / nominal.power(0.2, 0.4)


def test_before_any_measurement_the_model_is_nominal_with_a_wide_margin():
    model = EnergyModel(RobotInfo())
    assert model.scale == 1.0 and model.factor == pytest.approx(1.0 + 2 * model.prior_sigma)
    assert model.energy(1.0) > 1.0


@pytest.mark.parametrize("seed", [1, 2])
def test_it_learns_the_units_real_consumption_and_the_margin_shrinks(seed):
    model, ratio = _learn(seed, 240.0)
    assert abs(ratio - 1.0) > 0.01  # this unit really differs from the nominal model
    assert model.scale == pytest.approx(ratio, abs=0.03)
    assert model.sigma < 0.03
    assert model.factor >= ratio  # the margin covers the truth


def test_charging_starts_a_new_window_and_bad_readings_are_ignored():
    model = EnergyModel(RobotInfo())
    model.on_command(Twist(0.2, 0.0), 0.0)
    for i, soc in enumerate([50.0, 49.0, 48.0]):
        model.on_battery(BatteryState(float(i * 10), 11.1, soc), float(i * 10 + 10))
    assert model.scale != 1.0
    model.on_battery(BatteryState(40.0, float("nan"), float("nan")), 40.0)  # ignored
    model.on_battery(BatteryState(50.0, 11.1, 60.0), 50.0)  # charged meanwhile
    assert model.scale == 1.0 and model.sigma == model.prior_sigma


def test_the_first_seconds_of_noisy_readings_keep_the_factor_within_its_documented_bounds():
    """The variant generator predicts the layer's battery answers from ``factor_bounds``: a few
    noisy readings of a small battery (the scenarios' 0.1 Ah) at any unit spread must keep the
    factor inside them."""
    import numpy as np

    low, high = EnergyModel.factor_bounds()
    info = RobotInfo(capacity_ah=0.1, idle_power_w=8.0)
    worst = [np.inf, -np.inf]
    for seed in range(200):
        rng = np.random.default_rng(seed)
        truth = rng.uniform(0.9, 1.1)
        model = EnergyModel(info)
        soc = 20.0
        for t in range(4):  # 1 Hz readings until the near goal's check
            model.on_battery(BatteryState(float(t), 11.0, soc + rng.normal(0.0, model.soc_sigma)), float(t))
            soc -= info.percent_for(info.idle_power_w * truth / 3600.0, 11.0)
        worst = [min(worst[0], model.factor), max(worst[1], model.factor)]
        assert model.factor >= low
    assert worst[1] <= high
    assert worst[0] >= 1.0  # before the readings say much, never below the nominal model
