"""Tick cost of bt_runtime vs BT.CPP (via behaviortreepy) vs py_trees, same trees, one run.

Shapes (leaves are Python callbacks in every engine):
  flat100     Sequence of 100 conditions (all SUCCESS)
  deep50      50 nested Sequence/Fallback levels over one condition
  reactive10  ReactiveSequence of 10 conditions + an action left RUNNING
  autonomy52  52 nodes shaped like trees/autonomy.xml: ReactiveSequence root, an e-stop
              guard, 10 Fallback(health check, recover), a ReactiveFallback of 5 guarded
              behaviours, a navigate branch left RUNNING
Generated shapes (bench/treegen.py), at 10 / 100 / 1 000 / 10 000 nodes: Python leaves,
built-in leaves, scripts, pre/post conditions, blackboard-heavy 3-level remapped SubTrees,
and mixed trees with every control kind; and Nav2's stock trees (../shared, if present) with
their leaves as callbacks.

Every figure is CPU time (time.process_time) per tick: the engines run interleaved inside
each repetition (so machine load hits them alike), and each row prints the median with the
range (min-max over repetitions) and the ratio of medians to BT.CPP-py and py_trees. Load
time is measured with the garbage collector on, as a user has it.

Run: python bench/tick.py [--quick] [--shapes a,b] [--sizes 10,100] [--repeat N] [--tick-only]
"""

from __future__ import annotations

import argparse
import contextlib
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

def ours_tree(xml: str, preset: dict | None = None):
    from bt_runtime.blackboard import Blackboard

    f = BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda n: SUCCESS)
    f.register_simple_condition("No", lambda n: FAILURE)
    f.register_simple_action("Act", lambda n: SUCCESS)
    f.register_simple_stateful_action("Run", lambda n: RUNNING, lambda n: RUNNING, lambda n: None)
    f.register_simple_decorator("Pass", lambda status, n: status)
    bb = Blackboard.create()
    for key, value in (preset or {}).items():
        bb.set(key, value)
    tree = f.create_tree_from_text(xml, bb)
    ours_tree.keep = tree
    return tree.tick_exactly_once


def btcpp_tree(xml: str, preset: dict | None = None):
    import behaviortreepy as bt
    ok, no, run = bt.NodeStatus.SUCCESS, bt.NodeStatus.FAILURE, bt.NodeStatus.RUNNING
    f = bt.BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda n: ok)
    f.register_simple_condition("No", lambda n: no)
    f.register_simple_action("Act", lambda n: ok)
    f.register_simple_stateful_action("Run", lambda n: run, lambda n: run, lambda n: None)
    f.register_simple_decorator("Pass", lambda status, n: status)
    bb = bt.Blackboard.create(None)
    for key, value in (preset or {}).items():
        if isinstance(value, bool):
            bb.set_bool(key, value)
        elif isinstance(value, str):
            bb.set_string(key, value)
        else:
            bb.set_double(key, float(value))
    tree = f.create_tree_from_text(xml, bb)
    btcpp_tree.keep = (tree, bb)  # keep alive
    return tree.tick_exactly_once


def pytrees_tree(xml: str, preset: dict | None = None):
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
        if tag in ("Act", "AlwaysSuccess"):
            return Leaf(name, Status.SUCCESS)
        if tag == "AlwaysFailure":
            return Leaf(name, Status.FAILURE)
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
        raise NotImplementedError(tag)

    trees = etree.fromstring(xml.encode())
    if len(trees) != 1 or preset:
        raise NotImplementedError("py_trees has no BT.CPP scripts, SubTrees or pre-conditions")
    root = build(trees[0][0])
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    tick_once = root.tick_once

    def tick():
        tick_once()
        return root.status

    return tick


ENGINES = {"bt_runtime": ours_tree, "BT.CPP-py": btcpp_tree, "py_trees": pytrees_tree}


