"""The configuration a user edits: defaults printed as YAML, the example file, plain errors,
and gate priorities taken from the file."""

from __future__ import annotations

import asyncio

import pytest
import yaml

from bt_runtime.__main__ import main
from bt_runtime.runtime.config import GateConfig, RuntimeConfig
from bt_runtime.runtime.config_file import ConfigError, defaults_yaml, load_runtime_config
from bt_runtime.runtime.messages import Twist
from tests.paths import ROOT


def test_printed_defaults_load_back_as_the_defaults(tmp_path, capsys):
    assert main(["config"]) == 0
    text = capsys.readouterr().out
    assert text == defaults_yaml() and "# tree heartbeat older than this: zero" in text
    path = tmp_path / "c.yaml"
    path.write_text(text)
    assert load_runtime_config(path) == RuntimeConfig()


def test_the_example_file_loads_and_changes_what_it_says():
    cfg = load_runtime_config(ROOT / "docs" / "config.example.yaml")
    example = yaml.safe_load((ROOT / "docs" / "config.example.yaml").read_text())
    assert cfg.gate.deadman_timeout == example["gate"]["deadman_timeout"] != GateConfig().deadman_timeout
    assert cfg.supervisor.components["battery"].timeout == example["supervisor"]["components"]["battery"]["timeout"]
    assert cfg.safety_zones.file == str(ROOT / "docs" / "collision_monitor.example.yaml")  # relative to the file


@pytest.mark.parametrize("text, message", [
    ("gate:\n  deadman_timeut: 0.2\n", "'gate.deadman_timeut' is not a setting (known here: deadman_timeout,"),
    ("gate:\n  deadman_timeout: -1\n", "'gate.deadman_timeout': input should be greater than 0 (got -1)"),
    ("tick: {rate_hz: fast}\n", "'tick.rate_hz': input should be a valid number"),
    ("gate: {priorities: {tree: 1}}\n", "'gate.priorities': needs exactly the sources 'tree' and 'nav'"),
    ("- 1\n", "expected sections such as 'tick:'"),
    ("gate: [\n", "c.yaml:2: not valid YAML"),
])
def test_errors_name_the_key_in_plain_words(tmp_path, capsys, text, message):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_runtime_config(path)
    assert message in str(info.value) and "https://" not in str(info.value)
    assert main(["config", "--check", str(path)]) == 2
    assert message in capsys.readouterr().err


async def test_gate_priorities_from_the_configuration(make_runtime):
    """nav above tree: a fresh navigation command wins over the tree's; the e-stop still wins."""
    cfg = RuntimeConfig(gate=GateConfig(priorities={"tree": 1, "nav": 5}))
    rt = make_runtime(config=cfg)
    await rt.start()
    gate, bus = rt.gate, rt.driver.sim.bus
    try:
        for _ in range(30):
            bus.publish("nav_cmd_vel", Twist(0.1, 0.0))
            gate.set_tree_command(-0.05, 0.2)
            await asyncio.sleep(0.01)
        assert gate.source == "nav"
        gate.emergency_stop("test")
        await asyncio.sleep(0.02)
        assert gate.source == "estop"
    finally:
        await rt.stop()
