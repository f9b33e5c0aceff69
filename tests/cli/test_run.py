"""``python -m bt_runtime run``: the verdict, the reasons, the exit code a script can trust, the
start-up wait, ``--tree`` and ``--png`` (in-process, on the simulator, virtual time)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from bt_runtime.__main__ import main
from sim.render_layout import Layout
from sim.world import load_world
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")


def _run(tmp_path, *argv):
    out = tmp_path / "summary.json"
    code = main(["run", *argv, "--no-progress", "--summary-json", str(out)])
    return code, json.loads(out.read_text())


def test_a_reached_goal_exits_0_and_no_component_restarts_at_start(tmp_path, capsys):
    log = tmp_path / "run.jsonl"
    code, data = _run(tmp_path, AUTONOMY, "--goal", "3.5,-2.5", "--log-file", str(log))
    printed = capsys.readouterr().out
    assert code == 0 and data["exit_code"] == 0 and data["result"] == "OK"
    assert data["goals"][0]["outcome"] == "SUCCEEDED" and data["goal_outcomes"] == ["SUCCEEDED"]
    assert printed.splitlines()[0] == "result: OK"
    assert "goal 0 (3.50, -2.50, yaw 0.00 rad): SUCCEEDED" in printed
    events = [json.loads(line) for line in log.read_text().splitlines()]
    restarts = [e for e in events if e["event"] == "component_state" and e["state"] == "restarting"]
    assert restarts == []  # the goal waited for localization and the planner to report
    started = next(e for e in events if e["event"] == "component_state" and e["component"] == "tree")
    battery = next(e for e in events if e["event"] == "component_state" and e["component"] == "battery")
    assert started["sim_time"] >= battery["sim_time"]  # the tree got its goal once everything reported


def test_a_goal_outside_the_map_exits_1_and_says_why(tmp_path, capsys):
    code, data = _run(tmp_path, AUTONOMY, "--goal", "100,100", "--duration", "30")
    printed = capsys.readouterr().out
    assert code == 1 and data["result"] == "FAILED"
    goal = data["goals"][0]
    assert goal["outcome"] == "REFUSED"  # refused outright by the tree, without navigating
    assert goal["reason"].startswith("refused: GOAL_OUTSIDE_MAP (204)")
    assert goal["navigation_error"]["code"] == 204 and goal["navigation_error"]["code_name"] == "GOAL_OUTSIDE_MAP"
    assert "GOAL_OUTSIDE_MAP (204)" in goal["reason"]
    # the tree said why; a routine guard that failed on the way is not offered as the cause
    assert goal["failing_node"] is None and "last failing node" not in goal["reason"]
    assert printed.startswith("result: FAILED (goal 0 REFUSED)")


def test_a_run_that_ends_before_the_goal_says_so(tmp_path, capsys):
    code, data = _run(tmp_path, AUTONOMY, "--goal", "3.5,-2.5", "--goal", "0,-4", "--duration", "5")
    printed = capsys.readouterr().out
    assert code == 1
    assert [g["outcome"] for g in data["goals"]] == ["NOT_FINISHED", "NOT_STARTED"]
    assert "--duration 5 s ended" in data["goals"][0]["reason"]
    assert "goal 1 (0.00, -4.00, yaw 0.00 rad): NOT_STARTED" in printed


def test_a_tree_that_raises_on_every_tick_exits_1_with_the_node_and_a_traceback(tmp_path, capsys):
    tree = tmp_path / "raise.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="Main">'
                    '<Script name="broken" code="x := missing_key + 1"/></BehaviorTree></root>')
    code, data = _run(tmp_path, str(tree), "--duration", "2")
    captured = capsys.readouterr()
    assert code == 1 and data["tick_errors"] == data["ticks"] > 0
    assert any("every tick raised an error" in r for r in data["failure_reasons"])
    assert "missing_key" in data["last_error"]
    assert "Traceback (most recent call last)" in captured.err
    assert captured.err.count("Traceback (most recent call last)") <= 3  # once per distinct error (chained)


def test_no_goal_for_a_goal_taking_tree_prints_a_hint(tmp_path, capsys):
    code, data = _run(tmp_path, AUTONOMY, "--duration", "2")
    captured = capsys.readouterr()
    assert "the tree is waiting for a goal: pass --goal X,Y[,YAW]" in captured.err
    assert code == 0 and data["goals"] == []


def test_tree_picks_the_tree_to_run(tmp_path, capsys):
    tree = tmp_path / "two.xml"
    tree.write_text('<root BTCPP_format="4" main_tree_to_execute="Main">'
                    '<BehaviorTree ID="Main"><AlwaysFailure/></BehaviorTree>'
                    '<BehaviorTree ID="Other"><AlwaysSuccess/></BehaviorTree></root>')
    code, data = _run(tmp_path, str(tree))
    assert code == 1 and data["status"] == "FAILURE"
    code, data = _run(tmp_path, str(tree), "--tree", "Other")
    assert code == 0 and data["status"] == "SUCCESS"
    assert main(["run", str(tree), "--tree", "Nope", "--no-progress"]) == 2
    assert "Nope" in capsys.readouterr().err


def test_png_draws_the_run(tmp_path, capsys):
    png = tmp_path / "run.png"
    code, _ = _run(tmp_path, AUTONOMY, "--goal", "3.5,-2.5", "--png", str(png))
    assert code == 0 and f"picture: {png}" in capsys.readouterr().out
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    layout = Layout.of(load_world("apartment").bounds, 50.0)
    c, r = (int(round(v)) for v in layout.px(1.0, -2.47))  # the straight middle of the drive (pixel test)
    column = img[r - 12:r + 13, c]
    assert (np.abs(column - np.array((30, 90, 220))).sum(axis=-1) < 30).any()


def test_a_groot2_project_file_runs(tmp_path, capsys):
    """A Groot2 project (.btproj: <include>s plus the node models) validates and runs; with two
    trees and no main_tree_to_execute, run names them and asks for --tree."""
    for tree_id in ("MainTree", "Other"):
        (tmp_path / f"{tree_id}.xml").write_text(
            f'<root BTCPP_format="4"><BehaviorTree ID="{tree_id}"><Sequence><Script code="x := 1"/>'
            f'<AlwaysSuccess/></Sequence></BehaviorTree></root>')
    project = tmp_path / "project.btproj"
    project.write_text('<?xml version="1.0" encoding="UTF-8"?>\n<root BTCPP_format="4" project_name="P">\n'
                       '  <include path="MainTree.xml"/>\n  <include path="Other.xml"/>\n'
                       '  <TreeNodesModel><Action ID="Say"><input_port name="message"/></Action></TreeNodesModel>\n'
                       '</root>\n')
    assert main(["validate", str(project)]) == 0
    assert main(["run", str(project), "--no-progress"]) == 2
    assert "pick the tree to run with --tree ID (trees: MainTree, Other)" in capsys.readouterr().err
    code, data = _run(tmp_path, str(project), "--tree", "Other")
    assert code == 0 and data["status"] == "SUCCESS"


def test_waiting_hint_names_the_ros2_goal_action_and_topic():
    from types import SimpleNamespace

    pytest.importorskip("cyclonedds")  # the ros2 extra: the README's '.[dev]' install has none

    from bt_runtime.cli.run import _goal_serving_hint
    from bt_runtime.runtime.ros2.config import Ros2Config

    hint = _goal_serving_hint(SimpleNamespace(config=Ros2Config(namespace="/robot1")))
    assert "/robot1/autonomy/navigate_to_pose (NavigateToPose action)" in hint
    assert "/robot1/autonomy/goal_pose (PoseStamped" in hint
    off = Ros2Config.model_validate({"goals": {"topic": None}})
    assert "goal_pose" not in _goal_serving_hint(SimpleNamespace(config=off))
    assert _goal_serving_hint(SimpleNamespace()) == ""  # the simulator serves no goal topics


def test_goals_from_ros_clients_get_a_summary_line_each():
    from types import SimpleNamespace

    from bt_runtime.cli.run import client_goal_notes
    from bt_runtime.runtime.goal_intake import GoalResult

    def handle(i, source, result):
        return SimpleNamespace(id=i, source=source, pose=SimpleNamespace(x=-1.0, y=-2.0, yaw=0.0), result=result)

    cli = handle(1, "api", GoalResult("SUCCEEDED", "SUCCEEDED"))
    done = handle(2, "topic", GoalResult("SUCCEEDED", "SUCCEEDED"))
    failed = handle(3, "action", GoalResult("ABORTED", "ABORTED", 204, "goal outside the map"))
    running = handle(4, "action", None)
    intake = SimpleNamespace(finished=[cli, failed, done], current=running, queue=[])
    assert client_goal_notes(intake) == [
        "goal from topic (-1.00, -2.00, yaw 0.00 rad): SUCCEEDED",
        "goal from action (-1.00, -2.00, yaw 0.00 rad): ABORTED: goal outside the map",
        "goal from action (-1.00, -2.00, yaw 0.00 rad): not finished"]
    assert client_goal_notes(SimpleNamespace(finished=[cli], current=None, queue=[])) == []
