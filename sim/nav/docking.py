"""The docking server of the Nav2 stand-in: opennav_docking's ``dock_robot`` / ``undock_robot``.

Our own code after opennav_docking's sequence (nav2_docking, Jazzy and later):

``dock_robot``
  1. the dock: by id from the dock database (``docks``; the simulator's world dock is
     ``home_dock``), or the goal's ``dock_pose`` (``use_dock_id`` false; type must be empty or
     ``simple_charging_dock``). Unknown id: 901 DOCK_NOT_IN_DB; bad type: 902 DOCK_NOT_VALID;
  2. already on the charger (the battery says CHARGING/FULL) near the dock: SUCCEEDED at once;
  3. NAV_TO_STAGING_POSE: the staging pose is ``staging_x_offset`` (-0.7 m) along the dock's
     heading; the stack's own navigate_to_pose drives there (skipped when
     ``navigate_to_staging_pose`` is false or within ``dock_prestaging_tolerance``); failure or
     ``max_staging_time`` exceeded: 903 FAILED_TO_STAGE;
  4. INITIAL_PERCEPTION: the dock pose is the database's (no detector, as SimpleChargingDock
     without external detection);
  5. CONTROLLING: a slow approach along the dock's axis from the robot's localized pose, until
     the battery reports charging or the pose is ``docking_threshold`` past the dock pose;
     overshoot or ``dock_approach_timeout``: 905 FAILED_TO_CONTROL;
  6. WAIT_FOR_CHARGE: the battery messages must say CHARGING (or FULL) within
     ``wait_charge_timeout``, else 906 FAILED_TO_CHARGE;
  failures of 5-6 are retried (RETRY: back to the staging pose, approach again) up to
  ``max_retries`` times; then the last error ends the goal.

``undock_robot``
  no dock known (no database, no type): 902 DOCK_NOT_VALID; not on the charger: SUCCEEDED (nothing
  to do); else it backs straight out to the staging pose of where it stands and succeeds once
  the battery no longer reports charging; ``max_undocking_time`` exceeded: 905 FAILED_TO_CONTROL.

Charging is sensed only through the robot's battery messages (``battery`` stream), never the
simulator's truth. Commands go on ``nav_cmd_vel`` like the stand-in's other servers (the
decision gate decides what reaches the wheels).
"""

from __future__ import annotations

import asyncio
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import structlog
from pydantic import BaseModel, ConfigDict, Field

from bt_runtime.runtime.messages import (
    ZERO_TWIST,
    ActionStatus,
    BatteryState,
    DockFeedback,
    NavResult,
    Pose2D,
    Twist,
    wrap_angle,
)

if TYPE_CHECKING:
    from .stack import NavHandle, NavStack

log = structlog.get_logger("sim.nav.docking")

DOCK_TYPE = "simple_charging_dock"
# nav2_msgs/action/DockRobot (and UndockRobot) result codes
DOCK_NOT_IN_DB, DOCK_NOT_VALID, FAILED_TO_STAGE = 901, 902, 903
FAILED_TO_DETECT_DOCK, FAILED_TO_CONTROL, FAILED_TO_CHARGE, UNKNOWN = 904, 905, 906, 999
# DockRobot feedback states
NAV_TO_STAGING_POSE, INITIAL_PERCEPTION, CONTROLLING, WAIT_FOR_CHARGE, RETRY = 1, 2, 3, 4, 5


class DockingParams(BaseModel):
    """opennav_docking's parameters (its defaults unless marked)."""

    model_config = ConfigDict(extra="forbid")
    controller_frequency: float = Field(50.0, gt=0)
    wait_charge_timeout: float = Field(5.0, gt=0)
    dock_approach_timeout: float = Field(30.0, gt=0)
    undock_linear_tolerance: float = Field(0.05, gt=0)
    undock_angular_tolerance: float = Field(0.05, gt=0)
    max_retries: int = Field(3, ge=0)
    dock_prestaging_tolerance: float = Field(0.5, ge=0)
    staging_x_offset: float = -0.7  # SimpleChargingDock
    # deviation: SimpleChargingDock's docking_threshold is 0.05 m (distance to the dock pose);
    # here, without a charging report first, the approach stops once the localized pose is
    # ``docking_threshold`` past the dock pose along its axis, pressing the spring-loaded
    # contacts (the stand-in's pose is AMCL-like, 2 cm sigma, and the robot stops a little
    # behind it; the simulated contacts have 5 cm of play either way)
    docking_threshold: float = Field(0.01, ge=0)
    approach_speed: float = Field(0.1, gt=0)  # m/s, the final approach (graceful controller's v_linear_max 0.24 slowed near)
    undock_speed: float = Field(0.1, gt=0)  # m/s backwards


