"""Judging a run from its records against the scenario's success criteria.

Each criterion gives (passed, reason); the reason says what was observed either way, so a
failure without the autonomy layer is recorded for its real cause ("lidar never restarted",
"closest approach 0.84 m", ...).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..component_log import first_fault, restarts
from .record import RunRecord
from .spec import (
    AlternativeReached,
    ChargedThenReached,
    ComponentReset,
    GoalRefused,
    HitOnce,
    ObstacleInMap,
    OutOfContact,
    ReachGoal,
    ScenarioSpec,
)

T, X, Y, YAW, V, W, CONTACT = range(7)
STOPPED = 0.05  # m/s


@dataclass
class Verdict:
    criterion: str
    passed: bool
    reason: str


def _after(traj: np.ndarray, t0: float, t1: float | None = None) -> np.ndarray:
    mask = traj[:, T] >= t0
    if t1 is not None:
        mask &= traj[:, T] < t1
    return traj[mask]


def component_reset(rec: RunRecord, c: ComponentReset) -> Verdict:
    """From the simulator's own component log: the process was restarted, ran again and
    published again (a message on its topic, or a heartbeat), and runs at the end. What the
    layer's supervisor believes does not count."""
    name = f"component_reset({c.component})"
    entries = rec.component_log
    fault = first_fault(entries, c.component)
    attempts = restarts(entries, c.component)
    done = [(began, published) for began, published in attempts if published is not None]
    final = rec.component_states.get(c.component, "unknown")
    what = f"{fault.event} at {fault.t:.2f} s, " if fault is not None else ""
    if done and final == "active":
        began, published = done[-1]
        return Verdict(name, True, f"{what}restarted at {began:.2f} s, publishing again at {published:.2f} s")
    if not attempts:
        return Verdict(name, False, f"{what}never restarted (state at the end: {final})")
    if not done:
        return Verdict(name, False, f"{what}restart attempted {len(attempts)}x, never published again "
                                    f"(state at the end: {final})")
    return Verdict(name, False, f"{what}restarted {len(attempts)}x but the state at the end is {final}")


def _reached(rec: RunRecord, index: int, tolerance: float) -> tuple[bool, float, float | None]:
    goal = rec.goals[index]
    later = rec.goals[index + 1].sent if index + 1 < len(rec.goals) else None
    traj = _after(rec.trajectory, goal.sent, later)
    if not len(traj):
        return False, math.inf, None
    dist = np.hypot(traj[:, X] - goal.pose.x, traj[:, Y] - goal.pose.y)
    at_goal = (dist <= tolerance) & (np.abs(traj[:, V]) < STOPPED)
    hit = np.flatnonzero(at_goal)
    return bool(len(hit)), float(dist.min()), (float(traj[hit[0], T]) if len(hit) else None)


def _window(rec: RunRecord, index: int) -> tuple[float, float | None]:
    goal = rec.goals[index]
    return goal.sent, rec.goals[index + 1].sent if index + 1 < len(rec.goals) else None


def _charging(rec: RunRecord, t0: float, t1: float | None) -> list:
    """The simulator's true charging events (contacts touching, current flowing) in [t0, t1)."""
    return [e for e in rec.sim_events if e.kind in ("charging_started", "charging_stopped")
            and e.t >= t0 and (t1 is None or e.t < t1)]


def reach_goal(rec: RunRecord, c: ReachGoal) -> Verdict:
    name = f"reach_goal({c.goal})"
    if c.goal >= len(rec.goals):
        return Verdict(name, False, "the goal was never sent")
    ok, closest, when = _reached(rec, c.goal, c.tolerance)
    if not ok:
        return Verdict(name, False, f"not reached: closest approach {closest:.2f} m")
    if c.without_charging:
        charged = [e for e in _charging(rec, rec.goals[c.goal].sent, when) if e.kind == "charging_started"]
        if charged:
            return Verdict(name, False, f"reached at {when:.2f} s, but only after docking to charge at "
                                        f"{charged[0].t:.2f} s (the battery was enough)")
    return Verdict(name, True, f"stopped within {c.tolerance} m at {when:.2f} s")


