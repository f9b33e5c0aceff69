"""Text views of a tree for people: BT.CPP's ``printTreeRecursively``."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TextIO

if TYPE_CHECKING:
    from .node import TreeNode

_RULE = "-" * 16


def print_tree_recursively(root: TreeNode, stream: TextIO | None = None) -> None:
    """Write a rule, each node's name indented three spaces per level (through subtrees),
    and a closing rule, as BT.CPP does; to stdout unless ``stream`` is given."""
    out = sys.stdout if stream is None else stream

    def visit(node: TreeNode, depth: int) -> None:
        out.write("   " * depth + node.name + "\n")
        for child in node.children_nodes():
            visit(child, depth + 1)

    out.write(_RULE + "\n")
    visit(root, 0)
    out.write(_RULE + "\n")
