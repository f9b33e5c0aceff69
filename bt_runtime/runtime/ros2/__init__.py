"""The ROS 2 driver (extra ``[ros2]``): a robot running ROS 2, reached over DDS with Cyclone DDS's
Python binding, without a ROS installation. See docs/ros2.md."""
