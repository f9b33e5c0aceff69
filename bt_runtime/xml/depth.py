"""How deep a tree is once its SubTrees are expanded, checked before building it.

BT.CPP has no limit. Ticking and halting recurse once per level (about three Python frames
each), so a chain of a few hundred SubTrees would end in a RecursionError mid-run. We refuse
such trees at load time instead, naming the file and line where the limit is crossed. The walk
is iterative (a 2000-deep SubTree chain is measured without recursing) and each tree
definition is walked once.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..errors import XMLLoadError

if TYPE_CHECKING:
    from lxml import etree

    from .document import TreeDefinition
    from .reader import XMLDocument

MAX_TREE_DEPTH = 256  # node levels, SubTrees expanded (as the XML nesting limit of one file); real trees stay below 20


@dataclass(slots=True)
class Shape:
    """One definition: its deepest plain element and its SubTree elements, with their depth."""

    plain_depth: int
    plain_elem: etree._Element
    subtrees: list[tuple[str, etree._Element, int]]


@dataclass(slots=True)
class _Depth:
    depth: int
    elem: etree._Element  # the element of this definition on the deepest path
    doc: XMLDocument
    via: str | None  # the SubTree ID that element expands, if any


def _shape(definition: TreeDefinition) -> Shape:
    root = definition.root_element
    best, best_elem = 1, root
    subtrees: list[tuple[str, etree._Element, int]] = []
    stack = [(root, 1)]
    while stack:
        elem, depth = stack.pop()
        if elem.tag == "SubTree":
            subtrees.append((elem.get("ID") or "", elem, depth))
        elif depth > best:
            best, best_elem = depth, elem
        stack.extend((child, depth + 1) for child in elem if isinstance(child.tag, str))
    return Shape(best, best_elem, subtrees)


def _cached_shape(definition: TreeDefinition) -> Shape:
    """A definition's shape never changes: the registry notes it while checking the document
    (document.py); a definition made another way is walked once."""
    shape = getattr(definition, "_depth_shape", None)
    if shape is None:
        shape = _shape(definition)
        with contextlib.suppress(AttributeError):  # a slotted definition: recompute next time
            definition._depth_shape = shape  # type: ignore[attr-defined]
    return shape


def _memo(registry: Any) -> dict[str, _Depth]:
    """Depths already computed for this registry, while its set of definitions is unchanged
    (``validate`` builds every tree of a file: without this, a long chain costs O(n^2))."""
    key = tuple(map(id, registry.trees.values()))
    cached = getattr(registry, "_depth_memo", None)
    if cached is not None and cached[0] == key:
        return cached[1]
    done: dict[str, _Depth] = {}
    with contextlib.suppress(AttributeError):
        registry._depth_memo = (key, done)
    return done


def _depths(trees: dict[str, TreeDefinition], tree_id: str, done: dict[str, _Depth]) -> dict[str, _Depth]:
    """Expanded depth of ``tree_id`` and every tree it reaches (post-order, no recursion).
    Unknown IDs and cycles count as one level: the builder reports those with its own errors."""
    on_path: set[str] = set()
    stack = [tree_id]
    while stack:
        tid = stack[-1]
        if tid in done:
            stack.pop()
            on_path.discard(tid)
            continue
        on_path.add(tid)
        definition = trees[tid]
        shape = _cached_shape(definition)
        pending = [sub for sub, _, _ in shape.subtrees if sub in trees and sub not in done and sub not in on_path]
        if pending:
            stack.extend(dict.fromkeys(pending))
            continue
        best = _Depth(shape.plain_depth, shape.plain_elem, definition.document, None)
        for sub, elem, depth in shape.subtrees:
            inner = done[sub].depth if sub in done else 1
            if depth + inner > best.depth:
                best = _Depth(depth + inner, elem, definition.document, sub)
        done[tid] = best
        stack.pop()
        on_path.discard(tid)
    return done


def check_tree_depth(registry: Any, tree_id: str, limit: int = MAX_TREE_DEPTH) -> None:
    """Raise ``XMLLoadError`` at the element where the expanded tree ``tree_id`` (of the
    factory's ``registry``) gets deeper than ``limit`` levels."""
    trees = registry.trees
    if tree_id not in trees:
        return
    depths = _depths(trees, tree_id, _memo(registry))
    total = depths[tree_id].depth
    if total <= limit:
        return
    chain = [tree_id]
    offset, current = 0, depths[tree_id]  # walk down the deepest path to where it crosses the limit
    while current.via is not None and current.via in depths:
        level = offset + _level_of(current.elem)
        if level + 1 > limit or current.via in chain:
            break
        offset = level
        chain.append(current.via)
        current = depths[current.via]
    shown = chain if len(chain) <= 8 else [*chain[:4], f"({len(chain) - 7} more)", *chain[-3:]]
    path = " -> ".join(shown)
    raise XMLLoadError(f"tree '{tree_id}' is {total} levels deep with its SubTrees expanded (limit {limit}; "
                       f"ticking and halting recurse once per level); deepest path: {path}",
                       file=current.doc.file, line=current.doc.line_of(current.elem), element=current.elem.tag)


def _level_of(elem: etree._Element) -> int:
    """Depth of ``elem`` below its <BehaviorTree> (the tree's root element is 1)."""
    level = 0
    node = elem
    while node is not None and node.tag != "BehaviorTree":
        level += 1
        node = node.getparent()
    return level
