"""``run --collision-monitor FILE|off``: the zones a run uses, and bad files as usage errors."""

from __future__ import annotations

import json

from bt_runtime.__main__ import main
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")
EXAMPLE = str(ROOT / "docs" / "collision_monitor.example.yaml")


def test_a_bad_zones_file_is_a_usage_error_naming_file_and_field(tmp_path, capsys):
    bad = tmp_path / "cm.yaml"
    bad.write_text("collision_monitor:\n  ros__parameters:\n    polygons: [Stop]\n"
                   "    Stop: {type: circle, radius: 0.2, action_type: brake}\n    observation_sources: [scan]\n")
    assert main(["run", AUTONOMY, "--collision-monitor", str(bad), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "Stop.action_type" in err


def test_a_run_with_a_collision_monitor_file_reaches_its_goal_through_a_doorway(tmp_path, capsys):
    log = tmp_path / "run.jsonl"
    code = main(["run", AUTONOMY, "--robot", "rosbot2", "--goal", "3.5,-2.5", "--collision-monitor", EXAMPLE,
                 "--no-progress", "--log-file", str(log)])
    assert code == 0, capsys.readouterr()
    events = [json.loads(line) for line in log.read_text().splitlines()]
    zones = next(e for e in events if e["event"] == "safety_zones")
    assert zones["origin"] == EXAMPLE and "FootprintApproach:approach" in zones["zones"]


def test_off_runs_without_zones(tmp_path):
    log = tmp_path / "run.jsonl"
    main(["run", AUTONOMY, "--duration", "1", "--collision-monitor", "off", "--no-progress", "--log-file", str(log)])
    assert not any(json.loads(line)["event"] == "safety_zones" for line in log.read_text().splitlines())
