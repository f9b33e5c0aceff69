"""Translate BehaviorTree.CPP v3 tree files (Nav2 Humble ships them) to v4 on load.

Only renamed nodes and renamed SubTree attributes need translating; everything else in a
Nav2 v3 tree reads the same in v4. Every translation is reported once per document as a
``BTFormatWarning`` so users know their file is being rewritten in memory.
"""

from __future__ import annotations

import warnings

from lxml import etree

RENAMED_NODES = {
    "SequenceStar": "SequenceWithMemory",
    "RetryUntilSuccesful": "RetryUntilSuccessful",
    "SubTreePlus": "SubTree",
}


class BTFormatWarning(UserWarning):
    """A tree file used an older format and was translated (or lacks BTCPP_format)."""


def is_v3(root: etree._Element) -> bool:
    fmt = root.get("BTCPP_format")
    return fmt is None or fmt.strip() == "3"


def translate_v3(root: etree._Element, file: str | None) -> list[str]:
    """Rewrite v3 names in place; return the list of changes made (for the warning)."""
    changes: list[str] = []
    for elem in root.iter():
        if not isinstance(elem.tag, str) or elem.tag == "TreeNodesModel":
            continue
        tag = elem.tag
        if tag in ("Action", "Condition", "Control", "Decorator") and elem.get("ID") in RENAMED_NODES:
            old = elem.get("ID")
            elem.set("ID", RENAMED_NODES[old])
            changes.append(f"{old} -> {RENAMED_NODES[old]}")
        elif tag in RENAMED_NODES:
            if tag == "SubTreePlus":
                auto = elem.attrib.pop("__autoremap", None)
                if auto is not None:
                    elem.set("_autoremap", auto)
            elem.tag = RENAMED_NODES[tag]
            changes.append(f"{tag} -> {RENAMED_NODES[tag]}")
        if elem.tag == "SubTree" and "__shared_blackboard" in elem.attrib:
            shared = elem.attrib.pop("__shared_blackboard")
            elem.set("_autoremap", shared)
            changes.append("SubTree __shared_blackboard -> _autoremap")
    if changes:
        unique = sorted(set(changes))
        warnings.warn(f"{file or '<text>'}: BehaviorTree.CPP v3 file translated to v4: " + ", ".join(unique),
                      BTFormatWarning, stacklevel=4)
    return changes
