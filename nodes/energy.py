"""The layer's energy model: the profile's nominal power model, corrected online.

The driver tells the nominal constants (``RobotInfo``: idle power, W per m/s, W per rad/s);
this unit of the robot may draw more or less. The model watches two streams a real robot
has, the battery's measured state of charge (noisy) and the motion commands that reached the
base (``cmd_vel_out``), and learns one factor ``scale``: the energy the state of charge says
was used, over the energy the nominal model predicts for the same commands. It is a Gaussian
estimate: a prior N(1, ``prior_sigma``) from the nominal values, combined with the
measurement, whose uncertainty shrinks as more energy is used. Predictions carry a margin of
``margin_sigmas`` standard deviations. Charging (the monitor reports a charger, or the state of
charge rises) restarts the measurement window.
"""

from __future__ import annotations

import math
from typing import Any

from bt_runtime.runtime.messages import BatteryState, RobotInfo, Twist


class EnergyModel:
    # How far a unit may be from the nominal model before anything is measured: units of one
    # model draw within about +-10 % of their datasheet consumption (motor and electronics
    # tolerances), so 2 sigma = 16 % covers them; a wider prior only refuses goals the robot can
    # make. The measurements then shrink it.
    prior_sigma = 0.08
    soc_sigma = 0.1  # percentage points of noise on one state-of-charge reading
    margin_sigmas = 2.0

    @classmethod
    def factor_bounds(cls, early_drift_sigmas: float = 1.0) -> tuple[float, float]:
        """The factor a check can use in the first seconds, before the readings have told much:
        at least the nominal minus the unit spread (``1 - margin_sigmas * prior_sigma``), at most
        the prior's margin plus ``early_drift_sigmas`` priors for what a few noisy readings can
        move the estimate. For whoever must predict the layer's answers (the variant generator)."""
        spread = cls.margin_sigmas * cls.prior_sigma
        return 1.0 - spread, 1.0 + spread + early_drift_sigmas * cls.prior_sigma

    def __init__(self, robot: RobotInfo) -> None:
        self.robot = robot
        self.scale = 1.0
        self.sigma = self.prior_sigma
        self._cmd = (0.0, 0.0)
        self._cmd_t: float | None = None
        self._nominal_wh = 0.0  # nominal energy of the commands since the window started
        self._start_soc: float | None = None
        self._last_soc: float | None = None
        self._volts: list[float] = []
        self.readings = 0

    # --- inputs --------------------------------------------------------------------------------
    def _advance(self, now: float) -> None:
        """Add the nominal energy of the current command up to ``now`` (idle counts too)."""
        if self._cmd_t is not None and now > self._cmd_t:
            v, w = self._cmd
            self._nominal_wh += self.robot.power(v, w) * (now - self._cmd_t) / 3600.0
        self._cmd_t = now

    def on_command(self, twist: Twist, now: float) -> None:
        if not (math.isfinite(twist.linear) and math.isfinite(twist.angular)):
            return
        self._advance(now)
        self._cmd = (twist.linear, twist.angular)

    def on_battery(self, msg: BatteryState, now: float) -> None:
        soc, volts = msg.percentage, msg.voltage
        if not (math.isfinite(soc) and math.isfinite(volts) and volts > 0):
            return
        self._advance(now)
        self.readings += 1
        rising = msg.on_charger or (self._last_soc is not None and soc > self._last_soc + 4 * self.soc_sigma)
        self._last_soc = soc
        if self._start_soc is None or rising:  # first reading, or charging: a new window
            self._start_soc, self._nominal_wh, self._volts = soc, 0.0, []
            self.scale, self.sigma = 1.0, self.prior_sigma
            return
        self._volts.append(volts)
        self._update(soc)

    def _update(self, soc: float) -> None:
        nominal = self._nominal_wh
        if nominal <= 0.0:
            return
        volts = sum(self._volts) / len(self._volts)
        wh_per_percent = self.robot.capacity_ah * volts / 100.0
        used = (self._start_soc - soc) * wh_per_percent
        measured = used / nominal
        sigma_m = math.sqrt(2.0) * self.soc_sigma * wh_per_percent / nominal
        wp, wm = 1.0 / self.prior_sigma ** 2, 1.0 / sigma_m ** 2
        self.scale = (wp * 1.0 + wm * measured) / (wp + wm)
        self.sigma = math.sqrt(1.0 / (wp + wm))

    # --- predictions ---------------------------------------------------------------------------
    @property
    def factor(self) -> float:
        """What to multiply a nominal energy by: the learned scale plus the margin (never below
        the learned scale, never negative)."""
        return max(self.scale + self.margin_sigmas * self.sigma, 0.0)

    def energy(self, nominal_wh: float) -> float:
        return nominal_wh * self.factor


def energy_model(context: Any) -> EnergyModel | None:
    """The context's energy model, created (and fed from the driver's streams) on first use;
    None without a runtime context."""
    if context is None or not hasattr(context, "extras"):
        return None
    model = context.extras.get("energy_model")
    if isinstance(model, EnergyModel):
        return model
    model = context.extras["energy_model"] = EnergyModel(context.robot)
    clock = context.clock
    driver = context.driver
    driver.subscribe("battery", lambda msg: model.on_battery(msg, clock()) if isinstance(msg, BatteryState) else None)
    driver.subscribe("cmd_vel_out", lambda msg: model.on_command(msg, clock()) if isinstance(msg, Twist) else None)
    return model
