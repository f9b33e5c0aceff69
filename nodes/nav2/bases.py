"""The base classes of Nav2's client nodes and the port helpers they share.

``BtActionNode`` reproduces ``nav2_behavior_tree::BtActionNode``: the first tick of an
activation reads the ports (``on_tick``) and sends the goal, and the node returns RUNNING
until the result is in. SUCCEEDED -> ``on_success`` (SUCCESS), ABORTED -> ``on_aborted``
(FAILURE, the server's error code on ``error_code_id``), **CANCELED -> ``on_cancelled``
(SUCCESS)**. While running, ``on_wait_for_result`` may change the goal (FollowPath does when
``{path}`` changes) and the goal is re-sent. Halting a running node cancels its goal (and
calls ``on_cancelled``, as Nav2 does, so outputs such as the path are written).

``BtServiceNode`` reproduces ``BtServiceNode``: the request goes out on the first tick; SUCCESS
when the response arrives, FAILURE when it does not within ``server_timeout`` (ms; port, else
the blackboard's ``server_timeout``, else bt_navigator's 20 ms) or when the call fails.

``BtCancelActionNode`` cancels the goals this tree sent to one server; ``SelectorNode`` outputs
the id last published on its topic. Goals go to ``context.navigation``; the ticks never await:
coroutines (planning, costmap services) run as tasks that are polled.
"""

from __future__ import annotations

import asyncio
from typing import Any, ClassVar

from bt_runtime.errors import LogicError
from bt_runtime.node import NodeConfig, StatefulActionNode, SyncActionNode
from bt_runtime.ports import STRING, input_port, output_port
from bt_runtime.runtime.messages import ActionStatus, NavErrorCode, NavResult
from bt_runtime.status import FAILURE, RUNNING, SUCCESS, NodeStatus

from ..types import ERROR_CODE, SERVER_TIMEOUT
from .common import log, nav2_topics, server_timeout

NONE = 0


def server_ports(default_server: str, service: bool = False) -> list:
    kind = "Service" if service else "Action server"
    return [input_port("server_name", STRING, description=f"{kind} name. If not specified, "
                                                            f"`{default_server}` is used."),
            input_port("server_timeout", SERVER_TIMEOUT,
                       description=f"{kind} timeout (ms). If not provided, uses the BT Navigator's "
                                   "`default_server_timeout` (20 ms)")]


def error_ports(what: str) -> list:
    return [output_port("error_code_id", ERROR_CODE, description=f"{what} error code"),
            output_port("error_msg", STRING, description=f"{what} error message")]


def safe_set_output(node: Any, name: str, value: Any) -> None:
    """Write an output if the XML remaps it to a blackboard entry (BT.CPP's setOutput returns
    an error, it does not throw, when the port is not connected)."""
    raw = node.config.output_ports.get(name)
    if raw is None:
        return
    s = raw.strip()
    if raw in ("=", "{=}") or (len(s) >= 3 and s[0] == "{" and s[-1] == "}"):
        node.set_output(name, value)


def _running_loop(node: Any) -> asyncio.AbstractEventLoop:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        raise LogicError(f"'{node.config.path}' [{node.registration_name}] needs a running asyncio event loop "
                         "(run the tree with the runtime or tick_while_running_async)") from None


class TaskHandle:
    """A coroutine of the navigation client (planning, a costmap service) as a handle."""

    __slots__ = ("task", "cancel_requested")

    def __init__(self, task: asyncio.Task):
        self.task = task
        self.cancel_requested = False

    def done(self) -> bool:
        return self.task.done()

    def cancel(self) -> None:
        if not self.task.done():
            self.cancel_requested = True
            self.task.cancel()

    def result(self) -> NavResult:
        task = self.task
        if task.cancelled():
            return NavResult(ActionStatus.CANCELED, NavErrorCode.NONE, "canceled")
        exc = task.exception()
        if exc is not None:
            return NavResult(ActionStatus.ABORTED, NavErrorCode.NONE, f"{type(exc).__name__}: {exc}")
        value = task.result()
        if isinstance(value, NavResult):
            return value
        return NavResult(ActionStatus.SUCCEEDED)

    @property
    def feedback(self) -> Any:
        return None


