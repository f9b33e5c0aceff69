"""SimDriver: the simulator and the Nav2 stand-in behind the runtime's driver interface.

The map the navigation stack plans on is what a SLAM run would have produced: the world's
lidar-visible shapes rasterized at 0.05 m (or a ROS map_server map given by the user). Shapes
that block the body but not the lidar plane are missing from it, as in the paper's
"undetected obstacle" scenario.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bt_runtime.runtime.driver import STREAMS
from bt_runtime.runtime.messages import ComponentInfo, ComponentState, RobotInfo, Twist
from bt_runtime.runtime.twist_mux import INPUT_STREAM, LOCK_STREAM

from .nav import NavParams, NavStack, OccupancyGrid, RobotParams
from .simulator import Simulator


def occupancy_from_world(sim: Simulator, resolution: float = 0.05) -> OccupancyGrid:
    raster = sim.rasterize(resolution, layer="lidar", dynamic=True)  # incl. obstacles added before start
    data = np.where(raster.data > 0, 100, 0).astype(np.int8)
    return OccupancyGrid(data, raster.resolution, (raster.origin[0], raster.origin[1], 0.0))


def robot_params_for(sim: Simulator) -> RobotParams:
    profile = sim.profile
    lidar = profile.lidar
    return RobotParams(radius=profile.radius, max_linear_vel=profile.max_linear,
                       max_angular_vel=min(profile.max_angular, 1.0),
                       max_linear_accel=profile.max_linear_accel,
                       max_angular_accel=min(profile.max_angular_accel, 3.2),
                       laser_offset=(lidar.x, lidar.y, 0.0))


ROBOT_STREAMS = frozenset({*STREAMS, "plan", "component_state"})


class SimDriver:
    """A simulated robot: sensors and base from ``Simulator``, navigation from ``NavStack``."""

    name = "sim"

    def __init__(self, world: Any = "apartment", robot: Any = "burger", seed: int = 0, *,
                 sim_options: Any = None, nav_params: NavParams | dict | None = None,
                 map_yaml: str | Path | None = None, cruise_speed: float | None = None,
                 max_angular_speed: float | None = None,
                 prepare: Callable[[Simulator], Any] | None = None, **sim_overrides: Any):
        self.sim = Simulator(world, robot, seed=seed, options=sim_options, **sim_overrides)
        if prepare is not None:  # e.g. obstacles that must be on the map
            prepare(self.sim)
        grid = OccupancyGrid.load(map_yaml) if map_yaml else occupancy_from_world(self.sim)
        self.map = grid
        robot_params = robot_params_for(self.sim)
        if max_angular_speed is not None:
            robot_params = robot_params.model_copy(update={"max_angular_vel": max_angular_speed})
        docks = {"home_dock": self.sim.dock} if self.sim.dock is not None else {}  # the docking server's database
        self.navigation = NavStack(self.sim.bus, grid, robot=robot_params, params=nav_params, docks=docks)
        self.navigation.on_component_event = self.sim.log_component
        if cruise_speed is not None:
            self.navigation.set_desired_speed(cruise_speed)
        self._nav_names = {info.name for info in self.navigation.component_infos()}

    @property
    def faults(self) -> Any:
        return self.sim.faults

    async def start(self) -> None:
        await self.sim.start()
        await self.navigation.start()

    async def stop(self) -> None:
        await self.navigation.stop()
        await self.sim.stop()

    def subscribe(self, stream: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        """A robot stream (what a real robot's topics carry). The simulator's own topics (the
        ground truth, its event log) are refused: they are for judging and recording, never
        for deciding; those subscribe on ``driver.sim``."""
        if stream not in ROBOT_STREAMS and not stream.startswith(("heartbeat/", INPUT_STREAM, LOCK_STREAM)):
            raise ValueError(f"{stream!r} is not a robot stream (streams: {', '.join(sorted(ROBOT_STREAMS))}, "
                             "heartbeat/<component>, cmd_vel_input/<input>, lock/<lock>); the simulator's "
                             "truth is not on the driver interface")
        return self.sim.subscribe(stream, callback)

    def publish_command_input(self, name: str, linear: float, angular: float) -> None:
        """A velocity command on the gate's input ``name`` (e.g. "teleop"), as a joystick
        publishing on that input's topic would send it (``cmd_vel_input/<name>``)."""
        self.sim.bus.publish(INPUT_STREAM + name, Twist(float(linear), float(angular)))

    def publish_lock(self, name: str, locked: bool) -> None:
        """A lock message (std_msgs/Bool) on the gate's lock ``name`` (``lock/<name>``)."""
        self.sim.bus.publish(LOCK_STREAM + name, bool(locked))

    def send_velocity(self, linear: float, angular: float) -> None:
        self.sim.command(linear, angular)

    def emergency_zero(self) -> None:
        self.sim.emergency_zero()

    # Localization (AMCL-like) needs the odometry transform: restart odometry first.
    DEPENDENCIES = {"localization": ("odom",)}

    def components(self) -> list[ComponentInfo]:
        infos = [*self.sim.components(), *self.navigation.component_infos()]
        for info in infos:
            if info.name in self.DEPENDENCIES:
                info.extra["depends_on"] = self.DEPENDENCIES[info.name]
        return infos

    def component_state(self, name: str) -> ComponentState:
        if name in self._nav_names:
            return self.navigation.component_states()[name]
        return self.sim.component_state(name)

    def robot_info(self) -> RobotInfo:
        profile = self.sim.profile
        battery = profile.battery
        return RobotInfo(radius=profile.radius, max_linear=profile.max_linear, max_angular=profile.max_angular,
                         max_linear_accel=profile.max_linear_accel, max_angular_accel=profile.max_angular_accel,
                         capacity_ah=battery.capacity_ah,
                         voltage_nominal=(battery.voltage_full + battery.voltage_empty) / 2,
                         idle_power_w=battery.idle_power_w, k_linear=battery.k_linear,
                         k_angular=battery.k_angular,
                         bumper_segments=profile.bumper.spans() if profile.bumper is not None else (),
                         lidar_x=profile.lidar.x, lidar_y=profile.lidar.y)

    async def restart(self, name: str) -> bool:
        if name in self._nav_names:
            return await self.navigation.restart(name)
        return await self.sim.restart(name)
