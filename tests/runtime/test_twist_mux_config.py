"""twist_mux configuration: twist_mux's own YAML file (docs example, errors naming file and
field), the tree's and navigation's entries, inline inputs and locks, and the run CLI flag."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from bt_runtime.cli.run import UsageError, load_config
from bt_runtime.runtime.config import GateConfig
from bt_runtime.runtime.config_file import ConfigError, load_runtime_config
from bt_runtime.runtime.twist_mux_config import TwistMuxFileError, load_twist_mux_file
from tests.paths import ROOT

EXAMPLE = ROOT / "docs" / "twist_mux.example.yaml"


def test_the_docs_example_file_configures_the_gate():
    gate = GateConfig().with_twist_mux(EXAMPLE)
    assert gate.priorities == {"tree": 20, "nav": 10}
    assert gate.nav_stale_timeout == 0.25 and gate.tree_stale_timeout == 0.2
    assert {n: (i.topic, i.priority, i.timeout) for n, i in gate.inputs.items()} == {
        "joystick": ("joy_vel", 100, 0.5), "keyboard": ("key_vel", 90, 0.5)}
    assert {n: (lk.topic, lk.priority) for n, lk in gate.locks.items()} == {
        "e_stop": ("e_stop", 255), "pause": ("pause_navigation", 15)}


def test_defaults_keep_tree_over_navigation_and_add_teleop_below_the_e_stop_lock():
    gate = GateConfig()
    assert gate.priorities == {"tree": 20, "nav": 10}
    teleop, e_stop = gate.inputs["teleop"], gate.locks["e_stop"]
    assert teleop.topic == "cmd_vel_teleop" and 20 < teleop.priority < e_stop.priority
    assert e_stop.timeout == 0.0  # unlocked until someone publishes true


@pytest.mark.parametrize(("text", "expected"), [
    ("twist_mux:\n  ros__parameters:\n    topics:\n      joy: {topic: j, timeout: 0.5}\n",
     "'twist_mux.ros__parameters.topics.joy.priority': field required"),
    ("twist_mux:\n  ros__parameters:\n    topics:\n      joy: {topic: j, timeout: 0.5, priority: 256}\n",
     "'twist_mux.ros__parameters.topics.joy.priority': input should be less than or equal to 255 (got 256)"),
    ("twist_mux:\n  ros__parameters:\n    locks:\n      stop: {topic: s, timeout: -1, priority: 9}\n",
     "'twist_mux.ros__parameters.locks.stop.timeout': input should be greater than or equal to 0 (got -1)"),
    ("twist_mux:\n  ros__parameters:\n    topics:\n      joy: {topic: j, timeout: 0.5, priority: 9, rate: 3}\n",
     "'twist_mux.ros__parameters.topics.joy.rate': is not a twist_mux key"),
    ("twist_mux:\n  ros__parameters:\n    topics: [\n", "twist_mux.yaml:4: not valid YAML"),
    ("twist_mux:\n  parameters: {}\n", "'twist_mux' needs a 'ros__parameters:' mapping"),
    ("- 1\n", "expected 'twist_mux: ros__parameters: {topics, locks}', got list"),
])
def test_bad_twist_mux_files_name_the_file_and_the_field(tmp_path, text, expected):
    path = tmp_path / "twist_mux.yaml"
    path.write_text(text)
    with pytest.raises(TwistMuxFileError) as err:
        load_twist_mux_file(path)
    assert str(path) in str(err.value) and expected in str(err.value)


def test_inline_inputs_and_locks_and_their_checks():
    gate = GateConfig(inputs={"navigation": {"priority": 30, "timeout": 0.4},
                              "pad": {"topic": "pad_vel", "priority": 5, "timeout": 0.0}},
                      locks={"pause": {"topic": "pause", "priority": 40, "timeout": 1.0}})
    assert gate.priorities == {"tree": 20, "nav": 30} and gate.nav_stale_timeout == 0.4
    assert list(gate.inputs) == ["pad"]
    with pytest.raises(ValidationError, match="never stale"):
        GateConfig(inputs={"tree": {"priority": 30, "timeout": 0}})
    with pytest.raises(ValidationError, match="reserved"):
        GateConfig(inputs={"estop": {"topic": "x", "priority": 30, "timeout": 1}})
    with pytest.raises(ValidationError, match="needs a topic"):
        GateConfig(inputs={"pad": {"priority": 30, "timeout": 1}})
    with pytest.raises(ValidationError, match="greater than or equal to 1"):  # twist_mux never picks 0
        GateConfig(inputs={"pad": {"topic": "p", "priority": 0, "timeout": 1}})


def test_runtime_config_file_names_a_twist_mux_file_relative_to_itself(tmp_path):
    (tmp_path / "mux.yaml").write_text(EXAMPLE.read_text())
    (tmp_path / "runtime.yaml").write_text("gate:\n  twist_mux: mux.yaml\n")
    config = load_runtime_config(tmp_path / "runtime.yaml")
    assert set(config.gate.inputs) == {"joystick", "keyboard"}
    (tmp_path / "runtime.yaml").write_text("gate:\n  twist_mux: missing.yaml\n")
    with pytest.raises(ConfigError, match="runtime.yaml: 'gate': twist_mux file not found: .*missing.yaml"):
        load_runtime_config(tmp_path / "runtime.yaml")


def test_run_flag_replaces_the_configured_inputs(tmp_path):
    config = load_config(None, EXAMPLE)
    assert set(config.gate.inputs) == {"joystick", "keyboard"} and config.gate.twist_mux == EXAMPLE
    bad = tmp_path / "bad.yaml"
    bad.write_text("twist_mux:\n  ros__parameters:\n    topics:\n      idle: {topic: x, timeout: 1, priority: 3}\n")
    with pytest.raises(UsageError, match="--twist-mux .*bad.yaml: inputs.idle: the name is reserved"):
        load_config(None, bad)


def test_the_nodes_other_parameters_are_ignored_and_use_stamped_is_honoured(tmp_path):
    path = tmp_path / "twist_mux.yaml"
    path.write_text("twist_mux:\n  ros__parameters:\n    use_sim_time: true\n    use_stamped: true\n"
                    "    topics:\n      joy: {topic: joy_vel, timeout: 0.5, priority: 100}\n")
    inputs, locks = load_twist_mux_file(path)
    assert inputs["joy"].stamped and locks == {}
