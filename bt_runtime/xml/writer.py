"""Trees and node models back to BehaviorTree.CPP XML (spec 11).

Three writers, all printed the way tinyxml2 prints (4-space indent, ``<X a="b"/>`` for empty
elements, text-only elements inline, no XML declaration, ``</root>`` plus a newline at the end):

* ``write_tree_nodes_model_xml(manifests)``: BT.CPP's ``writeTreeNodesModelXML`` - a
  ``<TreeNodesModel>`` with one entry per registered node type, sorted by ID.
* ``write_tree_to_xml(tree)``: BT.CPP's ``WriteTreeToXML(tree, add_metadata, add_builtin_models)``,
  the "FULLTREE" form Groot2 receives on the wire and finds in a ``.btlog``: one
  ``<BehaviorTree ID=.. _fullpath=..>`` per expanded subtree instance, ``_uid`` on every node,
  defaulted ports written out, SubTree elements without ``name`` or children.
* ``write_tree(tree)``: an editable document that loads back into the same tree (same
  structure, names, ports, conditions, subtree ids and remappings): one ``<BehaviorTree>`` per
  tree ID, ``main_tree_to_execute``, no metadata, ports equal to their declared default left out.

Port order inside a model or a node follows declaration order (BT.CPP's follows a hash map,
so no order is canonical there).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..status import NodeType

if TYPE_CHECKING:
    from ..node import TreeNode, TreeNodeManifest
    from ..tree import Tree

PRE_CONDITIONS = ("_failureIf", "_successIf", "_skipIf", "_while")
POST_CONDITIONS = ("_onHalted", "_onFailure", "_onSuccess", "_post")


# ---------------------------------------------------------------------------------------------
# A tiny element tree and a tinyxml2-compatible printer
# ---------------------------------------------------------------------------------------------

@dataclass
class Element:
    tag: str
    attrs: list[tuple[str, str]] = field(default_factory=list)
    children: list[Element] = field(default_factory=list)
    text: str = ""

    def set(self, key: str, value: object) -> None:
        for i, (k, _) in enumerate(self.attrs):
            if k == key:
                self.attrs[i] = (key, str(value))
                return
        self.attrs.append((key, str(value)))

    def append(self, child: Element) -> Element:
        self.children.append(child)
        return child


_ATTR_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&apos;"})
_TEXT_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;"})


def escape_attribute(value: str) -> str:
    """tinyxml2's attribute escaping: ``& < > " '`` become entities, nothing else changes."""
    return value.translate(_ATTR_ESCAPES)


def escape_text(value: str) -> str:
    return value.translate(_TEXT_ESCAPES)


def render(root: Element) -> str:
    """Print like tinyxml2's XMLPrinter (non-compact mode)."""
    out: list[str] = []
    _render(root, 0, out)
    return "".join(out)


def _render(elem: Element, depth: int, out: list[str]) -> None:
    indent = "    " * depth
    attrs = "".join(f' {k}="{escape_attribute(v)}"' for k, v in elem.attrs)
    if elem.children:
        out.append(f"{indent}<{elem.tag}{attrs}>\n")
        for child in elem.children:
            _render(child, depth + 1, out)
        out.append(f"{indent}</{elem.tag}>\n")
    elif elem.text:
        out.append(f"{indent}<{elem.tag}{attrs}>{escape_text(elem.text)}</{elem.tag}>\n")
    else:
        out.append(f"{indent}<{elem.tag}{attrs}/>\n")


# ---------------------------------------------------------------------------------------------
# Node models (spec 11.1)
# ---------------------------------------------------------------------------------------------

def model_element(manifest: TreeNodeManifest) -> Element:
    """One ``<Action|Condition|Control|Decorator|SubTree ID="..">`` entry with its ports."""
    elem = Element(manifest.node_type.xml_name, [("ID", manifest.registration_id)])
    for name, port in manifest.ports.items():
        port_elem = Element(port.direction.xml_tag, [("name", name), ("type", port.type.name)])
        if port.has_default:
            port_elem.set("default", port.default_string())
        port_elem.text = port.description or ""
        elem.append(port_elem)
    if manifest.metadata:
        fields = elem.append(Element("MetadataFields"))
        for key, value in manifest.metadata:
            fields.append(Element("Metadata", [(str(key), str(value))]))
    return elem


def models_element(manifests: Iterable[TreeNodeManifest]) -> Element:
    """``<TreeNodesModel>`` with the given manifests sorted by registration ID (byte order)."""
    root = Element("TreeNodesModel")
    for manifest in sorted(manifests, key=lambda m: m.registration_id.encode("utf-8")):
        root.append(model_element(manifest))
    return root


def select_manifests(manifests: Mapping[str, TreeNodeManifest], include_builtin: bool = False,
                     only: Iterable[str] | None = None) -> list[TreeNodeManifest]:
    """Manifests to write: builtins only when asked, optionally restricted to some IDs."""
    wanted = None if only is None else set(only)
    return [m for rid, m in manifests.items()
            if (include_builtin or not m.builtin) and (wanted is None or rid in wanted)]


def write_tree_nodes_model_xml(manifests: Mapping[str, TreeNodeManifest], include_builtin: bool = False,
                               only: Iterable[str] | None = None) -> str:
    """BT.CPP ``writeTreeNodesModelXML``: ``<root BTCPP_format="4"><TreeNodesModel>..``.

    ``manifests`` is a factory's (or a tree's) ``manifests`` dict.
    """
    root = Element("root", [("BTCPP_format", "4")])
    root.append(models_element(select_manifests(manifests, include_builtin, only)))
    return render(root)


# ---------------------------------------------------------------------------------------------
# Trees
# ---------------------------------------------------------------------------------------------

