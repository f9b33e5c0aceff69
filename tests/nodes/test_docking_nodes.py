"""ChargeUntil and GoalStatusIs (nodes/docking.py) on a fake context: charging is known only
from the battery messages the test feeds."""

from __future__ import annotations

from bt_runtime.runtime.messages import (
    POWER_SUPPLY_CHARGING,
    POWER_SUPPLY_DISCHARGING,
    POWER_SUPPLY_FULL,
    BatteryState,
)
from bt_runtime.status import NodeStatus
from nodes import register_autonomy_nodes
from tests.nodes.nav2.support import build

S, F, R = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING
CHARGE = '<ChargeUntil full="99" timeout="10"><BatteryAbove percent="40"/></ChargeUntil>'


def reading(ctx, percent: float, status: int) -> None:
    ctx.backup.record("battery", BatteryState(ctx.clock(), 11.5, percent, -1.5, 0.0, 0.1, status))


def test_charge_until_runs_while_charging_and_succeeds_when_its_condition_holds():
    tree, ctx = build(CHARGE, register=(register_autonomy_nodes,))
    reading(ctx, 20.0, POWER_SUPPLY_CHARGING)
    assert tree.tick_exactly_once() is R
    ctx.clock.advance(30.0)
    reading(ctx, 39.0, POWER_SUPPLY_CHARGING)
    assert tree.tick_exactly_once() is R  # still charging, not enough yet
    reading(ctx, 41.0, POWER_SUPPLY_CHARGING)
    assert tree.tick_exactly_once() is S


def test_charge_until_stops_at_full_and_fails_when_the_charger_is_lost():
    tree, ctx = build('<ChargeUntil full="99"><AlwaysFailure/></ChargeUntil>', register=(register_autonomy_nodes,))
    reading(ctx, 99.5, POWER_SUPPLY_FULL)
    assert tree.tick_exactly_once() is S  # full: the condition can never be met by charging
    tree, ctx = build(CHARGE, register=(register_autonomy_nodes,))
    reading(ctx, 20.0, POWER_SUPPLY_CHARGING)
    assert tree.tick_exactly_once() is R
    ctx.clock.advance(1.0)
    reading(ctx, 20.1, POWER_SUPPLY_DISCHARGING)  # contacts lost
    ctx.clock.advance(8.5)
    assert tree.tick_exactly_once() is R  # 9.5 s since the charger was last seen: within the timeout
    ctx.clock.advance(1.0)
    assert tree.tick_exactly_once() is F


def test_goal_status_is_fails_before_any_goal():
    tree, _ = build('<GoalStatusIs value="CHARGING"/>', register=(register_autonomy_nodes,))
    assert tree.tick_exactly_once() is F
    tree, _ = build('<GoalStatusIs value="CHARGING"/>', register=(register_autonomy_nodes,),
                    bb_init={"goal_status": "CHARGING"})
    assert tree.tick_exactly_once() is S


def test_on_charger_holds_while_charging_and_when_full_on_the_charger():
    tree, ctx = build('<OnCharger/>', register=(register_autonomy_nodes,))
    assert tree.tick_exactly_once() is F  # no battery message yet: not known to be docked
    for status, expected in ((POWER_SUPPLY_CHARGING, S), (POWER_SUPPLY_FULL, S), (POWER_SUPPLY_DISCHARGING, F)):
        reading(ctx, 100.0, status)
        assert tree.tick_exactly_once() is expected, status


def test_while_goal_status_is_skips_its_branch_and_halts_it_when_the_status_changes():
    xml = ('<ReactiveFallback><WhileGoalStatusIs value="CHARGING"><ChargeUntil full="99" timeout="10">'
           '<AlwaysFailure/></ChargeUntil></WhileGoalStatusIs><AlwaysSuccess/></ReactiveFallback>')
    tree, ctx = build(xml, register=(register_autonomy_nodes,), bb_init={"goal_status": "ACTIVE"})
    charge = next(n for n in tree.nodes() if type(n).__name__ == "ChargeUntil")
    reading(ctx, 20.0, POWER_SUPPLY_CHARGING)
    assert tree.tick_exactly_once() is S  # not charging: the branch is skipped, the next child runs
    assert charge.status is NodeStatus.IDLE
    tree.root_blackboard.set("goal_status", "CHARGING")
    assert tree.tick_exactly_once() is R and charge.status is R
    tree.root_blackboard.set("goal_status", "PENDING")  # a new goal preempts the charge
    assert tree.tick_exactly_once() is S
    assert charge.status is NodeStatus.IDLE  # halted
    tree, _ = build('<WhileGoalStatusIs value="CHARGING"><AlwaysSuccess/></WhileGoalStatusIs>',
                    register=(register_autonomy_nodes,))
    assert tree.tick_exactly_once() is NodeStatus.SKIPPED  # no goal status at all yet: skipped, no error
