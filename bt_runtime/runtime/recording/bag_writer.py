"""A bag alone (no live view): the queue written by one function per stream, made on its first item.

Why: with no live view, the generic path (``RecordPipeline._write_one``: the viewing rate, the
live checks, a converter's list of ``(topic, typename, msg)`` outputs, a count per message on
the bag) spent more on its bookkeeping than on the encoding and the native MCAP write. Here each
``(kind, topic)`` gets a writer made once, with its layouts' encoders, its channels' native
``log`` calls and its per-topic counters bound in; the high-rate kinds (odometry and its
``/tf``, imu, commands, map -> odom, the ground truth and its pose) are fused into one function
each, the rest call their converter (``convert.CONVERTERS``) as the generic path does. The bytes
are the converters' own: ``tests/runtime/recording/test_bag_writer.py`` compares every message
(topic, log time, bytes) and every channel with the generic path's bag of the same queue.

Only when the loop clock is the robot's clock (``ConvertState.robot_time`` is None, as in the
simulator): the fused writers stamp with the loop time; with a robot clock to translate to
(``--driver ros2``) every kind goes through its converter.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import structlog

from .convert import (
    CONVERTERS,
    TF_T,
    ConvertState,
    imu_layout,
    odometry_layout,
    pose_stamped_layout,
    tf_layout,
    twist_layout,
)
from .types import serialize

if TYPE_CHECKING:
    from .bag import Rosbag2Bag

log = structlog.get_logger("bt_runtime.recording")

ODOMETRY_T, IMU_T, TWIST_T, POSE_T = ("nav_msgs/msg/Odometry", "sensor_msgs/msg/Imu", "geometry_msgs/msg/Twist",
                                      "geometry_msgs/msg/PoseStamped")
NS = 1_000_000_000

# (t, t_ns, payload) -> True when it logged anything (the segment's time span counts only those)
Write = Callable[[float, int, Any], bool]
Output = Callable[[str, str], tuple[Callable[[bytes, int, None], None], list[int]]]


class BagWriter:
    """Writes queued items to the bag's open segment and tells the bag what went in (messages
    per topic and their time span) once per batch, not per message."""

    def __init__(self, bag: Rosbag2Bag, state: ConvertState, add_channel: Callable[[str, str], None],
                 written: dict[str, int]):
        self.bag = bag
        self.written = written  # per topic, every message so far (the pipeline's report)
        self.state = state
        self.add_channel = add_channel
        self.writers: dict[tuple[str, str], Write] = {}
        self.counters: dict[str, list[int]] = {}  # topic -> [messages in this batch]
        self.errors = 0

    def output(self, name: str, typename: str) -> tuple[Callable[[bytes, int, None], None], list[int]]:
        """The native log call of ``name``'s channel (made now if new) and its counter."""
        loggers = self.bag.channels.loggers
        if name not in loggers:
            self.add_channel(name, typename)
        counter = self.counters.get(name)
        if counter is None:
            counter = self.counters[name] = [0]
        return loggers[name], counter

    def write(self, queue: deque, deadline: float = 0.0, clock: Callable[[], float] | None = None) -> None:
        """Write queued items, oldest first, until the queue is empty (or, with ``clock``, until
        ``clock() >= deadline``)."""
        bag = self.bag
        if bag.idle:
            bag.open_segment()
        writers, make, pop = self.writers, self._make, queue.popleft
        to_robot = self.state.robot if self.state.robot_time is not None else None
        lo, hi = 2**63 - 1, 0
        while queue:
            kind, topic, t, payload = pop()
            try:
                write = writers.get((kind, topic))
                if write is None:
                    write = writers[(kind, topic)] = make(kind, topic)
                t_ns = int(round((t if to_robot is None else to_robot(t)) * 1e9))  # log time: robot time
                if t_ns < 0:
                    t_ns = 0
                if write(t, t_ns, payload):
                    if t_ns < lo:
                        lo = t_ns
                    if t_ns > hi:
                        hi = t_ns
            except Exception as exc:
                self.errors += 1
                if self.errors <= 5:
                    log.error("recording_message_failed", kind=kind, topic=topic, error=repr(exc))
            if clock is not None and clock() >= deadline:
                break
        counts = {}
        for name, counter in self.counters.items():
            k = counter[0]
            if k:
                counts[name] = k
                counter[0] = 0
        if lo <= hi:  # something was logged
            bag.add(counts, lo, hi)
            written = self.written
            for name, k in counts.items():
                written[name] = written.get(name, 0) + k

    def _make(self, kind: str, topic: str) -> Write:
        fused = FUSED.get(kind) if self.state.robot_time is None else None
        if fused is not None:
            return fused(self.state, topic, self.output)
        return converted(self.state, kind, topic, self.output)


def converted(state: ConvertState, kind: str, topic: str, output: Output) -> Write:
    """Any kind: its converter's outputs, each logged on its topic."""
    convert = CONVERTERS[kind]
    outputs: dict[str, tuple[Callable[[bytes, int, None], None], list[int]]] = {}

    def write(t: float, t_ns: int, payload: Any) -> bool:
        wrote = False
        for name, typename, msg in convert(state, topic, t, payload):
            out = outputs.get(name)
            if out is None:
                out = outputs[name] = output(name, typename)
            out[0](msg if type(msg) is bytes else serialize(msg, typename), t_ns, None)
            out[1][0] += 1
            wrote = True
        return wrote

    return write


