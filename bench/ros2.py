"""Latency of the ROS 2 driver over real DDS on loopback (two processes, one machine).

* scan -> tree: a robot process publishes 400-beam LaserScans (a rosbot2 lidar) stamped with
  the wall clock just before ``write``; the runtime process measures when the converted scan
  reaches a subscriber of ``Ros2Driver`` on its event loop (what the supervisor, backup and tree
  see).
* gate -> robot: the runtime process calls ``Ros2Driver.send_velocity`` (what the decision gate
  calls) at 100 Hz with ``cmd_vel`` as TwistStamped, stamped at the call; the robot process
  measures when the command reaches its loop (where sim-robot hands it to the base).

    python bench/ros2.py [--samples 1000] [--rate 100]

Prints both distributions (ms). Target: p99 <= 5 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402


def stats(ms: list[float]) -> dict[str, float]:
    a = np.asarray(ms, dtype=float)
    return {"n": int(a.size), "p50": float(np.percentile(a, 50)), "p90": float(np.percentile(a, 90)),
            "p99": float(np.percentile(a, 99)), "max": float(a.max()), "mean": float(a.mean())}


def line(name: str, s: dict[str, float]) -> str:
    return (f"{name:<16} n={s['n']:5d}  p50 {s['p50']:.3f}  p90 {s['p90']:.3f}  p99 {s['p99']:.3f}  "
            f"max {s['max']:.3f}  mean {s['mean']:.3f} ms")


async def robot_side(domain: int, samples: int, rate: float) -> dict:
    from bt_runtime.runtime.ros2 import dds, idl

    node = dds.DdsNode(domain)
    cmd_ms: list[float] = []

    def on_cmd(msgs: list, _now: float) -> None:
        now = time.time()
        for m in msgs:
            cmd_ms.append((now - m.header.stamp.to_sec()) * 1e3)

    node.subscription("cmd_vel", idl.TwistStamped, dds.QosProfile(reliable=False, depth=10), on_cmd)
    writer = node.publisher("scan", idl.LaserScan, dds.SENSOR_DATA)
    ranges = np.linspace(0.2, 7.5, 400).astype(np.float32).tolist()
    while not writer.get_matched_subscriptions():
        await asyncio.sleep(0.01)
    await asyncio.sleep(1.0)  # let the other side finish discovery too
    loop = asyncio.get_running_loop()
    t0 = loop.time()
    for k in range(samples):
        await asyncio.sleep(max(0.0, t0 + k / rate - loop.time()))
        scan = idl.LaserScan(angle_min=0.0, angle_max=6.2675, angle_increment=0.0157, range_min=0.15,
                             range_max=8.0, ranges=ranges)
        scan.header.stamp = idl.Time.from_sec(time.time())
        writer.write(scan)
    await asyncio.sleep(1.0)
    node.close()
    return {"cmd_ms": cmd_ms}


async def runtime_side(domain: int, samples: int, rate: float, child: subprocess.Popen) -> tuple[list, list]:
    from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver

    config = Ros2Config(domain_id=domain, navigation={"enabled": False},
                        topics={"cmd_vel": {"stamped": True, "qos": {"reliability": "reliable"}}})
    driver = Ros2Driver(config)
    scan_ms: list[float] = []

    def on_scan(_scan) -> None:
        scan_ms.append((time.time() - driver.header_stamps["scan"]) * 1e3)

    driver.subscribe("scan", on_scan)
    await driver.start()
    loop = asyncio.get_running_loop()
    t0 = loop.time()
    k = 0
    while child.poll() is None:  # the gate's 100 Hz until the robot side is done
        k += 1
        await asyncio.sleep(max(0.0, t0 + k / rate - loop.time()))
        driver.send_velocity(0.25, 0.0)
    await driver.stop()
    return scan_ms


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--rate", type=float, default=100.0)
    parser.add_argument("--domain", type=int, default=None)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args()
    from bt_runtime.runtime.ros2 import dds

    os.environ.setdefault("CYCLONEDDS_URI", dds.loopback_config())
    domain = args.domain if args.domain is not None else 200 + os.getpid() % 30
    if args.child:
        result = asyncio.run(robot_side(domain, args.samples, args.rate))
        print(json.dumps(result))
        return 0
    child = subprocess.Popen([sys.executable, __file__, "--child", "--domain", str(domain), "--samples",
                              str(args.samples), "--rate", str(args.rate)], stdout=subprocess.PIPE, text=True)
    scan_ms = asyncio.run(runtime_side(domain, args.samples, args.rate, child))
    out, _ = child.communicate(timeout=60)
    cmd_ms = json.loads(out.strip().splitlines()[-1])["cmd_ms"]
    result = {"scan_to_tree": stats(scan_ms), "gate_to_robot": stats(cmd_ms)}
    if args.json:
        print(json.dumps(result))
    else:
        print(f"ROS 2 driver latency over DDS on loopback (Cyclone DDS, 2 processes), {args.rate:g} Hz")
        print(line("scan -> tree", result["scan_to_tree"]))
        print(line("gate -> robot", result["gate_to_robot"]))
        worst = max(result["scan_to_tree"]["p99"], result["gate_to_robot"]["p99"])
        print(f"target p99 <= 5 ms: {'met' if worst <= 5.0 else 'NOT met'} (worst p99 {worst:.3f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
