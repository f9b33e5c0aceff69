"""The robot simulator: pymunk world, differential-drive robot, sensors, faults, worlds.

Public API (see ``docs/sim.md``)::

    from sim import Simulator, load_world, load_profile
    from sim.faults import Crash, Push, InvisibleObstacle, ...
"""

from .bus import Bus
from .robot import RobotProfile, load_profile
from .simulator import GroundTruth, SimEvent, SimOptions, Simulator
from .world import World, WorldError, load_world

__all__ = ["Bus", "GroundTruth", "RobotProfile", "SimEvent", "SimOptions", "Simulator", "World",
           "WorldError", "load_profile", "load_world"]
