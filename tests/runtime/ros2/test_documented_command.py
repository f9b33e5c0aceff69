"""The ROS 2 commands of README/docs, as a user types them: ``sim-robot --loopback`` in one
process, ``run trees/autonomy.xml --driver ros2 --loopback --goal 3.5,-2.5`` in another, on
real DDS and the wall clock. The goal is reached (the run waits for the robot's components,
battery included, before handing it over) and ``run`` exits 0."""

import json
import os
import subprocess
import sys

import pytest

pytest.importorskip("cyclonedds")

from tests.helpers import dds_domain  # noqa: E402
from tests.paths import ROOT  # noqa: E402


def test_sim_robot_then_run_reaches_the_goal(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT), ROS_DOMAIN_ID=str(dds_domain()))
    env.pop("CYCLONEDDS_URI", None)
    robot = subprocess.Popen([sys.executable, "-m", "bt_runtime", "sim-robot", "--loopback", "--duration", "150"],
                             cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert "sim-robot ready" in robot.stdout.readline()
        summary = tmp_path / "summary.json"
        done = subprocess.run([sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--driver", "ros2",
                               "--loopback", "--goal", "3.5,-2.5", "--summary-json", str(summary)],
                              cwd=ROOT, env=env, capture_output=True, text=True, timeout=140)
    finally:
        robot.terminate()
        robot.wait(10)
    assert done.returncode == 0, done.stdout + done.stderr[-3000:]
    data = json.loads(summary.read_text())
    assert data["goals"][0]["outcome"] == "SUCCEEDED", data["goals"]
    assert done.stdout.startswith("result: OK")
