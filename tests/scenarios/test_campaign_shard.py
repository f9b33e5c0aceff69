"""`--shard K/N` slices a campaign deterministically; `scenarios merge` of the N result files
gives the table and runs of the campaign run in one piece."""

from __future__ import annotations

import json

from bt_runtime.__main__ import main
from sim.scenarios.backends import LocalBackend
from sim.scenarios.campaign import format_table, run_campaign

from .campaign_support import CHEAP, by_key, cheap_plan

RUNS, SEED, SHARDS = 3, 5, 3
ARGS = ["scenarios", "--only", ",".join(CHEAP), "--mode", "without", "--runs", str(RUNS), "--seed", str(SEED),
        "--jobs", "1"]


def test_shards_merged_equal_a_single_campaign(tmp_path, capsys):
    files = [tmp_path / f"shard{k}.jsonl" for k in range(1, SHARDS + 1)]
    for k, path in enumerate(files, 1):
        assert main([*ARGS, "--shard", f"{k}/{SHARDS}", "--results", str(path)]) == 0
    keys = [json.loads(line)["key"] for path in files for line in path.read_text().splitlines()
            if '"type":"run"' in line]
    assert sorted(keys) == sorted(r.key for r in cheap_plan(RUNS, SEED))  # disjoint, and cover the plan
    capsys.readouterr()

    merged = tmp_path / "merged.json"
    assert main(["scenarios", "merge", *map(str, files), "--json", str(merged)]) == 0
    printed = capsys.readouterr().out
    whole = run_campaign(cheap_plan(RUNS, SEED), LocalBackend(jobs=1))
    assert format_table(whole) in printed
    data = json.loads(merged.read_text())
    runs = [r for s in data["scenarios"].values() for r in s["without"]["results"]]
    assert by_key(runs) == by_key(whole.results)
    assert data["meta"]["runs"] == len(whole.results)
