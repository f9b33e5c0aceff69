"""The shipped Foxglove layout (docs/foxglove/bt_runtime_layout.json) is one Foxglove can open and
that shows our recording: its structure is Foxglove's exported-layout format, each panel is a
known panel type with only that panel's config keys, every topic it names is one a recording of
a simulated run writes, every message path parses and walks fields of that topic's ROS 2 type,
and the health strip's components are the supervisor's.

The panel types and config keys are Foxglove's (the open-source Studio, now Lichtblick:
``panels/index.ts`` for the type ids, each panel's config type; the foxglove-sdk's generated
``foxglove.layouts`` for the 3D topic settings)."""

from __future__ import annotations

import asyncio
import json
import re

import pytest

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.clock import run as run_loop  # noqa: E402
from bt_runtime.runtime.recording.cli import Recording  # noqa: E402
from bt_runtime.runtime.recording.types import typestore  # noqa: E402
from sim.driver import SimDriver  # noqa: E402
from sim.recording import recording_hooks  # noqa: E402
from tests.paths import ROOT  # noqa: E402

LAYOUT = ROOT / "docs" / "foxglove" / "bt_runtime_layout.json"
TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main"><Sleep msec="100000"/></BehaviorTree></root>"""
TITLE = "foxglovePanelTitle"  # a panel's own title, in any panel's config
PANEL_KEYS = {
    "3D": {"cameraState", "followTf", "followMode", "scene", "publish", "transforms", "topics", "layers", "imageMode"},
    "Plot": {"paths", "minXValue", "maxXValue", "minYValue", "maxYValue", "showLegend", "legendDisplay",
             "showPlotValuesInLegend", "showXAxisLabels", "showYAxisLabels", "isSynced", "xAxisVal", "xAxisPath",
             "followingViewWidth", "sidebarDimension"},
    "StateTransitions": {"isSynced", "paths", "xAxisMaxValue", "xAxisMinValue", "xAxisRange", "showPoints"},
    "RosOut": {"searchTerms", "minLogLevel", "topicToRender", "nameFilter"},
    "RawMessages": {"diffEnabled", "diffMethod", "diffTopicPath", "expansion", "showFullMessageForDiff",
                    "topicPath", "fontSize"},
    "DiagnosticSummary": {"minLevel", "pinnedIds", "topicToRender", "hardwareIdFilter", "sortByLevel",
                          "secondsUntilStale"},
}
PATH_KEYS = {"Plot": {"value", "enabled", "color", "label", "timestampMethod", "showLine", "lineSize"},
             "StateTransitions": {"value", "enabled", "color", "label", "timestampMethod"}}
# 3D topic settings by the topic's type (the types the 3D panel draws; it does not draw Odometry)
BASE = {"visible", "frameLocked"}
POINTS = BASE | {"pointSize", "pointShape", "decayTime", "colorMode", "flatColor", "colorField", "gradient",
                 "colorMap", "explicitAlpha", "minValue", "maxValue", "cubeSize", "cubeOutline"}
THREE_D_TOPIC_KEYS = {
    "nav_msgs/msg/OccupancyGrid": BASE | {"minColor", "maxColor", "unknownColor", "invalidColor", "colorMode", "alpha"},
    "sensor_msgs/msg/LaserScan": POINTS,
    "nav_msgs/msg/Path": BASE | {"type", "axisScale", "arrowScale", "lineWidth", "gradient"},
    "geometry_msgs/msg/PoseStamped": BASE | {"type", "axisScale", "arrowScale", "color", "showCovariance",
                                             "covarianceColor"},
}
THREE_D_ENUMS = {("nav_msgs/msg/OccupancyGrid", "colorMode"): {"custom", "costmap", "map", "raw"},
                 ("nav_msgs/msg/Path", "type"): {"axis", "arrow", "line"},
                 ("geometry_msgs/msg/PoseStamped", "type"): {"axis", "arrow"},
                 ("sensor_msgs/msg/LaserScan", "colorMode"): {"flat", "gradient", "colormap", "rgb", "rgba", "bgr",
                                                              "bgra", "rgba-fields"}}
