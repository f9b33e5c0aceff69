"""The configurable mock node used by substitution rules (BT.CPP 4.10's TestNode).

Config keys (as in BT.CPP's TestNodeConfig JSON): ``return_status`` (a status or its name,
default SUCCESS), ``return_status_script`` (a script whose value is the status: a name such as
``'FAILURE'``, one of the names IDLE/RUNNING/SUCCESS/FAILURE/SKIPPED, or a number; it wins over
``return_status``), ``async_delay`` (ms or a timedelta; 0 completes in the first tick), ``success_script``,
``failure_script``, ``post_script``, and ``complete_func`` (a callable returning the status,
which wins over both). A result of IDLE (or a number that is no status) raises BTRuntimeError.
"""

from __future__ import annotations

from typing import Any

from ..errors import BTRuntimeError
from ..node import NodeConfig, StatefulActionNode
from ..ports import EMPTY, parse_status
from ..script import compile_node_script
from ..status import FAILURE, IDLE, RUNNING, SUCCESS, NodeStatus

_STATUS_NAMES = {status.name: int(status) for status in NodeStatus}


def check_test_node_config(name: str, config: dict[str, Any]) -> None:
    """What BT.CPP's ``loadSubstitutionRuleFromJSON`` checks of one TestNodeConfigs entry: it
    names a status (``return_status``, a valid name) or a ``return_status_script``."""
    if "return_status" in config:
        parse_status(str(config["return_status"]))
    elif not config.get("return_status_script"):
        raise BTRuntimeError(f"TestNodeConfig [{name}] must contain return_status or return_status_script")


def _valid(status: NodeStatus, source: str) -> NodeStatus:
    if status is IDLE:
        raise BTRuntimeError(f"TestNode {source} resolved to invalid status (integer value: 0)")
    return status


def status_from_script_value(value: Any) -> NodeStatus:
    """BT.CPP's conversion of a ``return_status_script`` result: a status name, or a number
    that is a status's integer value (IDLE excluded)."""
    if value is EMPTY or value is None:
        raise BTRuntimeError("return_status_script returned an empty value")
    if isinstance(value, str):
        return _valid(parse_status(value), "return_status_script")
    if isinstance(value, (bool, int)) or (isinstance(value, float) and value.is_integer()):
        number = int(value)
        if number not in NodeStatus._value2member_map_:
            raise BTRuntimeError(f"TestNode return_status_script resolved to invalid status "
                                 f"(integer value: {number})")
        return _valid(NodeStatus(number), "return_status_script")
    raise BTRuntimeError("return_status_script must evaluate to a NodeStatus-compatible value")


class TestNode(StatefulActionNode):
    __test__ = False  # not a pytest class

    def __init__(self, name: str, config: NodeConfig, test_config: dict[str, Any]):
        self._cfg = dict(test_config)
        self._complete = self._cfg.get("complete_func")
        self._status_script = (compile_node_script(self._cfg["return_status_script"])
                               if self._cfg.get("return_status_script") else None)
        self._fixed_status = parse_status(str(self._cfg.get("return_status", "SUCCESS")))
        if self._status_script is None:
            _valid(self._fixed_status, "return_status")
        self._scripts = {k: compile_node_script(self._cfg[k]) for k in ("success_script", "failure_script",
                                                                         "post_script") if self._cfg.get(k)}
        self._timer = None
        self._done = False
        super().__init__(name, config)

    def _result(self) -> NodeStatus:
        cfg = self.config
        if self._complete is not None:
            status = self._complete()
        elif self._status_script is not None:
            # the status names are visible to this script only (they shadow same-named enums);
            # the scripts below see the node's own enums, so an entry named SUCCESS stays readable
            status = status_from_script_value(self._status_script.run(cfg.blackboard,
                                                                      {**(cfg.enums or {}), **_STATUS_NAMES}))
        else:
            status = self._fixed_status
        status = _valid(NodeStatus(status), "completion")
        key = {SUCCESS: "success_script", FAILURE: "failure_script"}.get(status)
        if key in self._scripts:
            self._scripts[key].run(cfg.blackboard, cfg.enums)
        if "post_script" in self._scripts:
            self._scripts["post_script"].run(cfg.blackboard, cfg.enums)
        return status

    def on_start(self) -> NodeStatus:
        delay = self._cfg.get("async_delay", 0) or 0
        delay_ms = delay.total_seconds() * 1000.0 if hasattr(delay, "total_seconds") else float(delay)
        if delay_ms <= 0:
            return self._result()
        self._done = False
        self._timer = self.config.timers.add(delay_ms / 1000.0, self._expired)
        return RUNNING

    def _expired(self) -> None:
        self._done = True
        self.config.wake_up.emit()

    def on_running(self) -> NodeStatus:
        return self._result() if self._done else RUNNING

    def on_halted(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