def start_task(node: Any, coro: Any) -> TaskHandle:
    loop = _running_loop(node)
    return TaskHandle(loop.create_task(coro, name=f"bt:{node.config.path}"))


def _goal_registry(node: Any) -> dict[str, set]:
    extras = getattr(node.context, "extras", None)
    if extras is None:
        return {}
    return extras.setdefault("nav2_goals", {})


# ---------------------------------------------------------------------------------------------
# BtActionNode
# ---------------------------------------------------------------------------------------------

class BtActionNode(StatefulActionNode):
    """Base of the Nav2 action-client nodes (see the module docstring)."""

    server: ClassVar[str] = ""  # Nav2's default action name (also the cancel-node registry key)
    code_map: ClassVar[dict[int, int]] = {}  # stack error code -> this action's Nav2 code

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.handle: Any = None
        self.goal: dict[str, Any] = {}
        self.goal_updated = False
        self.should_send_goal = True
        super().__init__(name, config)

    # -- hooks (Nav2's names) --------------------------------------------------------------------
    def on_tick(self) -> None:
        """Read the ports into ``self.goal``; set ``should_send_goal = False`` to fail."""

    def send_goal(self) -> Any:
        raise NotImplementedError

    def update_goal(self) -> None:
        """The goal changed while running: re-send it (Nav2 send_new_goal)."""
        self._send()

    def on_wait_for_result(self) -> None:
        """Called each tick while waiting; may set ``goal_updated``."""

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "error_code_id", NONE)
        safe_set_output(self, "error_msg", "")
        return SUCCESS

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "error_code_id", self.map_code(result.error_code))
        safe_set_output(self, "error_msg", result.error_msg)
        return FAILURE

    def on_cancelled(self) -> NodeStatus:
        safe_set_output(self, "error_code_id", NONE)
        safe_set_output(self, "error_msg", "")
        return SUCCESS

    def map_code(self, code: int) -> int:
        code = int(code)
        return self.code_map.get(code, code)

    # -- mechanics ---------------------------------------------------------------------------------
    def _send(self) -> None:
        old = self.handle
        self.handle = self.send_goal()
        reg = _goal_registry(self)
        if reg is not None and self.server:
            goals = reg.setdefault(self.server, set())
            if old is not None:
                goals.discard(old)
            goals.add(self.handle)

    def _forget(self) -> None:
        reg = _goal_registry(self)
        if self.handle is not None and self.server in reg:
            reg[self.server].discard(self.handle)
        self.handle = None

    def on_start(self) -> NodeStatus:
        self.should_send_goal = True
        self.goal_updated = False
        self.goal = {}
        self.on_tick()
        if not self.should_send_goal:
            return FAILURE
        try:
            self._send()
        except LogicError:
            raise
        except Exception as exc:  # Nav2: "send_goal failed" -> FAILURE
            log.warning("nav2_send_goal_failed", node=self.config.path, error=f"{type(exc).__name__}: {exc}")
            self.handle = None
            return FAILURE
        return self._poll()

    def on_running(self) -> NodeStatus:
        return self._poll()

    def _poll(self) -> NodeStatus:
        handle = self.handle
        if handle is None:
            return FAILURE
        if not handle.done():
            self.on_wait_for_result()
            if self.goal_updated:
                self.goal_updated = False
                self.update_goal()
                handle = self.handle
            if not handle.done():
                return RUNNING
        result = handle.result()
        self._forget()
        if result.status is ActionStatus.SUCCEEDED:
            return self.on_success(result)
        if result.status is ActionStatus.ABORTED:
            return self.on_aborted(result)
        return self.on_cancelled()

    def on_halted(self) -> None:
        handle = self.handle
        if handle is not None and not handle.done():
            handle.cancel()
            self.on_cancelled()
        self._forget()


# ---------------------------------------------------------------------------------------------
# Cancel nodes (BtCancelActionNode)
# ---------------------------------------------------------------------------------------------

