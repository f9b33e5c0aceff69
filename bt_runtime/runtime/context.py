"""The runtime context: how nodes reach the robot and the autonomy layer, without globals.

The factory is created with a context; every node sees it as ``node.context``. The same tree
therefore runs in unit tests (a context with fakes, or None), in simulation and on hardware.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .messages import RobotInfo

if TYPE_CHECKING:
    from .backup import DataBackup
    from .config import RuntimeConfig
    from .driver import NavigationClient, RobotDriver
    from .gate import DecisionGate
    from .supervisor import SystemSupervisor


@dataclass
class RuntimeContext:
    driver: RobotDriver
    supervisor: SystemSupervisor
    backup: DataBackup
    gate: DecisionGate
    config: RuntimeConfig
    clock: Callable[[], float]
    robot: RobotInfo = field(default_factory=RobotInfo)
    extras: dict[str, Any] = field(default_factory=dict)  # scenario or application specific

    @property
    def navigation(self) -> NavigationClient:
        return self.driver.navigation

    def now(self) -> float:
        return self.clock()
