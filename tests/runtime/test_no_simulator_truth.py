"""The robot never gets the truth: nodes and the runtime see the robot only through the driver
interface, and that interface carries no true pose, contact point or model constant.

Two checks: a scan of the source (no ``sim`` import, no reach into a driver's ``.sim`` or the
physics), and a run of the autonomy tree on the simulator that records every stream the layer
subscribes to and every message it receives.
"""

from __future__ import annotations

import ast
import asyncio
import dataclasses

import pytest

from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.driver import RobotDriver
from bt_runtime.runtime.messages import Contact, RobotInfo
from bt_runtime.runtime.twist_mux import INPUT_STREAM, LOCK_STREAM
from sim.driver import ROBOT_STREAMS, SimDriver
from tests.paths import ROOT

# the CLI and the pytest plugin wire the simulator in at the edge (DESIGN.md section 2):
# everything else stays out
EDGES = ("cli", "testing")
LAYER = [p for d in ("nodes", "bt_runtime") for p in sorted((ROOT / d).rglob("*.py"))
         if not set(EDGES) & set(p.relative_to(ROOT).parts)]
TRUTH_ATTRIBUTES = {"sim", "physics", "ground_truth", "component_log", "true_ranges", "dynamic_obstacles"}
TRUTH_TOPICS = {"ground_truth", "sim_event"}


def _violations(path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [f"{where}:{node.lineno} imports {a.name}" for a in node.names
                    if a.name == "sim" or a.name.startswith("sim.")]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module \
                and (node.module == "sim" or node.module.startswith("sim.")):
            out.append(f"{where}:{node.lineno} imports from {node.module}")
        elif isinstance(node, ast.Attribute) and node.attr in TRUTH_ATTRIBUTES:
            out.append(f"{where}:{node.lineno} reads .{node.attr}")
        elif isinstance(node, ast.Constant) and node.value in TRUTH_TOPICS:
            out.append(f"{where}:{node.lineno} names the simulator topic {node.value!r}")
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) \
                in ("import_module", "__import__") and node.args and isinstance(node.args[0], ast.Constant) \
                and str(node.args[0].value).split(".")[0] == "sim":
            out.append(f"{where}:{node.lineno} imports {node.args[0].value} dynamically")
    return out


def test_the_layer_scan_finds_its_files():
    names = {p.relative_to(ROOT).as_posix() for p in LAYER}
    assert {"nodes/collision.py", "nodes/battery.py", "bt_runtime/runtime/supervisor.py"} <= names
    assert not any(n.startswith(("bt_runtime/cli/", "bt_runtime/testing/")) for n in names)


def test_no_node_or_runtime_module_reaches_into_the_simulator():
    found = [v for path in LAYER for v in _violations(path)]
    assert not found, "\n".join(found)


def test_the_scan_would_catch_a_leak(tmp_path):
    leak = tmp_path / "leaky_node.py"
    leak.write_text("from sim.simulator import Simulator\n"
                    "def f(ctx):\n    return ctx.driver.sim.pose, ctx.driver.subscribe('ground_truth', print)\n")
    assert len(_violations(leak)) == 3


def test_the_driver_interface_has_no_truth_channel():
    assert [f.name for f in dataclasses.fields(Contact)] == ["stamp", "in_contact", "segments", "direction"]
    members = {m for m in dir(RobotDriver) if not m.startswith("_")}
    assert not {m for m in members if any(w in m for w in ("truth", "true", "pose", "contact", "physics"))}
    driver = SimDriver("apartment", "rosbot2", seed=1)
    for topic in TRUTH_TOPICS:
        with pytest.raises(ValueError, match="not a robot stream"):
            driver.subscribe(topic, print)
    # robot information is the profile's nominal data, not this unit's true constants
    info, profile, truth = driver.robot_info(), driver.sim.profile, driver.sim.battery
    assert isinstance(info, RobotInfo)
    assert info.k_linear == profile.battery.k_linear != truth.k_linear
    assert info.idle_power_w == profile.battery.idle_power_w != truth.idle_power_w


class SpyDriver:
    """The SimDriver, recording what the layer subscribes to and what it is handed."""

    def __init__(self, inner: SimDriver):
        self._inner = inner
        self.streams: set[str] = set()
        self.types: set[str] = set()

    def __getattr__(self, name):
        if name == "sim":
            raise AttributeError("the layer reached for the simulator")
        return getattr(self._inner, name)

    def subscribe(self, stream, callback):
        self.streams.add(stream)

        def spy(msg):
            self.types.add(type(msg).__name__)
            callback(msg)
        return self._inner.subscribe(stream, spy)


async def test_the_running_layer_receives_only_robot_streams():
    inner = SimDriver("apartment", "burger", seed=3)
    driver = SpyDriver(inner)
    rt = AutonomyRuntime(driver, register=[__import__("nodes").register_all])
    rt.load_tree(ROOT / "trees" / "autonomy.xml")
    rt.tree.root_blackboard.set("goal_status", "IDLE")
    await rt.start()
    await asyncio.sleep(1.0)
    inner.sim.faults.push(0.8, 0.0)  # a collision, so the collision branch runs too
    await asyncio.sleep(4.0)
    await rt.stop()
    robot_prefixes = ("heartbeat/", INPUT_STREAM, LOCK_STREAM)  # the gate's teleop input and e-stop lock
    assert driver.streams and all(s in ROBOT_STREAMS or s.startswith(robot_prefixes) for s in driver.streams)
    assert {"bumper", "imu", "battery", "pose"} <= driver.streams
    assert not driver.types & {"GroundTruth", "SimEvent", "ComponentLogEntry"}
    assert "Contact" in driver.types
