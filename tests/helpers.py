"""Small helpers shared by the runtime and node tests."""

from __future__ import annotations


def tree_xml(body: str) -> str:
    """A one-tree BT.CPP v4 document whose main tree ``Main`` is ``body``."""
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


IDLE_TREE = tree_xml('<KeepRunningUntilFailure><AlwaysSuccess/></KeepRunningUntilFailure>')


# DDS domain ids for the tests: 10..99. Their RTPS ports (7400 + 250 * id + ...) stay below Linux's
# ephemeral port range (32768..), where another socket could hold one; 0 (ROS' default) and small
# ids are left to users; 100..229 were computed from the pid before this allocator existed.
_FIRST_DOMAIN, _DOMAINS = 10, 90
_held_domains: dict[int, object] = {}


def dds_domain() -> int:
    """A DDS domain id that no other test of this run, and no other test run on this machine
    (another pytest, an xdist worker), is using: two tests that shared a domain would see each
    other's robots. Held by an exclusive lock on a file per id until this process ends, never
    handed out twice by it (a killed robot's DDS participant lingers for its lease)."""
    import fcntl
    import os
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.gettempdir()) / f"bt_runtime_dds_domains_{os.getuid()}"
    folder.mkdir(exist_ok=True)
    start = os.getpid() % _DOMAINS  # concurrent runs start apart, so they rarely probe the same files
    for i in range(_DOMAINS):
        domain = _FIRST_DOMAIN + (start + i) % _DOMAINS
        if domain in _held_domains:
            continue
        lock = open(folder / f"{domain}.lock", "w")  # noqa: SIM115 - held (open) until the process exits
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        _held_domains[domain] = lock
        return domain
    raise RuntimeError(f"every DDS domain id {_FIRST_DOMAIN}..{_FIRST_DOMAIN + _DOMAINS - 1} is in use "
                       f"(locks in {folder})")


class SimRobotProcess:
    """``sim-robot`` in its own process on DDS domain ``domain`` (the DDS end-to-end tests).

    Its stderr goes to a temporary file, not a pipe: a pipe nobody reads fills up with the
    robot's warnings and blocks it mid-run; the file is read back if the robot fails to start."""

    def __init__(self, domain: int, *args: str, duration: float = 80.0):
        import os
        import subprocess
        import sys
        import tempfile

        from tests.paths import ROOT

        env = dict(os.environ, PYTHONPATH=str(ROOT))
        self._stderr = tempfile.TemporaryFile(mode="w+", encoding="utf-8")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "bt_runtime.cli.sim_robot", "--domain", str(domain), "--duration",
             f"{duration:g}", *args], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=self._stderr, text=True)

    async def ready(self, timeout: float = 30.0) -> None:
        import asyncio

        loop = asyncio.get_running_loop()
        line = await asyncio.wait_for(loop.run_in_executor(None, self.proc.stdout.readline), timeout)
        if "sim-robot ready" not in line:
            self.stop(close=False)
            self._stderr.seek(0)
            errors = self._stderr.read()[-2000:]
            self._stderr.close()
            raise AssertionError(f"sim-robot did not start: {line!r} {errors}")

    def kill(self) -> None:
        """SIGKILL: the robot vanishes without a goodbye (its DDS participant lingers for its lease)."""
        self.proc.kill()
        self.proc.wait(10)

    def stop(self, close: bool = True) -> None:
        import contextlib
        import subprocess

        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.kill()
        with contextlib.suppress(Exception):
            self.proc.stdout.close()
        if close:
            with contextlib.suppress(Exception):
                self._stderr.close()


async def wait_until(predicate, timeout: float, what: str) -> None:
    """Poll ``predicate`` on the wall clock until true; AssertionError naming ``what`` after ``timeout`` s."""
    import asyncio
    import time

    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.02)


# --- a tree that ignores obstacles (the safety-zone tests: the gate's zones must stop it) -----

