"""Time-based nodes: Sleep, Timeout, Delay (spec 4.3, 4.5).

They use the tree's timer queue, which runs on the tree's clock (the event loop's clock under
the runtime), so they behave identically on virtual and real time. A timer that expires emits
the wake-up signal, like BT.CPP's timer thread does.
"""

from __future__ import annotations

from ..errors import BTRuntimeError
from ..node import DecoratorNode, NodeConfig, StatefulActionNode, tick_cell
from ..ports import UINT, input_port
from ..status import FAILURE, RUNNING, SUCCESS, NodeStatus
from ..timers import Timer


class SleepNode(StatefulActionNode):
    """RUNNING for ``msec`` milliseconds, then SUCCESS."""

    @classmethod
    def provided_ports(cls):
        return [input_port("msec", UINT)]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._timer: Timer | None = None
        self._waiting = False
        super().__init__(name, config)

    def on_start(self) -> NodeStatus:
        try:
            msec = self.get_input("msec")
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [msec] in SleepNode") from None
        if msec <= 0:
            return SUCCESS
        self.set_status(RUNNING)
        self._waiting = True
        self._timer = self.config.timers.add(msec / 1000.0, self._expired)
        return RUNNING

    def _expired(self) -> None:
        self._waiting = False
        self.config.wake_up.emit()

    def on_running(self) -> NodeStatus:
        return RUNNING if self._waiting else SUCCESS

    def on_halted(self) -> None:
        self._waiting = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None


class TimeoutNode(DecoratorNode):
    """Halt the child and return FAILURE if it is still RUNNING after ``msec`` ms."""

    _bare_tick_ok = True  # tick() resets a completed child itself

    @classmethod
    def provided_ports(cls):
        return [input_port("msec", UINT, description="After a certain amount of time, halt() the child "
                                                     "if it is still running.")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._started = False
        self._child_halted = False
        self._timer: Timer | None = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        try:
            msec = self.get_input("msec")
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [msec] in TimeoutNode") from None
        if not self._started:
            self._started = True
            self.set_status(RUNNING)
            self._child_halted = False
            if msec > 0:
                self._timer = self.config.timers.add(msec / 1000.0, self._expired)
        if self._child_halted:
            self._started = False
            return FAILURE
        status = tick_cell(self._child_cell)
        if status is SUCCESS or status is FAILURE:
            self._started = False
            self._cancel()
            self.reset_child()
        return status

    def _expired(self) -> None:
        if self._child is not None and self._child_cell.status is RUNNING:
            self._child_halted = True
            self.reset_child()
            self.config.wake_up.emit()

    def _cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def halt(self) -> None:
        self._started = False
        self._cancel()
        DecoratorNode.halt(self)


class DelayNode(DecoratorNode):
    """Wait ``delay_msec`` ms (returning RUNNING) before ticking the child."""

    _bare_tick_ok = True  # tick() resets a completed child itself

    @classmethod
    def provided_ports(cls):
        return [input_port("delay_msec", UINT, description="Tick the child after a few milliseconds")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._started = False
        self._complete = False
        self._timer: Timer | None = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        try:
            msec = self.get_input("delay_msec")
        except BTRuntimeError:
            raise BTRuntimeError("Missing parameter [delay_msec] in DelayNode") from None
        if not self._started:
            self._complete = False
            self._started = True
            self.set_status(RUNNING)
            self._timer = self.config.timers.add(msec / 1000.0, self._expired)
        if self._complete:
            status = tick_cell(self._child_cell)
            if status is SUCCESS or status is FAILURE:
                self._started = False
                self.reset_child()
            return status
        return RUNNING

    def _expired(self) -> None:
        self._complete = True
        self.config.wake_up.emit()

    def halt(self) -> None:
        self._started = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        DecoratorNode.halt(self)