class BtCancelActionNode(SyncActionNode):
    """Cancels every goal this tree's Nav2 nodes sent to the action server (Nav2 cancels all
    goals of the server sent more than 10 ms ago). SUCCESS (also when nothing runs)."""

    server: ClassVar[str] = ""

    @classmethod
    def provided_ports(cls):
        return server_ports(cls.server)

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        for handle in list(_goal_registry(self).get(self.server, ())):
            if not handle.done():
                handle.cancel()
        return SUCCESS


# ---------------------------------------------------------------------------------------------
# Services
# ---------------------------------------------------------------------------------------------

class BtServiceNode(StatefulActionNode):
    """Base of the Nav2 service-client nodes (see the module docstring)."""

    service: ClassVar[str] = ""

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.future: TaskHandle | None = None
        self.sent_time = 0.0
        self.timeout = 0.02
        self.should_send_request = True
        super().__init__(name, config)

    def on_tick(self) -> None:
        """Fill the request; set ``should_send_request = False`` to fail."""

    def call(self) -> Any:
        """The coroutine (or plain value) that serves the request."""
        raise NotImplementedError

    def on_completion(self, response: Any) -> NodeStatus:
        return SUCCESS

    def on_start(self) -> NodeStatus:
        self.should_send_request = True
        self.on_tick()
        if not self.should_send_request:
            return FAILURE
        self.timeout = server_timeout(self)
        try:
            result = self.call()
        except LogicError:
            raise
        except Exception as exc:
            log.warning("nav2_service_failed", node=self.config.path, error=f"{type(exc).__name__}: {exc}")
            return FAILURE
        if asyncio.iscoroutine(result):
            self.future = start_task(self, result)
            self.sent_time = self.config.clock()
            return self.check_future()
        return self.on_completion(result)

    def on_running(self) -> NodeStatus:
        return self.check_future()

    def check_future(self) -> NodeStatus:
        future = self.future
        if future is None:
            return FAILURE
        if future.done():
            self.future = None
            task = future.task
            if task.cancelled() or task.exception() is not None:
                exc = None if task.cancelled() else task.exception()
                log.warning("nav2_service_failed", node=self.config.path,
                            error=f"{type(exc).__name__}: {exc}" if exc else "cancelled")
                return FAILURE
            return self.on_completion(task.result())
        if self.config.clock() - self.sent_time < self.timeout:
            return RUNNING
        log.warning("nav2_service_timeout", node=self.config.path, service=self.service,
                    timeout_ms=round(self.timeout * 1000))
        future.cancel()
        self.future = None
        return FAILURE

    def on_halted(self) -> None:
        if self.future is not None:
            self.future.cancel()
            self.future = None


# ---------------------------------------------------------------------------------------------
# Selectors
# ---------------------------------------------------------------------------------------------

class SelectorNode(SyncActionNode):
    """A selector: outputs the id last published on its topic, else the default; FAILURE if
    neither exists. Publish with ``nodes.nav2.common.publish(context, topic, "id")``."""

    topic_default: ClassVar[str] = ""
    default_port: ClassVar[str] = ""
    output_name: ClassVar[str] = ""
    what: ClassVar[str] = ""

    @classmethod
    def provided_ports(cls):
        return [input_port("topic_name", STRING, cls.topic_default, f"the input topic name to select the "
                                                                     f"{cls.what}"),
                input_port(cls.default_port, STRING, description=f"the default {cls.what} to use if there "
                                                                 "is not any external topic message received."),
                output_port(cls.output_name, STRING, description=f"Selected {cls.what} by subscription")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        super().__init__(name, config)
        self.topic = self.get_input("topic_name", self.topic_default) or self.topic_default
        self.last_selected = ""

    def tick(self) -> NodeStatus:
        msg = nav2_topics(self.context).get(self.topic)
        if isinstance(msg, str) and msg:
            self.last_selected = msg
        if not self.last_selected:
            default = self.get_input(self.default_port, "") or ""
            if not default:
                return FAILURE
            self.last_selected = default
        safe_set_output(self, self.output_name, self.last_selected)
        return SUCCESS