def charged_then_reached(rec: RunRecord, c: ChargedThenReached) -> Verdict:
    """Refused at first (no navigation towards the goal before charging began), docked and
    charged (true charging events, state of charge rising), then stopped at the goal."""
    name = f"charged_then_reached({c.goal})"
    if c.goal >= len(rec.goals):
        return Verdict(name, False, "the goal was never sent")
    goal = rec.goals[c.goal]
    t0, t1 = _window(rec, c.goal)
    events = _charging(rec, t0, t1)
    starts = [e for e in events if e.kind == "charging_started"]
    if not starts:
        _, closest, _ = _reached(rec, c.goal, c.tolerance)
        return Verdict(name, False, f"never docked to charge (closest approach to the goal {closest:.2f} m)")
    began = starts[0]
    early = [r for r in rec.nav_requests if r.method in ("navigate_to_pose", "follow_path") and r.goal is not None
             and r.goal.distance_to(goal.pose) < 0.3 and t0 <= r.t < began.t]
    if early:
        return Verdict(name, False, f"drove towards it before charging: {len(early)} navigation request(s) "
                                    f"before {began.t:.2f} s")
    stops = [e for e in events if e.kind == "charging_stopped" and e.t > began.t]
    if not stops:
        return Verdict(name, False, f"charging from {began.t:.2f} s never ended (still on the dock)")
    stop = stops[0]
    soc0, soc1 = float(began.data.get("soc", math.nan)), float(stop.data.get("soc", math.nan))
    if not soc1 > soc0:
        return Verdict(name, False, f"docked at {began.t:.2f} s but the charge did not rise ({soc0:.1f} -> {soc1:.1f} %)")
    traj = _after(rec.trajectory, stop.t, t1)
    if not len(traj):
        return Verdict(name, False, "no trajectory after charging")
    dist = np.hypot(traj[:, X] - goal.pose.x, traj[:, Y] - goal.pose.y)
    hit = np.flatnonzero((dist <= c.tolerance) & (np.abs(traj[:, V]) < STOPPED))
    if not len(hit):
        return Verdict(name, False, f"charged {soc0:.1f} -> {soc1:.1f} % ({began.t:.1f}-{stop.t:.1f} s), then not "
                                    f"reached: closest approach {float(dist.min()):.2f} m")
    return Verdict(name, True, f"refused, charged {soc0:.1f} -> {soc1:.1f} % ({began.t:.1f}-{stop.t:.1f} s), "
                               f"reached at {float(traj[hit[0], T]):.2f} s")


def goal_refused(rec: RunRecord, c: GoalRefused) -> Verdict:
    name = f"goal_refused({c.goal})"
    if c.goal >= len(rec.goals):
        return Verdict(name, False, "the goal was never sent")
    goal = rec.goals[c.goal]
    until = rec.goals[c.goal + 1].sent if c.goal + 1 < len(rec.goals) else None
    traj = _after(rec.trajectory, goal.sent, until)
    travelled = float(np.hypot(np.diff(traj[:, X]), np.diff(traj[:, Y])).sum()) if len(traj) > 1 else 0.0
    moves = [r for r in rec.nav_requests
             if r.method in ("navigate_to_pose", "follow_path") and r.goal is not None
             and r.goal.distance_to(goal.pose) < 0.3 and r.t >= goal.sent and (until is None or r.t < until)]
    if not moves and travelled <= c.max_travel:
        return Verdict(name, True, f"no navigation towards it; moved {travelled:.2f} m meanwhile")
    why = f"{len(moves)} navigation request(s) towards it" if moves else ""
    return Verdict(name, False, f"drove towards it: {why} {travelled:.2f} m travelled".strip())


