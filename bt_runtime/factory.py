"""The node registry and tree factory: BT.CPP's BehaviorTreeFactory in Python.

A factory starts with every node BT.CPP registers by default. Register your node types, load
tree documents (text or file), then create trees. Nodes reach the outside world (the runtime's
supervisor, backup, gate, driver) through ``factory.context``, which every node sees as
``node.context``: no globals, so one tree runs the same in tests, simulation and hardware.
"""

from __future__ import annotations

import fnmatch
import json
from collections.abc import Callable, Iterable
from enum import Enum
from pathlib import Path
from typing import Any

from .blackboard import Blackboard
from .errors import BTRuntimeError, LogicError, XMLLoadError
from .node import (
    NodeConfig,
    SimpleActionNode,
    SimpleConditionNode,
    SimpleDecoratorNode,
    SimpleStatefulActionNode,
    TreeNode,
    TreeNodeManifest,
    manifest_for,
)
from .ports import PortInfo, ports_dict
from .status import NodeStatus, NodeType
from .tree import Tree
from .xml.builder import TreeBuilder
from .xml.document import LoadResult, NodeModel, TreeRegistry

Builder = Callable[[str, NodeConfig], TreeNode]


class BehaviorTreeFactory:
    """Registry of node types and tree definitions; builds Trees."""

    def __init__(self, context: Any = None):
        self.context = context
        self.builders: dict[str, Builder] = {}
        self.manifests: dict[str, TreeNodeManifest] = {}
        self.enums: dict[str, int] = {}
        self.substitution_rules: list[tuple[str, Any]] = []
        self.registry = TreeRegistry(self)
        from .builtins import register_builtins

        register_builtins(self)  # (their manifests say builtin=True)
        self._builtin_ids = frozenset(self.builders)

    # -- registration --------------------------------------------------------------------------
    def register_builder(self, manifest: TreeNodeManifest, builder: Builder) -> None:
        rid = manifest.registration_id
        if rid in self.builders:
            raise LogicError(f"ID [{rid}] already registered")
        if not rid or rid in ("Root", "root"):
            raise LogicError(f"Invalid node registration ID '{rid}'")
        self.builders[rid] = builder
        self.manifests[rid] = manifest

    def register_node_type(self, cls: type[TreeNode], name: str | None = None, *args: Any,
                           **kwargs: Any) -> None:
        """Register a node class; its ports come from ``cls.provided_ports()``.

        Extra arguments are passed to the constructor after ``(name, config)``.
        """
        rid = name or getattr(cls, "registration_id_default", None) or cls.__name__
        manifest = manifest_for(cls, rid)
        if args or kwargs:
            def builder(n: str, c: NodeConfig) -> TreeNode:
                return cls(n, c, *args, **kwargs)
        else:
            builder = cls
        self.register_builder(manifest, builder)

    def register_simple_action(self, name: str, fn: Callable[[TreeNode], NodeStatus],
                               ports: Iterable[PortInfo] = ()) -> None:
        manifest = TreeNodeManifest(name, NodeType.ACTION, ports_dict(ports))
        self.register_builder(manifest, SimpleActionNode.builder(fn))

    def register_simple_condition(self, name: str, fn: Callable[[TreeNode], NodeStatus],
                                  ports: Iterable[PortInfo] = ()) -> None:
        manifest = TreeNodeManifest(name, NodeType.CONDITION, ports_dict(ports))
        self.register_builder(manifest, SimpleConditionNode.builder(fn))

    def register_simple_stateful_action(self, name: str, on_start: Callable[[TreeNode], NodeStatus],
                                        on_running: Callable[[TreeNode], NodeStatus],
                                        on_halted: Callable[[TreeNode], None] | None = None,
                                        ports: Iterable[PortInfo] = ()) -> None:
        manifest = TreeNodeManifest(name, NodeType.ACTION, ports_dict(ports))
        self.register_builder(manifest,
                              lambda n, c: SimpleStatefulActionNode(n, c, on_start, on_running, on_halted))

    def register_simple_decorator(self, name: str, fn: Callable[[NodeStatus, TreeNode], NodeStatus],
                                  ports: Iterable[PortInfo] = ()) -> None:
        manifest = TreeNodeManifest(name, NodeType.DECORATOR, ports_dict(ports))
        self.register_builder(manifest, lambda n, c: SimpleDecoratorNode(n, c, fn))

    def unregister_builder(self, registration_id: str) -> None:
        if registration_id in self._builtin_ids:
            raise LogicError(f"You can not remove the builtin registration ID [{registration_id}]")
        self.builders.pop(registration_id, None)
        self.manifests.pop(registration_id, None)

    def builtin_nodes(self) -> frozenset[str]:
        return self._builtin_ids

    def add_metadata_to_manifest(self, registration_id: str, metadata: list[tuple[str, str]]) -> None:
        manifest = self.manifests.get(registration_id)
        if manifest is None:
            raise LogicError(f"addMetadataToManifest: wrong ID [{registration_id}]")
        manifest.metadata = list(metadata)

    def register_scripting_enum(self, name: str, value: int) -> None:
        previous = self.enums.get(name)
        if previous is not None and previous != value:
            raise LogicError(f"Registering the enum [{name}] twice with different values, first "
                             f"{previous} and later {value}")
        self.enums[name] = int(value)

    def register_scripting_enums(self, enum_cls: type[Enum]) -> None:
        for member in enum_cls:
            self.register_scripting_enum(member.name, int(member.value))

    # -- models (node types known only by their TreeNodesModel entry) -----------------------------
    def register_models_from_text(self, text: str, file: str | None = None) -> list[str]:
        """Register placeholder node types for every model in a TreeNodesModel document.

        Used to validate trees whose nodes are implemented elsewhere (e.g. Nav2's). The
        placeholders have the declared ports; ticking one raises an error.
        """
        before = dict(self.registry.node_models)
        self.registry.load_text(text, file=file)
        added = []
        for rid, model in self.registry.node_models.items():
            if rid in self.builders or (rid in before and before[rid] is model):
                continue
            self.register_builder(TreeNodeManifest(rid, model.node_type, model.ports, model.description),
                                  _placeholder_builder(model))
            added.append(rid)
        return added

    def register_models_from_file(self, path: str | Path) -> list[str]:
        return self.register_models_from_text(Path(path).read_text(encoding="utf-8"), file=str(path))

    # -- substitution rules --------------------------------------------------------------------
    def add_substitution_rule(self, pattern: str, rule: str | dict) -> None:
        """Replace matching nodes (by instance name, type ID or full-path wildcard) with another
        registered type or a test node config dict (return_status, async_delay, ...).

        As in BT.CPP (a map keyed by pattern) a second rule for the same pattern replaces the
        first. The substitute keeps the original node's ports and registration ID: only the
        object that is built changes, so the XML's attributes stay valid.
        """
        for i, (existing, _) in enumerate(self.substitution_rules):
            if existing == pattern:
                self.substitution_rules[i] = (pattern, rule)
                return
        self.substitution_rules.append((pattern, rule))

    def clear_substitution_rules(self) -> None:
        self.substitution_rules.clear()

    def load_substitution_rule_from_json(self, text: str) -> None:
        """BT.CPP's JSON form: ``TestNodeConfigs`` (optional) and ``SubstitutionRules``, whose
        values name a config or else a registered node type. Every config must give
        ``return_status`` or ``return_status_script`` (BTRuntimeError otherwise)."""
        from .builtins.test_node import check_test_node_config

        data = json.loads(text)
        configs = data.get("TestNodeConfigs", {})
        for name, config in configs.items():
            check_test_node_config(name, config)
        for pattern, rule in data.get("SubstitutionRules", {}).items():
            self.add_substitution_rule(pattern, configs.get(rule, rule))

    def substitution_builder(self, rule: Any) -> Builder:
        """The builder a rule puts in place of a node's own."""
        if isinstance(rule, str):
            if rule not in self.builders:
                raise BTRuntimeError(f"Substituted Node ID [{rule}] not found")
            return self.builders[rule]
        if not isinstance(rule, dict):
            raise LogicError("Substitution rule is not a string or a TestNodeConfig")
        from .builtins.test_node import TestNode

        return lambda n, c: TestNode(n, c, rule)

    def substitution_for(self, name: str, type_id: str, path: str) -> Any | None:
        """The first rule whose pattern is the instance name, the type ID or matches the path."""
        for pattern, rule in self.substitution_rules:
            if pattern in (name, type_id) or fnmatch.fnmatchcase(path, pattern):
                return rule
        return None

    # -- trees ---------------------------------------------------------------------------------
    def register_behavior_tree_from_text(self, xml: str | bytes) -> LoadResult:
        return self.registry.load_text(xml)

    def register_behavior_tree_from_file(self, path: str | Path) -> LoadResult:
        return self.registry.load_file(path)

    def add_include_search_path(self, folder: str | Path) -> None:
        """Let ``<include>`` reach files below ``folder`` too (by default an include must stay
        below the folder of the file the user loaded)."""
        self.registry.include_search_paths.append(Path(folder))

    def registered_behavior_trees(self) -> list[str]:
        """The IDs of the registered trees, sorted (BT.CPP keeps them in a std::map)."""
        return sorted(self.registry.trees)

    def clear_registered_behavior_trees(self) -> None:
        self.registry.clear()

    def create_tree(self, tree_id: str, blackboard: Blackboard | None = None) -> Tree:
        return TreeBuilder(self).build(tree_id, blackboard)

    def create_tree_from_text(self, xml: str | bytes, blackboard: Blackboard | None = None) -> Tree:
        return self._create_from(self.registry.load_text(xml), blackboard)

    def create_tree_from_file(self, path: str | Path, blackboard: Blackboard | None = None) -> Tree:
        return self._create_from(self.registry.load_file(path), blackboard)

    def _create_from(self, result: LoadResult, blackboard: Blackboard | None) -> Tree:
        main = self._main_tree_id(result)
        return self.create_tree(main, blackboard)

    def _main_tree_id(self, result: LoadResult) -> str:
        """Choose the tree to run from a just-loaded document (spec 2.2)."""
        if result.main_tree:
            return result.main_tree
        if len(result.all_tree_ids) == 1:
            return result.all_tree_ids[0]
        if len(result.new_tree_ids) == 1:
            return result.new_tree_ids[0]
        if self.registry.first_main_tree:
            return self.registry.first_main_tree
        if len(self.registry.trees) == 1:
            return next(iter(self.registry.trees))
        raise XMLLoadError("[main_tree_to_execute] was not specified correctly", file=result.document.file)

    def main_tree_id_of(self, result: LoadResult) -> str:
        return self._main_tree_id(result)


def _placeholder_builder(model: NodeModel) -> Builder:
    from .builtins.placeholder import placeholder_class

    cls = placeholder_class(model.node_type)
    return lambda n, c: cls(n, c)
