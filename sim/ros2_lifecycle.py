"""sim-robot's lifecycle nodes: ``<node>/get_state`` and ``<node>/change_state`` as rclcpp_lifecycle
answers them, over the simulator's components and the Nav2 stand-in's servers.

The state machine is ROS 2's managed-node design (lifecycle_msgs): unconfigured -configure->
inactive -activate-> active -deactivate-> inactive -cleanup-> unconfigured, shutdown from any
primary state to finalized; a transition not allowed from the current state is refused
(``success: false``), as rclcpp_lifecycle does. While activating, the node reports the
transition state *activating* (13). ``on_activate`` returning FAILURE leaves the node inactive
(``refuse_activate``: a node that will not activate, for tests); an error during activation
(the component does not come up) ends in unconfigured, as ErrorProcessing does.

What the states do: only an *active* node runs. The Nav2 stand-in's servers start
unconfigured (their actions fail until they are brought up, as Nav2's servers reject goals
while inactive) unless sim-robot is started with ``--nav-autostart``; the sensor drivers start
active. Deactivating stops the component (``Simulator.crash`` / ``NavStack.crash``); activating
starts it (``Simulator.restart`` / ``NavStack.restart``). A component that crashes by itself
while active reports *unconfigured* (its driver went through ErrorProcessing).
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

import structlog

from bt_runtime.runtime.messages import ComponentState
from bt_runtime.runtime.ros2 import idl

log = structlog.get_logger("sim.ros2_lifecycle")

T = idl.Transition
ST = idl.State
UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = (ST.PRIMARY_STATE_UNCONFIGURED, ST.PRIMARY_STATE_INACTIVE,
                                             ST.PRIMARY_STATE_ACTIVE, ST.PRIMARY_STATE_FINALIZED)
CONFIGURING, CLEANINGUP, SHUTTINGDOWN, ACTIVATING, DEACTIVATING = 10, 11, 12, 13, 14
LABELS = {UNCONFIGURED: "unconfigured", INACTIVE: "inactive", ACTIVE: "active", FINALIZED: "finalized",
          CONFIGURING: "configuring", CLEANINGUP: "cleaningup", SHUTTINGDOWN: "shuttingdown",
          ACTIVATING: "activating", DEACTIVATING: "deactivating"}
# lifecycle_msgs/msg/Transition ids of the shutdown transitions from each primary state
SHUTDOWN = {5: UNCONFIGURED, 6: INACTIVE, 7: ACTIVE}


class EmulatedLifecycleNode:
    """One managed node. ``running()`` is the component's actual state; ``start(first)`` brings
    it up (True when running), ``stop()`` takes it down; ``hung()`` True: no answers at all."""

    def __init__(self, name: str, *, initial: int, running: Callable[[], ComponentState],
                 start: Callable[[bool], Awaitable[bool]], stop: Callable[[], None],
                 hung: Callable[[], bool] = lambda: False, refuse_activate: bool = False):
        self.name = name
        self.recorded = initial
        self.running = running
        self._start = start
        self._stop = stop
        self.hung = hung
        self.refuse_activate = refuse_activate
        self.in_transition: int | None = None
        self.was_active = initial == ACTIVE
        self.crashed = False  # went down by itself (not through a transition)
        self.transitions: list[tuple[int, bool]] = []  # (transition id, success), for tests and logs

    def state(self) -> int:
        if self.in_transition is not None:
            return self.in_transition
        actual = self.running()
        if self.recorded == ACTIVE:
            if actual is ComponentState.STARTING:
                return ACTIVATING
            if actual is not ComponentState.ACTIVE:  # it crashed: ErrorProcessing -> unconfigured
                self.recorded = UNCONFIGURED
                self.crashed = True
        elif self.crashed and actual is ComponentState.ACTIVE:  # a transient fault is over: running again
            self.recorded = ACTIVE
            self.crashed = False
        return self.recorded

    def get_state(self, _request: Any) -> Any:
        if self.hung():
            return None  # a hung node does not answer
        sid = self.state()
        return idl.GetState_Response(current_state=ST(sid, LABELS.get(sid, "unknown")))

    async def change_state(self, request: Any) -> Any:
        if self.hung():
            return None
        t = int(request.transition.id)
        ok = await self._apply(t, self.state())
        self.transitions.append((t, ok))
        log.info("sim_robot_lifecycle", node=self.name, transition=t, success=ok, state=LABELS.get(self.recorded))
        return idl.ChangeState_Response(success=ok)

    async def _apply(self, t: int, state: int) -> bool:
        if t == T.TRANSITION_CONFIGURE and state == UNCONFIGURED:
            self.recorded = INACTIVE
            return True
        if t == T.TRANSITION_CLEANUP and state == INACTIVE:
            self.recorded = UNCONFIGURED
            return True
        if t == T.TRANSITION_ACTIVATE and state == INACTIVE:
            if self.refuse_activate:  # on_activate() returned FAILURE: back to inactive
                return False
            self.in_transition = ACTIVATING
            self.crashed = False
            try:
                ok = await self._start(not self.was_active)
            finally:
                self.in_transition = None
            self.recorded = ACTIVE if ok else UNCONFIGURED  # an error: ErrorProcessing -> unconfigured
            self.was_active = self.was_active or ok
            return ok
        if t == T.TRANSITION_DEACTIVATE and state == ACTIVE:
            self._stop()
            self.recorded = INACTIVE
            return True
        if SHUTDOWN.get(t) == state:
            if state == ACTIVE:
                self._stop()
            self.recorded = FINALIZED
            return True
        return False  # not a transition of the current state


def take_down(nav: Any, name: str) -> None:
    """A stand-in server that has not been activated yet: not running, without a crash report."""
    comp = nav.components[name]
    comp.state = ComponentState.INACTIVE
    comp.generation += 1
    comp.changed()
