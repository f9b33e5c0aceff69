"""What a run hands back besides its verdicts: artifact makers, called on the worker.

A maker is ``fn(run_spec, run_result, **options) -> value`` and is named either by a short name listed
in ``MAKERS`` or by ``'module:function'``, so a worker on another host finds it by import
(nothing has to be registered in the worker's process first). The value travels back to the
driver (keep it small: the trajectory for ``--report`` is a few kB), or the maker writes a
file to a path every worker shares and returns that path as a string; string values are also
kept in the results file.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .runner import RunResult
    from .runspec import RunSpec


def trajectory(run: RunSpec, result: RunResult) -> dict[str, Any] | None:
    """What the campaign report draws: the true path, the obstacle marks, faults, collisions, goals."""
    rec = result.record
    if rec is None:
        return None
    return {"trajectory": rec.trajectory[:, :3].copy(),
            "marks": [(r.goal.x, r.goal.y) for r in rec.nav_requests if r.method == "add_obstacle"],
            "faults": [(f.t, f.kind) for f in rec.fault_log],
            "collisions": [tuple(map(float, e.data["point"])) for e in rec.sim_events
                           if e.kind == "collision" and e.data.get("point") is not None],
            "goals": [(g.pose.x, g.pose.y) for g in rec.goals]}


MAKERS: dict[str, str] = {"trajectory": f"{__name__}:trajectory"}


def resolve(name: str) -> Callable[[Any, Any], Any]:
    """A maker by short name or 'module:function' (a clear error for a bad name)."""
    target = MAKERS.get(name, name)
    module, _, attr = target.partition(":")
    if not attr:
        raise ValueError(f"artifact {name!r}: not one of {sorted(MAKERS)} and not 'module:function'")
    try:
        fn = getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"artifact {name!r}: cannot import {target}: {exc}") from None
    if not callable(fn):
        raise ValueError(f"artifact {name!r}: {target} is not callable")
    return fn


def make_artifact(name: str, run: RunSpec, result: RunResult, **options: Any) -> Any:
    return resolve(name)(run, result, **options)