def _inner_for(nodes: int) -> int:
    """Ticks per timed batch: about 2 ms of work, at least one tick."""
    return max(1, 20_000 // max(nodes, 1))


def measure_interleaved(ticks: dict, repeat: int, inner: int) -> dict[str, list[float]]:
    """CPU microseconds per tick of every engine, ``repeat`` batches each, engines interleaved."""
    for tick in ticks.values():
        for _ in range(inner):
            tick()
    samples: dict[str, list[float]] = {name: [] for name in ticks}
    clock = time.process_time
    for _ in range(repeat):
        for name, tick in ticks.items():
            t0 = clock()
            for _ in range(inner):
                tick()
            samples[name].append((clock() - t0) / inner * 1e6)
    return samples


def _build_all(xml: str, preset: dict | None) -> dict:
    ticks = {}
    for name, build in ENGINES.items():
        with contextlib.suppress(ImportError, NotImplementedError):  # an engine that lacks the feature
            ticks[name] = build(xml, preset)
    return ticks


def _check_same_status(ticks: dict, n: int = 3) -> str:
    """Root status of the first ticks in every engine (speed must never change a trace)."""
    seen = {name: [str(getattr(t(), "name", "?")).upper() for _ in range(n)] for name, t in ticks.items()}
    first = next(iter(seen.values()))
    return "" if all(v == first for v in seen.values()) else f"  STATUS DIFFERS {seen}"


def _fmt(samples: list[float] | None) -> str:
    if not samples:
        return f"{'n/a':>26}"
    med = statistics.median(samples)
    return f"{med:>10.2f} ({min(samples):.2f}-{max(samples):.2f})".rjust(26)


def _ratio(ours: list[float], peer: list[float] | None) -> str:
    if not peer:
        return f"{'n/a':>10}"
    return f"{statistics.median(ours) / statistics.median(peer):>9.2f}x"


def _print_header() -> None:
    print(f"{'shape':<22}{'nodes':>7}" + "".join(f"{e + ' us/tick':>26}" for e in ENGINES)
          + f"{'vs BT.CPP':>10}{'vs py_trees':>12}")


def _print_row(shape: str, nodes: int, samples: dict, note: str = "") -> None:
    ours = samples["bt_runtime"]
    print(f"{shape:<22}{nodes:>7}" + "".join(_fmt(samples.get(e)) for e in ENGINES)
          + _ratio(ours, samples.get("BT.CPP-py")) + _ratio(ours, samples.get("py_trees")).rjust(12) + note)


def run_classic(repeat: int) -> None:
    for shape, make in SHAPES.items():
        xml = make()
        ticks = _build_all(xml, None)
        nodes = count_nodes(xml)
        _print_row(shape, nodes, measure_interleaved(ticks, repeat, _inner_for(nodes)), _check_same_status(ticks))


def run_generated(shapes: list[str], sizes: list[int], repeat: int) -> None:
    from treegen import SHAPES as GENERATED

    for shape in shapes:
        for size in sizes:
            g = GENERATED[shape](size)
            ticks = _build_all(g.xml, g.preset)
            note = _check_same_status(ticks)
            _print_row(shape, g.nodes, measure_interleaved(ticks, repeat, _inner_for(g.nodes)), note)


def run_nav2(repeat: int) -> None:
    from nav2_shapes import stock_trees

    for name, xml in stock_trees():
        ticks = _build_all(xml, None)
        nodes = count_nodes(xml)
        _print_row(name[:22], nodes, measure_interleaved(ticks, repeat, _inner_for(nodes)), _check_same_status(ticks))


def _clear_script_cache() -> None:
    """Forget compiled scripts (a fresh process): BT.CPP compiles every script it loads."""
    from bt_runtime.script import compiler

    getattr(compiler, "forget_compiled", compiler.compile_script.cache_clear)()


def _load_cell(samples: list[float], nodes: int) -> str:
    if not samples:
        return f"{'n/a':>32}"
    med = statistics.median(samples)
    return f" {med:.2f} ({min(samples):.2f}-{max(samples):.2f}) {med * 1e3 / nodes:5.1f}".rjust(32)


def load_times(shape: str, sizes: list[int], loads: int) -> None:
    """CPU time to load a tree (GC on, as a user has it), bt_runtime against BT.CPP-py, the
    engines interleaved within each repetition. Each load drops the previous tree, as a
    runtime reloading a tree does. bt_runtime is timed cold (compiled scripts forgotten, as in
    a fresh process) and warm (scripts cached from the previous load). ``2nd/1st`` is the
    median of the later cold loads over the first cold load of that size: above 1 when a
    dropped tree waits for the cyclic collector."""
    import gc

    from treegen import SHAPES as GENERATED

    gc.enable()
    clock = time.process_time
    print(f"\nload time, {shape} trees, GC on, CPU time (median (min-max) of {loads} loads, ms; us per node)")
    print(f"{'nodes':>7}{'bt_runtime cold':>32}{'bt_runtime warm':>32}{'BT.CPP-py':>32}"
          f"{'cold/BT.CPP':>13}{'warm/BT.CPP':>13}{'2nd/1st':>9}")
    warm_up = GENERATED[shape](10)
    for build in (ours_tree, btcpp_tree):  # imports and first-call costs stay out of the figures
        with contextlib.suppress(ImportError):
            build(warm_up.xml, warm_up.preset)
    for size in sizes:
        g = GENERATED[shape](size)
        times: dict[str, list[float]] = {"cold": [], "warm": [], "BT.CPP-py": []}
        first = None
        for _ in range(loads + 1):
            for name in times:
                if name == "cold":
                    _clear_script_cache()
                build = btcpp_tree if name == "BT.CPP-py" else ours_tree
                t0 = clock()
                try:
                    build(g.xml, g.preset)
                except ImportError:
                    continue
                elapsed = (clock() - t0) * 1e3
                if name == "cold" and first is None:
                    first = elapsed
                    continue
                times[name].append(elapsed)
        med = {name: statistics.median(v) for name, v in times.items() if v}
        peer = med.get("BT.CPP-py")
        ratios = (f"{med['cold'] / peer:>12.2f}x{med['warm'] / peer:>12.2f}x" if peer else f"{'':>26}")
        print(f"{g.nodes:>7}" + "".join(_load_cell(times[n], g.nodes) for n in times) + ratios
              + f"{med['cold'] / first:>8.2f}x")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=15, help="timed batches per engine and row")
    parser.add_argument("--shapes", default="leaves,builtin,scripts,precond,bbheavy,mixed")
    parser.add_argument("--sizes", default="10,100,1000,10000")
    parser.add_argument("--load-sizes", default="100,1000,5000,20000")
    parser.add_argument("--loads", type=int, default=7)
    parser.add_argument("--load-shapes", default="mixed", help="generated shapes whose load time is measured")
    parser.add_argument("--load-only", action="store_true", help="only the load-time tables")
    parser.add_argument("--tick-only", action="store_true", help="only the tick tables (no load times)")
    parser.add_argument("--quick", action="store_true", help="sizes 10,100,1000, 5 repetitions, small loads")
    args = parser.parse_args()
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    if args.quick:
        args.sizes, args.repeat, args.load_sizes, args.loads = "10,100,1000", 5, "100,1000,5000", 3
    sizes = [int(s) for s in args.sizes.split(",")]
    if args.load_only:
        for shape in args.load_shapes.split(","):
            load_times(shape, [int(s) for s in args.load_sizes.split(",")], args.loads)
        return
    _print_header()
    run_classic(args.repeat)
    run_generated(args.shapes.split(","), sizes, args.repeat)
    run_nav2(args.repeat)
    for shape in ([] if args.tick_only else args.load_shapes.split(",")):
        load_times(shape, [int(s) for s in args.load_sizes.split(",")], args.loads)
    print("\nCPU time per tick: median (min-max) over repetitions; ratio < 1 means bt_runtime is faster.")


if __name__ == "__main__":
    main()
