"""Tick cost of bt_runtime vs BT.CPP (via behaviortreepy) vs py_trees, same trees, one run.

Shapes (leaves are Python callbacks in every engine):
  flat100     Sequence of 100 conditions (all SUCCESS)
  deep50      50 nested Sequence/Fallback levels over one condition
  reactive10  ReactiveSequence of 10 conditions + an action left RUNNING
  autonomy52  52 nodes shaped like trees/autonomy.xml: ReactiveSequence root, an e-stop
              guard, 10 Fallback(health check, recover), a ReactiveFallback of 5 guarded
              behaviours, a navigate branch left RUNNING
Also: time to load a 500-node tree from XML.

Prints the median microseconds per tick and the ratios to BT.CPP-py and py_trees.
Run: python bench/tick.py [--repeat N]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repo, ahead of bench/ (bench/sim.py)
import statistics
import time

from bt_runtime import BehaviorTreeFactory, NodeStatus

SUCCESS, FAILURE, RUNNING = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING


def _wrap(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


def flat100() -> str:
    return _wrap("<Sequence>" + "".join(f'<Ok name="c{i}"/>' for i in range(100)) + "</Sequence>")


def deep50() -> str:
    opening, closing = "", ""
    for i in range(50):
        tag = "Sequence" if i % 2 == 0 else "Fallback"
        opening += f"<{tag}>"
        closing = f"</{tag}>" + closing
    return _wrap(opening + '<Ok name="leaf"/>' + closing)


def reactive10() -> str:
    return _wrap("<ReactiveSequence>" + "".join(f'<Ok name="c{i}"/>' for i in range(10))
                 + '<Run name="act"/></ReactiveSequence>')


def autonomy52() -> str:
    health = "".join(f'<Fallback><Ok name="healthy{i}"/><Act name="recover{i}"/></Fallback>' for i in range(10))
    guarded = "".join(f'<Sequence><No name="need{i}"/><Act name="behaviour{i}"/></Sequence>' for i in range(5))
    body = ('<ReactiveSequence><Inverter><No name="estop"/></Inverter>' + health
            + "<ReactiveFallback>" + guarded + '<Sequence><Ok name="nav_ok"/><Run name="navigate"/></Sequence>'
            + "</ReactiveFallback></ReactiveSequence>")
    return _wrap(body)


def big500() -> str:
    groups = "".join(f'<Fallback><No name="n{i}"/><Sequence><Ok name="a{i}"/><Ok name="b{i}" /></Sequence></Fallback>'
                     for i in range(100))
    return _wrap(f"<Sequence>{groups}</Sequence>")


SHAPES = {"flat100": flat100, "deep50": deep50, "reactive10": reactive10, "autonomy52": autonomy52}


def count_nodes(xml: str) -> int:
    from lxml import etree
    return sum(1 for e in etree.fromstring(xml.encode()).iter() if e.tag not in ("root", "BehaviorTree"))


# ---- engines ---------------------------------------------------------------------------------

def ours_tree(xml: str):
    f = BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda n: SUCCESS)
    f.register_simple_condition("No", lambda n: FAILURE)
    f.register_simple_action("Act", lambda n: SUCCESS)
    f.register_simple_stateful_action("Run", lambda n: RUNNING, lambda n: RUNNING, lambda n: None)
    tree = f.create_tree_from_text(xml)
    return tree.tick_exactly_once


def btcpp_tree(xml: str):
    import behaviortreepy as bt
    ok, no, run = bt.NodeStatus.SUCCESS, bt.NodeStatus.FAILURE, bt.NodeStatus.RUNNING
    f = bt.BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda n: ok)
    f.register_simple_condition("No", lambda n: no)
    f.register_simple_action("Act", lambda n: ok)
    f.register_simple_stateful_action("Run", lambda n: run, lambda n: run, lambda n: None)
    tree = f.create_tree_from_text(xml)
    btcpp_tree.keep = tree  # keep alive
    return tree.tick_exactly_once


def pytrees_tree(xml: str):
    """Translate our XML shapes into py_trees (memoryless composites = BT.CPP semantics)."""
    import py_trees
    from lxml import etree

    Status = py_trees.common.Status

    class Leaf(py_trees.behaviour.Behaviour):
        def __init__(self, name: str, status):
            super().__init__(name)
            self._status = status

        def update(self):
            return self._status

    def build(e):
        tag = e.tag
        name = e.get("name", tag)
        if tag == "Ok":
            return Leaf(name, Status.SUCCESS)
        if tag == "No":
            return Leaf(name, Status.FAILURE)
        if tag == "Act":
            return Leaf(name, Status.SUCCESS)
        if tag == "Run":
            return Leaf(name, Status.RUNNING)
        kids = [build(c) for c in e]
        if tag in ("Sequence",):
            return py_trees.composites.Sequence(name, memory=True, children=kids)
        if tag == "ReactiveSequence":
            return py_trees.composites.Sequence(name, memory=False, children=kids)
        if tag == "Fallback":
            return py_trees.composites.Selector(name, memory=True, children=kids)
        if tag == "ReactiveFallback":
            return py_trees.composites.Selector(name, memory=False, children=kids)
        if tag == "Inverter":
            return py_trees.decorators.Inverter(name, child=kids[0])
        raise ValueError(tag)

    root = build(etree.fromstring(xml.encode())[0][0])
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    return root.tick_once


def measure(tick, repeat: int, inner: int) -> float:
    """Median microseconds per tick over ``repeat`` batches of ``inner`` ticks."""
    for _ in range(inner):
        tick()
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(inner):
            tick()
        samples.append((time.perf_counter() - t0) / inner * 1e6)
    return statistics.median(samples)


def _time_loads(load, repeat: int) -> tuple[float, float]:
    """Median and 90th percentile (ms) of `repeat` loads, after a warm-up of five."""
    for _ in range(5):
        load()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        load()
        times.append((time.perf_counter() - t0) * 1e3)
    times.sort()
    return statistics.median(times), times[int(0.9 * (len(times) - 1))]


def measure_load(repeat: int) -> tuple[tuple[float, float], tuple[float, float] | None, int]:
    xml = big500()
    n = count_nodes(xml)
    f = BehaviorTreeFactory()
    for name in ("Ok", "No"):
        f.register_simple_condition(name, lambda node: SUCCESS)
    ours = _time_loads(lambda: f.create_tree_from_text(xml), repeat)
    try:
        import behaviortreepy as bt
    except ImportError:
        return ours, None, n
    g = bt.BehaviorTreeFactory()
    for name in ("Ok", "No"):
        g.register_simple_condition(name, lambda node: bt.NodeStatus.SUCCESS)
    return ours, _time_loads(lambda: g.create_tree_from_text(xml), repeat), n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--inner", type=int, default=2000)
    parser.add_argument("--load-repeat", type=int, default=101, help="timed loads of the 500-node tree")
    args = parser.parse_args()
    engines = {"bt_runtime": ours_tree, "BT.CPP-py": btcpp_tree, "py_trees": pytrees_tree}
    print(f"{'shape':<12}{'nodes':>6}" + "".join(f"{e:>14}" for e in engines)
          + f"{'vs BT.CPP':>11}{'vs py_trees':>13}")
    for shape, make in SHAPES.items():
        xml = make()
        results = {}
        for engine, build in engines.items():
            try:
                results[engine] = measure(build(xml), args.repeat, args.inner)
            except ImportError:
                results[engine] = None
        ours = results["bt_runtime"]
        row = f"{shape:<12}{count_nodes(xml):>6}"
        row += "".join(f"{results[e]:>12.2f}us" if results[e] is not None else f"{'n/a':>14}" for e in engines)
        for peer in ("BT.CPP-py", "py_trees"):
            row += f"{ours / results[peer]:>11.2f}x" if results[peer] else f"{'n/a':>11}"
        print(row)
    (ours_ms, ours_p90), theirs, n = measure_load(max(5, args.load_repeat))
    peer = (f"; BT.CPP-py {theirs[0]:.2f} ms (p90 {theirs[1]:.2f}; ratio {ours_ms / theirs[0]:.2f}x)"
            if theirs else "")
    print(f"load {n}-node tree from XML: bt_runtime {ours_ms:.2f} ms (p90 {ours_p90:.2f}){peer}")
    print("(ratio < 1 means bt_runtime is faster; medians of per-tick microseconds)")


if __name__ == "__main__":
    main()
