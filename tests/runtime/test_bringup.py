"""The lifecycle bring-up sequence (runtime/bringup.py) against scripted lifecycle nodes: the
order nav2_lifecycle_manager uses, its checks, where it stops, and how the supervisor reports it."""

import asyncio

import pytest

from bt_runtime.runtime import bringup as B
from bt_runtime.runtime.bringup import BringupPlan, bring_up
from bt_runtime.runtime.goal_intake import GoalState
from bt_runtime.runtime.messages import Pose2D
from bt_runtime.runtime.supervisor import Health
from tests.helpers import tree_xml


class ScriptedNodes:
    """Lifecycle nodes that follow the managed-node state machine; ``refuse`` fails activation,
    ``silent`` never answers, ``lag`` moves the node only after the reply (verification matters)."""

    def __init__(self, states: dict[str, int], refuse=(), silent=(), others=None):
        self.states = dict(states)
        self.refuse, self.silent = set(refuse), set(silent)
        self.calls: list[tuple[str, str]] = []
        self.others = others  # another manager that moves a node between our get_state and change_state

    async def node_state(self, node, timeout):
        await asyncio.sleep(0)
        if node in self.silent:
            await asyncio.sleep(timeout)
            return None
        return self.states[node]

    async def change_node_state(self, node, transition, timeout):
        self.calls.append((B.TRANSITION_LABELS[transition], node))
        if node in self.silent:
            await asyncio.sleep(timeout)
            return None
        if self.others is not None:
            self.others(self.states)
        start = {B.CONFIGURE: B.UNCONFIGURED, B.ACTIVATE: B.INACTIVE}[transition]
        if self.states[node] != start or (transition == B.ACTIVATE and node in self.refuse):
            return False
        self.states[node] = B.GOAL_STATE[transition]
        return True


def plan(*nodes, components=None):
    return BringupPlan(tuple(nodes), components or {}, service_timeout=0.5, transition_timeout=0.5)


def loop_clock():
    return asyncio.get_running_loop().time


async def test_configures_every_node_in_order_then_activates_every_node_in_order():
    nodes = ScriptedNodes({"controller_server": 1, "planner_server": 1, "behavior_server": 1})
    report = await bring_up(nodes, plan("controller_server", "planner_server", "behavior_server"), loop_clock())
    assert nodes.calls == [("configure", "controller_server"), ("configure", "planner_server"),
                           ("configure", "behavior_server"), ("activate", "controller_server"),
                           ("activate", "planner_server"), ("activate", "behavior_server")]
    assert report.status == "active" and all(n.state == "active" for n in report.nodes)
    assert set(nodes.states.values()) == {B.ACTIVE}


async def test_a_node_that_will_not_activate_stops_the_bring_up_there():
    nodes = ScriptedNodes({"a": 1, "b": 1, "c": 1}, refuse={"b"})
    report = await bring_up(nodes, plan("a", "b", "c"), loop_clock())
    assert report.status == "failed" and report.failed_node == "b"
    assert "activate refused" in report.reason and "inactive" in report.reason
    assert ("activate", "c") not in nodes.calls  # aborted, as nav2_lifecycle_manager does
    assert nodes.states == {"a": B.ACTIVE, "b": B.INACTIVE, "c": B.INACTIVE}
    assert "bring-up failed: b" in report.describe()


async def test_nodes_already_up_are_left_alone_and_a_concurrent_manager_is_tolerated():
    # 'a' is active already (Nav2's own lifecycle_manager with autostart); 'b' is configured by
    # someone else between our get_state and our configure: refused, but it reached inactive
    def other_manager(states):
        if states["b"] == B.UNCONFIGURED:
            states["b"] = B.INACTIVE

    nodes = ScriptedNodes({"a": B.ACTIVE, "b": B.UNCONFIGURED}, others=other_manager)
    report = await bring_up(nodes, plan("a", "b"), loop_clock())
    assert report.status == "active", report
    assert ("configure", "a") not in nodes.calls and ("activate", "a") not in nodes.calls
    assert report.nodes[0].steps == ["already active"]


async def test_a_node_whose_services_never_answer_fails_with_the_wait_named():
    nodes = ScriptedNodes({"a": 1, "ghost": 1}, silent={"ghost"})
    report = await bring_up(nodes, plan("a", "ghost"), loop_clock())
    assert report.failed_node == "ghost" and "did not answer within 0.5 s" in report.reason
    assert nodes.states["a"] == B.INACTIVE  # configured, never activated: the bring-up stopped


class LifecycleSimDriver:
    """The simulator driver plus scripted lifecycle nodes (what the ROS 2 driver offers)."""

    def __init__(self, sim_driver, nodes: ScriptedNodes, the_plan: BringupPlan):
        self._sim, self._nodes, self._plan = sim_driver, nodes, the_plan

    def __getattr__(self, name):
        return getattr(self._sim, name)

    def bringup_plan(self):
        return self._plan

    async def node_state(self, node, timeout):
        return await self._nodes.node_state(node, timeout)

    async def change_node_state(self, node, transition, timeout):
        return await self._nodes.change_node_state(node, transition, timeout)


GOAL_TREE = tree_xml('<KeepRunningUntilFailure><SetBlackboard value="{goal_status}" output_key="seen"/>'
                     '</KeepRunningUntilFailure>')


@pytest.mark.virtual_time
async def test_supervisor_reports_the_failed_node_and_goals_are_refused(bt_quiet_logs):
    from bt_runtime.runtime.app import AutonomyRuntime
    from sim.driver import SimDriver

    nodes = ScriptedNodes({"planner_server": 1, "velocity_smoother": 1, "lidar": 1}, refuse={"velocity_smoother"})
    driver = LifecycleSimDriver(SimDriver("apartment", "burger", seed=1), nodes,
                                plan("planner_server", "velocity_smoother", "lidar", components={"lidar": "lidar"}))
    runtime = AutonomyRuntime(driver)
    runtime.load_tree(GOAL_TREE)
    runtime.tree.root_blackboard.set("goal_status", "IDLE")
    await runtime.start()
    try:
        report = await asyncio.wait_for(asyncio.shield(runtime.bringup_task), 10)
        assert report.failed and report.failed_node == "velocity_smoother"
        events = runtime.supervisor.events_of("velocity_smoother")
        assert events and events[-1].state is Health.FAILED
        assert "bring-up failed at velocity_smoother: activate refused" in events[-1].reason
        lidar = runtime.supervisor.events_of("lidar")  # left inactive by the aborted bring-up
        assert lidar[-1].state is Health.FAILED and "bring-up stopped at velocity_smoother" in lidar[-1].reason
        handle = runtime.send_goal(Pose2D(-1.0, -2.0, 0.0))
        result = await asyncio.wait_for(handle, 1)
        assert result.status == GoalState.REJECTED and "velocity_smoother" in result.error_msg
        from bt_runtime.runtime.diagnostics import ERROR, component_diagnostics

        status = next(d for d in component_diagnostics(runtime.supervisor, runtime.clock())
                      if d.hardware_id == "bringup")
        assert status.level == ERROR and "velocity_smoother" in status.message
    finally:
        await runtime.stop()
    assert runtime.summary().bringup["failed_node"] == "velocity_smoother"
