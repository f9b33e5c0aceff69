"""sim-robot refuses a bad world or robot file with a usage error naming it, not a traceback."""

import subprocess
import sys

import pytest

from tests.paths import ROOT

pytest.importorskip("cyclonedds")


@pytest.mark.parametrize(("args", "named"), [
    (["--robot", "nosuchrobot"], "nosuchrobot: no such robot profile"),
    (["--world", "missing_world.yaml"], "missing_world.yaml"),
])
def test_a_bad_world_or_robot_is_a_usage_error(args, named):
    proc = subprocess.run([sys.executable, "-m", "bt_runtime", "sim-robot", "--domain", "151", *args],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert named in proc.stderr and "Traceback" not in proc.stderr