NUMERIC = {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
           "float32", "float64"}


@pytest.fixture(scope="module")
def layout() -> dict:
    return json.loads(LAYOUT.read_text())


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[dict[str, str], set[str]]:
    """What a recording of a simulated run may write (topic -> type: what the live view
    advertises) and the component names its /diagnostics carries."""
    bag = tmp_path_factory.mktemp("layout") / "bag"

    async def main() -> dict[str, str]:
        driver = SimDriver("apartment", "burger", seed=1)
        runtime = AutonomyRuntime(driver)
        runtime.load_tree(TREE)
        rec = Recording(bag=bag).start(runtime, recording_hooks(driver))
        topics = rec.recorder.topics()
        await runtime.start()
        await asyncio.sleep(1.5)
        await runtime.stop()
        rec.stop()
        return topics

    topics = run_loop(main(), virtual=True)
    names = set()
    with AnyReader([bag]) as reader:
        for connection, _t, raw in reader.messages([c for c in reader.connections if c.topic == "/diagnostics"]):
            names |= {s.name for s in reader.deserialize(raw, connection.msgtype).status}
    return topics, names


def _leaves(node, where: str = "layout") -> list[str]:
    if isinstance(node, str):
        return [node]
    assert isinstance(node, dict), f"{where}: a panel id or a split"
    assert set(node) <= {"direction", "first", "second", "splitPercentage"}, f"{where}: {sorted(node)}"
    assert node.get("direction") in ("row", "column"), f"{where}.direction"
    split = node.get("splitPercentage", 50)
    assert isinstance(split, int | float) and 0 < split < 100, f"{where}.splitPercentage"
    return _leaves(node["first"], where + ".first") + _leaves(node["second"], where + ".second")


TOKEN = re.compile(r"""\.(?P<field>[A-Za-z_]\w*)|\[(?P<slice>-?\d*(?::-?\d*)?)\]"""
                   r"""|\{(?P<key>[A-Za-z_]\w*)==(?P<literal>"[^"]*"|'[^']*'|-?\d+(?:\.\d+)?|true|false)\}""")


def walk_path(path: str, types: dict[str, str]) -> tuple[str, str, list[str]]:
    """Parse a Foxglove message path (topic, then ``.field``, ``[i]``/``[a:b]``, ``{field==literal}``)
    against our schemas: returns (topic, leaf type, filter literals); asserts on any mismatch."""
    store = typestore()
    topic = re.match(r"/[\w/]*", path).group(0).rstrip("/")
    assert topic in types, f"{path}: topic {topic} is not recorded"
    node: tuple = ("msg", types[topic])  # ("msg", typename) | ("seq", element) | ("base", name)
    literals, rest = [], path[len(topic):]
    while rest:
        m = TOKEN.match(rest)
        assert m, f"{path}: cannot parse {rest!r}"
        rest = rest[m.end():]
        if m.group("slice") is not None:
            assert node[0] == "seq", f"{path}: [{m.group('slice')}] on a non-array"
            node = node[1]
            continue
        name = m.group("field") or m.group("key")
        assert node[0] == "msg", f"{path}: .{name} on {node}"
        fields = dict(store.fielddefs[node[1]][1])
        assert name in fields, f"{path}: {node[1]} has no field {name} (fields: {sorted(fields)})"
        found = _node(fields[name])
        if m.group("key"):
            assert found[0] == "base", f"{path}: filter on the non-primitive {name}"
            literal = m.group("literal")
            is_text = literal[0] in "'\""
            assert is_text == (found[1] in ("string", "wstring")), f"{path}: {name} is {found[1]}, not {literal}"
            literals.append(literal[1:-1] if is_text else literal)
        else:
            node = found
    return topic, node[1] if node[0] != "seq" else "sequence", literals


def _node(desc) -> tuple:
    from rosbags.interfaces import Nodetype

    kind, detail = desc
    if kind == Nodetype.BASE:
        return ("base", detail[0])
    if kind == Nodetype.NAME:
        return ("msg", detail)
    return ("seq", _node(detail[0]))


