"""Command-line commands, one module each (see ``bt_runtime/__main__.py``)."""

COMMANDS: tuple[str, ...] = ("run", "scenarios", "validate", "models", "sim_robot", "config", "list")