# one collision_monitor stop zone 0.3 m ahead of the base (the safety-zone tests in the
# simulator and over DDS)
STOP_ZONE_YAML = """\
collision_monitor:
  ros__parameters:
    source_timeout: 1.0
    polygons: ["PolygonStop"]
    PolygonStop:
      type: "polygon"
      points: "[[0.3, 0.12], [0.3, -0.12], [0.0, -0.12], [0.0, 0.12]]"
      action_type: "stop"
      min_points: 4
    observation_sources: ["scan"]
    scan: {type: "scan", topic: "scan"}
"""

BLIND_TREE = tree_xml("""
  <Parallel success_count="-1" failure_count="1">
    <KeepRunningUntilFailure><DriveBlindly speed="0.22"/></KeepRunningUntilFailure>
    <KeepRunningUntilFailure><ForceSuccess>
      <SafetyZoneTriggered action="stop" triggered_zone="{zone}" triggered_action="{action}"/>
    </ForceSuccess></KeepRunningUntilFailure>
  </Parallel>""")


def register_blind_driving(factory) -> None:
    """The node library plus ``DriveBlindly`` (straight ahead every tick, whatever is there)."""
    import nodes
    from bt_runtime import NodeStatus, SyncActionNode
    from bt_runtime.ports import input_port

    class DriveBlindly(SyncActionNode):
        @classmethod
        def provided_ports(cls):
            return [input_port("speed", float, 0.2)]

        def tick(self):
            self.context.gate.set_tree_command(self.get_input("speed"), 0.0)
            return NodeStatus.SUCCESS

    nodes.register_all(factory)
    factory.register_node_type(DriveBlindly)


# --- docs/ros2.md's first block: sim-robot, then run on it (test_documented_command.py runs it) ---

DOCUMENTED_ROBOT = "python -m bt_runtime sim-robot --loopback &"  # the block's first line


def documented_ros2_commands() -> tuple[list[str], list[str]]:
    """The two commands of docs/ros2.md's block that starts with ``DOCUMENTED_ROBOT``, as argument
    lists with this interpreter for ``python``; AssertionError if the block is anything else."""
    import shlex
    import sys

    from tests.paths import ROOT

    text = (ROOT / "docs" / "ros2.md").read_text(encoding="utf-8")
    start = text.index("```bash\n" + DOCUMENTED_ROBOT + "\n")
    block = text[start:text.index("```\n", start + 8)].splitlines()[1:]
    assert len(block) == 2 and block[0] == DOCUMENTED_ROBOT, block
    robot, run = shlex.split(block[0].removesuffix("&")), shlex.split(block[1])
    assert robot[0] == run[0] == "python" and run[1:5] == ["-m", "bt_runtime", "run", "trees/autonomy.xml"], block
    return [sys.executable, *robot[1:]], [sys.executable, *run[1:]]


def stop_slow_approach_zones(clock, min_points: int):
    """Safety zones of the gate tests: a stop polygon, a slowdown circle and an approach circle
    (collision_monitor's three kinds) on the ``scan`` source, each acting at ``min_points``."""
    from bt_runtime.runtime.safety_zones import SafetyZones
    from bt_runtime.runtime.safety_zones_config import from_parameters

    params = {"source_timeout": 0.3, "polygons": ["Stop", "Slow", "Approach"],
              "Stop": {"type": "polygon", "points": "[[0.3, 0.2], [0.3, -0.2], [0.0, -0.2], [0.0, 0.2]]",
                       "action_type": "stop", "min_points": min_points},
              "Slow": {"type": "circle", "radius": 0.8, "action_type": "slowdown", "slowdown_ratio": 0.5,
                       "min_points": min_points},
              "Approach": {"type": "circle", "radius": 0.2, "action_type": "approach", "min_points": min_points,
                           "time_before_collision": 1.0, "simulation_time_step": 0.1},
              "observation_sources": ["scan"], "scan": {"type": "scan", "topic": "scan"}}
    return SafetyZones(from_parameters(params, "test"), clock=clock)
