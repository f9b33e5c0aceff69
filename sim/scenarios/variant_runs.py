"""``scenarios --variants N``: the variant generator's runs as a campaign, summarised per
failure family (success rate per family, then every failed run with its reasons)."""

from __future__ import annotations

import collections
from typing import Any

from .campaign import CampaignResult
from .runspec import RunSpec
from .spec import ScenarioSpec
from .variants import FAMILIES, family_of, generate


def variant_campaign(args: Any, artifacts: dict, options: dict) -> tuple[list[ScenarioSpec], list[RunSpec], Any, Any]:
    """(specs, plan, table formatter, failures formatter) for the CLI's ``--variants N``."""
    if args.variants < 1:
        raise ValueError("--variants must be at least 1")
    families = [n for item in args.only for n in item.split(",") if n] or None
    modes = ("with",) if args.mode == "both" else (args.mode,)
    plan = generate(args.variants, args.seed, families=families, modes=modes, artifacts=artifacts, options=options)
    specs = list({r.scenario.name: r.scenario for r in plan}.values())
    return specs, plan, format_families, format_variant_failures


def format_families(result: CampaignResult) -> str:
    """Per family and mode: runs, successes, success %; and all families together."""
    counts: dict[tuple[str, str], list[int]] = collections.defaultdict(lambda: [0, 0])
    for r in result.results:
        c = counts[(family_of(r["scenario"]), r["mode"])]
        c[0] += 1
        c[1] += int(r["success"])
    head = f"{'Family':<18}{'Mode':<9}{'Runs':>6}{'OK':>6}{'Success %':>11}"
    lines = [head, "-" * len(head)]
    total: dict[str, list[int]] = collections.defaultdict(lambda: [0, 0])
    order = {f: i for i, f in enumerate(FAMILIES)}
    for (fam, mode), (n, ok) in sorted(counts.items(), key=lambda kv: (order.get(kv[0][0], 99), kv[0][1])):
        lines.append(f"{fam:<18}{mode:<9}{n:>6}{ok:>6}{100.0 * ok / n:>11.1f}")
        total[mode][0] += n
        total[mode][1] += ok
    for mode, (n, ok) in sorted(total.items()):
        lines.append(f"{'all':<18}{mode:<9}{n:>6}{ok:>6}{100.0 * ok / n:>11.1f}")
    return "\n".join(lines)


def format_variant_failures(result: CampaignResult) -> str:
    """Every failed run with the layer: the variant, what it varied, and why it failed."""
    lines = []
    for r in result.results:
        if r["success"] or r["mode"] != "with":
            continue
        spec = result.specs[r["scenario"]]
        why = "; ".join(f"{v['criterion']}: {v['reason']}" for v in r["verdicts"] if not v["passed"])
        lines.append(f"  {r['scenario']} (seed {r['seed']}): {spec.description} -> {why}")
    return "\n".join(lines)


__all__ = ["format_families", "format_variant_failures", "variant_campaign"]
