"""BT.CPP's own tree for the Groot2 comparisons: the demo XML with the demo leaves, in behaviortreepy."""

from __future__ import annotations

from groot.testing import DEMO_XML as XML
from groot.testing import DemoBehaviour, register_demo


def reference_tree():
    """(tree, blackboard) of the demo tree in BT.CPP; needs behaviortreepy."""
    import behaviortreepy as bt

    bb = bt.Blackboard.create(None)
    bb.set_string("goal_a", "kitchen")
    bb.set_string("goal_b", "dock")
    bb.set_double("battery", 0.97)
    bb.set_int("ticks", 0)
    bb.set_bool("skip_flag", False)
    f = bt.BehaviorTreeFactory()
    register_demo(f, DemoBehaviour(bb.set_int, bb.set_bool, lambda n: n.uid()), bt.NodeStatus)
    return f.create_tree_from_text(XML, bb), bb