class _Failed(Exception):  # noqa: N818 - carries a result code
    def __init__(self, code: int, msg: str):
        super().__init__(msg)
        self.code = code


@dataclass(slots=True)
class _Goal:
    dock: Pose2D
    dock_type: str
    max_staging_time: float
    navigate_to_staging_pose: bool


class DockingServer:
    """``dock_robot`` / ``undock_robot`` on a ``NavStack`` (see the module docstring)."""

    def __init__(self, stack: NavStack, docks: dict[str, Pose2D] | None = None,
                 params: DockingParams | dict | None = None):
        self.stack = stack
        self.docks = dict(docks or {})
        self.params = params if isinstance(params, DockingParams) else DockingParams.model_validate(params or {})
        self.battery: BatteryState | None = None
        self.current_dock_type = ""  # set by a successful docking (undock's default)
        self._unsub = stack.bus.subscribe("battery", self._on_battery)

    def _on_battery(self, msg: Any) -> None:
        if isinstance(msg, BatteryState):
            self.battery = msg

    def close(self) -> None:
        self._unsub()

    @property
    def on_charger(self) -> bool:
        b = self.battery
        return b is not None and b.on_charger

    def staging_pose(self, dock: Pose2D) -> Pose2D:
        off = self.params.staging_x_offset
        return Pose2D(dock.x + math.cos(dock.yaw) * off, dock.y + math.sin(dock.yaw) * off, dock.yaw)

    # -- actions -----------------------------------------------------------------------------------
    def dock_robot(self, handle: NavHandle, *, use_dock_id: bool = True, dock_id: str = "",
                   dock_pose: Pose2D | None = None, dock_type: str = "", max_staging_time: float = 1000.0,
                   navigate_to_staging_pose: bool = True) -> Any:
        """The coroutine of one dock_robot goal (launched by ``NavStack.dock_robot``)."""
        return self._dock(handle, use_dock_id, dock_id, dock_pose, dock_type, max_staging_time,
                          navigate_to_staging_pose)

    def undock_robot(self, handle: NavHandle, *, dock_type: str = "", max_undocking_time: float = 30.0) -> Any:
        return self._undock(handle, dock_type, max_undocking_time)

    # -- dock ----------------------------------------------------------------------------------------
    def _resolve(self, use_dock_id: bool, dock_id: str, dock_pose: Pose2D | None, dock_type: str) -> _Goal:
        if use_dock_id:
            if not dock_id and len(self.docks) == 1:
                dock_id = next(iter(self.docks))
            if dock_id not in self.docks:
                known = ", ".join(sorted(self.docks)) or "none"
                raise _Failed(DOCK_NOT_IN_DB, f"dock '{dock_id}' is not in the dock database (docks: {known})")
            return _Goal(self.docks[dock_id], DOCK_TYPE, 0.0, True)
        if dock_type not in ("", DOCK_TYPE):
            raise _Failed(DOCK_NOT_VALID, f"dock type '{dock_type}' is not a dock plugin here ({DOCK_TYPE})")
        if dock_pose is None or not all(math.isfinite(v) for v in (dock_pose.x, dock_pose.y, dock_pose.yaw)):
            raise _Failed(DOCK_NOT_VALID, "no valid dock pose given")
        return _Goal(dock_pose, DOCK_TYPE, 0.0, True)

    async def _dock(self, handle: NavHandle, use_dock_id: bool, dock_id: str, dock_pose: Pose2D | None,
                    dock_type: str, max_staging_time: float, navigate_to_staging_pose: bool) -> NavResult:
        loop = asyncio.get_running_loop()
        start = loop.time()
        retries = 0

        def feedback(state: int) -> None:
            handle._set_feedback(DockFeedback(loop.time(), state, loop.time() - start, retries))

        try:
            goal = self._resolve(use_dock_id, dock_id, dock_pose, dock_type)
            dock = goal.dock
            pose = self.stack._pose
            if self.on_charger and pose is not None and pose.distance_to(dock) < self.params.dock_prestaging_tolerance:
                log.info("dock_already_docked", sim_time=self.stack._sim_time())
                self.current_dock_type = goal.dock_type
                return NavResult(ActionStatus.SUCCEEDED, 0, "already docked")
            feedback(NAV_TO_STAGING_POSE)
            staging = self.staging_pose(dock)
            if navigate_to_staging_pose and (pose is None or pose.distance_to(staging)
                                             >= self.params.dock_prestaging_tolerance):
                await self._stage(handle, staging, max_staging_time)
            feedback(INITIAL_PERCEPTION)
            while True:
                try:
                    feedback(CONTROLLING)
                    await self._approach(dock)
                    feedback(WAIT_FOR_CHARGE)
                    await self._wait_for_charge()
                    self.current_dock_type = goal.dock_type
                    log.info("dock_docked", retries=retries, sim_time=self.stack._sim_time())
                    return NavResult(ActionStatus.SUCCEEDED, 0, "docked and charging", num_retries=retries)
                except _Failed as exc:
                    if exc.code not in (FAILED_TO_CONTROL, FAILED_TO_CHARGE) or retries >= self.params.max_retries:
                        raise
                    retries += 1
                    log.info("dock_retry", reason=str(exc), retries=retries, sim_time=self.stack._sim_time())
                    feedback(RETRY)
                    await self._drive_to(staging, backwards=True, timeout=self.params.dock_approach_timeout)
        except _Failed as exc:
            self.stack._publish(ZERO_TWIST)
            log.warning("dock_failed", code=exc.code, reason=str(exc), sim_time=self.stack._sim_time())
            return NavResult(ActionStatus.ABORTED, exc.code, str(exc), num_retries=retries)
        except asyncio.CancelledError:
            self.stack._publish(ZERO_TWIST)
            if handle.preempted:
                return NavResult(ActionStatus.ABORTED, 0, "preempted by a new goal", num_retries=retries)
            return NavResult(ActionStatus.CANCELED, 0, "canceled", num_retries=retries)

    async def _stage(self, handle: NavHandle, staging: Pose2D, max_staging_time: float) -> None:
        from .stack import NavHandle

        sub = NavHandle("navigate_to_pose")
        try:
            result = await asyncio.wait_for(self.stack._navigate(sub, staging), max(max_staging_time, 0.0))
        except TimeoutError:
            raise _Failed(FAILED_TO_STAGE, f"staging pose not reached within {max_staging_time:g} s") from None
        if handle.cancel_requested or handle.preempted:
            raise asyncio.CancelledError
        if result.status is not ActionStatus.SUCCEEDED:
            raise _Failed(FAILED_TO_STAGE, f"failed to navigate to the staging pose: {result.error_msg} "
                                           f"(error {int(result.error_code)})")

    def _robot_pose(self) -> Pose2D:
        stack = self.stack
        now = stack._now()
        if stack._pose is None or stack._pose_age(now) > stack.params.controller.pose_abort_timeout:
            raise _Failed(FAILED_TO_CONTROL, "robot pose is not available")
        return stack._pose

    async def _approach(self, dock: Pose2D) -> None:
        """Drive along the dock's axis until the battery says charging or the pose is at the dock's face."""
        p = self.params
        loop = asyncio.get_running_loop()
        period = 1.0 / p.controller_frequency
        deadline = loop.time() + p.dock_approach_timeout
        c, s = math.cos(dock.yaw), math.sin(dock.yaw)
        while True:
            if self.on_charger:
                break
            pose = self._robot_pose()
            dx, dy = pose.x - dock.x, pose.y - dock.y
            along = c * dx + s * dy  # < 0 before the dock
            if along >= p.docking_threshold:  # on the contacts (whether they touch, the battery tells)
                break
            if along > 0.1:
                raise _Failed(FAILED_TO_CONTROL, f"passed the dock by {along:.3f} m without contact")
            if loop.time() > deadline:
                raise _Failed(FAILED_TO_CONTROL, "timed out approaching the dock; no contact detected")
            carrot = min(along + 0.25, 0.0)  # a point on the dock's axis ahead of the robot
            tx, ty = dock.x + c * carrot, dock.y + s * carrot
            err = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.yaw)
            if abs(along) < 0.05:  # at the end, hold the dock's heading
                err = wrap_angle(dock.yaw - pose.yaw)
            v = min(p.approach_speed, max(0.02, 0.8 * -along)) * max(0.0, math.cos(err))
            w = max(-0.6, min(0.6, 2.0 * err))
            self.stack._publish(Twist(v, w))
            await asyncio.sleep(period)
        self.stack._publish(ZERO_TWIST)

    async def _wait_for_charge(self) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.params.wait_charge_timeout
        while not self.on_charger:
            if loop.time() > deadline:
                raise _Failed(FAILED_TO_CHARGE, "timed out waiting for charge to start")
            await asyncio.sleep(1.0 / self.params.controller_frequency)

    async def _drive_to(self, target: Pose2D, *, backwards: bool, timeout: float) -> None:
        """Straight back (or forward) to ``target`` within the undock tolerances."""
        p = self.params
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        period = 1.0 / p.controller_frequency
        while True:
            pose = self._robot_pose()
            dx, dy = target.x - pose.x, target.y - pose.y
            dist = math.hypot(dx, dy)
            yaw_err = wrap_angle(target.yaw - pose.yaw)
            if dist < p.undock_linear_tolerance and abs(yaw_err) < p.undock_angular_tolerance:
                break
            if loop.time() > deadline:
                raise _Failed(FAILED_TO_CONTROL, f"timed out driving to ({target.x:.2f}, {target.y:.2f})")
            if dist < p.undock_linear_tolerance:  # there: turn to the heading
                v, w = 0.0, max(-0.6, min(0.6, 2.0 * yaw_err))
            else:
                heading = math.atan2(dy, dx) + (math.pi if backwards else 0.0)
                err = wrap_angle(heading - pose.yaw)
                speed = min(p.undock_speed, max(0.03, 0.8 * dist)) * max(0.0, math.cos(err))
                v, w = (-speed if backwards else speed), max(-0.6, min(0.6, 2.0 * err))
            self.stack._publish(Twist(v, w))
            await asyncio.sleep(period)
        self.stack._publish(ZERO_TWIST)

    # -- undock --------------------------------------------------------------------------------------
    async def _undock(self, handle: NavHandle, dock_type: str, max_undocking_time: float) -> NavResult:
        loop = asyncio.get_running_loop()
        kind = dock_type or self.current_dock_type or (DOCK_TYPE if self.docks else "")
        try:
            if kind != DOCK_TYPE:
                raise _Failed(DOCK_NOT_VALID, "no dock information to undock from" if not kind
                              else f"dock type '{kind}' is not a dock plugin here ({DOCK_TYPE})")
            if not self.on_charger:
                log.info("undock_not_docked", sim_time=self.stack._sim_time())
                return NavResult(ActionStatus.SUCCEEDED, 0, "not on the dock: nothing to undock")
            deadline = loop.time() + max_undocking_time
            here = self._robot_pose()
            await self._drive_to(self.staging_pose(here), backwards=True,
                                 timeout=max(0.0, deadline - loop.time()))
            while self.on_charger:  # the battery monitor reports at its own rate
                if loop.time() > deadline:
                    raise _Failed(FAILED_TO_CONTROL, "still charging at the staging pose")
                await asyncio.sleep(1.0 / self.params.controller_frequency)
            self.current_dock_type = ""
            log.info("undock_done", sim_time=self.stack._sim_time())
            return NavResult(ActionStatus.SUCCEEDED, 0, "undocked")
        except _Failed as exc:
            self.stack._publish(ZERO_TWIST)
            log.warning("undock_failed", code=exc.code, reason=str(exc), sim_time=self.stack._sim_time())
            return NavResult(ActionStatus.ABORTED, exc.code, str(exc))
        except asyncio.CancelledError:
            self.stack._publish(ZERO_TWIST)
            if handle.preempted:
                return NavResult(ActionStatus.ABORTED, 0, "preempted by a new goal")
            return NavResult(ActionStatus.CANCELED, 0, "canceled")

