"""The tick task: 100 Hz on absolute deadlines, errors never kill it, context reaches nodes."""

from __future__ import annotations

import asyncio

from bt_runtime import NodeStatus, SyncActionNode
from bt_runtime.runtime.context import RuntimeContext
from tests.helpers import tree_xml


async def test_ticks_on_absolute_deadlines(make_runtime):
    stamps = []

    def register(factory):
        factory.register_simple_condition("Stamp", lambda n: (stamps.append(n.context.clock()),
                                                              NodeStatus.SUCCESS)[1])

    rt = make_runtime(tree_xml('<KeepRunningUntilFailure><Stamp/></KeepRunningUntilFailure>'),
                      register=[register])
    await rt.start()
    await asyncio.sleep(2.0)
    await rt.stop()
    diffs = [b - a for a, b in zip(stamps, stamps[1:])]
    assert len(stamps) >= 199
    assert max(abs(d - 0.01) for d in diffs) < 1e-9
    assert abs(stamps[-1] - (stamps[0] + 0.01 * (len(stamps) - 1))) < 1e-9  # no drift
    assert rt.tick_loop.stats.overruns == 0


class Flaky(SyncActionNode):
    """Raises on chosen calls, succeeds otherwise."""

    calls = 0
    fail_on = {3, 4}

    def tick(self):
        type(self).calls += 1
        if type(self).calls in self.fail_on:
            raise ValueError("sensor parse error")
        return NodeStatus.SUCCESS


async def test_a_tick_error_does_not_kill_the_loop(make_runtime):
    Flaky.calls = 0

    def register(factory):
        factory.register_node_type(Flaky)

    rt = make_runtime(tree_xml('<KeepRunningUntilFailure><Sequence name="outer"><Flaky name="reader"/>'
                               '</Sequence></KeepRunningUntilFailure>'), register=[register])
    await rt.start()
    gate = rt.gate
    await asyncio.sleep(0.025)
    assert Flaky.calls == 2
    await asyncio.sleep(0.01)  # call 3 raises
    assert rt.tick_loop.stats.errors == 1
    assert gate.estop_active and gate.last_output.is_zero
    err = rt.tick_loop.last_error
    assert err.node_path == "reader" and "sensor parse error" in str(err)
    await asyncio.sleep(0.01)  # call 4 raises again
    await asyncio.sleep(0.01)  # call 5 succeeds: the latch is released
    assert rt.tick_loop.stats.errors == 2 and not gate.estop_active
    await asyncio.sleep(0.5)
    assert Flaky.calls > 50 and rt.tick_task is not None and not rt.tick_task.done()
    await rt.stop()


async def test_nodes_reach_the_runtime_through_the_context(make_runtime):
    seen = {}

    class Probe(SyncActionNode):
        def tick(self):
            ctx = self.context
            seen["ctx"] = ctx
            seen["health"] = ctx.supervisor.summary()
            ctx.gate.set_tree_command(0.05, 0.0)
            return NodeStatus.SUCCESS

    rt = make_runtime(tree_xml('<Sequence><Sleep msec="300"/><Probe/></Sequence>'),
                      register=[lambda f: f.register_node_type(Probe)])
    await rt.start()
    summary = await rt.run(duration=5)
    await rt.stop()
    assert summary.status == "SUCCESS" and summary.completed
    assert isinstance(seen["ctx"], RuntimeContext) and seen["ctx"].driver is rt.driver
    assert seen["health"]["lidar"] == "ok"


async def test_tree_restarted_by_supervisor_after_the_tick_task_dies(make_runtime):
    rt = make_runtime()
    await rt.start()
    await asyncio.sleep(0.2)
    rt.tick_task.cancel()
    await asyncio.sleep(2.5)
    states = [e.state.value for e in rt.supervisor.events_of("tree")]
    assert states[-3:] == ["failed", "restarting", "ok"]
    assert not rt.tick_task.done()
    await rt.stop()


