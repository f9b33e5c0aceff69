"""The ROS 2 commands of docs/ros2.md, as a user types them: ``sim-robot --loopback`` in one
process, ``run trees/autonomy.xml --driver ros2 --loopback --goal 3.5,-2.5`` in another, on
real DDS and the wall clock. The goal is reached (the run waits for the robot's components,
battery included, before handing it over) and ``run`` exits 0. The two commands are read from
the documentation's block (tests/docs/test_code_blocks.py leaves that block to this test)."""

import json
import os
import subprocess

import pytest

pytest.importorskip("cyclonedds")

from tests.helpers import dds_domain, documented_ros2_commands  # noqa: E402
from tests.paths import ROOT  # noqa: E402


def test_sim_robot_then_run_reaches_the_goal(tmp_path):
    robot_cmd, run_cmd = documented_ros2_commands()
    env = dict(os.environ, PYTHONPATH=str(ROOT), ROS_DOMAIN_ID=str(dds_domain()))
    env.pop("CYCLONEDDS_URI", None)
    robot_log = (tmp_path / "sim_robot.err").open("w")  # a file, not a pipe nobody reads (it would fill up)
    robot = subprocess.Popen(robot_cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=robot_log, text=True)
    try:
        assert "sim-robot ready" in robot.stdout.readline(), (tmp_path / "sim_robot.err").read_text()[-3000:]
        summary = tmp_path / "summary.json"
        done = subprocess.run([*run_cmd, "--summary-json", str(summary)],
                              cwd=ROOT, env=env, capture_output=True, text=True, timeout=140)
    finally:
        robot.terminate()
        try:
            robot.wait(10)
        except subprocess.TimeoutExpired:
            robot.kill()
            robot.wait(10)
        robot.stdout.close()
        robot_log.close()
    (tmp_path / "run.err").write_text(done.stderr)  # all of it, for a failure's post-mortem (--basetemp)
    assert done.returncode == 0, done.stdout + done.stderr[-3000:]
    data = json.loads(summary.read_text())
    assert data["goals"][0]["outcome"] == "SUCCEEDED", data["goals"]
    assert done.stdout.startswith("result: OK")
