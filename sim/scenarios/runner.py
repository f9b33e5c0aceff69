"""Run one scenario once, with or without the autonomy layer, and judge it.

* ``with``: the full runtime (supervisor, backup, decision gate) and ``trees/autonomy.xml``,
  ticking continuously; goals are handed over on the blackboard.
* ``without``: the navigation stack alone, orchestrated the way Nav2 does it:
  ``trees/navigation.xml`` (Nav2's navigate-with-replanning-and-recovery) ticked once per
  goal, navigation commands straight to the base (the gate in pass-through), nobody acting on
  component health. Same world, seed and faults.

Randomness (start pose jitter, fault time jitter, every sensor's noise) comes from the seed.
"""

from __future__ import annotations

import asyncio
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.clock import run as run_loop
from bt_runtime.runtime.config import GateConfig, RuntimeConfig, TickConfig
from bt_runtime.runtime.messages import Pose2D

from ..driver import SimDriver
from ..faults import parse_fault
from ..robot import load_profile
from .judge import Verdict, judge
from .record import GoalRecord, RecordingNavigation, RunRecord
from .spec import NAV_FAULTS, ScenarioSpec, load_scenario

ROOT = Path(__file__).resolve().parents[2]
TREES = {"with": ROOT / "trees" / "autonomy.xml", "without": ROOT / "trees" / "navigation.xml"}
MODES = ("with", "without")
TERMINAL = ("SUCCEEDED", "ABORTED", "REFUSED")


@dataclass
class RunResult:
    scenario: str
    mode: str
    seed: int
    success: bool
    verdicts: list[Verdict]
    sim_time: float
    wall_time: float
    record: RunRecord | None = field(default=None, repr=False)

    @property
    def reasons(self) -> list[str]:
        return [f"{v.criterion}: {v.reason}" for v in self.verdicts if not v.passed]

    def to_dict(self) -> dict[str, Any]:
        return {"scenario": self.scenario, "mode": self.mode, "seed": self.seed, "success": self.success,
                "sim_time": round(self.sim_time, 3), "wall_time": round(self.wall_time, 4),
                "verdicts": [{"criterion": v.criterion, "passed": v.passed, "reason": v.reason}
                             for v in self.verdicts]}


def _register(factory) -> None:
    import nodes

    nodes.register_all(factory)


def runtime_config(mode: str) -> RuntimeConfig:
    """``with``: the full layer; ``without``: the gate in pass-through, the tree ticked per goal."""
    if mode == "with":
        return RuntimeConfig()
    return RuntimeConfig(gate=GateConfig(passthrough=True), tick=TickConfig(stop_on_completion=True))


