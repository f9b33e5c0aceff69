"""Runtime configuration (validated at the edge with pydantic; plain objects inside)."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from .driver import STREAMS
from .twist_mux_config import (
    NAV_NAMES,
    TREE_NAMES,
    MuxInputConfig,
    MuxLockConfig,
    check_names,
    default_inputs,
    default_locks,
    load_twist_mux_file,
)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)  # deadman_timeout: .inf is an error


class TickConfig(_Model):
    rate_hz: float = Field(100.0, gt=0, description="tree tick rate")
    stop_on_completion: bool = Field(True, description="stop when the root returns SUCCESS/FAILURE")
    pacing: Literal["efficient", "precise"] = Field(
        "efficient", description="real-time pacing: 'efficient' is one loop timer per deadline "
                                 "(microsecond timers; pacing alone ~1-2 % of a core at 100 Hz); 'precise' "
                                 "also yields to the loop for spin_window_s before it (lowest lateness, "
                                 "~20-30 % of a core)")
    spin_window_s: float = Field(0.0035, ge=0, description="pacing 'precise': yield-until-deadline window")
    phase: float = Field(0.5, ge=0, lt=1, description="tick deadlines sit this fraction of a period after "
                                                       "the driver's start, away from its periodic work")
    max_reticks: int = Field(100, ge=0, description="wake-up re-ticks within one tick (BT.CPP: unbounded); "
                                                    "bounds a Repeat -1 of a synchronous child so the "
                                                    "loop keeps running")


class ComponentWatch(_Model):
    """Per-component watchdog settings (overrides the supervisor defaults)."""

    timeout: float | None = Field(None, gt=0, description="silence (s) after which it is failed")
    auto_restart: bool | None = None
    critical: bool | None = Field(None, description="a dead critical component stops the robot")
    watched: bool = True


class SupervisorConfig(_Model):
    max_sleep: float = Field(0.5, gt=0, description="the watchdog wakes at each component's deadline, "
                                                     "and at least this often")
    default_timeout: float = Field(1.0, gt=0, description="the paper's 1 s; a component that publishes "
                                                           "slower than 2.5 Hz gets 2.5 of its periods")
    startup_grace: float = Field(2.0, ge=0, description="time allowed for a first message")
    auto_restart: bool = Field(False, description="restart failed components without being asked")
    max_failed_restarts: int = Field(2, ge=1, description="then the component is dead")
    restart_timeout: float = Field(5.0, gt=0, description="a restart that takes longer failed")
    recovery_timeout: float = Field(2.0, gt=0, description="after a restart, data must flow within this")
    dependency_grace: float = Field(1.0, ge=0, description="after a dependency recovers, give the components "
                                                           "that need it this long to recover by themselves")
    check_data: bool = Field(True, description="only fresh, valid data proves a component alive (stale "
                                               "timestamps, repeated identical scans and NaN data do not)")
    invalid_share: float = Field(0.3, ge=0, le=1, description="a scan with more than this share of NaN or "
                                                              "out-of-range ranges is invalid")
    components: dict[str, ComponentWatch] = Field(default_factory=dict)


class BackupConfig(_Model):
    period: float = Field(0.5, gt=0, description="housekeeping period (s)")
    sizes: dict[str, int] = Field(default_factory=lambda: {
        "scan": 50, "imu": 500, "odom": 500, "pose": 200, "bumper": 200, "battery": 120,
        "cmd_vel": 1000, "nav_cmd_vel": 500})

    @field_validator("sizes")
    @classmethod
    def _known_positive_sizes(cls, sizes: dict[str, int]) -> dict[str, int]:
        known = (*STREAMS, "cmd_vel")  # cmd_vel: what the gate sent
        for stream, size in sizes.items():
            if stream not in known:
                raise ValueError(f"unknown stream {stream!r} (streams: {', '.join(known)})")
            if not 1 <= size <= 1_000_000:
                raise ValueError(f"{stream}: buffer size must be 1..1000000, got {size}")
        return sizes


class GateConfig(_Model):
    min_rate_hz: float = Field(10.0, gt=0, description="the gate publishes after every tick and every "
                                                       "navigation command, and at least this often")
    deadman_timeout: float = Field(0.1, gt=0, description="tree heartbeat older than this: zero")
    nav_stale_timeout: float = Field(0.25, gt=0, description="navigation command older than this: ignored "
                                                         "(inputs.navigation.timeout, when given, sets it)")
    tree_stale_timeout: float = Field(0.2, gt=0, description="tree command older than this: ignored "
                                                          "(inputs.tree.timeout, when given, sets it)")
    passthrough: bool = Field(False, description="baseline mode: forward navigation commands only, "
                                                 "no dead-man, like a plain Nav2 setup")
    priorities: dict[str, int] = Field(
        default_factory=lambda: {"tree": 20, "nav": 10},
        description="twist_mux-style priorities of the two command sources (higher wins while fresh); "
                    "an emergency stop and the dead-man always come first; an inputs entry "
                    "named tree or navigation, when given, sets these instead")

    @field_validator("priorities")
    @classmethod
    def _two_sources(cls, value: dict[str, int]) -> dict[str, int]:
        if set(value) != {"tree", "nav"}:
            raise ValueError(f"needs exactly the sources 'tree' and 'nav' (got {', '.join(sorted(value)) or 'none'})")
        return value
    watchdog: bool | None = Field(None, description="dead-man on its own OS thread (zeroes the base when the "
                                                    "event loop stalls); None: on for real-time loops")
    nonfinite_repeats: int = Field(3, ge=1, description="non-finite commands in a row from one source before "
                                                        "the tree gets a failure")
    inputs: dict[str, MuxInputConfig] = Field(
        default_factory=default_inputs,
        description="twist_mux-style velocity inputs beside the tree and navigation (name: topic, priority "
                    "1..255, timeout s); entries named tree or navigation set those sources' priority and "
                    "timeout (docs/runtime.md)")
    locks: dict[str, MuxLockConfig] = Field(
        default_factory=default_locks,
        description="twist_mux-style locks (std_msgs/Bool): while true, or silent past a timeout > 0, inputs "
                    "with a lower priority are masked")
    twist_mux: Path | None = Field(None, description="a twist_mux parameter file (its topics and locks replace "
                                                     "inputs and locks); relative to this file's folder")

    @model_validator(mode="after")
    def _twist_mux(self) -> GateConfig:
        """Read the twist_mux file, then move the tree's and navigation's entries into
        ``priorities`` and the stale timeouts, so ``inputs`` holds only the extra inputs."""
        if self.twist_mux is not None:
            self.inputs, self.locks = load_twist_mux_file(self.twist_mux)
        check_names(self.inputs, self.locks)
        priorities = dict(self.priorities)
        for names, source, field in ((TREE_NAMES, "tree", "tree_stale_timeout"),
                                     (NAV_NAMES, "nav", "nav_stale_timeout")):
            given = [n for n in names if n in self.inputs]
            if len(given) > 1:
                raise ValueError(f"inputs: {' and '.join(given)} are the same source; give one")
            if given:
                spec = self.inputs.pop(given[0])
                if spec.timeout == 0:
                    raise ValueError(f"inputs.{given[0]}.timeout: 0 (never stale) is not allowed for the "
                                     f"{source} command: the gate must stop a source that went silent")
                priorities[source] = spec.priority
                setattr(self, field, spec.timeout)
        self.priorities = priorities
        return self

    def with_twist_mux(self, path: str | Path) -> GateConfig:
        """This configuration with its inputs and locks from a twist_mux file (``run --twist-mux``)."""
        inputs, locks = load_twist_mux_file(path)  # TwistMuxFileError names the file and the field
        data = self.model_dump(exclude={"inputs", "locks", "twist_mux"})
        config = GateConfig.model_validate({**data, "inputs": {k: v.model_dump() for k, v in inputs.items()},
                                            "locks": {k: v.model_dump() for k, v in locks.items()}})
        config.twist_mux = Path(path)
        return config


class SafetyZonesSettings(_Model):
    enabled: bool = Field(True, description="collision_monitor-style zones on the lidar scan, applied by the "
                                            "gate to every command (never in passthrough mode)")
    file: str | None = Field(None, description="a collision_monitor parameter file (YAML); none: zones sized "
                                               "for the robot (docs/safety_zones.md)")


class RuntimeConfig(_Model):
    tick: TickConfig = Field(default_factory=TickConfig)
    supervisor: SupervisorConfig = Field(default_factory=SupervisorConfig)
    backup: BackupConfig = Field(default_factory=BackupConfig)
    gate: GateConfig = Field(default_factory=GateConfig)
    safety_zones: SafetyZonesSettings = Field(default_factory=SafetyZonesSettings)
    shutdown_timeout: float = Field(2.0, gt=0, description="at stop, tasks that ignore cancellation (and a "
                                                           "driver that does not stop) are abandoned after this")
