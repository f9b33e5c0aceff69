"""Scenario files: validation errors name the file and the field; the shipped ones load."""

from __future__ import annotations

import pytest

from sim.scenarios.spec import ScenarioError, load_scenario, scenario_names


def test_the_fourteen_paper_scenarios_ship():
    names = scenario_names()
    assert len(names) == 14
    tables = {load_scenario(n).table for n in names}
    assert tables == {"II", "III"}
    runs = sum(load_scenario(n).paper.runs for n in names)
    assert runs == 135  # Table IV: 5 x 9 + 20 x 4 + 10


def test_bad_file_names_the_field(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: X\ntable: II\nrequirements: []\ndescription: d\nstart: {x: 0, y: 0}\n"
                   "success: [{kind: reach_goal, goal: 3}]\npaper: {runs: 1, without: 0, with: 100}\n")
    with pytest.raises(ScenarioError, match="bad.yaml"):
        load_scenario(bad)
    bad.write_text("name: X\ntable: II\nrequirements: []\ndescription: d\nstart: {x: 0, y: zero}\n"
                   "success: []\npaper: {runs: 1, without: 0, with: 100}\n")
    with pytest.raises(ScenarioError, match=r"start\.y"):
        load_scenario(bad)


def test_faults_are_validated_on_load(tmp_path):
    bad = tmp_path / "f.yaml"
    bad.write_text("name: X\ntable: II\nrequirements: []\ndescription: d\nstart: {x: 0, y: 0}\n"
                   "faults: [{at: 1, fault: {kind: crash}}]\n"
                   "success: []\npaper: {runs: 1, without: 0, with: 100}\n")
    with pytest.raises(ScenarioError, match="faults.0"):
        load_scenario(bad)


def test_unknown_scenario_lists_the_shipped_ones():
    with pytest.raises(ScenarioError, match="Lidar_1"):
        load_scenario("Nope_9")
