"""Instantiating a registered tree: nodes, uids, paths, subtree blackboards (spec 2.6-2.12).

Uids start at 1 and are assigned depth-first pre-order over the fully expanded tree: a node
gets its uid before its children and a SubTree node's whole subtree is numbered before its
next sibling. Everything that can be resolved once (port remapping strings, literal
conversions, script compilation, blackboard entries for remapped ports) is done here so the
tick itself stays cheap. Errors name the file, line and element.
"""

from __future__ import annotations

import re
import time
from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from lxml import etree

from ..blackboard import Blackboard, Entry
from ..builtins.decorators import SubTreeNode
from ..condition_tick import SharedConditions, shared_during_build
from ..errors import BehaviorTreeException, XMLLoadError, XMLLogicError, located
from ..node import _NO_PORTS, NodeConfig, TreeNode, TreeNodeManifest
from ..ports import (
    ANYTYPE,
    DOUBLE,
    INT,
    INT64,
    RESERVED_ATTRIBUTES,
    blackboard_key,
    is_allowed_port_name,
    parse_bool,
    polymorphic,
)
from ..script import compile_script
from ..status import PortDirection
from ..timers import TimerQueue, WakeUpSignal
from ..tree import SubtreeRecord, Tree
from .depth import check_tree_depth
from .document import POST_CONDITIONS, PRE_CONDITIONS, ElementPlan, TreeDefinition, suggest
from .long_lived import long_lived
from .reader import XMLDocument

if TYPE_CHECKING:
    from ..factory import BehaviorTreeFactory

