"""Registering tree documents: root checks, includes, TreeNodesModel, per-tree validation.

This is BT.CPP's XMLParser minus instantiation (see ``builder.py``): documents are checked
when they are loaded (spec 2.2-2.4, 2.8, 2.11), so a bad file fails at load time with its
file, line and element, before anything is built.
"""

from __future__ import annotations

import difflib
import warnings
import weakref
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from ..errors import XMLLoadError
from ..ports import RESERVED_ATTRIBUTES, PortInfo, find_forbidden_char, port_type
from ..status import NodeType, PortDirection
from .depth import Shape
from .long_lived import long_lived
from .reader import ELEMENT, XMLDocument, element_children, parse_xml_text, read_xml_file
from .v3 import BTFormatWarning, is_v3, translate_v3

if TYPE_CHECKING:
    from ..factory import BehaviorTreeFactory

EXPLICIT_TAGS = ("Action", "Condition", "Control", "Decorator")
EXPLICIT_TAG_SET = frozenset(EXPLICIT_TAGS)  # for membership tests (a hash instead of 4 compares)
MAX_DEPTH = 256
_PORT_TAGS = {"input_port": PortDirection.INPUT, "output_port": PortDirection.OUTPUT,
              "inout_port": PortDirection.INOUT}


# What the builder needs of one element, read from lxml once when the document is checked (a
# SubTree used in many places is expanded as often; lxml calls cost 0.1-0.3 us each):
# (tag, type ID (a SubTree's ID), name attribute or None, attribute items, attributes as a dict
# or None when there are none (for a node other than a SubTree: none but reserved ones),
# pre/post-condition attributes in BT.CPP's order, children's plans, the element itself (for
# error messages, and what a node keeps to find its line if asked: NodeConfig.source)).
# Never mutated.
ElementPlan = tuple[str, str, "str | None", tuple, "dict[str, str] | None", tuple, tuple, etree._Element]

PRE_CONDITIONS = ("_failureIf", "_successIf", "_skipIf", "_while")  # in BT.CPP's order
POST_CONDITIONS = ("_onHalted", "_onFailure", "_onSuccess", "_post")
CONDITION_ATTRIBUTES = PRE_CONDITIONS + POST_CONDITIONS
_CONDITION_ATTRIBUTE_SET = frozenset(CONDITION_ATTRIBUTES)
_CONDITION_RANK = {name: i for i, name in enumerate(CONDITION_ATTRIBUTES)}


def _condition_rank(item: tuple[str, str]) -> int:
    return _CONDITION_RANK[item[0]]


@dataclass
class TreeDefinition:
    """A registered <BehaviorTree>: its single root element and where it came from."""

    tree_id: str
    element: etree._Element  # the <BehaviorTree> element
    document: XMLDocument
    plan: ElementPlan | None = None  # of the root element (see ElementPlan)

    @cached_property
    def root_element(self) -> etree._Element:
        """(kept: a subtree used in many places is expanded as often)"""
        return element_children(self.element)[0]


@dataclass
class NodeModel:
    """A <TreeNodesModel> entry: a node type known by its ports only (e.g. Nav2's nodes)."""

    registration_id: str
    node_type: NodeType
    ports: dict[str, PortInfo] = field(default_factory=dict)
    description: str = ""


@dataclass
class LoadResult:
    new_tree_ids: list[str]
    all_tree_ids: list[str]  # every <BehaviorTree> of the document, new or replaced
    main_tree: str | None
    document: XMLDocument


def suggest(name: str, candidates: list[str]) -> str:
    close = difflib.get_close_matches(name, candidates, n=3, cutoff=0.6)
    if not close:
        close = [c for c in candidates if c.lower().startswith(name[:3].lower())][:3] if name else []
    return f" (did you mean: {', '.join(close)}?)" if close else ""


def check_model_name(name: str, what: str, doc: XMLDocument, elem: etree._Element) -> None:
    if not name:
        raise XMLLoadError(f"{what} name must not be empty", file=doc.file, line=doc.line_of(elem),
                           element=elem.tag)
    if name in ("Root", "root"):
        raise XMLLoadError(f"{what} name '{name}' is reserved", file=doc.file, line=doc.line_of(elem),
                           element=elem.tag)
    bad = find_forbidden_char(name)
    if bad is not None:
        raise XMLLoadError(f"{what} name '{name}' contains the forbidden character {bad!r}",
                           file=doc.file, line=doc.line_of(elem), element=elem.tag)