def test_layout_is_foxgloves_exported_layout_format(layout):
    assert set(layout) == {"configById", "layout", "globalVariables", "userNodes", "playbackConfig"}
    assert isinstance(layout["globalVariables"], dict) and isinstance(layout["userNodes"], dict)
    assert layout["playbackConfig"]["speed"] > 0
    leaves = _leaves(layout["layout"])
    assert len(leaves) == len(set(leaves)), "a panel placed twice"
    assert set(leaves) == set(layout["configById"]), "every placed panel has a config and every config is placed"
    for panel_id, config in layout["configById"].items():
        kind, _, instance = panel_id.partition("!")
        assert instance and kind in PANEL_KEYS, f"{panel_id}: not a Foxglove panel id (TYPE!id)"
        unknown = set(config) - PANEL_KEYS[kind] - {TITLE}
        assert not unknown, f"{panel_id}: keys Foxglove's {kind} panel does not read: {sorted(unknown)}"
        for k, path in enumerate(config.get("paths", [])):
            assert set(path) <= PATH_KEYS[kind] and "value" in path, f"{panel_id}.paths[{k}]: {sorted(path)}"
            assert path.get("timestampMethod", "receiveTime") in ("receiveTime", "headerStamp")
    kinds = {p.split("!")[0] for p in layout["configById"]}
    assert {"3D", "Plot", "StateTransitions", "RosOut", "RawMessages", "DiagnosticSummary"} <= kinds


def test_layout_names_recorded_topics_and_valid_message_paths(layout, recording):
    types, components = recording
    shown = set()
    for panel_id, config in layout["configById"].items():
        kind = panel_id.split("!")[0]
        for key in ("topicToRender",):
            if key in config:
                assert config[key] in types, f"{panel_id}.{key}: {config[key]} is not recorded"
                shown.add(config[key])
        if kind == "RosOut":
            assert types[config["topicToRender"]] == "rcl_interfaces/msg/Log", panel_id
        if kind == "DiagnosticSummary":
            assert types[config["topicToRender"]] == "diagnostic_msgs/msg/DiagnosticArray", panel_id
        if kind == "RawMessages":
            shown.add(walk_path(config["topicPath"], types)[0])
        for k, path in enumerate(config.get("paths", [])):
            topic, leaf, literals = walk_path(path["value"], types)
            shown.add(topic)
            assert leaf in NUMERIC or (kind == "StateTransitions" and leaf == "string"), \
                f"{panel_id}.paths[{k}]: {path['value']} ends at {leaf}"
            if topic == "/diagnostics":  # the health strip's rows are the supervisor's components
                assert all(name in components for name in literals), (literals, sorted(components))
        if kind == "3D":
            for topic, settings in config["topics"].items():
                assert topic in types, f"{panel_id}: {topic} is not recorded"
                typename = types[topic]
                assert typename in THREE_D_TOPIC_KEYS, f"{panel_id}: the 3D panel does not draw {topic} ({typename})"
                assert set(settings) <= THREE_D_TOPIC_KEYS[typename], f"{panel_id}.topics.{topic}: {sorted(settings)}"
                for key, value in settings.items():
                    allowed = THREE_D_ENUMS.get((typename, key))
                    assert allowed is None or value in allowed, f"{panel_id}.topics.{topic}.{key}: {value}"
                shown.add(topic)
            assert config["followTf"] in ("map", "odom", "base_link")
            assert config["followMode"] in ("follow-pose", "follow-position", "follow-none")
    assert {"/map", "/scan", "/plan", "/cmd_vel", "/behavior_tree_log", "/diagnostics"} <= shown


def test_message_path_check_catches_mistakes(recording):
    """The walker refuses what Foxglove would show as an error or an empty series."""
    types, _ = recording
    assert walk_path("/cmd_vel.linear.x", types) == ("/cmd_vel", "float64", [])
    for bad in ("/cmd_vel.linear.q", "/cmd_vel/nowhere.linear.x", "/cmd_vel.linear[0]",
                '/diagnostics.status[:]{level=="ok"}.message', "/diagnostics.status[:].{name}"):
        with pytest.raises(AssertionError):
            walk_path(bad, types)
