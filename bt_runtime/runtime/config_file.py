"""The runtime configuration as a file a person edits: the defaults as commented YAML
(``python -m bt_runtime config``) and loading with errors that name the key in plain words.

    tick:
      rate_hz: 100.0        # tree tick rate
    gate:
      deadman_timeout: 0.1  # tree heartbeat older than this: zero

Every key is optional; a file holds only what it changes (see docs/config.example.yaml).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError

from .config import RuntimeConfig


class ConfigError(ValueError):
    """A configuration file that cannot be used; the message names the file and the key."""


def defaults_yaml(model: type[BaseModel] = RuntimeConfig) -> str:
    """Every setting with its default value and, as a comment, what it does."""
    return "\n".join(_lines(model(), 0)) + "\n"


def _lines(value: BaseModel, indent: int) -> list[str]:
    out = []
    pad = "  " * indent
    for name, field in type(value).model_fields.items():
        current = getattr(value, name)
        note = f"  # {field.description}" if field.description else ""
        if isinstance(current, BaseModel):
            out.append(f"{pad}{name}:{note}")
            out += _lines(current, indent + 1)
        elif isinstance(current, dict) and current:
            out.append(f"{pad}{name}:{note}")
            dumped = yaml.safe_dump(_plain(current), default_flow_style=False, sort_keys=False).splitlines()
            out += [f"{pad}  {line}" for line in dumped]
        else:
            text = yaml.safe_dump(_plain(current), default_flow_style=True).strip()
            text = text.removesuffix("\n...").removesuffix("...").strip()
            out.append(f"{pad}{name}: {text}{note}")
    return out


def _plain(value: Any) -> Any:
    if isinstance(value, BaseModel):
        return value.model_dump()
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def load_runtime_config(path: str | Path | None) -> RuntimeConfig:
    """The file's settings over the defaults; ``ConfigError`` names file, key and problem."""
    if path is None:
        return RuntimeConfig()
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"config file not found: {path}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f":{mark.line + 1}" if mark is not None else ""
        raise ConfigError(f"{path}{where}: not valid YAML ({getattr(exc, 'problem', exc)})") from None
    if data is None:
        return RuntimeConfig()
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected sections such as 'tick:' or 'gate:' at the top, "
                          f"got {type(data).__name__}")
    gate = data.get("gate")
    if isinstance(gate, dict) and isinstance(gate.get("twist_mux"), str):  # relative to this file's folder
        gate["twist_mux"] = str(path.parent / Path(gate["twist_mux"]).expanduser())
    zones = data.get("safety_zones")
    if isinstance(zones, dict) and isinstance(zones.get("file"), str):  # likewise
        zones["file"] = str(path.parent / Path(zones["file"]).expanduser())
    try:
        return RuntimeConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"{path}: " + "; ".join(plain_errors(exc))) from None


def plain_errors(exc: ValidationError, model: type[BaseModel] = RuntimeConfig) -> list[str]:
    """One sentence per problem, naming the key as it is written in the file (no URLs)."""
    out = []
    for err in exc.errors(include_url=False):
        loc = [str(p) for p in err["loc"]]
        key = ".".join(loc) or "(top level)"
        if err["type"] == "extra_forbidden":
            known = _known_keys(model, loc[:-1])
            out.append(f"'{key}' is not a setting" + (f" (known here: {', '.join(known)})" if known else ""))
            continue
        msg = err["msg"].removeprefix("Value error, ")
        given = err.get("input")
        shown = "" if isinstance(given, dict | list) else f" (got {given!r})"
        out.append(f"'{key}': {msg[:1].lower() + msg[1:]}{shown}")
    return out


def _known_keys(model: type[BaseModel], loc: list[str]) -> list[str]:
    current: Any = model
    for part in loc:
        field = getattr(current, "model_fields", {}).get(part)
        if field is None:
            return []
        current = field.annotation
    fields = getattr(current, "model_fields", None)
    return sorted(fields) if fields else []
