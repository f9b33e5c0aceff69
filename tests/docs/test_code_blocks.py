"""Every code block of README.md and docs/*.md runs as written.

* ``python`` blocks run as a program (``PYTHONPATH`` = the checkout); a block that defines
  ``test_`` functions is a test file and runs under pytest with the package's plugin.
* ``sh``/``bash`` blocks run in bash, in a scratch folder holding a copy of ``trees/`` and
  ``docs/`` (commands that write files, like ``models --embed``, change the copies), with
  ``python`` being this interpreter and a DDS domain of their own. A line ending in ``&`` runs
  in the background and is stopped when the block ends.
* ``yaml`` blocks are parsed; ROS 2 driver files are validated as ``Ros2Config``, runtime
  configuration files as ``RuntimeConfig``.
* Untagged blocks are output or diagrams, not code.

A block is left out only when an HTML comment right above it says ``docs-test: skip: REASON``
(installing into a fresh venv, running the whole test suite, needing a real robot); the
reasons are listed by ``test_skipped_blocks_say_why``.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path

import pytest
import yaml

from tests.paths import ROOT

FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.S | re.M)
DIRECTIVE = re.compile(r"<!--\s*docs-test:\s*skip:\s*(.*?)\s*-->\s*\n\s*$")
RUNNABLE = ("python", "sh", "bash", "yaml")


@dataclass(frozen=True)
class Block:
    file: str
    line: int
    lang: str
    code: str
    skip: str | None

    @property
    def id(self) -> str:
        return f"{self.file}:{self.line}"


def blocks() -> list[Block]:
    out = []
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text(encoding="utf-8")
        for m in FENCE.finditer(text):
            if m.group(1) not in RUNNABLE:
                continue
            before = text[max(0, m.start() - 300):m.start()]
            d = DIRECTIVE.search(before)
            out.append(Block(str(path.relative_to(ROOT)), text.count("\n", 0, m.start()) + 1, m.group(1),
                             m.group(2), d.group(1) if d else None))
    return out


BLOCKS = blocks()


_DOMAIN: list[int] = []


def _docs_domain() -> int:
    """One DDS domain for the blocks of this run (a block's background robot ends with its block)."""
    if not _DOMAIN:
        from tests.helpers import dds_domain

        _DOMAIN.append(dds_domain())
    return _DOMAIN[0]


def _env(tmp: Path) -> dict[str, str]:
    bin_dir = tmp / "bin"
    bin_dir.mkdir(exist_ok=True)
    for name in ("python", "python3"):
        wrapper = bin_dir / name  # a script, not a symlink: the venv is found from the invoked path
        wrapper.write_text(f'#!/bin/sh\nexec "{sys.executable}" "$@"\n')
        wrapper.chmod(0o755)
    env = dict(os.environ, PYTHONPATH=str(ROOT), PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
               ROS_DOMAIN_ID=str(_docs_domain()), NO_COLOR="1")
    env.pop("CYCLONEDDS_URI", None)
    return env


def _run_python(block: Block, tmp: Path) -> subprocess.CompletedProcess:
    if re.search(r"^(async )?def test_", block.code, re.M):
        (tmp / "test_from_docs.py").write_text(block.code, encoding="utf-8")
        plugin = [] if any(ep.value == "bt_runtime.testing.plugin" for ep in entry_points(group="pytest11")) \
            else ["-p", "bt_runtime.testing.plugin"]
        argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *plugin, "test_from_docs.py"]
        return subprocess.run(argv, cwd=tmp, env=_env(tmp), capture_output=True, text=True, timeout=300)
    script = tmp / "from_docs.py"
    script.write_text(block.code, encoding="utf-8")
    return subprocess.run([sys.executable, str(script)], cwd=ROOT, env=_env(tmp), capture_output=True, text=True,
                          timeout=300)


# `--foxglove` with no port or 8765: the documented default, the same for every checkout on the machine
DEFAULT_PORT_FOXGLOVE = re.compile(r"--foxglove(?![-\w])(?!\s+(?!8765\b)\d)")


@contextlib.contextmanager
def _machine_lock(name: str) -> Iterator[None]:
    """An exclusive lock held across processes (every checkout and test run on this machine)."""
    with open(Path(tempfile.gettempdir()) / f"bt_runtime-{name}.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _run_shell(block: Block, tmp: Path) -> subprocess.CompletedProcess:
    work = tmp / "checkout"
    for folder in ("trees", "docs"):
        shutil.copytree(ROOT / folder, work / folder)
    script = "set -e\ntrap 'kill $(jobs -p) 2>/dev/null || true' EXIT\n" + block.code
    # a block serving Foxglove on the default port runs as written, one at a time on the machine: two
    # test runs at once (other checkouts, a full suite beside a landing) had the second one's server
    # refused with 'cannot serve on 127.0.0.1:8765'
    uses_port = DEFAULT_PORT_FOXGLOVE.search(block.code) is not None
    with _machine_lock("foxglove-8765") if uses_port else contextlib.nullcontext():
        return subprocess.run(["bash", "-c", script], cwd=work, env=_env(tmp), capture_output=True, text=True,
                              timeout=300)


def _check_yaml(block: Block) -> None:
    data = yaml.safe_load(block.code)
    if block.file == "docs/ros2.md":
        pytest.importorskip("cyclonedds")
        from bt_runtime.runtime.ros2 import Ros2Config

        Ros2Config.model_validate(data)
    elif isinstance(data, dict) and set(data) == {"collision_monitor"}:  # docs/safety_zones.md
        from bt_runtime.runtime.safety_zones_config import from_parameters

        from_parameters(data["collision_monitor"]["ros__parameters"], block.id)
    elif isinstance(data, dict) and set(data) <= {"tick", "supervisor", "backup", "gate", "safety_zones"}:
        from bt_runtime.runtime.config import RuntimeConfig

        RuntimeConfig.model_validate(data)


def _run_by_a_test_of_its_own(block: Block) -> bool:
    """docs/ros2.md's sim-robot + run pair: test_documented_command.py runs those two commands,
    read from the block, and checks the goal's outcome too (one run of a 30 s DDS drive, not two)."""
    from tests.helpers import DOCUMENTED_ROBOT

    return block.file == "docs/ros2.md" and block.code.startswith(DOCUMENTED_ROBOT + "\n")


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.skip is None], ids=lambda b: b.id)
def test_code_block_runs_as_written(block, tmp_path):
    if _run_by_a_test_of_its_own(block):
        from tests.helpers import documented_ros2_commands

        documented_ros2_commands()  # the block is still the two commands that test runs
        return
    if block.lang == "yaml":
        _check_yaml(block)
        return
    if "--driver ros2" in block.code or "sim-robot" in block.code:
        pytest.importorskip("cyclonedds")
    done = _run_python(block, tmp_path) if block.lang == "python" else _run_shell(block, tmp_path)
    assert done.returncode == 0, f"{block.id} exited {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"


def test_skipped_blocks_say_why():
    skipped = [b for b in BLOCKS if b.skip is not None]
    assert all(len(b.skip) > 10 for b in skipped), skipped
    assert len(skipped) <= 6, [b.id for b in skipped]  # the exceptions stay few