_PRE_CONDITION_SET = frozenset(PRE_CONDITIONS)
_node_config = NodeConfig._for_node
_subtree_blackboard = Blackboard._for_subtree
_subtree_node = SubTreeNode._built
_BAD_INSTANCE_CHAR = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")
_INT_RE = re.compile(r"-?[0-9]+")
_DOUBLE_RE = re.compile(r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")


_port_name_verdicts: dict[str, bool] = {}
_NOT_OTHER = frozenset(("ID", "name", *PRE_CONDITIONS, *POST_CONDITIONS))  # (see _subtree_plan)


def _allowed_port_name(name: str) -> bool:
    """``is_allowed_port_name``, decided once per distinct attribute name (a tree repeats the
    same few names on thousands of elements; the check walks every character)."""
    verdict = _port_name_verdicts.get(name)
    if verdict is None:
        verdict = is_allowed_port_name(name)
        if len(_port_name_verdicts) < 10_000:  # bounded: attribute names are few in practice
            _port_name_verdicts[name] = verdict
    return verdict


def subtree_literal(text: str) -> Any:
    """BT.CPP 4.10 typing of a literal SubTree port value: int, int64, double or string."""
    if _INT_RE.fullmatch(text) and -(2**63) <= int(text) < 2**63:
        return int(text)
    if _DOUBLE_RE.fullmatch(text):
        return float(text)
    return text


def _fill_defaults(inputs: dict[str, str], outputs: dict[str, str], defaults: tuple, given: Any) -> None:
    for name, text, to_in, to_out in defaults:
        if name in given:
            continue
        if to_in:
            inputs[name] = text
        if to_out:
            outputs[name] = text


def _shared(ports: dict[str, str]) -> Mapping[str, str]:
    """A node's port mapping as shared between nodes: read-only (nothing changes a built
    node's ports)."""
    return MappingProxyType(ports) if ports else _NO_PORTS


class TreeBuilder:
    """Builds one Tree from the factory's registry."""

    def __init__(self, factory: BehaviorTreeFactory):
        self.factory = factory
        self.registry = factory.registry
        self._uid = 0
        self._records: list[SubtreeRecord] = []
        self._paths: set[str] = set()
        self.wake_up = WakeUpSignal()
        self.timers = TimerQueue()
        self.clock_holder: list = [time.monotonic]
        # (port type, enums, text) literals already converted once in this build: the same
        # literal on many nodes is checked once (the conversion is a pure function of these)
        self._literals_ok: set[tuple[int, str]] = set()
        self._subtree_plans: dict[int, tuple] = {}  # see _subtree_plan
        self._port_tables: dict[TreeNodeManifest, tuple] = {}  # see _port_table
        self._types: dict[str, tuple] = {}  # see _type
        self._port_sets: dict[int, tuple] = {}  # see _ports
        # what every node's config gets, read once per build
        self._enums = factory.enums
        self._context = factory.context
        self._clock = time.monotonic  # (clock_holder[0] while building)
        self._substituting = bool(factory.substitution_rules)
        self._condition_sets: dict[tuple, tuple] = {}  # see _compile_conditions

    def build(self, tree_id: str, blackboard: Blackboard | None = None) -> Tree:
        """Build the tree ``tree_id``, the cyclic collector paused and the tree's objects put
        in its oldest generation (see long_lived.py)."""
        with long_lived(), shared_during_build():  # (equal pre/post-condition closures built once)
            return self._build(tree_id, blackboard)

    def _build(self, tree_id: str, blackboard: Blackboard | None) -> Tree:
        definition = self.registry.trees.get(tree_id)
        if definition is None:
            raise XMLLoadError(f"Can't find a tree with name: {tree_id}"
                               f"{suggest(tree_id, list(self.registry.trees))}")
        check_tree_depth(self.registry, tree_id)  # before recursing into it
        record = SubtreeRecord(tree_id, "", blackboard if blackboard is not None else Blackboard())
        self._records.append(record)
        self._build_node(definition.plan, definition.document, record, "", [tree_id])
        source = definition.document.text
        return Tree(self._records, self.factory.manifests, self.wake_up, self.timers, source_xml=source,
                    clock_holder=self.clock_holder)

    # -- helpers -------------------------------------------------------------------------------
    def _next_uid(self) -> int:
        self._uid += 1
        if self._uid > 0xFFFF:
            raise XMLLoadError("Too many nodes: uids are 16-bit in BT.CPP (max 65535)")
        return self._uid

    def _err(self, doc: XMLDocument, elem: etree._Element, message: str) -> XMLLoadError:
        return XMLLoadError(message, file=doc.file, line=doc.line_of(elem), element=elem.tag)

    def _compile_conditions(self, cfg: NodeConfig, conditions: tuple[tuple[str, str], ...], doc: XMLDocument,
                            elem: etree._Element) -> None:
        """Give the config the element's pre/post-condition scripts (its plan lists them in
        BT.CPP's order): compiled once per distinct attribute set in a build and shared by
        its nodes (read-only; see condition_tick.SharedConditions)."""
        shared = self._condition_sets.get(conditions)
        if shared is None:
            pre = SharedConditions()
            post = SharedConditions()
            pre.key = post.key = conditions
            for attr, text in conditions:
                try:
                    script = compile_script(text)
                except BehaviorTreeException as exc:  # BT.CPP: LogicError("Error in the script ...")
                    raise XMLLogicError(f"{attr}: {exc}", file=doc.file, line=doc.line_of(elem),
                                        element=elem.tag) from None
                (pre if attr in _PRE_CONDITION_SET else post)[attr] = script
            shared = self._condition_sets[conditions] = (pre or None, post or None)
        cfg._pre, cfg._post = shared

    @staticmethod
    def _check_instance_name(name: str) -> str | None:
        m = _BAD_INSTANCE_CHAR.search(name)
        return m.group(0) if m else None

    # -- nodes ---------------------------------------------------------------------------------
    def _build_node(self, plan: ElementPlan, doc: XMLDocument, record: SubtreeRecord, prefix: str,
                    stack: list[str]) -> TreeNode:
        """Build the node of ``plan`` (what the registry read of its element, see ElementPlan)
        and its children: no lxml call here, so a SubTree expanded in many places reads its
        elements once."""
        tag, type_id, name, items, attrs, conditions, child_plans, elem = plan
        if tag == "SubTree":
            return self._build_subtree(plan, doc, record, prefix, stack)
        known = self._types.get(type_id)
        if known is None:
            known = self._type(type_id, doc, elem)
        manifest, builder, defaults, single = known
        if name is None:
            name = type_id
        # (every forbidden character is unprintable; isprintable() costs far less than the search)
        elif not name.isprintable() and _BAD_INSTANCE_CHAR.search(name) is not None:
            bad = self._check_instance_name(name)
            raise self._err(doc, elem, f"The instance name '{name!r}' contains the forbidden character {bad!r}")
        self._uid = uid = self._uid + 1  # _next_uid(), inlined
        if uid > 0xFFFF:
            raise XMLLoadError("Too many nodes: uids are 16-bit in BT.CPP (max 65535)")
        if self._substituting:  # (the path is joined only when a rule needs it: see _for_node)
            path = prefix + name + (f"::{uid}" if name == type_id else "")
            rule = self.factory.substitution_for(name, type_id, path)
            if rule is not None:
                builder = self.factory.substitution_builder(rule)
        cfg = _node_config(record.blackboard, self._enums, manifest, uid, prefix, name, self._context,
                           self.wake_up, self.timers, self._clock, doc, elem)
        # Port passes only when there is something to do (most nodes have no port attributes).
        if attrs is not None:
            # (a type whose one port is an input needing no check, given a literal, perhaps named:
            # Script/ScriptCondition's code; the port pass would give the same mapping)
            raw = attrs.get(single) if single is not None else None
            if (raw is not None and raw[:1] != "{" and raw != "="
                    and (len(attrs) == 1 or (len(attrs) == 2 and "name" in attrs))):
                cfg.input_ports = MappingProxyType({single: raw})
            else:
                self._ports(cfg, manifest, attrs, record.blackboard, doc, elem)
        elif defaults is not None:
            cfg.input_ports, cfg.output_ports = defaults
        if conditions:
            self._compile_conditions(cfg, conditions, doc, elem)
        try:
            node = builder(name, cfg)
        except XMLLoadError:
            raise
        except BehaviorTreeException as exc:  # keeps the class the constructor threw
            raise located(exc, str(exc), file=doc.file, line=doc.line_of(elem), element=elem.tag) from None
        except Exception as exc:
            raise self._err(doc, elem, f"creating node '{cfg.path}' [{type_id}] failed: "
                                       f"{type(exc).__name__}: {exc}") from exc
        record.nodes.append(node)
        if child_plans:
            build_node = self._build_node
            add_child = node.add_child
            for child_plan in child_plans:
                add_child(build_node(child_plan, doc, record, prefix, stack))
        return node

    def _type(self, type_id: str, doc: XMLDocument, elem: etree._Element) -> tuple:
        """(manifest, builder, (input ports, output ports) of a node without port attributes
        or None when both are empty, the name of its port when that is its only one, an input
        without default whose literal needs no check (Script's code), else None) of a registered
        node type, looked up once per type in a build."""
        manifests = self.factory.manifests
        manifest = manifests.get(type_id)
        if manifest is None:
            raise self._err(doc, elem, f"Node not recognized: {type_id}{suggest(type_id, list(manifests))}")
        if not type_id.isprintable() and _BAD_INSTANCE_CHAR.search(type_id) is not None:  # (the name)
            bad = self._check_instance_name(type_id)
            raise self._err(doc, elem, f"The instance name '{type_id!r}' contains the forbidden character {bad!r}")
        entries, defaults = self._port_table(manifest) if manifest.ports else ({}, ())
        single = None
        if len(entries) == 1 and len(manifest.ports) == 1 and not defaults:
            ((port_name, (to_in, to_out, port, check)),) = entries.items()
            if to_in and not to_out and not check:
                single = port_name
        if defaults:
            inputs: dict[str, str] = {}
            outputs: dict[str, str] = {}
            _fill_defaults(inputs, outputs, defaults, ())
            defaults = (_shared(inputs), _shared(outputs))
        else:
            defaults = None
        known = self._types[type_id] = (manifest, self.factory.builders[type_id], defaults, single)
        return known

    def _port_table(self, manifest: TreeNodeManifest) -> tuple[dict[str, tuple], tuple]:
        """What a node type's ports mean for the port pass, worked out once per type in a build:
        {attribute: (to inputs, to outputs, port, literal to check)} for the attributes that
        are ports, and the defaults a node gets for ports it does not give:
        ((name, text, to inputs, to outputs), ...)."""
        table = self._port_tables.get(manifest)
        if table is None:
            entries: dict[str, tuple] = {}
            defaults = []
            for name, port in manifest.ports.items():
                direction = port.direction
                to_in, to_out = direction is not PortDirection.OUTPUT, direction is not PortDirection.INPUT
                if name not in RESERVED_ATTRIBUTES and _allowed_port_name(name):
                    ptype = port.type
                    # (a string converts to a string port without fail: nothing to check)
                    check = to_in and ptype.strongly_typed and ptype.has_converter and ptype.kind != "string"
                    entries[name] = (to_in, to_out, port, check)
                if port.has_default:
                    text = port.default_string()
                    defaults.append((name, text, to_in, to_out and blackboard_key(text, name) is not None))
            table = self._port_tables[manifest] = (entries, tuple(defaults))
        return table

    def _ports(self, cfg: NodeConfig, manifest: TreeNodeManifest, attrs: dict[str, str], bb: Blackboard,
               doc: XMLDocument, elem: etree._Element) -> None:
        """The port pass of one node. ``attrs`` is shared by the plans of equal elements of a
        document: from the second node with these attributes on, the pass is made once more
        and its outcome shared (``_first_ports``); the nodes after it get the same read-only
        port mappings and only the blackboard entries of their remapped ports (their
        blackboard may differ). Most elements with attributes are distinct (scripts): the
        first pass of such an element costs no more than the plain pass."""
        known = self._port_sets.get(id(attrs))  # (plans keep every attrs alive during a build)
        if known is None or type(known) is not tuple or known[0] is not manifest:
            self._first_ports(cfg, manifest, attrs, bb, doc, elem, known is manifest)
            return
        _, cfg.input_ports, cfg.output_ports, other, remapped = known
        if other:
            cfg._other = dict(other)
        for name, raw, port in remapped:
            self._port_entry(name, raw, port, bb, doc, elem)

    def _first_ports(self, cfg: NodeConfig, manifest: TreeNodeManifest, attrs: dict[str, str],
                     bb: Blackboard, doc: XMLDocument, elem: etree._Element, share: bool) -> None:
        """The port pass: port attributes into the config (an unknown port is an error),
        defaults for the others, then blackboard entries for the remapped ports and the
        conversion check of literal ones (after every attribute was accepted, as before).
        With ``share`` (the second node with these attributes) the outcome is kept for the
        next ones (``_ports``); otherwise only that these attributes were seen."""
        table = self._port_tables.get(manifest)
        entries, defaults = table if table is not None else self._port_table(manifest)
        pending = None  # the given ports that may need a blackboard entry or a literal check
        inputs: dict[str, str] = {}
        outputs: dict[str, str] = {}
        for attr, value in attrs.items():
            entry = entries.get(attr)
            if entry is None:
                if attr in RESERVED_ATTRIBUTES:
                    continue
                if not _allowed_port_name(attr):
                    cfg.other_attributes[attr] = value
                    continue
                line = doc.line_of(elem)
                ports = list(manifest.ports)
                raise self._err(doc, elem, f"a port with name [{attr}] is found in the XML (<{elem.tag}>, "
                                           f"line {line}) but not in the providedPorts() of its registered "
                                           f"node type.{suggest(attr, ports) or (' Ports: ' + ', '.join(ports) if ports else ' It has no ports.')}")
            if entry[0]:
                inputs[attr] = value
            if entry[1]:
                outputs[attr] = value
            if entry[3] or value[:1] == "{" or value == "=":
                if pending is None:
                    pending = []
                pending.append((attr, value, entry))
        if defaults:
            _fill_defaults(inputs, outputs, defaults, [attr for attr in attrs if attr in entries])
        # read-only on every built node, shared or not: a built node's ports never change, and
        # one rule for all (a write fails on every node, not on some)
        cfg.input_ports = inputs = _shared(inputs)
        cfg.output_ports = outputs = _shared(outputs)
        remapped = []
        for name, raw, (_, _, port, check) in pending or ():
            if (len(raw) >= 3 and raw[0] == "{" and raw[-1] == "}") or raw == "=" or raw == "{=}":
                self._port_entry(name, raw, port, bb, doc, elem)  # (a strict blackboard pointer)
                remapped.append((name, raw, port))
            elif check:
                checked = (id(port.type), raw)  # the manifests keep every port type alive
                if checked not in self._literals_ok:
                    self._check_literal(name, raw, port, cfg.enums, doc, elem)
                    self._literals_ok.add(checked)
        if share:
            other = cfg._other
            self._port_sets[id(attrs)] = (manifest, inputs, outputs, dict(other) if other else None,
                                          tuple(remapped))
        else:
            self._port_sets[id(attrs)] = manifest  # (seen once)

    def _port_entry(self, name: str, raw: str, port: Any, bb: Blackboard, doc: XMLDocument,
                    elem: etree._Element) -> None:
        """Create (or type-check) the blackboard entry a remapped port points to."""
        ptype = port.type
        key = blackboard_key(raw, name)
        existing = bb.get_entry(key)
        if existing is not None:
            et = existing.type
            if (et.strongly_typed and ptype.strongly_typed and et != ptype
                    and et.kind != "string"
                    and not (port.direction is PortDirection.INPUT and polymorphic(et, ptype))):
                raise self._err(doc, elem, f"The creation of the tree failed because the port "
                                           f"[{name}] was initially created with type [{et.name}] "
                                           f"and, later type [{ptype.name}] was used somewhere else.")
        else:
            try:
                bb.create_entry(key, ptype)
            except BehaviorTreeException as exc:
                raise self._err(doc, elem, str(exc)) from None

    @staticmethod
    def _check_literal(name: str, raw: str, port: Any, enums: dict[str, int], doc: XMLDocument,
                       elem: etree._Element) -> None:
        try:
            port.type.from_string(raw, enums)
        except Exception:  # BT.CPP catches any exception of the converter: LogicError
            raise XMLLogicError(f'The port with name "{name}" and value "{raw}" can not be '
                                f"converted to {port.type.name}", file=doc.file, line=doc.line_of(elem),
                                element=elem.tag) from None

    # -- subtrees ------------------------------------------------------------------------------
    def _build_substituted_subtree(self, rule: Any, name: str, cfg: NodeConfig, attrs: dict[str, str],
                                   record: SubtreeRecord, doc: XMLDocument, elem: etree._Element) -> TreeNode:
        cfg.input_ports = {k: v for k, v in attrs.items() if k not in ("ID", "name", "_autoremap")
                           and is_allowed_port_name(k)}
        try:
            node = self.factory.substitution_builder(rule)(name, cfg)
        except BehaviorTreeException as exc:
            raise located(exc, str(exc), file=doc.file, line=doc.line_of(elem), element=elem.tag) from None
        record.nodes.append(node)
        return node

    def _subtree_plan(self, sub_id: str, attrs: dict[str, str], doc: XMLDocument,
                      elem: etree._Element) -> tuple:
        """What a <SubTree> element's attributes mean, worked out once per distinct (ID,
        attributes) in a build (a subtree used in many places is mostly used the same way):
        (port remapping, _autoremap, blackboard remappings, literal entries, other attributes)."""
        remap: dict[str, str] = {}
        other: dict[str, str] = {}  # the attributes that are neither ports nor ID, name, conditions
        autoremap = False
        allowed = _port_name_verdicts.get
        for attr, value in attrs.items():
            verdict = allowed(attr)
            if verdict is None:
                verdict = _allowed_port_name(attr)
            if verdict:
                remap[attr] = "{" + attr + "}" if value == "{=}" else value
                continue
            if attr == "_autoremap":
                text = "{" + attr + "}" if value == "{=}" else value
                try:
                    autoremap = parse_bool(text)
                except BehaviorTreeException:
                    raise self._err(doc, elem, f"_autoremap must be true or false, got '{text}'") from None
            elif attr in _NOT_OTHER:
                continue
            other[attr] = value
        model = self.registry.subtree_models.get(sub_id)
        if model and not autoremap:
            for port_name, port in model.items():
                if port_name in remap:
                    continue
                if not port.has_default:
                    raise self._err(doc, elem, f"In the <TreeNodesModel> the <Subtree ID=\"{sub_id}\"> is "
                                               f"defining a mandatory port called [{port_name}], but you are "
                                               "not remapping it")
                remap[port_name] = port.default_string()
                other.pop(port_name, None)  # (a model port given under a name that is not a port's)
        remapped: list[tuple[str, str]] = []
        literals: list[tuple[str, Any, Any]] = []
        for internal, value in remap.items():
            stripped = value.strip(" ")  # (is_strict_blackboard_pointer of it, inlined)
            key = (blackboard_key(value, internal) if len(stripped) >= 3 and stripped[0] == "{"
                   and stripped[-1] == "}" else None)
            if key is not None:
                remapped.append((internal, key))
            else:
                literal = subtree_literal(value)
                # a string goes in as BT.CPP's set<std::string> on a new entry: untyped
                entry_type = (ANYTYPE if isinstance(literal, str) else
                              DOUBLE if isinstance(literal, float) else
                              INT if -(2**31) <= literal < 2**31 else INT64)
                literals.append((internal, literal, entry_type))
        if "_autoremap" not in other:
            other["_autoremap"] = "true" if autoremap else "false"
        return _shared(remap), autoremap, tuple(remapped), tuple(literals), other

    def _build_subtree(self, plan: ElementPlan, doc: XMLDocument, record: SubtreeRecord, prefix: str,
                       stack: list[str]) -> TreeNode:
        _, sub_id, name_attr, items, attrs, conditions, _, elem = plan
        if attrs is None:
            attrs = {}
        definition: TreeDefinition | None = self.registry.trees.get(sub_id)
        if definition is None:
            raise self._err(doc, elem, f"SubTree ID '{sub_id}' is not a registered BehaviorTree"
                                       f"{suggest(sub_id or '', list(self.registry.trees))}")
        if sub_id in stack:
            raise self._err(doc, elem, f"Recursive behavior tree cycle detected: tree '{sub_id}' references "
                                       "itself (directly or indirectly)")
        manifest = self.factory.manifests["SubTree"]
        self._uid = uid = self._uid + 1  # _next_uid(), inlined
        if uid > 0xFFFF:
            raise XMLLoadError("Too many nodes: uids are 16-bit in BT.CPP (max 65535)")
        path = prefix + (name_attr if name_attr is not None else f"{sub_id}::{uid}")
        paths = self._paths
        if path in paths:
            raise self._err(doc, elem, f"Duplicate SubTree path detected: '{path}'. Use the 'name' attribute "
                                       "to give each SubTree instance a unique name.")
        paths.add(path)
        cfg = _node_config(record.blackboard, self._enums, manifest, uid, path, None, self._context,
                           self.wake_up, self.timers, self._clock, doc, elem)
        if conditions:
            self._compile_conditions(cfg, conditions, doc, elem)
        if self._substituting:
            rule = self.factory.substitution_for(name_attr or sub_id, "SubTree", path)
            if rule is not None:  # BT.CPP builds the substitute in its place and expands nothing
                return self._build_substituted_subtree(rule, name_attr or sub_id, cfg, attrs, record, doc, elem)

        # (items: one tuple per distinct element of a document, and it holds the ID; the plans
        # keep it alive during the build, so its id is a key)
        plan = self._subtree_plans.get(id(items))
        if plan is None:
            plan = self._subtree_plans[id(items)] = self._subtree_plan(sub_id, attrs, doc, elem)
        remap, autoremap, remapped, literals, other = plan
        child_bb = _subtree_blackboard(record.blackboard, dict(remapped), autoremap)
        if literals:
            local = child_bb.local_entries()
            for internal, literal, entry_type in literals:
                entry = Entry(entry_type)
                entry.write(literal)
                local[internal] = entry
        cfg.input_ports = remap  # (read-only, shared by the SubTrees of this element)
        cfg._other = dict(other)  # (cfg.other_attributes = ..., without the property's call)
        try:  # (the registered "SubTree" builder, which can be neither replaced nor removed)
            node = _subtree_node(name_attr or sub_id, cfg, sub_id)
        except BehaviorTreeException as exc:
            raise self._err(doc, elem, str(exc)) from None
        record.nodes.append(node)
        sub_record = SubtreeRecord(sub_id, path, child_bb, [])
        self._records.append(sub_record)
        root = self._build_node(definition.plan, definition.document, sub_record, path + "/",
                                [*stack, sub_id])
        node._child = root  # node.set_child(root) on the new node, without its two calls
        node._child_cell = root._cell
        return node
