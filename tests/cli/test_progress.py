"""The progress line and log lines share the terminal: a log line erases the status line first."""

import io

from bt_runtime.cli.progress import WIDTH, SharedConsole


def test_a_log_line_is_not_written_over_the_progress_line():
    out = io.StringIO()
    console = SharedConsole(out)
    console.show_status("t=1.00s pose=(0, 0)")
    console.write("warning: battery low\n")
    console.show_status("t=2.00s pose=(1, 0)")
    console.end_status()
    text = out.getvalue()
    # the status is erased (carriage return, blanks, carriage return) before the warning ...
    assert "\r" + " " * WIDTH + "\rwarning: battery low\n" in text
    # ... so the warning starts its own line and the next status is drawn below it
    lines = text.split("\n")
    assert lines[1].lstrip("\r").startswith("t=2.00s") and text.endswith("\n")
    assert [line.rstrip() for line in _as_a_terminal_shows(text)] == ["warning: battery low", "t=2.00s pose=(1, 0)", ""]


def _as_a_terminal_shows(text: str) -> list[str]:
    """Apply carriage returns as a terminal does: later text overwrites from the line's start."""
    shown = []
    for line in text.split("\n"):
        cells: list[str] = []
        for part in line.split("\r"):
            cells[:len(part)] = part
        shown.append("".join(cells))
    return shown
