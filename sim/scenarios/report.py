"""PNG reports of a campaign: one picture per scenario (map, every run's trajectory, goals,
obstacle marks the autonomy layer added) and a summary in Markdown."""

from __future__ import annotations

from pathlib import Path

from ..render import position_at, render_png
from ..world import load_world
from .campaign import CampaignResult, failure_reasons, format_table

WITH, WITHOUT, MARK = (20, 150, 60), (220, 30, 30), (200, 0, 160)


def write_report(result: CampaignResult, out_dir: str | Path) -> list[Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, spec in result.specs.items():
        world = load_world(spec.world)
        lines, marks, events, goals = [], [], [], {}
        for (scenario, mode, _run), data in sorted(result.trajectories.items()):
            if scenario != name:
                continue
            lines.append((data["trajectory"], WITH if mode == "with" else WITHOUT))
            if mode == "with":
                marks += [(x, y, MARK, "obstacle added by the layer") for x, y in data["marks"]]
            for i, (gx, gy) in enumerate(data["goals"]):
                goals[f"goal {i}"] = (gx, gy)
            events += _fault_events(data) + [{"kind": "collision", "data": {"x": x, "y": y}}
                                              for x, y in data.get("collisions", ())]
        rate_with = result.success_rate(name, "with")
        rate_without = result.success_rate(name, "without")
        title = (f"{name}: {len(lines)} runs; reached with the autonomy layer {rate_with:.0f}%, "
                 f"without {rate_without:.0f}%")
        legend = {f"with the autonomy layer ({rate_with:.0f}% succeeded)": WITH,
                  f"without ({rate_without:.0f}% succeeded)": WITHOUT}
        written.append(render_png(out / f"{name}.png", world, goals=goals, trajectories=lines, marks=marks,
                                  events=events, title=title, legend=legend, scale=40.0))
    summary = out / "summary.md"
    parts = ["# Scenario campaign", "", f"{len(result.results)} runs in {result.wall_time:.1f} s on "
             f"{result.jobs} process(es).", "", "```", format_table(result), "```", "",
             "## Failure reasons", ""]
    for name, modes in result.by_scenario().items():
        for mode in ("with", "without"):
            reasons = failure_reasons(modes[mode])
            for reason, count in reasons.items():
                parts.append(f"- **{name}** ({mode}, {count}x): {reason}")
    parts += ["", "## Pictures", ""] + [f"![{p.stem}]({p.name})" for p in written]
    summary.write_text("\n".join(parts) + "\n", encoding="utf-8")
    written.append(summary)
    return written


def _fault_events(data: dict) -> list[dict]:
    """Each injected fault, placed where the robot was when it struck (the run's own trajectory)."""
    events = []
    for t, kind in data.get("faults", ()):
        p = position_at(data["trajectory"], t)
        if p is not None:
            events.append({"kind": "fault", "data": {"x": p[0], "y": p[1], "fault": kind}})
    return events
