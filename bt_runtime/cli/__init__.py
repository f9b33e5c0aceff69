"""Command-line commands, one module each (see ``bt_runtime/__main__.py``)."""

COMMANDS: tuple[str, ...] = ("validate",)
