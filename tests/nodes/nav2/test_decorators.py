"""Nav2 decorators on a scripted clock and fake robot data."""

from __future__ import annotations

import numpy as np
import pytest

from bt_runtime.runtime.messages import Path, Pose2D
from bt_runtime.status import FAILURE, RUNNING, SUCCESS
from nodes.nav2 import publish_stamped
from tests.nodes.nav2.support import Counter, build, fake_context


def pipeline_with(decorated: str) -> str:
    """The decorator in front of a stage that keeps running (so the decorator is never reset,
    as in Nav2's PipelineSequence)."""
    return f'<PipelineSequence>{decorated}<Busy name="follow"/></PipelineSequence>'


def runner(decorated: str, ctx=None, bb_init=None):
    c = Counter()
    c.status["follow"] = RUNNING
    tree, ctx = build(pipeline_with(decorated), ctx, register=(c.register, c.register_running),
                      bb_init=bb_init)
    return tree, ctx, c


def test_rate_controller_ticks_its_child_at_the_rate_on_the_tree_clock():
    tree, ctx, c = runner('<RateController hz="2.0"><Count name="plan"/></RateController>')
    counts = []
    for _ in range(17):  # 0.0 .. 2.0 s in 0.125 s steps
        assert tree.tick_exactly_once() is RUNNING
        counts.append(c.ticks["plan"])
        ctx.clock.advance(0.125)
    # first tick, then every 0.5 s after the child's last success
    assert counts[0] == 1 and counts[3] == 1 and counts[4] == 2 and counts[8] == 3 and counts[16] == 5


def test_rate_controller_ticks_a_running_child_every_tick_and_restarts_after_success():
    c = Counter()
    c.status["follow"] = RUNNING
    c.status["plan"] = RUNNING
    tree, ctx = build(pipeline_with('<RateController hz="1.0"><Busy name="plan"/></RateController>'),
                      register=(c.register_running,))
    for _ in range(4):  # t = 0 .. 0.375
        tree.tick_exactly_once()
        ctx.clock.advance(0.125)
    assert c.ticks["plan"] == 4 and c.ticks["follow"] == 0  # a RUNNING first stage stops the sweep
    c.status["plan"] = SUCCESS
    tree.tick_exactly_once()  # t = 0.5: plan succeeds, the timer restarts now
    assert c.ticks["follow"] == 1
    for _ in range(7):  # t = 0.625 .. 1.375
        ctx.clock.advance(0.125)
        tree.tick_exactly_once()
    assert c.ticks["plan"] == 5
    ctx.clock.advance(0.125)  # t = 1.5 = 0.5 + 1.0
    tree.tick_exactly_once()
    assert c.ticks["plan"] == 6


def test_rate_controller_failure_passes_through():
    c = Counter()
    c.status["plan"] = FAILURE
    tree, _ = build('<RateController hz="1.0"><Count name="plan"/></RateController>', register=(c.register,))
    assert tree.tick_exactly_once() is FAILURE


def test_distance_controller_ticks_each_distance_travelled():
    ctx = fake_context()
    ctx.backup.pose(0.0, 0.0)
    tree, ctx, c = runner('<DistanceController distance="1.0"><Count name="plan"/></DistanceController>', ctx)
    seen = []
    for x in np.arange(0.0, 3.05, 0.25):
        ctx.backup.pose(float(x), 0.0)
        tree.tick_exactly_once()
        seen.append(c.ticks["plan"])
    assert seen[0] == 1 and seen[3] == 1 and seen[4] == 2 and seen[8] == 3 and seen[12] == 4


def test_distance_controller_fails_without_a_pose():
    c = Counter()
    tree, _ = build('<DistanceController><Count name="plan"/></DistanceController>', register=(c.register,))
    assert tree.tick_exactly_once() is FAILURE and c.ticks["plan"] == 0


def test_speed_controller_rate_follows_the_odometry_speed():
    ctx = fake_context()
    tree, ctx, c = runner('<SpeedController min_rate="0.1" max_rate="1.0" min_speed="0.0" max_speed="0.5" '
                          'goal="{goal}"><Count name="plan"/></SpeedController>', ctx,
                          bb_init={"goal": Pose2D(1, 1)})
    ticks_at = []

    def run_for(seconds: float, speed: float):
        for _ in range(int(round(seconds / 0.125))):
            ctx.backup.odom(speed)
            before = c.ticks["plan"]
            tree.tick_exactly_once()
            if c.ticks["plan"] != before:
                ticks_at.append(ctx.clock())
            ctx.clock.advance(0.125)

    run_for(10.5, 0.0)  # first tick; after the first period (1 / max_rate) standing still: 10 s
    assert ticks_at == [0.0, 1.0]
    run_for(3.0, 0.5)  # at 11.0 the robot drives at max_speed: 1 Hz from then on
    assert ticks_at == [0.0, 1.0, 11.0, 12.0, 13.0]
    tree.root_blackboard.set("goal", Pose2D(2, 2))  # a new goal ticks at once and resets the period
    run_for(0.5, 0.5)
    assert ticks_at[-1] == 13.5 and len(ticks_at) == 6


