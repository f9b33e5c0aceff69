"""The configurable mock node used by substitution rules (BT.CPP's TestNode).

Config keys (as in BT.CPP's TestNodeConfig JSON): ``return_status`` (name, default SUCCESS),
``return_status_script`` (a script whose value names the status, 4.10), ``async_delay`` (ms;
0 completes in the first tick), ``success_script``, ``failure_script``, ``post_script``.
"""

from __future__ import annotations

from typing import Any

from ..node import NodeConfig, StatefulActionNode
from ..ports import parse_status
from ..status import FAILURE, RUNNING, SUCCESS, NodeStatus


class TestNode(StatefulActionNode):
    __test__ = False  # not a pytest class

    def __init__(self, name: str, config: NodeConfig, test_config: dict[str, Any]):
        from ..script import compile_script

        self._cfg = dict(test_config)
        self._status_script = (compile_script(self._cfg["return_status_script"])
                               if self._cfg.get("return_status_script") else None)
        self._scripts = {k: compile_script(self._cfg[k]) for k in ("success_script", "failure_script",
                                                                    "post_script") if self._cfg.get(k)}
        self._timer = None
        self._done = False
        super().__init__(name, config)

    def _result(self) -> NodeStatus:
        cfg = self.config
        if self._status_script is not None:
            status = parse_status(str(self._status_script.run(cfg.blackboard, cfg.enums)))
        else:
            status = parse_status(str(self._cfg.get("return_status", "SUCCESS")))
        key = {SUCCESS: "success_script", FAILURE: "failure_script"}.get(status)
        if key in self._scripts:
            self._scripts[key].run(cfg.blackboard, cfg.enums)
        if "post_script" in self._scripts:
            self._scripts["post_script"].run(cfg.blackboard, cfg.enums)
        return status

    def on_start(self) -> NodeStatus:
        delay_ms = float(self._cfg.get("async_delay", 0) or 0)
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
