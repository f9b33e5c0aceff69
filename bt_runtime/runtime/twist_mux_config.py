"""twist_mux-style gate inputs and locks as configuration, and twist_mux's own YAML file.

A ROS user describes a velocity multiplexer to twist_mux like this (its README's format)::

    twist_mux:
      ros__parameters:
        topics:
          navigation: {topic: cmd_vel_nav, timeout: 0.5, priority: 10}
          joystick:   {topic: joy_vel,     timeout: 0.5, priority: 100}
        locks:
          e_stop:     {topic: e_stop,      timeout: 0.0, priority: 255}

The gate accepts the same file (``gate.twist_mux: FILE`` or ``run --twist-mux FILE``) and the
same entries inline (``gate.inputs`` / ``gate.locks``). Entries named ``tree`` or
``navigation`` (also ``nav``) are the gate's own sources (the tree's command, and the
navigation stack's command from the driver's ``nav_cmd_vel`` stream): they set those sources'
priority and timeout; every other entry is an extra input read from its topic.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import structlog
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

log = structlog.get_logger("bt_runtime.gate")

TREE_NAMES = ("tree",)
NAV_NAMES = ("navigation", "nav")
RESERVED = ("estop", "deadman", "idle", "lock")  # gate sources that are not inputs


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class MuxInputConfig(_Model):
    """One velocity input (geometry_msgs/msg/Twist), as a twist_mux ``topics`` entry."""

    topic: str | None = Field(None, description="ROS topic (relative names go below the driver's namespace); "
                                                "not used for 'tree' and 'navigation'")
    priority: int = Field(..., ge=1, le=255, description="higher wins while fresh (twist_mux's 0..255; "
                                                        "twist_mux never selects priority 0, so 0 is refused)")
    timeout: float = Field(..., ge=0, description="a command older than this (s) is ignored; 0: never "
                                                   "(as twist_mux), refused for 'tree' and 'navigation'")
    stamped: bool = Field(False, description="the topic carries geometry_msgs/msg/TwistStamped "
                                             "(our addition; twist_mux's own file has no such key)")


class MuxLockConfig(_Model):
    """One lock (std_msgs/msg/Bool), as a twist_mux ``locks`` entry."""

    topic: str = Field(..., description="ROS topic")
    priority: int = Field(..., ge=0, le=255, description="while locked, inputs with a lower priority are "
                                                        "masked (equal or higher ones are not)")
    timeout: float = Field(..., ge=0, description="> 0: the lock must be refreshed this often, and a silent "
                                                   "lock (also before its first message) is locked; 0: "
                                                   "locked only while the last message said true")


def default_inputs() -> dict[str, MuxInputConfig]:
    """A teleop input above navigation (10) and the tree (20)."""
    return {"teleop": MuxInputConfig(topic="cmd_vel_teleop", priority=100, timeout=0.5)}


def default_locks() -> dict[str, MuxLockConfig]:
    """An e-stop lock above every default input."""
    return {"e_stop": MuxLockConfig(topic="e_stop", priority=255, timeout=0.0)}


class TwistMuxFileError(ValueError):
    """A twist_mux YAML file that cannot be used; the message names the file and the field."""


class _Section(_Model):
    topics: dict[str, MuxInputConfig] = Field(default_factory=dict)
    locks: dict[str, MuxLockConfig] = Field(default_factory=dict)
    use_stamped: bool = Field(False, description="twist_mux >= 4.4: every input is TwistStamped")


def load_twist_mux_file(path: str | Path) -> tuple[dict[str, MuxInputConfig], dict[str, MuxLockConfig]]:
    """(inputs, locks) from a twist_mux parameter file; ``TwistMuxFileError`` names file and field.

    Accepts ``twist_mux: ros__parameters: {topics, locks}`` (also under any node name, e.g. a
    renamed twist_mux node, or the wildcard ``/**``) and the bare ``{topics, locks}``."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TwistMuxFileError(f"twist_mux file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TwistMuxFileError(f"{path}: cannot read it ({exc})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f":{mark.line + 1}" if mark is not None else ""
        raise TwistMuxFileError(f"{path}{where}: not valid YAML ({getattr(exc, 'problem', exc)})") from None
    section, prefix = _parameters(path, data)
    ignored = sorted(str(k) for k in section if k not in _Section.model_fields)
    if ignored:  # the node's other parameters (use_sim_time, qos_overrides...) do not concern the gate
        log.info("twist_mux_file_keys_ignored", file=str(path), keys=ignored)
        section = {k: v for k, v in section.items() if k in _Section.model_fields}
    try:
        parsed = _Section.model_validate(section)
    except ValidationError as exc:
        raise TwistMuxFileError(f"{path}: " + "; ".join(_plain(exc, prefix))) from None
    if not parsed.topics and not parsed.locks:
        raise TwistMuxFileError(f"{path}: '{prefix}' has neither 'topics' nor 'locks'")
    if parsed.use_stamped:
        for spec in parsed.topics.values():
            spec.stamped = True
    return parsed.topics, parsed.locks


def _parameters(path: Path, data: Any) -> tuple[dict, str]:
    if not isinstance(data, dict):
        raise TwistMuxFileError(f"{path}: expected 'twist_mux: ros__parameters: {{topics, locks}}', "
                                f"got {type(data).__name__}")
    if "topics" in data or "locks" in data:
        return data, "(top level)"
    if len(data) != 1:
        raise TwistMuxFileError(f"{path}: expected one node (e.g. 'twist_mux:') at the top, got "
                                f"{', '.join(map(str, data)) or 'nothing'}")
    node, body = next(iter(data.items()))
    if not isinstance(body, dict) or not isinstance(body.get("ros__parameters"), dict):
        raise TwistMuxFileError(f"{path}: '{node}' needs a 'ros__parameters:' mapping with 'topics' and/or 'locks'")
    return body["ros__parameters"], f"{node}.ros__parameters"


def _plain(exc: ValidationError, prefix: str) -> list[str]:
    out = []
    for err in exc.errors(include_url=False):
        key = ".".join([prefix, *map(str, err["loc"])])
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = "is not a twist_mux key (topics/locks entries take topic, timeout, priority)"
        given = err.get("input")
        shown = "" if isinstance(given, dict | list) or err["type"] in ("missing", "extra_forbidden") \
            else f" (got {given!r})"
        out.append(f"'{key}': {msg[:1].lower() + msg[1:]}{shown}")
    return out


def check_names(inputs: dict[str, MuxInputConfig], locks: dict[str, MuxLockConfig]) -> None:
    """Extra inputs need a topic and a name that is not a gate source; locks need distinct names."""
    for name, spec in inputs.items():
        if name in TREE_NAMES or name in NAV_NAMES:
            continue
        if name in RESERVED or "/" in name or not name:
            raise ValueError(f"inputs.{name}: the name is reserved or not usable as a source name "
                             f"(reserved: {', '.join(RESERVED)}; no '/')")
        if not spec.topic:
            raise ValueError(f"inputs.{name}: needs a topic")
    for name in locks:
        if "/" in name or not name:
            raise ValueError(f"locks.{name}: not usable as a lock name (no '/')")
