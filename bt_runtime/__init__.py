"""bt_runtime: BehaviorTree.CPP v4 trees in pure Python, hosted on asyncio.

    from bt_runtime import BehaviorTreeFactory, NodeStatus
    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_file("tree.xml")
    tree.tick_while_running()
"""

from .blackboard import Blackboard
from .errors import (
    BehaviorTreeException,
    BTRuntimeError,
    LogicError,
    NodeExecutionError,
    XMLLoadError,
    XMLLogicError,
    XMLRuntimeError,
)
from .factory import BehaviorTreeFactory
from .node import (
                     AsyncActionNode,
                     ConditionNode,
                     ControlNode,
                     DecoratorNode,
                     NodeConfig,
                     StatefulActionNode,
                     SyncActionNode,
                     TreeNode,
)
from .ports import bidirectional_port, input_port, output_port
from .printing import print_tree_recursively
from .status import NodeStatus, NodeType, PortDirection
from .tree import Tree

__all__ = [
    "AsyncActionNode", "BTRuntimeError", "BehaviorTreeException", "BehaviorTreeFactory", "Blackboard",
    "ConditionNode", "ControlNode", "DecoratorNode", "LogicError", "NodeConfig", "NodeExecutionError",
    "NodeStatus", "NodeType", "PortDirection", "StatefulActionNode", "SyncActionNode", "Tree", "TreeNode",
    "XMLLoadError", "XMLLogicError", "XMLRuntimeError", "bidirectional_port", "input_port", "output_port", "print_tree_recursively",
]
__version__ = "0.1.0"
