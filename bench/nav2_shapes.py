"""Nav2's stock trees (from ../shared, when present) reduced to shapes every engine can tick.

The trees keep their structure; Nav2's own leaves become the callbacks ``Ok`` (conditions)
and ``Act`` (actions), its controls become the BT.CPP built-in with the same flow
(PipelineSequence -> Sequence, RecoveryNode / RoundRobin -> Fallback) and its decorators a
pass-through callback decorator, since behaviortreepy cannot register Nav2's C++ nodes.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from lxml import etree

BUILTIN = {"Sequence", "Fallback", "ReactiveSequence", "ReactiveFallback", "Inverter", "ForceSuccess",
           "ForceFailure", "Repeat", "RetryUntilSuccessful", "KeepRunningUntilFailure", "SubTree",
           "SequenceWithMemory", "Parallel", "ParallelAll", "IfThenElse", "WhileDoElse", "Delay",
           "Timeout", "RunOnce", "AlwaysSuccess", "AlwaysFailure", "Script", "ScriptCondition"}
CONTROL_AS = {"PipelineSequence": "Sequence", "RecoveryNode": "Fallback", "RoundRobin": "Fallback",
              "NonblockingSequence": "Sequence", "PersistentSequence": "Sequence", "PauseResumeController": "Sequence"}


def _shared() -> Path | None:
    here = Path(__file__).resolve().parents[1]
    for base in (here.parent, Path("/work")):
        cand = base / "shared" / "reference" / "nav2" / "trees" / "jazzy"
        if cand.is_dir():
            return cand
    return None


def _kinds(models: Path) -> dict[str, str]:
    root = etree.parse(str(models), etree.XMLParser(resolve_entities=False, no_network=True)).getroot()
    return {e.get("ID"): e.tag for e in root.iter() if e.get("ID")}


def _reduce(element, kinds: dict[str, str]) -> None:
    for e in list(element.iter()):
        if not isinstance(e.tag, str):  # a comment or processing instruction
            continue
        tag = e.tag
        if tag in ("root", "BehaviorTree") or tag in BUILTIN and tag != "SubTree":
            continue
        if tag == "SubTree":
            for key in [k for k in e.attrib if k not in ("ID", "name")]:
                del e.attrib[key]
            continue
        kind = kinds.get(tag, "Action")
        keep_name = e.get("name")
        e.attrib.clear()
        if keep_name:
            e.set("name", keep_name)
        if kind == "Control":
            e.tag = CONTROL_AS.get(tag, "Sequence")
        elif kind == "Decorator":
            e.tag = "Pass"
        else:
            e.tag = "Ok" if kind == "Condition" else "Act"


def _reduced(path: Path, kinds: dict[str, str]) -> str:
    root = etree.parse(str(path), etree.XMLParser(resolve_entities=False, no_network=True)).getroot()
    for models in root.findall("TreeNodesModel"):
        root.remove(models)
    _reduce(root, kinds)
    root.set("BTCPP_format", "4")
    return etree.tostring(root, encoding="unicode")


def reduced_file(path: Path) -> str:
    """A tree file of our own (trees/autonomy.xml) reduced the same way, its node kinds taken
    from its own TreeNodesModel (a node it does not declare counts as an action)."""
    return _reduced(path, _kinds(path))


def stock_trees() -> Iterator[tuple[str, str]]:
    folder = _shared()
    if folder is None:
        return
    kinds = _kinds(folder / "nav2_tree_nodes.xml")
    for path in sorted(folder.glob("navigate*.xml")):
        yield path.stem.replace("navigate_", "nav2:").replace("_w_", "_"), _reduced(path, kinds)
