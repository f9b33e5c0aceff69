"""Interleaved A/B of the ros2 shape between two checkouts: the CPU figures of a change.

One ``sim-robot`` (from checkout A) on loopback DDS; measurement processes alternate between
the checkouts (A B, B A, ...), each running ``bench/loop.py``'s ``run_one`` from its own tree
(idle, or driving with ``--drive``) for ``--windows`` windows of ``--seconds`` s after an
unmeasured first connection. Prints every window, then median (range) per checkout of: CPU %
of a core (total, event loop, DDS threads), the loop's CPU per tick and lateness p50/p99, the
ratio B/A, and the load average during the run. A checkout may be written ``DIR@STREAMS`` to
set ``deliver_at_tick`` there (``@`` alone: none).

Run: python bench/loop_ab.py /path/to/before /path/to/after [--pairs 6] [--seconds 5] [--windows 2] [--drive]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

MEASURE = """
import json, os, sys
sys.path.insert(0, os.getcwd()); sys.path.insert(0, os.path.join(os.getcwd(), "bench"))
import loop as bl
from bt_runtime.logging_setup import quiet_logging
quiet_logging("error")
domain, seconds, windows, drive = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "1"
if os.environ.get("BENCH_DELIVER_AT_TICK") is not None:
    bl.DELIVER_AT_TICK = [x for x in os.environ["BENCH_DELIVER_AT_TICK"].split(",") if x]
robot = type("Robot", (), {"domain": domain})()
bl.run_one("ros2", robot, 0.5, 1.2, "efficient", None)
for w in range(windows):
    out = bl.run_one("ros2", robot, seconds, 1.5, "efficient", bl.GOALS[w % 2] if drive else None)
    st, threads = out["stats"], out["threads"]
    p = st.lateness_percentiles((50, 99))
    print(json.dumps({"cpu": out["cpu"] * 100, "loop": threads.get("loop", 0) * 100, "dds": threads.get("other", 0) * 100,
                      "loop_us": threads.get("loop", 0) * out["wall"] / max(1, st.count) * 1e6,
                      "p50": p["p50"] * 1e3, "p99": p["p99"] * 1e3}), flush=True)
"""
KEYS = ("cpu", "loop", "dds", "loop_us", "p50", "p99")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--pairs", type=int, default=6)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--windows", type=int, default=2)
    parser.add_argument("--drive", action="store_true")
    parser.add_argument("--domain", type=int, default=229)
    args = parser.parse_args()
    checkouts = {}
    for spec in (args.a, args.b):
        path, _, deliver = spec.partition("@")
        checkouts[spec] = (str(Path(path).resolve()), deliver if "@" in spec else None)
    root_a = checkouts[args.a][0]
    sys.path.insert(0, root_a)
    from bt_runtime.runtime.ros2 import dds

    env = dict(os.environ, CYCLONEDDS_URI=os.environ.get("CYCLONEDDS_URI") or dds.loopback_config())
    env.pop("PYTHONPATH", None)
    robot = subprocess.Popen([sys.executable, "-m", "bt_runtime", "sim-robot", "--loopback", "--nav-autostart",
                              "--domain", str(args.domain), "--duration", "36000"], cwd=root_a,
                             env=dict(env, PYTHONPATH=root_a), stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             text=True)
    if "sim-robot ready" not in (robot.stdout.readline() if robot.stdout else ""):
        robot.kill()
        raise SystemExit("sim-robot did not start")
    rows: dict[str, list[dict]] = {args.a: [], args.b: []}
    loads = [os.getloadavg()[0]]
    try:
        for i in range(args.pairs):
            for spec in (args.a, args.b) if i % 2 == 0 else (args.b, args.a):
                path, deliver = checkouts[spec]
                e = dict(env) if deliver is None else dict(env, BENCH_DELIVER_AT_TICK=deliver)
                out = subprocess.run([sys.executable, "-c", MEASURE, str(args.domain), str(args.seconds),
                                      str(args.windows), "1" if args.drive else "0"],
                                     cwd=path, env=e, capture_output=True, text=True)
                got = [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]
                if not got:
                    print(f"pair {i} {spec}: failed\n{out.stderr[-1500:]}")
                    continue
                rows[spec].extend(got)
                print(f"pair {i} {spec}: " + "  ".join(f"{r['cpu']:.2f} ({r['loop']:.2f} + {r['dds']:.2f}) "
                                                       f"p99 {r['p99']:.2f} ms" for r in got), flush=True)
            loads.append(os.getloadavg()[0])
    finally:
        robot.terminate()
        robot.wait(10)
    print(f"\n{'':>8}  {'A':>22}  {'B':>22}  B/A   (A {args.a}, B {args.b}; {'driving' if args.drive else 'idle'})")
    for key in KEYS:
        a, b = ([r[key] for r in rows[s]] for s in (args.a, args.b))
        if not a or not b:
            continue
        print(f"{key:>8}  " + "  ".join(f"{statistics.median(v):8.2f} ({min(v):.2f}-{max(v):.2f})".rjust(22)
                                       for v in (a, b)) + f"  {statistics.median(b) / max(1e-9, statistics.median(a)):.3f}")
    print("load average (1 min) during: " + " ".join(f"{x:.2f}" for x in loads))


if __name__ == "__main__":
    main()
