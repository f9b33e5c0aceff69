"""Cold load time of this checkout's bt_runtime against another checkout's, and both against
BT.CPP-py: the before/after table of a load change, measured in one run.

Each round runs one subprocess per checkout (alternating which goes first), so machine load
hits both alike; each subprocess loads every tree ``--loads`` times cold (compiled scripts
forgotten first, as in a fresh process), interleaved with BT.CPP-py loads of the same XML,
with the garbage collector on. The trees come from this checkout's bench/treegen.py and the
loading code from bench/tick.py (``ours_tree``, ``btcpp_tree``), run against each checkout's
bt_runtime. Printed per tree: us per node (median over rounds of each round's median), the
ratio new/old, BT.CPP-py's us per node, each checkout's ratio to BT.CPP-py (median and range
over rounds), and 2nd/1st (later loads over the first load of a subprocess: about 1 when a
dropped tree is freed at once), and the first tick of a loaded tree (us per node: work a load
leaves to the first tick shows there).

Tree specs (``--trees``, comma-separated): ``shape:nodes`` for a bench/treegen.py shape, plain
(``mixed:1000``) or with a unique name on every node as Groot2 writes it (``mixed-named:1000``);
``nav2`` for Nav2's stock trees (bench/nav2_shapes.py, one row each); ``autonomy`` for
trees/autonomy.xml reduced the same way (its own leaves become ``Ok``/``Act``, names kept), so
BT.CPP-py can load it too. A first tick that raises (a script reading an entry nobody wrote)
is left out of the tick column.

Run: python bench/load_compare.py --other /path/to/old/checkout [--trees mixed:1000,...]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parent
DEFAULT_TREES = ("mixed:100,mixed:1000,mixed:5000,mixed:20000,builtin:1000,builtin:10000,scripts:1000,"
                 "scripts:10000,precond:1000,precond:10000,bbheavy:1000,bbheavy:10000,mixed-named:1000,"
                 "mixed-named:5000,scripts-named:1000,scripts-named:10000,builtin-named:1000,nav2,autonomy")

# Runs in a subprocess whose working directory is the checkout measured.
WORKER = """
import gc, json, os, sys, time
sys.path[:0] = [os.getcwd(), sys.argv[1]]
import bt_runtime  # this checkout's, before tick.py puts its own repository first on sys.path
import tick
assert os.path.dirname(os.path.dirname(bt_runtime.__file__)) == os.getcwd(), bt_runtime.__file__
from load_compare import trees_for
gc.enable()
clock = time.process_time

def first_tick(run, into):
    t0 = clock()
    try:
        run()
    except Exception:
        return
    into.append(clock() - t0)

for label, xml, preset, nodes in trees_for("mixed:10"):
    tick.ours_tree(xml, preset)
    tick.btcpp_tree(xml, preset)
out = {}
for spec in sys.argv[2].split(","):
  for label, xml, preset, nodes in trees_for(spec):
    ours, peer, first, ours_tick, peer_tick = [], [], None, [], []
    for i in range(int(sys.argv[3]) + 1):
        tick._clear_script_cache()
        t0 = clock(); run = tick.ours_tree(xml, preset); elapsed = clock() - t0
        first_tick(run, ours_tick)
        if i == 0:
            first = elapsed
        else:
            ours.append(elapsed)
        t0 = clock(); run = tick.btcpp_tree(xml, preset); peer.append(clock() - t0)
        first_tick(run, peer_tick)
    tick.ours_tree.keep = None
    out[label] = {"nodes": nodes, "ours": ours, "peer": peer[1:], "first": first,
                  "ours_tick": ours_tick[1:] or [0.0], "peer_tick": peer_tick[1:] or [0.0]}
print(json.dumps(out))
"""


def trees_for(spec: str) -> list[tuple[str, str, dict, int]]:
    """(row label, XML, blackboard preset, node count) for one ``--trees`` entry."""
    from tick import count_nodes

    if spec == "nav2":
        from nav2_shapes import stock_trees

        return [(name, xml, {}, count_nodes(xml)) for name, xml in stock_trees()]
    if spec == "autonomy":
        from nav2_shapes import reduced_file

        xml = reduced_file(BENCH.parent / "trees" / "autonomy.xml")
        return [("autonomy.xml", xml, {}, count_nodes(xml))]
    from treegen import SHAPES

    shape, size = spec.split(":")
    g = SHAPES[shape](int(size))
    return [(spec, g.xml, g.preset, g.nodes)]


def _run(checkout: Path, trees: str, loads: int) -> dict:
    done = subprocess.run([sys.executable, "-c", WORKER, str(BENCH), trees, str(loads)], cwd=checkout,
                          capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"worker in {checkout} failed:\n{done.stderr}")
    return json.loads(done.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--other", required=True, type=Path, help="the checkout to compare against (old)")
    parser.add_argument("--trees", default=DEFAULT_TREES, help="shape:nodes,... (bench/treegen.py shapes)")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--loads", type=int, default=5, help="cold loads per tree per subprocess")
    args = parser.parse_args()
    checkouts = {"old": args.other.resolve(), "new": BENCH.parent}
    rows: dict[str, dict[str, dict[str, list[float]]]] = {"old": {}, "new": {}}
    nodes: dict[str, int] = {}
    print(f"load average at start: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    for r in range(args.rounds):
        for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
            for spec, d in _run(checkouts[name], args.trees, args.loads).items():
                nodes[spec] = d["nodes"]
                row = rows[name].setdefault(spec, {"ours": [], "peer": [], "ratio": [], "second": [], "tick": [],
                                                   "peer_tick": []})
                ours, peer = statistics.median(d["ours"]), statistics.median(d["peer"])
                row["ours"].append(ours)
                row["peer"].append(peer)
                row["ratio"].append(ours / peer)
                row["second"].append(ours / d["first"])
                row["tick"].append(statistics.median(d["ours_tick"]))
                row["peer_tick"].append(statistics.median(d["peer_tick"]))
    print(f"load average at end: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    med = statistics.median
    w = max(map(len, nodes)) + 1
    print(f"{'tree':<{w}}{'nodes':>7} | {'old us/n':>9}{'new us/n':>9}{'new/old':>8} | {'BT us/n':>8} | "
          f"{'old/BT.CPP':>16}{'new/BT.CPP':>16} | {'2nd/1st old, new':>16} | 1st tick us/n old, new, BT")
    for spec, n in nodes.items():
        old, new = rows["old"][spec], rows["new"][spec]
        span = lambda v: f"{med(v):.2f} ({min(v):.1f}-{max(v):.1f})"  # noqa: E731
        print(f"{spec:<{w}}{n:>7} | {med(old['ours']) * 1e6 / n:>9.2f}{med(new['ours']) * 1e6 / n:>9.2f}"
              f"{med(new['ours']) / med(old['ours']):>8.2f} | {med(old['peer'] + new['peer']) * 1e6 / n:>8.2f} | "
              f"{span(old['ratio']):>16}{span(new['ratio']):>16} | "
              f"{med(old['second']):>7.2f}, {med(new['second']):.2f} | "
              f"{med(old['tick']) * 1e6 / n:.2f}, {med(new['tick']) * 1e6 / n:.2f}, "
              f"{med(old['peer_tick'] + new['peer_tick']) * 1e6 / n:.2f}")


if __name__ == "__main__":
    main()
