"""Topic names, frames and buffer sizes of a recording (pydantic: checked at the edge)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class TopicNames(BaseModel):
    """Where each stream goes. Empty string: not recorded."""

    model_config = ConfigDict(extra="forbid")
    scan: str = "/scan"
    odom: str = "/odom"
    imu: str = "/imu"
    tf: str = "/tf"
    tf_static: str = "/tf_static"
    map: str = "/map"
    plan: str = "/plan"
    cmd_vel: str = "/cmd_vel"
    cmd_vel_source: str = "/cmd_vel/{source}"  # one topic per command source (navigation, tree, teleop)
    battery: str = "/battery_state"
    diagnostics: str = "/diagnostics"
    behavior_tree_log: str = "/behavior_tree_log"
    supervisor_events: str = "/supervisor/events"
    gate_events: str = "/gate/events"


class Frames(BaseModel):
    model_config = ConfigDict(extra="forbid")
    map: str = "map"
    odom: str = "odom"
    base: str = "base_link"
    laser: str = "laser"
    imu: str = "base_link"


class RecordingOptions(BaseModel):
    """How a recording is written and served."""

    model_config = ConfigDict(extra="forbid")
    topics: TopicNames = Field(default_factory=TopicNames)
    frames: Frames = Field(default_factory=Frames)
    queue_size: int = Field(20_000, ge=100, description="messages waiting for the writer; more are dropped")
    flush_interval_s: float = Field(5.0, gt=0, le=3600,
                                    description="wall seconds between segment closes (a killed run keeps "
                                                "everything up to the last one)")
    diagnostics_period_s: float = Field(1.0, gt=0, description="robot seconds between /diagnostics")
    map_check_period_s: float = Field(0.5, gt=0, description="robot seconds between map-change checks")
    compression: str = Field("lz4", pattern="^(zstd|lz4|none)$",
                             description="MCAP chunk compression: lz4 (default) costs a run ~2 % less CPU than "
                                         "zstd for larger files; every reader (rosbags, mcap, Foxglove, ros2 bag) "
                                         "reads both")
    tree_log: str = Field("states", pattern="^(states|changes|all)$",
                          description="'states': after each tick, the nodes whose status changed since the last "
                                      "tick (cheap); 'changes': every status transition (Nav2's RosTopicLogger), a "
                                      "tick that repeats the previous one not logged again; 'all': every tick's "
                                      "transitions (see tree_log.py for what each costs)")
    live_rate_hz: float = Field(10.0, ge=0, description="the live view sends odometry (and its /tf), imu and "
                                "the ground truth at most this often per topic, a viewing rate; the bag keeps "
                                "every message (0: every message live too)")
    cmd_vel_repeat_s: float = Field(0.1, ge=0, description="an unchanged gate output (same command and "
                                    "source) is recorded again only after this many robot seconds (0: always)")
