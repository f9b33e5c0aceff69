"""The ROS 2 driver (extra ``[ros2]``): a robot running ROS 2, reached over DDS with Cyclone DDS's
Python binding, without a ROS installation. See docs/ros2.md."""

from .config import Ros2Config
from .driver import Ros2Driver
from .navigation import Ros2Navigation

__all__ = ["Ros2Config", "Ros2Driver", "Ros2Navigation"]
