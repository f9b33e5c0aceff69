"""What the gate's safety zones are doing, for the tree (docs/safety_zones.md).

The decision gate runs every command through collision_monitor-style zones and records each
change of state in the data backup (stream ``safety_zone``). ``SafetyZoneTriggered`` reads the
latest one, so a tree can react when a zone stops or slows the robot (e.g. replan, back off,
or wait) and log which zone it was.
"""

from __future__ import annotations

from bt_runtime import ConditionNode, NodeStatus
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.safety_zones import STREAM, ZoneState

SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE
ACTIONS = ("stop", "slowdown", "limit", "approach")


class SafetyZoneTriggered(ConditionNode):
    """SUCCESS while a safety zone acts on the robot's commands (optionally only the named zone
    or action); writes the zone's name and action ("invalid source" with "stop" when the scan
    is stale), and empty strings once no zone acts."""

    @classmethod
    def provided_ports(cls):
        return [input_port("zone", str, "", "only this zone, e.g. PolygonStop (empty: any)"),
                input_port("action", str, "", "only this action: stop | slowdown | limit | approach "
                                              "(empty: any)"),
                output_port("triggered_zone", str, "{safety_zone}", "the zone acting now, or empty"),
                output_port("triggered_action", str, "{safety_action}", "its action, or empty")]

    def __init__(self, name, config=None):
        super().__init__(name, config)
        self._written: tuple[str, str] | None = None

    def tick(self):
        state = self.context.backup.latest(STREAM)
        zone, action = ("", "")
        if isinstance(state, ZoneState) and state.triggered:
            zone, action = state.zone, state.action
        if (zone, action) != self._written:
            self._written = (zone, action)
            self.set_output("triggered_zone", zone)
            self.set_output("triggered_action", action)
        if not zone:
            return FAILURE
        want_action = self.get_input("action")
        if want_action and want_action not in ACTIONS:
            raise ValueError(f"action must be one of {', '.join(ACTIONS)} or empty, got {want_action!r}")
        want_zone = self.get_input("zone")
        return SUCCESS if (not want_zone or want_zone == zone) and (not want_action or want_action == action) \
            else FAILURE
