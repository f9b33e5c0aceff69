"""Stand-ins for node types known only from a TreeNodesModel (e.g. when validating Nav2's
trees without Nav2): they load and check ports like the real node, and refuse to tick."""

from __future__ import annotations

from functools import cache

from ..errors import LogicError
from ..node import ActionNodeBase, ConditionNode, ControlNode, DecoratorNode, TreeNode
from ..status import NodeStatus, NodeType

_BASES = {NodeType.ACTION: ActionNodeBase, NodeType.CONDITION: ConditionNode,
          NodeType.CONTROL: ControlNode, NodeType.DECORATOR: DecoratorNode}


@cache
def placeholder_class(node_type: NodeType) -> type[TreeNode]:
    base = _BASES.get(node_type, ActionNodeBase)

    def tick(self: TreeNode) -> NodeStatus:
        raise LogicError(f"'{self.config.registration_id}' is only known from a TreeNodesModel; "
                         "register an implementation to tick it")

    return type(f"Placeholder{base.__name__}", (base,), {"tick": tick})
