from .nav2 import register_nav2_nodes

__all__ = ["register_nav2_nodes"]