def test_speed_controller_rejects_zero_rates():
    with pytest.raises(Exception, match="rate <= 0.0"):
        build('<SpeedController min_rate="0.0"><AlwaysSuccess/></SpeedController>')


def test_goal_updated_controller_ticks_only_on_goal_changes():
    tree, ctx, c = runner('<GoalUpdatedController goal="{goal}"><Count name="plan"/></GoalUpdatedController>',
                          bb_init={"goal": Pose2D(1, 0)})
    for _ in range(5):
        tree.tick_exactly_once()
    assert c.ticks["plan"] == 1
    tree.root_blackboard.set("goal", Pose2D(2, 0))
    tree.tick_exactly_once()
    tree.tick_exactly_once()
    assert c.ticks["plan"] == 2


def test_goal_updater_outputs_a_newer_published_goal():
    ctx = fake_context(t=10.0)
    tree, ctx = build('<GoalUpdater input_goal="{goal}" output_goal="{updated_goal}"><AlwaysSuccess/>'
                      '</GoalUpdater>', ctx, bb_init={"goal": Pose2D(1, 0)})
    assert tree.tick_exactly_once() is SUCCESS
    assert tree.root_blackboard.get("updated_goal") == Pose2D(1, 0)
    publish_stamped(ctx, "goal_update", Pose2D(5, 5), stamp=9.0)  # older than the goal: ignored
    tree.tick_exactly_once()
    assert tree.root_blackboard.get("updated_goal") == Pose2D(1, 0)
    ctx.clock.advance(1.0)
    publish_stamped(ctx, "goal_update", Pose2D(5, 5))
    tree.tick_exactly_once()
    assert tree.root_blackboard.get("updated_goal") == Pose2D(5, 5)
    ctx.clock.advance(1.0)
    tree.root_blackboard.set("goal", Pose2D(7, 7))  # a new input goal is newer than the update
    tree.tick_exactly_once()
    assert tree.root_blackboard.get("updated_goal") == Pose2D(7, 7)


def straight(length: float, n: int, goal=(0.0, 0.0), stamp: float = 0.0) -> Path:
    """A path of n poses ending at ``goal``, ``length`` long, coming from the west."""
    xs = np.linspace(goal[0] - length, goal[0], n)
    return Path(stamp, np.column_stack([xs, np.full(n, goal[1]), np.zeros(n)]))


def test_path_longer_on_approach_ticks_its_child_for_a_much_longer_new_path():
    c = Counter()
    tree, _ = build('<PathLongerOnApproach path="{path}" prox_len="3.0" length_factor="2.0">'
                    '<Count name="patience"/></PathLongerOnApproach>', register=(c.register,),
                    bb_init={"path": straight(2.0, 21)})
    bb = tree.root_blackboard
    assert tree.tick_exactly_once() is SUCCESS and c.ticks["patience"] == 0  # first time
    bb.set("path", straight(2.5, 26))  # same goal, not 2x longer
    assert tree.tick_exactly_once() is SUCCESS and c.ticks["patience"] == 0
    bb.set("path", straight(6.0, 61))  # > 2 x 2.5 m while within 3 m of the goal
    assert tree.tick_exactly_once() is SUCCESS and c.ticks["patience"] == 1
    bb.set("path", straight(12.0, 121, goal=(5.0, 0.0)))  # another goal: not "longer on approach"
    assert tree.tick_exactly_once() is SUCCESS and c.ticks["patience"] == 1


def test_single_trigger_ticks_once_per_activation():
    c = Counter()
    tree, _ = build('<SingleTrigger><Count name="once"/></SingleTrigger>', register=(c.register,))
    # as the root it is reset after each completion: a new activation each time
    assert tree.tick_exactly_once() is SUCCESS and tree.tick_exactly_once() is SUCCESS
    assert c.ticks["once"] == 2
    tree2, _, c2 = runner('<SingleTrigger><Count name="once"/></SingleTrigger>')
    statuses = [tree2.tick_exactly_once() for _ in range(4)]
    # later ticks of the same activation: FAILURE without ticking the child (the pipeline then
    # fails, which ends the activation)
    assert statuses == [RUNNING, FAILURE, RUNNING, FAILURE]
    assert c2.ticks["once"] == 2
