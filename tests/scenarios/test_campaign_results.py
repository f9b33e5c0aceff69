"""Results files: a cut-off last line is skipped and trimmed on resume; runs that disagree,
a changed scenario, another seed, or writing over a campaign are refused with file and line."""

from __future__ import annotations

import json

import pytest

from sim.scenarios.results import ResultsError, ResultsLog, read_results, spec_line
from sim.scenarios.runspec import parse_shard, shard_runs
from sim.scenarios.spec import load_scenario

from .campaign_support import cheap_plan


def _line(run, success=False, reason="never restarted") -> dict:
    return {"type": "run", "key": run.key, "scenario": run.scenario.name, "mode": run.mode, "run": run.run,
            "seed": run.seed, "success": success, "sim_time": 1.0, "wall_time": 0.1,
            "verdicts": [{"criterion": "c", "passed": success, "reason": reason}]}


def _write(path, lines, tail="") -> None:
    path.write_text("".join(json.dumps(x) + "\n" for x in lines) + tail, encoding="utf-8")


def test_a_cut_off_last_line_is_skipped_and_trimmed_before_appending(tmp_path):
    plan = cheap_plan(runs=2)
    spec = plan[0].scenario
    path = tmp_path / "r.jsonl"
    _write(path, [spec_line(spec), _line(plan[0])], tail='{"type":"run","ke')
    assert list(read_results([path]).runs) == [plan[0].key]
    with ResultsLog(path, [spec], resume=True) as log:
        log.append(_line(plan[1]))
    assert list(read_results([path]).runs) == [plan[0].key, plan[1].key]


def test_runs_recorded_differently_are_refused_with_file_and_line(tmp_path):
    run = cheap_plan(runs=1)[0]
    a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    _write(a, [spec_line(run.scenario), _line(run)])
    _write(b, [spec_line(run.scenario), _line(run, reason="restarted")])
    assert len(read_results([a, a]).runs) == 1  # the same run twice counts once
    with pytest.raises(ResultsError, match=r"b\.jsonl:2: run Lidar_1/without/0 was recorded differently"):
        read_results([a, b])


def test_a_bad_line_names_file_and_line(tmp_path):
    path = tmp_path / "r.jsonl"
    path.write_text('{"type": "scenario"}\n', encoding="utf-8")
    with pytest.raises(ResultsError, match=r"r\.jsonl:1: bad scenario record"):
        read_results([path])
    run = cheap_plan(runs=1)[0]
    path.write_text(json.dumps({**_line(run), "mode": "sometimes"}) + "\n", encoding="utf-8")
    with pytest.raises(ResultsError, match=r"r\.jsonl:1: run record: mode: "):
        read_results([path])
    path.write_text(json.dumps({**_line(run), "run": 7}) + "\n", encoding="utf-8")
    with pytest.raises(ResultsError, match="does not match its scenario, mode and run"):
        read_results([path])
    path.write_text("[1, 2]\n", encoding="utf-8")
    with pytest.raises(ResultsError, match=r"r\.jsonl:1: unknown record type"):
        read_results([path])


def test_an_existing_campaign_is_not_overwritten_and_a_changed_scenario_not_resumed(tmp_path):
    run = cheap_plan(runs=1)[0]
    path = tmp_path / "r.jsonl"
    _write(path, [spec_line(run.scenario), _line(run)])
    with pytest.raises(ResultsError, match="pass --resume"):
        ResultsLog(path, [run.scenario], resume=False)
    header_only = tmp_path / "h.jsonl"  # a campaign that failed before its first run
    _write(header_only, [spec_line(run.scenario)])
    ResultsLog(header_only, [run.scenario], resume=False).close()
    changed = run.scenario.model_copy(update={"time_limit": run.scenario.time_limit + 1})
    with pytest.raises(ResultsError, match="scenario Lidar_1 differs"):
        ResultsLog(path, [changed], resume=True)


def test_a_resume_with_another_seed_is_refused(tmp_path):
    run = cheap_plan(runs=1)[0]
    path = tmp_path / "r.jsonl"
    _write(path, [spec_line(run.scenario), _line(run)])
    with ResultsLog(path, [run.scenario], resume=True) as log:
        log.check_seeds(cheap_plan(runs=1))
        with pytest.raises(ResultsError, match="another --seed"):
            log.check_seeds(cheap_plan(runs=1, seed=6))


def test_a_spec_survives_the_results_file():
    spec = load_scenario("Battery_1")
    line = json.loads(json.dumps(spec_line(spec)))
    assert type(spec).model_validate(line["spec"]) == spec


def test_shards_partition_the_plan():
    plan = cheap_plan(runs=3)
    shards = [shard_runs(plan, k, 4) for k in range(1, 5)]
    assert sorted(r.key for s in shards for r in s) == sorted(r.key for r in plan)
    assert {r.scenario.name for r in shards[0]} == {"Lidar_1", "NoPathFound_2"}  # every shard a mix
    assert parse_shard("2/4") == (2, 4)
    for bad in ("0/4", "5/4", "2", "a/b"):
        with pytest.raises(ValueError, match="--shard"):
            parse_shard(bad)


def test_the_cli_reports_bad_results_files_and_flags_as_usage_errors(tmp_path, capsys):
    from bt_runtime.__main__ import main

    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type": "run", "key": "x"}\n', encoding="utf-8")
    assert main(["scenarios", "merge", str(bad)]) == 2
    assert f"{bad}:1: run record: scenario: Field required" in capsys.readouterr().err
    assert main(["scenarios", "--only", "Lidar_1", "--ray-address", "auto"]) == 2
    assert "--ray-address needs --backend ray" in capsys.readouterr().err
    assert main(["scenarios", "--only", "Lidar_1", "--shard", "3/2"]) == 2
    assert "K must be between 1 and N" in capsys.readouterr().err


def test_merged_variant_results_are_summarised_per_family(tmp_path, capsys):
    from bt_runtime.__main__ import main
    from sim.scenarios.variants import family_of, generate

    plan = generate(3, 0, modes=("with",))
    path = tmp_path / "variants.jsonl"
    _write(path, [spec_line(r.scenario) for r in plan] + [_line(r, success=True) for r in plan])
    assert main(["scenarios", "merge", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("Family")
    for r in plan:
        assert f"{family_of(r.scenario.name):<18}with" in out