class TreeRegistry:
    """The factory's registry of tree definitions and models, fed by documents."""

    def __init__(self, factory: BehaviorTreeFactory):
        # The factory's registry of node types (never replaced), not the factory: a registry
        # pointing back at its factory made every dropped factory (with its documents and
        # plans) garbage for the cyclic collector to find.
        self._manifests = factory.manifests
        self._factory = weakref.ref(factory)
        self.trees: dict[str, TreeDefinition] = {}
        self.subtree_models: dict[str, dict[str, PortInfo]] = {}
        self.node_models: dict[str, NodeModel] = {}
        self.first_main_tree: str | None = None
        self._documents_opened = 0
        self._anonymous = 0
        self.include_search_paths: list[Path] = []  # folders <include> may reach besides the top file's
        self._infos: dict[object, tuple] = {}  # see _check_node

    @property
    def factory(self) -> BehaviorTreeFactory | None:
        return self._factory()

    # -- entry points --------------------------------------------------------------------------
    def load_text(self, text: str | bytes, file: str | None = None) -> LoadResult:
        with long_lived():  # a document's elements and plans live as long as the registry
            doc = parse_xml_text(text, file=file)
            return self._load(doc, [], doc)

    def load_file(self, path: str | Path) -> LoadResult:
        with long_lived():
            doc = read_xml_file(path)
            return self._load(doc, [str(Path(path).resolve())], doc)

    def _include_roots(self, top: XMLDocument) -> tuple[Path, ...]:
        """Where includes of a document loaded by the user may lead: below its folder (the
        working directory for text) or below a registered search path. (Asked only when there
        is an include: resolving paths costs file-system calls.)"""
        return (top.directory.resolve(), *(p.resolve() for p in self.include_search_paths))

    def clear(self) -> None:
        self.trees.clear()
        self.subtree_models.clear()
        self.first_main_tree = None
        self._documents_opened = 0

    # -- loading -------------------------------------------------------------------------------
    def _err(self, doc: XMLDocument, elem: etree._Element | None, message: str) -> XMLLoadError:
        return XMLLoadError(message, file=doc.file, line=doc.line_of(elem) if elem is not None else None,
                            element=elem.tag if elem is not None else None)

    def _load(self, doc: XMLDocument, include_stack: list[str], top: XMLDocument) -> LoadResult:
        """Register the trees of ``doc``; ``top`` is the document the user loaded (whose folder
        bounds where includes may lead)."""
        root = doc.root
        if root.tag != "root":
            raise self._err(doc, root, "The XML must have a root node called <root>")
        if is_v3(root):
            if root.get("BTCPP_format") is None and not _looks_v3(root):
                warnings.warn(f"{doc.file or '<text>'}: The first tag of the XML (<root>) should contain "
                              'the attribute [BTCPP_format="4"]', BTFormatWarning, stacklevel=3)
            translate_v3(root, doc.file)
        self._documents_opened += 1
        main_tree = root.get("main_tree_to_execute")
        if self._documents_opened == 1 and self.first_main_tree is None:
            self.first_main_tree = main_tree

        children = element_children(root)
        # Includes first, recursively (their trees are registered in the same registry).
        for child in children:
            if child.tag == "include":
                self._load_include(doc, child, include_stack, top)

        models = [c for c in children if c.tag == "TreeNodesModel"]
        if len(models) > 1:
            raise self._err(doc, models[1], "Only a single node <TreeNodesModel> is supported")
        if models:
            self._load_models(doc, models[0])

        tree_elements = [c for c in children if c.tag == "BehaviorTree"]
        before = set(self.trees)
        ids: list[str] = []
        for bt in tree_elements:
            tree_id = bt.get("ID")
            if tree_id is None:
                if len(children) != 1:
                    raise self._err(doc, bt, "The tag <BehaviorTree> must have the attribute [ID]")
                tree_id = f"BehaviorTree_{self._anonymous}"
                self._anonymous += 1
            else:
                check_model_name(tree_id, "BehaviorTree ID", doc, bt)
            if tree_id in self._manifests:
                raise self._err(doc, bt, "The attribute [ID] of tag <BehaviorTree> must not use the name "
                                         "of a registered Node")
            if len(element_children(bt)) != 1:
                raise self._err(doc, bt, f"The tag <BehaviorTree> with ID '{tree_id}' must have exactly 1 child")
            ids.append(tree_id)

        # Validate every tree before registering any, so a bad document changes nothing.
        shapes = []
        plans = []
        self._infos = {}  # see _check_node (valid while the manifests do not change: one document)
        for bt in tree_elements:
            root_elem = element_children(bt)[0]
            shape = Shape(1, root_elem, [])
            plans.append(self._check_node(doc, root_elem, 1, None, shape))
            shapes.append(shape)
        self._infos = {}
        for bt, tree_id, shape, plan in zip(tree_elements, ids, shapes, plans):
            definition = self.trees[tree_id] = TreeDefinition(tree_id, bt, doc, plan)
            definition._depth_shape = shape  # type: ignore[attr-defined]  # see depth.py
        new_ids = [i for i in ids if i not in before]
        return LoadResult(new_ids, ids, main_tree, doc)

    def _load_include(self, doc: XMLDocument, elem: etree._Element, include_stack: list[str],
                      top: XMLDocument) -> None:
        """Load an included file: its path is relative to the including file (as in BT.CPP) and
        must stay below the top-level file's folder or a registered search path, so an included
        file in a child folder may include ``../x.xml`` but nothing outside."""
        path_attr = elem.get("path")
        if path_attr is None:
            raise self._err(doc, elem, "Invalid <include> tag: missing 'path' attribute")
        if elem.get("ros_pkg") is not None and not Path(path_attr).is_absolute():
            raise self._err(doc, elem, "<include ros_pkg=...> needs ROS package lookup, which bt_runtime "
                                       "does not do; use a path relative to this file")
        target = (doc.directory.resolve() / path_attr).resolve()
        roots = self._include_roots(top)
        if not any(root == target or root in target.parents for root in roots):
            allowed = ", ".join(str(root) for root in roots)
            raise self._err(doc, elem, f"include path '{path_attr}' resolves outside the folder of the "
                                       f"top-level file and the include search paths ({allowed}); refused")
        if str(target) in include_stack:
            raise self._err(doc, elem, f"include cycle: '{path_attr}' is already being loaded")
        if not target.is_file():
            raise self._err(doc, elem, f"included file not found: {target}")
        included = read_xml_file(target)
        self._load(included, [*include_stack, str(target)], top)

    def _load_models(self, doc: XMLDocument, models: etree._Element) -> None:
        for entry in element_children(models):
            node_type = NodeType.from_xml_name(entry.tag)
            model_id = entry.get("ID")
            if entry.tag == "SubTree" and model_id is None:
                raise self._err(doc, entry, "Missing attribute 'ID' in SubTree element within TreeNodesModel")
            if model_id is None:
                continue
            ports: dict[str, PortInfo] = {}
            for port_elem in element_children(entry):
                direction = _PORT_TAGS.get(port_elem.tag)
                if direction is None:
                    continue
                name = port_elem.get("name")
                if not name:
                    raise self._err(doc, port_elem, f"A port of model '{model_id}' has no [name] attribute")
                bad = find_forbidden_char(name)
                if bad is not None or name[0].isdigit() or name in RESERVED_ATTRIBUTES:
                    raise self._err(doc, port_elem, f"Invalid port name '{name}' in model '{model_id}'"
                                                    + (" (a reserved attribute name)" if name in RESERVED_ATTRIBUTES
                                                       else ""))
                description = port_elem.get("description") or (port_elem.text or "").strip()
                type_name = port_elem.get("type") or ""
                ptype = port_type(type_name) if type_name else port_type(None)
                default = port_elem.get("default")
                # built directly, as BT.CPP's model ports are (CreatePort's stricter name rule is not applied)
                ports[name] = (PortInfo(name, direction, ptype, description=description) if default is None
                               else PortInfo(name, direction, ptype, default, description))
            if entry.tag == "SubTree":
                self.subtree_models[model_id] = ports
            else:
                self.node_models[model_id] = NodeModel(model_id, node_type, ports,
                                                       (entry.get("description") or "").strip())

    # -- per-tree validation (spec 2.8) ----------------------------------------------------------
    def _check_node(self, doc: XMLDocument, elem: etree._Element, depth: int,
                    parent: etree._Element | None, shape: Shape) -> ElementPlan:
        """Check one element and its children; note in ``shape`` its SubTrees and the
        deepest other element (what the expanded-depth check needs, without a walk of its own).
        Returns the element's plan, what the builder reads instead of the element.

        What an element's tag and attributes say (``_element_info``) is worked out once per
        distinct (tag, attributes) in a document: trees repeat the same few elements."""
        if depth > MAX_DEPTH:
            raise self._err(doc, elem, f"Maximum XML nesting depth exceeded (limit: {MAX_DEPTH}). "
                                       "The XML is too deeply nested.")
        tag = elem.tag
        children = elem[:] if len(elem) else ()  # element_children(elem), inlined: most are leaves
        for child in children:  # (a loop in this frame: a comprehension costs a frame and a list)
            if type(child) is not ELEMENT:  # a comment, PI or entity among them: filter (rare)
                children = [c for c in children if type(c) is ELEMENT or isinstance(c.tag, str)]
                break
        items = elem.items()  # one lxml call for every attribute (elem.get costs as much)
        if not items:
            info = self._infos.get(tag)
            if info is None:
                info = self._element_info(doc, elem, tag, (), tag, children)
            type_id, name, items, attrs, conditions, node_type, explicit = info
        elif len(items) == 1 and items[0][0] == "name" and tag != "SubTree":
            # A name alone (Groot2 names every node, each differently): what the tag says, as
            # for the element without attributes (the same checks), with this name.
            info = self._infos.get(tag)
            if info is None:
                info = self._element_info(doc, elem, tag, (), tag, children)
            type_id, _, _, attrs, conditions, node_type, explicit = info
            name = items[0][1]
            items = tuple(items)
        else:
            name = None
            for item in items:
                if item[0] == "name":  # (a name differs on every node: the rest is what repeats)
                    name = item[1]
                    items.remove(item)
                    break
            items = tuple(items)
            key = (tag, items)
            info = self._infos.get(key)
            if info is None:
                info = self._element_info(doc, elem, tag, items, key, children)
            if name is None:
                type_id, name, items, attrs, conditions, node_type, explicit = info
            else:
                type_id, _, items, attrs, conditions, node_type, explicit = info
        if node_type is None:  # a SubTree
            if children:
                raise self._err(doc, elem, f"<SubTree> with ID '{type_id}' should not have any child")
            shape.subtrees.append((type_id, elem, depth))
            return (tag, type_id, name, items, attrs, conditions, (), elem)
        if depth >= shape.plain_depth:  # (the last deepest, as depth.py's own walk finds)
            shape.plain_depth = depth
            shape.plain_elem = elem
        if explicit and parent is not None and parent.tag == "ReactiveSequence":
            raise self._err(doc, elem, f"Unknown node type: {tag} (BehaviorTree.CPP rejects explicit "
                                       "<Action ID=...> children of a ReactiveSequence; use the compact "
                                       f"form <{type_id}/>)")
        if node_type is _UNKNOWN:
            manifests = self._manifests
            raise self._err(doc, elem, f"Node not recognized: {type_id}{suggest(type_id, list(manifests))}")
        if node_type is _DECORATOR and len(children) != 1:
            raise self._err(doc, elem, f"The node '{type_id}' must have exactly 1 child")
        if children:
            if node_type is _CONTROL:
                if type_id == "TryCatch" and len(children) < 2:
                    raise self._err(doc, elem, "The node 'TryCatch' must have at least 2 children")
                if type_id == "ReactiveSequence":
                    self._check_reactive_children(doc, elem, children)
            elif node_type in _LEAF_TYPES:
                raise self._err(doc, elem, f"The node '{type_id}' must not have any child")
            plans = []
            for child in children:
                plans.append(self._check_node(doc, child, depth + 1, elem, shape))
            plans = tuple(plans)
        else:
            if node_type is _CONTROL:
                raise self._err(doc, elem, f"The node '{type_id}' must have 1 or more children")
            plans = ()
        return (tag, type_id, name, items, attrs, conditions, plans, elem)

    def _element_info(self, doc: XMLDocument, elem: etree._Element, tag: str, items: tuple, key: object,
                      children: object) -> tuple:
        """What an element's tag and attributes say, checked (the errors name this element, the
        first with them): (type ID (a SubTree's ID), name attribute or None, attribute items,
        attributes as a dict or None when there are none (for a node other than a SubTree: none
        but reserved ones), pre/post-condition attributes in BT.CPP's order, node type (None
        for a SubTree, _UNKNOWN for an unregistered type), whether the tag is an explicit
        Action/Condition/...). Plans with the same attributes share these objects (plans are
        never mutated). The checks run in the order they always did (``children`` for the first)."""
        if items:
            attrs = dict(items)
            get = attrs.get
            name = get("name")
            if _CONDITION_ATTRIBUTE_SET.isdisjoint(attrs):
                conditions = ()
            else:  # (the element's few attributes, not the eight names)
                conditions = []
                for item in items:
                    if item[0] in _CONDITION_ATTRIBUTE_SET:
                        conditions.append(item)
                if len(conditions) > 1:
                    conditions.sort(key=_condition_rank)  # BT.CPP's order
                conditions = tuple(conditions)
        else:
            items = conditions = ()
            attrs = name = None
            get = _no_attribute
        manifests = self._manifests
        if tag == "SubTree":
            sub_id = get("ID")
            if children:
                raise self._err(doc, elem, f"<SubTree> with ID '{sub_id}' should not have any child")
            if sub_id is None:
                raise self._err(doc, elem, "The tag <SubTree> must have the attribute [ID]")
            if sub_id in manifests:
                raise self._err(doc, elem, "The attribute [ID] of tag <SubTree> must not use the name of "
                                           "a registered Node")
            info = (sub_id, name, items, attrs, conditions, None, False)
        else:
            explicit = tag in EXPLICIT_TAG_SET
            if explicit:
                type_id = get("ID")
                if type_id is None:
                    raise self._err(doc, elem, f"The tag <{tag}> must have the attribute [ID]")
            else:
                type_id = tag
                if attrs is not None and "ID" in attrs:
                    raise self._err(doc, elem, f"Attribute [ID] is not allowed in <{tag}>")
            manifest = manifests.get(type_id)
            if attrs is not None and RESERVED_ATTRIBUTES.issuperset(attrs):
                attrs = None  # only a name, conditions...: the builder has no port pass to make
            info = (type_id, name, items, attrs, conditions, manifest.node_type if manifest else _UNKNOWN,
                    explicit)
        self._infos[key] = info
        return info

    def _check_reactive_children(self, doc: XMLDocument, elem: etree._Element,
                                 children: list[etree._Element]) -> None:
        """BT.CPP 4.10 refuses a ReactiveSequence with more than one asynchronous control child
        (by element name: an AsyncSequence, or a control registered under one of BT.CPP's
        asynchronous class names). ReactiveFallback has no such check in 4.10."""
        manifests = self._manifests
        async_count = 0
        for child in children:
            manifest = manifests.get(child.tag)
            if manifest is not None and manifest.node_type is _CONTROL and child.tag in _ASYNC_CONTROL_NAMES:
                async_count += 1
                if async_count > 1:
                    raise self._err(doc, elem, "A ReactiveSequence cannot have more than one async child.")


_DECORATOR, _CONTROL = NodeType.DECORATOR, NodeType.CONTROL
_UNKNOWN = object()  # the node type of an element whose type is not registered (_element_info)


def _no_attribute(name: str) -> None:
    return None

_ASYNC_CONTROL_NAMES = frozenset({"AsyncSequence", "ThreadedAction", "StatefulActionNode", "CoroActionNode"})
_LEAF_TYPES = (NodeType.ACTION, NodeType.CONDITION)


def _looks_v3(root: etree._Element) -> bool:
    """A file without BTCPP_format that uses v3-only names (then translation warns instead)."""
    from .v3 import RENAMED_NODES
    for elem in root.iter():
        if isinstance(elem.tag, str) and (elem.tag in RENAMED_NODES or elem.get("ID") in RENAMED_NODES
                                          or "__shared_blackboard" in elem.attrib):
            return True
    return False
