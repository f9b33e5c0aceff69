"""bt_runtime: BehaviorTree.CPP v4 trees in pure Python, hosted on asyncio."""

from .status import NodeStatus, NodeType, PortDirection

__all__ = ["NodeStatus", "NodeType", "PortDirection"]
__version__ = "0.1.0"
