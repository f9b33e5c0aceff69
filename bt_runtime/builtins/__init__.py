"""Every node BehaviorTree.CPP 4.10 registers by default (spec 4.1), under the same IDs."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..node import TreeNodeManifest, manifest_for
from .actions import (
    AlwaysFailureNode,
    AlwaysSuccessNode,
    ScriptConditionNode,
    ScriptNode,
    SetBlackboardNode,
    UnsetBlackboardNode,
)
from .branching import IfThenElseNode, TryCatchNode, WhileDoElseNode, switch_class
from .decorators import (
    ForceFailureNode,
    ForceSuccessNode,
    InverterNode,
    KeepRunningUntilFailureNode,
    PreconditionNode,
    RepeatNode,
    RetryNode,
    RunOnceNode,
    SubTreeNode,
)
from .loops import LoopBoolNode, LoopDoubleNode, LoopIntNode, LoopStringNode
from .parallel import ParallelAllNode, ParallelNode
from .reactive import ReactiveFallbackNode, ReactiveNode, ReactiveSequenceNode
from .sequences import (
    AsyncFallbackNode,
    AsyncSequenceNode,
    FallbackNode,
    SequenceNode,
    SequenceWithMemoryNode,
    SequentialNode,
)
from .timing import DelayNode, SleepNode, TimeoutNode
from .updates import SkipUnlessUpdatedNode, WaitValueUpdateNode, WasEntryUpdatedNode

if TYPE_CHECKING:
    from ..factory import BehaviorTreeFactory

BUILTIN_NODES = {
    # controls
    "Fallback": FallbackNode,
    "AsyncFallback": AsyncFallbackNode,
    "Sequence": SequenceNode,
    "AsyncSequence": AsyncSequenceNode,
    "SequenceWithMemory": SequenceWithMemoryNode,
    "Parallel": ParallelNode,
    "ParallelAll": ParallelAllNode,
    "ReactiveSequence": ReactiveSequenceNode,
    "ReactiveFallback": ReactiveFallbackNode,
    "IfThenElse": IfThenElseNode,
    "WhileDoElse": WhileDoElseNode,
    "TryCatch": TryCatchNode,
    "Switch2": switch_class(2),
    "Switch3": switch_class(3),
    "Switch4": switch_class(4),
    "Switch5": switch_class(5),
    "Switch6": switch_class(6),
    # decorators
    "Inverter": InverterNode,
    "RetryUntilSuccessful": RetryNode,
    "KeepRunningUntilFailure": KeepRunningUntilFailureNode,
    "Repeat": RepeatNode,
    "Timeout": TimeoutNode,
    "Delay": DelayNode,
    "RunOnce": RunOnceNode,
    "ForceSuccess": ForceSuccessNode,
    "ForceFailure": ForceFailureNode,
    "Precondition": PreconditionNode,
    "LoopInt": LoopIntNode,
    "LoopBool": LoopBoolNode,
    "LoopDouble": LoopDoubleNode,
    "LoopString": LoopStringNode,
    "SkipUnlessUpdated": SkipUnlessUpdatedNode,
    "WaitValueUpdate": WaitValueUpdateNode,
    # actions and conditions
    "AlwaysSuccess": AlwaysSuccessNode,
    "AlwaysFailure": AlwaysFailureNode,
    "Script": ScriptNode.builder(),
    "SetBlackboard": SetBlackboardNode,
    "Sleep": SleepNode,
    "UnsetBlackboard": UnsetBlackboardNode,
    "WasEntryUpdated": WasEntryUpdatedNode,
    "ScriptCondition": ScriptConditionNode.builder(),
    # subtree
    "SubTree": SubTreeNode,
}


_CLASS_OF = {"Fallback": SequentialNode, "AsyncFallback": SequentialNode, "Sequence": SequentialNode,
             "AsyncSequence": SequentialNode, "ReactiveSequence": ReactiveNode,
             "ReactiveFallback": ReactiveNode, "Script": ScriptNode, "ScriptCondition": ScriptConditionNode}


_BUILTIN_MANIFESTS: dict[str, TreeNodeManifest] = {}


def register_builtins(factory: BehaviorTreeFactory) -> None:
    """Every factory starts with these. Their manifests are worked out once per process
    (ports from ``provided_ports()``, names checked) and each factory gets its own copies:
    a factory costs a tenth of a millisecond instead of ~0.3 ms, which small trees feel."""
    if not _BUILTIN_MANIFESTS:
        for registration_id, builder in BUILTIN_NODES.items():
            cls = _CLASS_OF.get(registration_id, builder)
            _BUILTIN_MANIFESTS[registration_id] = manifest_for(cls, registration_id, builtin=True)
    # (stored directly: a new factory has nothing registered, and these IDs are valid)
    builders, manifests = factory.builders, factory.manifests
    for registration_id, builder in BUILTIN_NODES.items():
        builders[registration_id] = builder
        manifests[registration_id] = _BUILTIN_MANIFESTS[registration_id].copy()