def alternative_reached(rec: RunRecord, c: AlternativeReached) -> Verdict:
    name = f"alternative_reached({c.goal})"
    if c.goal >= len(rec.goals):
        return Verdict(name, False, "the goal was never sent")
    goal = rec.goals[c.goal]
    traj = _after(rec.trajectory, goal.sent)
    if len(traj) < 2:
        return Verdict(name, False, "no trajectory after the goal")
    start = traj[0]
    final = traj[-1]
    d_final = math.hypot(final[X] - goal.pose.x, final[Y] - goal.pose.y)
    d_start = math.hypot(start[X] - goal.pose.x, start[Y] - goal.pose.y)
    stopped = abs(final[V]) < STOPPED and not final[CONTACT]
    if d_final <= c.within and stopped and d_start - d_final > 0.3:
        return Verdict(name, True, f"stopped {d_final:.2f} m from the unreachable goal")
    return Verdict(name, False, f"ended {d_final:.2f} m from the goal (needed <= {c.within} m, stopped={stopped})")


def out_of_contact(rec: RunRecord, c: OutOfContact) -> Verdict:
    name = "out_of_contact"
    traj = rec.trajectory
    if not len(traj):
        return Verdict(name, False, "no trajectory")
    last = _after(traj, traj[-1, T] - c.for_last)
    touching = bool(last[:, CONTACT].any())
    if not touching:
        return Verdict(name, True, f"no contact in the last {c.for_last:.1f} s")
    return Verdict(name, False, f"still in contact during the last {c.for_last:.1f} s")


def obstacle_in_map(rec: RunRecord, c: ObstacleInMap) -> Verdict:
    name = f"obstacle_in_map({c.obstacle})"
    shape = rec.obstacles.get(c.obstacle)
    if shape is None:
        return Verdict(name, False, f"no obstacle named {c.obstacle} was created")
    marks = [r for r in rec.nav_requests if r.method == "add_obstacle" and r.goal is not None]
    near = [r for r in marks if shape.distance(r.goal.x, r.goal.y) <= c.within]
    if near:
        return Verdict(name, True, f"{len(near)} map mark(s) within {c.within} m of it")
    if c.only_if_hit and not _hits(rec, c.obstacle):
        return Verdict(name, True, "never touched it, nothing to mark")
    return Verdict(name, False, f"not in the map ({len(marks)} mark(s) elsewhere)" if marks else "not in the map")


def _hits(rec: RunRecord, obstacle: str, merge: float = 0.5) -> list[float]:
    """Times the robot ran into ``obstacle``, from the simulator's collision events (true
    contacts, for judging only); contacts less than ``merge`` s apart are one hit (a bounce)."""

    def ours(e) -> bool:
        key = str(e.data.get("obstacle", ""))
        return key == obstacle or key.endswith(":" + obstacle)

    hits, last_end = [], None
    for e in rec.sim_events:
        if e.kind == "collision" and ours(e):
            if not hits or last_end is None or e.t - last_end > merge:
                hits.append(e.t)
        elif e.kind == "collision_end" and ours(e):
            last_end = e.t
    return hits


def hit_once(rec: RunRecord, c: HitOnce) -> Verdict:
    name = f"hit_once({c.obstacle})"
    hits = _hits(rec, c.obstacle, c.merge)
    if len(hits) <= 1:
        return Verdict(name, True, f"hit {len(hits)}x" + (f" (at {hits[0]:.2f} s)" if hits else ""))
    return Verdict(name, False, f"hit {len(hits)}x, at " + ", ".join(f"{t:.2f}" for t in hits) + " s")


JUDGES = {"component_reset": component_reset, "reach_goal": reach_goal, "goal_refused": goal_refused,
          "alternative_reached": alternative_reached, "out_of_contact": out_of_contact,
          "obstacle_in_map": obstacle_in_map, "hit_once": hit_once, "charged_then_reached": charged_then_reached}


def judge(spec: ScenarioSpec, rec: RunRecord) -> list[Verdict]:
    verdicts = [JUDGES[c.kind](rec, c) for c in spec.success]
    if rec.tick_errors:
        verdicts.append(Verdict("no_tick_errors", False, f"{rec.tick_errors} tick error(s)"))
    return verdicts
