"""``scenarios --file``: a user's own scenario files run with the same validation and output."""

from __future__ import annotations

import json

from bt_runtime.__main__ import main

MINE = """\
name: My_IMU_crash
world: apartment
robot: rosbot2
start: {x: -2.0, y: -2.0, yaw: 0.0}
faults:
  - {at: 1.0, fault: {kind: crash, component: imu}}
success:
  - {kind: component_reset, component: imu}
time_limit: 6
"""


def test_a_users_scenario_file_runs_with_the_table_and_json(tmp_path, capsys):
    (tmp_path / "mine.yaml").write_text(MINE)
    out = tmp_path / "out.json"
    code = main(["scenarios", "--file", str(tmp_path / "mine.yaml"), "--runs", "1", "--jobs", "1",
                 "--json", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "My_IMU_crash" in text and "Lidar_1" not in text  # only the user's scenario
    data = json.loads(out.read_text())
    runs = data["scenarios"]["My_IMU_crash"]
    assert runs["with"]["success_rate"] == 100 and runs["without"]["success_rate"] == 0
    assert data["scenarios"]["My_IMU_crash"]["paper"] is None


def test_a_folder_of_scenarios_and_a_bad_file_named_by_file_and_field(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "a.yaml").write_text(MINE)
    (folder / "b.yaml").write_text(MINE.replace("My_IMU_crash", "Other").replace("time_limit: 6", "time_limit: -1"))
    assert main(["scenarios", "--file", str(folder), "--runs", "1", "--mode", "with"]) == 2
    err = capsys.readouterr().err
    assert "b.yaml" in err and "time_limit" in err
    assert main(["scenarios", "--file", str(tmp_path / "nope.yaml")]) == 2
    assert "nope.yaml: no such file or folder" in capsys.readouterr().err
    (folder / "b.yaml").unlink()
    (folder / "c.yml").write_text(MINE.replace("My_IMU_crash", "Other"))
    assert main(["scenarios", "--file", str(folder), "--runs", "1", "--mode", "with", "--jobs", "1"]) == 0
    text = capsys.readouterr().out
    assert "My_IMU_crash" in text and "Other" in text