def is_subtree_node(node: TreeNode) -> bool:
    return node.node_type is NodeType.SUBTREE and hasattr(node, "subtree_id")


def _condition_attrs(node: TreeNode) -> list[tuple[str, str]]:
    cfg = node.config
    out = []
    for names, scripts in ((PRE_CONDITIONS, cfg.pre_conditions), (POST_CONDITIONS, cfg.post_conditions)):
        if not scripts:
            continue
        for attr in names:
            script = scripts.get(attr)
            if script is not None:
                out.append((attr, getattr(script, "text", str(script))))
    return out


def _port_attrs(node: TreeNode) -> list[tuple[str, str]]:
    """Every input port, then output ports not already written (INOUT ports once)."""
    cfg = node.config
    attrs = [(k, str(v)) for k, v in cfg.input_ports.items()]
    attrs += [(k, str(v)) for k, v in cfg.output_ports.items() if k not in cfg.input_ports]
    return attrs


def _fulltree_node(node: TreeNode) -> Element:
    if is_subtree_node(node):
        elem = Element("SubTree", [("ID", node.subtree_id), ("_fullpath", node.full_path),
                                   ("_uid", str(node.uid))])
    else:
        elem = Element(node.registration_name, [("name", node.name), ("_uid", str(node.uid))])
    elem.attrs += _port_attrs(node)
    elem.attrs += _condition_attrs(node)
    if not is_subtree_node(node):
        for child in node.children_nodes():
            elem.append(_fulltree_node(child))
    return elem


def _plain_fulltree_node(node: TreeNode) -> Element:
    """``add_metadata=False``: no _uid/_fullpath."""
    if is_subtree_node(node):
        elem = Element("SubTree", [("ID", node.subtree_id)])
    else:
        elem = Element(node.registration_name, [("name", node.name)])
    elem.attrs += _port_attrs(node)
    elem.attrs += _condition_attrs(node)
    if not is_subtree_node(node):
        for child in node.children_nodes():
            elem.append(_plain_fulltree_node(child))
    return elem


def write_tree_to_xml(tree: Tree, add_metadata: bool = True, add_builtin_models: bool = True) -> str:
    """BT.CPP ``WriteTreeToXML``: the FULLTREE reply of Groot2 and the XML inside a .btlog."""
    root = Element("root", [("BTCPP_format", "4")])
    for record in tree.subtrees:
        block = root.append(Element("BehaviorTree", [("ID", record.tree_id),
                                                     ("_fullpath", record.instance_name)]))
        if record.nodes:
            top = record.nodes[0]
            block.append(_fulltree_node(top) if add_metadata else _plain_fulltree_node(top))
    root.append(models_element(select_manifests(tree.manifests, add_builtin_models)))
    return render(root)


# -- the editable form ---------------------------------------------------------------------------

def _explicit_subtree_name(node: TreeNode) -> str | None:
    """The ``name`` attribute the SubTree element had, or None when it had none."""
    sub_id = node.subtree_id
    if node.name != sub_id:
        return node.name
    # name == ID: either name="ID" was written (path ends with the name) or no name at all
    # (the builder then appended ID::uid to the path).
    return None if node.full_path.endswith(f"{sub_id}::{node.uid}") else node.name


def _edit_node(node: TreeNode, include_defaults: bool, used: set[str]) -> Element:
    cfg = node.config
    if is_subtree_node(node):
        elem = Element("SubTree", [("ID", node.subtree_id)])
        name = _explicit_subtree_name(node)
        if name is not None:
            elem.set("name", name)
        elem.attrs += [(k, str(v)) for k, v in cfg.input_ports.items()]
        for key, value in cfg.other_attributes.items():
            if key == "_autoremap" and value in ("false", "0", "False", "FALSE"):
                continue
            elem.set(key, value)
        elem.attrs += _condition_attrs(node)
        return elem
    rid = node.registration_name
    used.add(rid)
    elem = Element(rid)
    if node.name != rid:
        elem.set("name", node.name)
    manifest = cfg.manifest
    ports = manifest.ports if manifest is not None else {}
    for key, value in _port_attrs(node):
        port = ports.get(key)
        if (not include_defaults and port is not None and port.has_default
                and str(value) == port.default_string()):
            continue
        elem.set(key, value)
    for key, value in cfg.other_attributes.items():
        elem.set(key, value)
    elem.attrs += _condition_attrs(node)
    for child in node.children_nodes():
        elem.append(_edit_node(child, include_defaults, used))
    return elem


def write_tree(tree: Tree, *, include_defaults: bool = False, models: bool = True) -> str:
    """An editable BT.CPP document of ``tree`` that loads back into the same tree.

    One ``<BehaviorTree>`` per tree ID (the first instance of each; every instance of a
    subtree has the same definition), main tree first and named by ``main_tree_to_execute``.
    Ports whose value equals their declared default are left out unless ``include_defaults``.
    With ``models``, a ``<TreeNodesModel>`` of the non-builtin node types the tree uses.
    """
    main_id = tree.subtrees[0].tree_id if tree.subtrees else ""
    root = Element("root", [("BTCPP_format", "4"), ("main_tree_to_execute", main_id)])
    seen: set[str] = set()
    used: set[str] = set()
    for record in tree.subtrees:
        if record.tree_id in seen or not record.nodes:
            continue
        seen.add(record.tree_id)
        block = root.append(Element("BehaviorTree", [("ID", record.tree_id)]))
        block.append(_edit_node(record.nodes[0], include_defaults, used))
    if models:
        chosen = select_manifests(tree.manifests, include_builtin=False, only=used)
        if chosen:
            root.append(models_element(chosen))
    return render(root)
