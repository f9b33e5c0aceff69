"""The ``<TreeNodesModel>`` section of a tree file that uses Nav2-named nodes.

``python -m nodes.nav2.models trees/navigation.xml`` rewrites the file's section (or the
``<!-- TREE_NODES_MODEL -->`` placeholder) with an entry for every non-builtin node type the
file's trees use, in the form BT.CPP's ``writeTreeNodesModelXML`` writes (ports in declaration
order, type, default, description as text). Only the section changes; the rest of the file is
kept byte for byte. (A general tool for this lives in ``groot/models``; this one needs nothing
but the factory.)
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from lxml import etree

from bt_runtime.factory import BehaviorTreeFactory

from . import register_nav2_nodes

_SECTION = re.compile(r"<TreeNodesModel>.*?</TreeNodesModel>|<!-- TREE_NODES_MODEL -->", re.S)
_EXPLICIT = ("Action", "Condition", "Control", "Decorator")


def used_node_ids(xml_text: str) -> list[str]:
    """Node type IDs used in the document's ``<BehaviorTree>`` elements."""
    root = etree.fromstring(xml_text.encode("utf-8"))
    ids: list[str] = []
    for tree in root.iter("BehaviorTree"):
        for elem in tree.iter():
            if not isinstance(elem.tag, str) or elem is tree or elem.tag == "SubTree":
                continue
            rid = elem.get("ID") if elem.tag in _EXPLICIT else elem.tag
            if rid and rid not in ids:
                ids.append(rid)
    return ids


def models_section(factory: BehaviorTreeFactory, ids: list[str], indent: str = "  ") -> str:
    lines = [f"{indent}<TreeNodesModel>"]
    for rid in sorted(ids, key=lambda s: s.encode("utf-8")):
        manifest = factory.manifests[rid]
        if manifest.builtin:
            continue
        kind = manifest.node_type.xml_name
        if not manifest.ports:
            lines.append(f"{indent * 2}<{kind} ID={quoteattr(rid)}/>")
            continue
        lines.append(f"{indent * 2}<{kind} ID={quoteattr(rid)}>")
        for name, port in manifest.ports.items():
            tag = port.direction.xml_tag
            attrs = f"name={quoteattr(name)} type={quoteattr(port.type.name)}"
            if port.has_default:
                attrs += f" default={quoteattr(port.default_string())}"
            lines.append(f"{indent * 3}<{tag} {attrs}>{escape(port.description or '')}</{tag}>")
        lines.append(f"{indent * 2}</{kind}>")
    lines.append(f"{indent}</TreeNodesModel>")
    return "\n".join(lines).lstrip()


def nav2_factory() -> BehaviorTreeFactory:
    factory = BehaviorTreeFactory()
    register_nav2_nodes(factory)
    return factory


def refreshed(xml_text: str, factory: BehaviorTreeFactory | None = None) -> str:
    """The document with its TreeNodesModel section regenerated."""
    factory = factory or nav2_factory()
    section = models_section(factory, used_node_ids(xml_text))
    if not _SECTION.search(xml_text):
        raise ValueError("no <TreeNodesModel> section or <!-- TREE_NODES_MODEL --> placeholder")
    return _SECTION.sub(lambda _m: section, xml_text, count=1)


def main(argv: list[str]) -> int:
    for name in argv:
        path = Path(name)
        text = path.read_text(encoding="utf-8")
        new = refreshed(text)
        if new != text:
            path.write_text(new, encoding="utf-8")
            print(f"{path}: TreeNodesModel updated")
        else:
            print(f"{path}: up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
