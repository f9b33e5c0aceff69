"""Campaign results as JSON lines: streamed as runs finish, read back to resume or merge.

One line per record. ``{"type": "scenario", "name": ..., "spec": {...}}`` carries a scenario's
full spec (a merged table needs the paper's figures, and a resumed campaign must not mix runs
of a changed scenario); ``{"type": "run", "key": "Name/mode/i", ...}`` is one finished run and
its verdicts. Lines are appended and flushed one at a time, so a campaign killed at any
moment leaves every finished run on disk and at worst one cut-off last line, which readers
skip (and a resume trims before appending).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .runspec import run_key
from .spec import ScenarioSpec


class VerdictLine(BaseModel):
    criterion: str
    passed: bool
    reason: str


class RunLine(BaseModel):
    """What a run record must hold (more fields, e.g. host, cpu_time, artifacts, are kept as they are)."""

    model_config = ConfigDict(extra="allow")
    key: str
    scenario: str
    mode: Literal["with", "without"]
    run: int = Field(ge=0)
    seed: int
    success: bool
    sim_time: float = 0.0
    wall_time: float = 0.0
    verdicts: list[VerdictLine]


class ResultsError(ValueError):
    """A results file that cannot be used; the message names the file and line."""


@dataclass
class Recorded:
    """What one or more results files hold: specs by name, runs by key (each once)."""

    specs: dict[str, ScenarioSpec] = field(default_factory=dict)
    runs: dict[str, dict[str, Any]] = field(default_factory=dict)
    _where: dict[str, str] = field(default_factory=dict, repr=False)

    def add_spec(self, spec: ScenarioSpec, where: str) -> None:
        known = self.specs.get(spec.name)
        if known is not None and known != spec:
            raise ResultsError(f"{where}: scenario {spec.name} differs from the one in "
                               f"{self._where[spec.name]}; results of different scenarios cannot be combined")
        if known is None:
            self.specs[spec.name] = spec
            self._where[spec.name] = where

    def add_run(self, line: dict[str, Any], where: str) -> None:
        key = line["key"]
        known = self.runs.get(key)
        if known is not None and _comparable(known) != _comparable(line):
            raise ResultsError(f"{where}: run {key} was recorded differently in {self._where[key]}")
        if known is None:
            self.runs[key] = line
            self._where[key] = where


def _comparable(line: dict[str, Any]) -> tuple:
    """What must agree when a run appears twice (timings and the host may differ)."""
    return line.get("seed"), line.get("success"), json.dumps(line.get("verdicts"), sort_keys=True)


def read_results(paths: Iterable[str | Path], into: Recorded | None = None) -> Recorded:
    """Every spec and run in the files; a run in several files must agree and counts once."""
    recorded = into if into is not None else Recorded()
    for path in paths:
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ResultsError(f"{path}: no such results file") from None
        lines = text.split("\n")
        complete = lines[:-1]  # the part after the last newline is empty or a cut-off line
        for number, raw in enumerate(complete, 1):
            if raw.strip():
                _read_line(recorded, raw, f"{path}:{number}")
    return recorded


def _read_line(recorded: Recorded, raw: str, where: str) -> None:
    try:
        line = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise ResultsError(f"{where}: not a JSON line ({exc.msg})") from None
    kind = line.get("type") if isinstance(line, dict) else None
    if kind == "scenario":
        try:
            recorded.add_spec(ScenarioSpec.model_validate(line["spec"]), where)
        except (KeyError, ValidationError) as exc:
            raise ResultsError(f"{where}: bad scenario record: {exc}") from None
    elif kind == "run":
        try:
            run = RunLine.model_validate(line)
        except ValidationError as exc:
            first = exc.errors()[0]
            field_name = ".".join(str(p) for p in first["loc"])
            raise ResultsError(f"{where}: run record: {field_name}: {first['msg']}") from None
        if run.key != run_key(run.scenario, run.mode, run.run):
            raise ResultsError(f"{where}: run record: key {run.key!r} does not match its scenario, mode and run")
        recorded.add_run(line, where)
    else:
        raise ResultsError(f"{where}: unknown record type {kind!r} (expected 'scenario' or 'run')")


def spec_line(spec: ScenarioSpec) -> dict[str, Any]:
    return {"type": "scenario", "name": spec.name, "spec": spec.model_dump(mode="json", by_alias=True)}


class ResultsLog:
    """The results file of a running campaign: new, or resumed (its runs are skipped)."""

    def __init__(self, path: str | Path, specs: Sequence[ScenarioSpec], *, resume: bool):
        self.path = Path(path)
        self.recorded = Recorded()
        exists = self.path.exists() and self.path.stat().st_size > 0
        if exists and not resume:
            if _holds_runs(self.path):
                raise ResultsError(f"{self.path}: already holds results; pass --resume {self.path} to continue "
                                   f"that campaign, or choose another file")
            self.path.unlink()  # only the header of a campaign that never got to run: start afresh
        elif exists:
            _trim_cut_off_line(self.path)
            read_results([self.path], self.recorded)
        where = "this campaign"
        new_specs = []
        for spec in specs:
            if spec.name not in self.recorded.specs:
                new_specs.append(spec)
            self.recorded.add_spec(spec, where)  # raises if the file's spec differs
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: IO[str] = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 - closed in close()
        for spec in new_specs:
            self._write(spec_line(spec))

    def check_seeds(self, runs: Iterable[Any]) -> None:
        """A recorded run must have the seed this campaign would give it (else: another --seed)."""
        for run in runs:
            line = self.recorded.runs.get(run.key)
            if line is not None and line["seed"] != run.seed:
                raise ResultsError(f"{self.path}: run {run.key} was recorded with seed {line['seed']}, this "
                                   f"campaign gives it seed {run.seed} (was it started with another --seed?)")

    def append(self, line: dict[str, Any]) -> None:
        self.recorded.add_run(line, "this campaign")
        self._write(line)

    def _write(self, line: dict[str, Any]) -> None:
        self._file.write(json.dumps(line, separators=(",", ":")) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> ResultsLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _holds_runs(path: Path) -> bool:
    with open(path, encoding="utf-8", errors="replace") as f:
        return any('"type":"run"' in line.replace(" ", "") for line in f)


def _trim_cut_off_line(path: Path) -> None:
    """Drop a last line without its newline (the campaign died while writing it)."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)
