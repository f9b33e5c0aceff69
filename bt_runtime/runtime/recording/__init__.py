"""Recording a run as a rosbag2 bag (MCAP storage, ROS 2 CDR) and serving it live to Foxglove.

The tick path only appends small tuples to a bounded queue (``pipeline``); a writer thread
turns them into ROS 2 messages (``convert``), serializes them once with the ``rosbags``
typestore (``types``) and hands the bytes to the sinks: the bag (``bag``) and the Foxglove
WebSocket server (``live``). ``Recorder`` wires a running ``AutonomyRuntime`` to it; the
simulator adds its own topics (ground truth, faults, the map) through ``RecordingHooks``.
"""

from .config import RecordingOptions, TopicNames
from .hooks import MapSnapshot, RecordingHooks, StreamSpec

__all__ = ["MapSnapshot", "RecordingHooks", "RecordingOptions", "StreamSpec", "TopicNames"]