async def test_endless_wake_up_reticks_do_not_freeze_the_loop(make_runtime):
    """Repeat -1 of a synchronous child asks for a re-tick forever (BT.CPP's tickOnce never
    returns); the host bounds the re-ticks per tick so the loop, watchdog and gate go on."""
    counts = []

    def register(factory):
        factory.register_simple_action("Count", lambda n: (counts.append(1), NodeStatus.SUCCESS)[1])

    rt = make_runtime(tree_xml('<Repeat num_cycles="-1"><Count/></Repeat>'), register=[register])
    rt.tick_loop.config.max_reticks = 5
    await rt.start()
    await asyncio.sleep(0.5)
    ticks = rt.tick_loop.stats.count
    assert 45 <= ticks <= 51
    assert len(counts) == ticks * 6  # the tick and 5 re-ticks, one Count each
    assert rt.tree.retick_cutoffs == ticks and rt.tick_loop.status is NodeStatus.RUNNING
    assert not rt.tick_task.done()
    await rt.stop()


async def test_a_wake_up_between_ticks_does_not_tick_twice(make_runtime):
    """A wake-up emitted between two ticks (a timer firing) is answered by the next scheduled
    tick alone: the pause consumed it, so that tick does not re-tick the tree at once."""
    ticks = []

    def register(factory):
        def stamp(node):
            ticks.append(node.context.clock())
            if len(ticks) == 1:
                node.config.timers.add(0.004, node.emit_wake_up_signal)  # fires mid-period
            return NodeStatus.SUCCESS

        factory.register_simple_condition("Stamp", stamp)

    rt = make_runtime(tree_xml('<ReactiveSequence><Stamp/><Sleep msec="1000"/></ReactiveSequence>'), register=[register])
    await rt.start()
    await asyncio.sleep(0.035)
    await rt.stop()
    assert len(ticks) >= 3
    gaps = [b - a for a, b in zip(ticks, ticks[1:])]
    assert min(gaps) > 0.009  # one tick per period, never a back-to-back re-tick


async def test_tick_cost_is_the_threads_cpu_and_the_wall_time_is_kept_apart(make_runtime):
    """A tick that waits without computing (here: a blocking sleep, as a descheduled thread on
    a busy machine) costs wall time, not CPU: the two are reported apart."""
    import time

    def register(factory):
        factory.register_simple_condition("Blocked", lambda n: (time.sleep(0.003), NodeStatus.SUCCESS)[1])

    rt = make_runtime(tree_xml('<KeepRunningUntilFailure><Blocked/></KeepRunningUntilFailure>'),
                      register=[register])
    await rt.start()
    await asyncio.sleep(0.3)
    await rt.stop()
    stats = rt.tick_loop.stats
    assert stats.count >= 20
    assert stats.wall_mean >= 0.003
    assert stats.cost_mean < 0.001


async def test_before_tick_hooks_run_first_in_every_tick_and_a_failing_one_does_not_stop_it(make_runtime):
    """The ROS 2 driver delivers the streams held for the tick (deliver_at_tick) in this hook:
    the tree must see them in the same tick, and a failing hook must not stop the ticks."""
    order = []

    def register(factory):
        factory.register_simple_condition("Mark", lambda n: (order.append("tree"), NodeStatus.SUCCESS)[1])

    rt = make_runtime(tree_xml('<KeepRunningUntilFailure><Mark/></KeepRunningUntilFailure>'), register=[register])
    rt.tick_loop.before_tick.append(lambda: order.append("hook"))
    rt.tick_loop.before_tick.append(lambda: 1 / 0)
    await rt.start()
    await asyncio.sleep(0.1)
    await rt.stop()
    assert len(order) >= 18 and order[:4] == ["hook", "tree", "hook", "tree"]
    assert order[::2] == ["hook"] * len(order[::2]) and order[1::2] == ["tree"] * len(order[1::2])
    assert rt.tick_loop.stats.errors == 0