# -- the high-rate kinds, fused (each the same bytes as its converter in convert.py; the fields go to
# struct.pack as they are: its "d" converts with float() as the converters do) -----------------------

def odom(state: ConvertState, topic: str, output: Output) -> Write:
    f = state.frames
    odom_enc = state.layout("odom", odometry_layout, f.odom, f.base).encode
    tf_enc = state.layout("tf_odom", tf_layout, f.odom, f.base).encode
    odom_log, odom_n = output(topic, ODOMETRY_T)
    tf_log, tf_n = output(state.tf_topic, TF_T)
    sin, cos = math.sin, math.cos

    def write(t: float, t_ns: int, m: Any) -> bool:
        p, tw = m.pose, m.twist
        x, y, yaw = p.x, p.y, p.yaw
        state.odom_pose = (x, y, yaw)
        sec, ns = divmod(int(round(m.stamp * 1e9)), NS)
        half = yaw / 2.0
        s, c = sin(half), cos(half)
        odom_log(odom_enc(sec, ns, x, y, 0.0, 0.0, 0.0, s, c, tw.linear, 0.0, 0.0, 0.0, 0.0, tw.angular), t_ns, None)
        tf_log(tf_enc(sec, ns, x, y, 0.0, 0.0, 0.0, s, c), t_ns, None)
        odom_n[0] += 1
        tf_n[0] += 1
        return True

    return write


def localized(state: ConvertState, topic: str, output: Output) -> Write:
    """map -> odom (``convert.localized``); its channel made on its first message, as there."""
    f = state.frames
    tf_enc = state.layout("tf_map", tf_layout, f.map, f.odom).encode
    sin, cos = math.sin, math.cos
    out: list[Any] = []

    def write(t: float, t_ns: int, m: Any) -> bool:
        odom_pose = state.odom_pose
        if odom_pose is None:
            return False
        ox, oy, oyaw = odom_pose
        p = m.pose
        yaw = p.yaw - oyaw
        c, sn = cos(yaw), sin(yaw)
        x = p.x - (c * ox - sn * oy)
        y = p.y - (sn * ox + c * oy)
        sec, ns = divmod(int(round(m.stamp * 1e9)), NS)
        half = yaw / 2.0
        if not out:
            out.extend(output(topic, TF_T))
        out[0](tf_enc(sec, ns, x, y, 0.0, 0.0, 0.0, sin(half), cos(half)), t_ns, None)
        out[1][0] += 1
        return True

    return write


def imu(state: ConvertState, topic: str, output: Output) -> Write:
    enc = state.layout("imu", imu_layout, state.frames.imu).encode
    imu_log, n = output(topic, IMU_T)
    sin, cos = math.sin, math.cos

    def write(t: float, t_ns: int, m: Any) -> bool:
        sec, ns = divmod(int(round(m.stamp * 1e9)), NS)
        half = m.yaw / 2.0
        imu_log(enc(sec, ns, 0.0, 0.0, sin(half), cos(half), 0.0, 0.0, m.yaw_rate, m.accel_x, m.accel_y, 0.0),
                t_ns, None)
        n[0] += 1
        return True

    return write


def command(state: ConvertState, topic: str, output: Output) -> Write:
    enc = state.layout("twist", twist_layout).encode
    twist_log, n = output(topic, TWIST_T)

    def write(t: float, t_ns: int, m: Any) -> bool:
        twist_log(enc(m.linear, 0.0, 0.0, 0.0, 0.0, m.angular), t_ns, None)
        n[0] += 1
        return True

    return write


def odometry_like(state: ConvertState, topic: str, output: Output) -> Write:
    """A hook's odometry (the simulator's ground truth) and its pose topic, if any."""
    f = state.frames
    enc = state.layout(("odometry", topic), odometry_layout, f.map, f.base).encode
    odom_log, odom_n = output(topic, ODOMETRY_T)
    pose_topic = state.pose_topics.get(topic)
    if pose_topic:
        pose_enc = state.layout(("pose", pose_topic), pose_stamped_layout, f.map).encode
        pose_log, pose_n = output(pose_topic, POSE_T)
    sin, cos = math.sin, math.cos

    def write(t: float, t_ns: int, m: Any) -> bool:
        p, tw = m.pose, m.twist
        sec, ns = divmod(int(round(m.stamp * 1e9)), NS)
        half = p.yaw / 2.0
        s, c = sin(half), cos(half)
        x, y = p.x, p.y
        odom_log(enc(sec, ns, x, y, 0.0, 0.0, 0.0, s, c, tw.linear, 0.0, 0.0, 0.0, 0.0, tw.angular), t_ns, None)
        odom_n[0] += 1
        if pose_topic:
            pose_log(pose_enc(sec, ns, x, y, 0.0, 0.0, 0.0, s, c), t_ns, None)
            pose_n[0] += 1
        return True

    return write


FUSED: dict[str, Callable[[ConvertState, str, Output], Write]] = {
    "odom": odom, "pose": localized, "imu": imu, "command": command, "odometry": odometry_like,
}
