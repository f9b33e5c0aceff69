"""The benchmark's generated trees (bench/treegen.py) and Nav2's reduced stock trees tick alike in
bt_runtime and BT.CPP: a benchmark that compared different work would report a false ratio."""

from __future__ import annotations

import sys

import pytest

from tests.paths import ROOT

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle
sys.path.insert(0, str(ROOT / "bench"))

import tick  # noqa: E402
import treegen  # noqa: E402


@pytest.mark.parametrize("shape", sorted(treegen.SHAPES))
def test_generated_shape_ticks_the_same_in_both_engines(shape: str) -> None:
    g = treegen.SHAPES[shape](120)
    ours, theirs = tick.ours_tree(g.xml, g.preset), tick.btcpp_tree(g.xml, g.preset)
    statuses = [(ours().name, theirs().name) for _ in range(4)]
    assert all(a == b for a, b in statuses), statuses
    assert statuses[-1][0] == "SUCCESS"  # the whole tree is walked every tick
    tree, (_, bb) = tick.ours_tree.keep, tick.btcpp_tree.keep
    for key in g.preset:
        if isinstance(g.preset[key], float):
            assert tree.root_blackboard.get(key) == pytest.approx(bb.get_double(key)), key


def test_generated_sizes_are_close_to_asked() -> None:
    for make in treegen.SHAPES.values():
        for n in (100, 1000, 10000):
            assert 0.5 * n <= make(n).nodes <= 1.5 * n + 30


def test_nav2_stock_shapes_tick_the_same() -> None:
    import nav2_shapes

    trees = list(nav2_shapes.stock_trees())
    if not trees:
        pytest.skip("../shared (Nav2's stock trees) is absent")
    for name, xml in trees:
        ours, theirs = tick.ours_tree(xml), tick.btcpp_tree(xml)
        assert [ours().name for _ in range(3)] == [theirs().name for _ in range(3)], name


def test_named_shapes_name_every_node_once() -> None:
    from lxml import etree

    for shape in ("mixed", "scripts", "bbheavy"):
        g = treegen.SHAPES[f"{shape}-named"](200)
        elements = [e for e in etree.fromstring(g.xml).iter() if e.tag not in ("root", "BehaviorTree")]
        names = [e.get("name") for e in elements]
        assert None not in names and len(set(names)) == len(names), shape
        assert g.nodes == treegen.SHAPES[shape](200).nodes


def test_reduced_autonomy_tree_loads_and_ticks_alike() -> None:
    import nav2_shapes

    xml = nav2_shapes.reduced_file(ROOT / "trees" / "autonomy.xml")
    ours, theirs = tick.ours_tree(xml), tick.btcpp_tree(xml)
    assert [ours().name for _ in range(3)] == [theirs().name for _ in range(3)]
