"""Bad recording options end in a one-line error and exit code 2, never a traceback."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from tests.paths import ROOT

pytest.importorskip("foxglove")


def _run(*extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--duration", "1",
                           "--no-progress", *extra], cwd=ROOT, capture_output=True, text=True, timeout=120)


def test_existing_bag_folder_is_never_overwritten(tmp_path):
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "keep.txt").write_text("mine")
    result = _run("--record", str(tmp_path / "bag"))
    assert result.returncode == 2 and "not an empty folder" in result.stderr and "Traceback" not in result.stderr
    assert (tmp_path / "bag" / "keep.txt").read_text() == "mine"


def test_port_in_use_names_the_option_and_leaves_no_empty_bag(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = _run("--foxglove", str(port), "--record", str(tmp_path / "bag"))
    assert result.returncode == 2 and f"--foxglove: cannot serve on 127.0.0.1:{port}" in result.stderr
    assert not (tmp_path / "bag").exists()


@pytest.mark.parametrize("value", ["0", "-1", "nan"])
def test_flush_interval_must_be_positive(tmp_path, value):
    result = _run("--record", str(tmp_path / "bag"), "--record-flush", value)
    assert result.returncode == 2 and "--record-flush must be a positive number" in result.stderr


def test_bad_record_config_names_file_and_field(tmp_path):
    config = tmp_path / "rec.yaml"
    config.write_text("topics: {scann: /x}\n")
    result = _run("--record", str(tmp_path / "bag"), "--record-config", str(config))
    assert result.returncode == 2 and str(config) in result.stderr and "scann" in result.stderr