class ScenarioRun:
    """The state of one run (on the running loop)."""

    def __init__(self, spec: ScenarioSpec, mode: str, seed: int, *, bag: Path | None = None):
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
        self.spec = spec
        self.mode = mode
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        j = spec.jitter
        s = spec.start
        self.start = Pose2D(s.x + self.rng.uniform(-j.start_xy, j.start_xy),
                            s.y + self.rng.uniform(-j.start_xy, j.start_xy),
                            s.yaw + self.rng.uniform(-j.start_yaw, j.start_yaw))
        self.goals: list[GoalRecord] = []
        self.bag = bag  # record the run to this rosbag2 folder (scenarios --record)

    def _fault_jitter(self) -> float:
        j = self.spec.jitter.fault_time
        return float(self.rng.uniform(-j, j)) if j > 0 else 0.0

    def _build_driver(self) -> SimDriver:
        spec = self.spec
        profile = load_profile(spec.robot, **spec.robot_overrides)

        def prepare(sim) -> None:
            for obstacle in spec.map_obstacles:
                sim.faults.apply(parse_fault(dict(obstacle)))

        nav_params = {"controller": {"xy_goal_tolerance": spec.speeds.goal_tolerance}}
        return SimDriver(spec.world, profile, seed=self.seed, spawn=(self.start.x, self.start.y, self.start.yaw),
                         cruise_speed=spec.speeds.linear, max_angular_speed=spec.speeds.angular,
                         nav_params=nav_params, prepare=prepare)

    def _apply_fault(self, driver: SimDriver, fault: dict[str, Any]) -> None:
        kind = fault.get("kind")
        nav = driver.navigation
        if kind in NAV_FAULTS:
            comp = fault.get("component", "planner_server")
            if kind == "nav_crash":
                nav.crash(comp)
            elif kind == "nav_hang":
                nav.hang(comp)
            elif kind == "nav_fail_until_restart":
                nav.fail_until_restart(comp)
            else:
                nav.inject_phantom_obstacle(fault["x"], fault["y"], fault.get("radius", 0.3))
        else:
            driver.faults.apply(parse_fault(dict(fault)))

    def _schedule_fault(self, driver: SimDriver, loop, at: float, fault: dict[str, Any]) -> None:
        loop.call_at(max(at, loop.time()), self._apply_fault, driver, fault)

    async def execute(self) -> RunRecord:
        spec = self.spec
        loop = asyncio.get_running_loop()
        wall0 = time.perf_counter()
        driver = self._build_driver()
        driver.navigation = RecordingNavigation(driver.navigation, loop.time)
        rt = AutonomyRuntime(driver, runtime_config(self.mode), register=[_register])
        rt.load_tree(TREES[self.mode])
        bb = rt.tree.root_blackboard
        if self.mode == "with":
            bb.set("goal_status", "IDLE")
            if driver.sim.dock is not None:  # configuration, as opennav_docking's dock database
                bb.set("dock_pose", driver.sim.dock)
        recording = None
        if self.bag is not None:
            from .bags import start_bag

            recording = start_bag(rt, driver, self.bag, scenario=spec.name, mode=self.mode, seed=self.seed)
        t0 = loop.time()
        await rt.start(tick=(self.mode == "with"))
        for f in spec.faults:
            if f.at is not None:
                self._schedule_fault(driver, loop, t0 + f.at + self._fault_jitter(), f.fault)
        deadline = t0 + spec.time_limit
        try:
            await self._send_goals(rt, driver, loop, t0, deadline)
            end = deadline if not spec.goals else min(deadline, loop.time() + spec.settle)
            await asyncio.sleep(max(0.0, end - loop.time()))
        finally:
            record = self._collect(rt, driver, loop.time() - t0, time.perf_counter() - wall0)
            await rt.stop()
            if recording is not None:
                recording.stop()
        return record

    async def _send_goals(self, rt: AutonomyRuntime, driver: SimDriver, loop, t0: float, deadline: float) -> None:
        bb = rt.tree.root_blackboard
        previous_done = t0
        for index, step in enumerate(self.spec.goals):
            send_at = t0 + step.at if step.at is not None else previous_done + step.delay
            await asyncio.sleep(max(0.0, send_at - loop.time()))
            if loop.time() >= deadline:
                return
            pose = Pose2D(step.pose.x, step.pose.y, step.pose.yaw)
            record = GoalRecord(index, pose, loop.time())
            self.goals.append(record)
            for f in self.spec.faults:
                if f.after_goal == index:
                    self._schedule_fault(driver, loop, record.sent + f.delay + self._fault_jitter(), f.fault)
            if self.mode == "with":
                bb.set("goal", pose)
                bb.set("goal_status", "PENDING")
                outcome = await self._wait_status(bb, loop, deadline)
            else:
                bb.set("goal", pose)
                done = rt.restart_tree()
                outcome = await self._wait_future(done, loop, deadline)
            record.finished = loop.time()
            record.outcome = outcome
            previous_done = record.finished

    @staticmethod
    async def _wait_status(bb, loop, deadline: float) -> str:
        while loop.time() < deadline:
            status = bb.get("goal_status", default="")
            if status in TERMINAL:
                return status
            await asyncio.sleep(0.05)
        return "TIMEOUT"

    @staticmethod
    async def _wait_future(done: asyncio.Future, loop, deadline: float) -> str:
        try:
            status = await asyncio.wait_for(asyncio.shield(done), max(0.0, deadline - loop.time()))
            return status.name
        except TimeoutError:
            return "TIMEOUT"

    def _collect(self, rt: AutonomyRuntime, driver: SimDriver, duration: float, wall: float) -> RunRecord:
        sim = driver.sim
        stats = rt.tick_loop.stats if rt.tick_loop else None
        names = [c.name for c in driver.components()]
        return RunRecord(
            scenario=self.spec.name, mode=self.mode, seed=self.seed, duration=duration,
            trajectory=np.asarray(sim.trajectory(), dtype=float), goals=list(self.goals),
            supervisor_events=list(rt.supervisor.events), final_health=rt.supervisor.summary(),
            component_states={n: driver.component_state(n).value for n in names},
            nav_requests=list(driver.navigation.requests), fault_log=list(sim.faults.log),
            sim_events=list(sim.events), obstacles=dict(getattr(sim, "dynamic_obstacles", {}) or {}),
            gate_switches=list(rt.gate.switches), tick_errors=stats.errors if stats else 0,
            tick_cost_mean_us=(stats.cost_mean * 1e6) if stats else 0.0, wall_time=wall, start=self.start,
            map_grid=driver.map, component_log=list(sim.component_log))


def run_scenario(spec: ScenarioSpec | str, mode: str, seed: int = 0, *, keep_record: bool = True,
                 record_dir: str | None = None, record_failures: bool = False) -> RunResult:
    """Run one scenario once on a fresh virtual-time loop and judge it; with ``record_dir``, record
    it as a rosbag2 bag there (kept only if it failed, with ``record_failures``)."""
    if isinstance(spec, str):
        spec = load_scenario(spec)
    wall0 = time.perf_counter()
    from .bags import bag_path, discard

    bag = bag_path(record_dir, spec.name, mode, seed) if record_dir else None
    run = ScenarioRun(spec, mode, seed, bag=bag)
    record = run_loop(run.execute(), virtual=True)
    verdicts = judge(spec, record)
    if bag is not None and record_failures and all(v.passed for v in verdicts):
        discard(bag)
    return RunResult(spec.name, mode, seed, all(v.passed for v in verdicts), verdicts, record.duration,
                     time.perf_counter() - wall0, record if keep_record else None)


def scenario_seed(base: int, index: int) -> int:
    """Seeds for the runs of a campaign: distinct, reproducible from the base seed."""
    return int(np.random.SeedSequence([base, index]).generate_state(1)[0])


__all__ = ["MODES", "RunResult", "ScenarioRun", "run_scenario", "scenario_seed"]
