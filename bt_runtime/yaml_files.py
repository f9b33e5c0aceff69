"""One safe YAML loader for every file the project reads (worlds, robot profiles, maps, configs).

Safe loading only (plain data, no Python objects); libyaml's C parser when PyYAML was built with
it (about 5x faster, which matters for campaign runs that read worlds and profiles), the
pure-Python safe loader otherwise.
"""

from __future__ import annotations

import yaml

SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def safe_load(text: str):
    """Parse YAML text to plain data (dicts, lists, scalars) with the safe loader."""
    return yaml.load(text, Loader=SAFE_LOADER)  # noqa: S506 (a safe loader)
