"""The shipped Foxglove layout refers only to topics a recording writes (default names)."""

from __future__ import annotations

import json
import re

from bt_runtime.runtime.recording.config import TopicNames
from tests.paths import ROOT

LAYOUT = ROOT / "docs" / "foxglove" / "bt_runtime_layout.json"
SIM_TOPICS = {"/sim/ground_truth", "/sim/faults", "/sim/events"}


def _panels(node) -> set[str]:
    if isinstance(node, str):
        return {node}
    return _panels(node["first"]) | _panels(node["second"])


def test_layout_topics_are_recorded_topics():
    layout = json.loads(LAYOUT.read_text())
    names = TopicNames()
    recorded = {v for k, v in names.model_dump().items() if k != "cmd_vel_source"} | SIM_TOPICS
    recorded |= {names.cmd_vel_source.format(source=s) for s in ("navigation", "tree", "teleop")}
    used = set()
    for config in layout["configById"].values():
        used |= set(config.get("topics", {}))
        used |= {p["value"] for p in config.get("paths", [])}
        for key in ("topicToRender", "topicPath"):
            if key in config:
                used.add(config[key])
    topics = {re.match(r"(/[\w/]+?)(?:\.|$)", u).group(1) for u in used}
    assert topics, "the layout shows topics"
    assert topics <= recorded, topics - recorded
    assert _panels(layout["layout"]) == set(layout["configById"]), "every panel is placed, none is missing"
    kinds = {p.split("!")[0] for p in layout["configById"]}
    assert {"3D", "Plot", "StateTransitions", "RosOut", "RawMessages", "DiagnosticSummary"} <= kinds
