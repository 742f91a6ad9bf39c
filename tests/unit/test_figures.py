"""The declaration of the figures (fatswarm/domain/figures.py) and what is derived from it: the
record's schema, the result line, the sweep table, the dashboard's rows, `to_dataframe`, the
summary; a scratch figure added in a test reaches each of them with no other edit."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.engine import api, notebook
from fatswarm.deploy.sweep import grid, table
from fatswarm.deploy.sweep.grid import RunSpec
from fatswarm.deploy.sweep.pool import RunTable
from fatswarm.deploy.view import panels, summary
from fatswarm.domain import figures, record_lines
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.record import RecordWriter, Result, result_figures, round_entry
from fatswarm.world.record_read import read_record

SCHEMA = Path(__file__).resolve().parents[2] / "docs" / "record.schema.json"
START = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 4.0]])


def spread(positions: Points) -> float | None:
    """The scratch figure: how far the centres reach along x."""
    return float(np.ptp(np.asarray(positions)[:, 0])) if len(positions) else None


SCRATCH = figures.Figure(
    "x_spread",
    float,
    "robot radii",
    "A scratch figure of a test: the centres' reach along x.",
    figures.Summary.MAX,
    figures.Place.CSV | figures.Place.SUMMARY | figures.Place.DASHBOARD | figures.Place.DATAFRAME,
    derive=spread,
    csv=".2f",
)
LINE_SCRATCH = figures.Figure(
    "line_scratch",
    int,
    "",
    "A scratch figure of the result line.",
    places=figures.Place.RESULT_LINE,
    schema={"type": "integer", "minimum": 0},
)


@pytest.fixture
def scratch(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(figures, "FIGURES", (*figures.FIGURES, SCRATCH, LINE_SCRATCH))


def test_the_schema_file_is_what_the_declaration_generates() -> None:
    on_disk = json.loads(SCHEMA.read_text(encoding="utf-8"))  # as JSON: its layout is free
    assert on_disk == record_lines.record_schema(on_disk), (
        "docs/record.schema.json is stale: python -m fatswarm.domain.record_lines"
    )


def test_regenerating_the_schema_rewrites_only_a_stale_file(tmp_path: Path) -> None:
    target = tmp_path / "record.schema.json"
    target.write_text(SCHEMA.read_text(encoding="utf-8"))
    assert not record_lines.write_record_schema(str(target))  # up to date: left as written
    stale = json.loads(target.read_text())
    del stale["$defs"]["result"]["properties"]["epochs"]
    target.write_text(json.dumps(stale))
    assert record_lines.write_record_schema(str(target))
    assert json.loads(target.read_text()) == json.loads(SCHEMA.read_text(encoding="utf-8"))


def test_the_result_line_carries_the_declared_result_figures_typed() -> None:
    declared = {f.name for f in figures.place(figures.Place.RESULT_LINE)}
    head = {f.name for f in record_lines.RESULT_HEAD}
    assert set(result_figures()) == declared - head
    typed = {f.name: f.type for f in dataclasses.fields(Result)}
    for f in figures.place(figures.Place.RESULT_LINE):
        assert f.name in typed, f.name


def test_a_result_line_reads_back_typed_with_its_figures_in_their_order(tmp_path: Path) -> None:
    target = tmp_path / "run.jsonl"
    with RecordWriter(target) as w:
        w.header(3, 1, "async", START, algorithm="gathering", params={})
        w.append(round_entry(1, (0,), {}, {}, START))
        w.append(Result(Status.STALLED, 1, START, 1, 0, 0.0, 0, time=2.5))
    last = json.loads(target.read_text().splitlines()[-1])
    assert list(last) == [
        *("type", "status", "rounds", "positions"),
        *("epochs", "moves", "total_distance", "collisions", "time"),
    ]
    result = read_record(target).result
    assert result is not None and (result.epochs, result.time, result.extra) == (1, 2.5, {})


def test_the_round_line_builder_writes_only_declared_fields(tmp_path: Path) -> None:
    entry = round_entry(
        2,
        (0, 1),
        {},
        {},
        START,
        times={"look": 0.0, "start": 0.0, "end": 1.0, "origin": [0.0, 0.0]},
        robots=(("cut", []), ("timed_out", [1])),
        model={"lights": ["off", "off", "off"]},
    )
    assert list(entry.extra) == ["look", "start", "end", "origin", "timed_out", "lights"]
    declared = {f.name for f in record_lines.ROUND_FIELDS}
    assert set(entry.extra) <= declared
    with pytest.raises(AssertionError, match="no robot list"):
        round_entry(1, (0,), {}, {}, START, robots=(("nobody", [0]),))


def test_a_scratch_figure_reaches_the_sweep_table(scratch: None, tmp_path: Path) -> None:
    assert "x_spread" in table.columns() and "x_spread" in table.plain_columns()
    spec = RunSpec("gathering", 3, "clustered", "fsync", 0)
    run = table.RunFigures("formed", rounds=2, derived={"x_spread": 3.0})
    assert table.make_row(spec, run, "0")["x_spread"] == "3.00"
    failed = table.RunFigures(table.ERROR, derived={"x_spread": 3.0})
    assert table.make_row(spec, failed, "0")["x_spread"] == ""


def test_a_table_written_before_a_new_figure_resumes_with_its_column_blank(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    out = tmp_path / "runs.csv"
    spec = RunSpec("gathering", 3, "clustered", "fsync", 0)
    first = RunTable.open(str(out))
    first.append(table.make_row(spec, table.RunFigures("formed", rounds=2), "0"))
    first.close()
    before = out.read_text()
    monkeypatch.setattr(figures, "FIGURES", (*figures.FIGURES, SCRATCH))
    again = RunTable.open(str(out))
    try:
        assert again.keys() == {spec.key()} and again.rows[0]["x_spread"] == ""
        assert again.columns == table.plain_columns()
    finally:
        again.close()
    header, row = out.read_text().splitlines()
    assert header + "\n" == table.header_line(table.plain_columns())
    assert before.splitlines()[1].split(",")[:5] == row.split(",")[:5]


def test_a_foreign_csv_is_still_refused(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    out.write_text("algorithm,n,score\nx,1,2\n")
    with pytest.raises(table.TableError, match="other columns"):
        RunTable.open(str(out))
    assert out.read_text() == "algorithm,n,score\nx,1,2\n"


def test_a_scratch_figure_reaches_the_dashboard_rows(scratch: None) -> None:
    frame = panels.Frame(round=1, n=3, scheduler="fsync", positions=START)
    assert ("x spread", "3.000") in panels.derived_rows(frame)


def test_a_scratch_figure_reaches_the_dataframe(scratch: None, tmp_path: Path) -> None:
    pytest.importorskip("pandas")
    record = fatswarm.read_record(_record(tmp_path))
    df = record.to_dataframe()
    assert "x_spread" in df.columns and list(df.columns) == list(notebook.columns())
    assert df.x_spread.tolist() == [3.0] * 3


def test_a_scratch_figure_reaches_the_progress_summary_json_and_schema(
    scratch: None, tmp_path: Path
) -> None:
    tracker = ProgressTracker(3, lambda _: False)
    tracker.observe([0], [], START, START)
    tracker.observe([1], [], START, START * 2)
    assert tracker.snapshot().derived["x_spread"] == 6.0  # its MAX over the rounds
    record = fatswarm.read_record(_record(tmp_path))
    assert api.summary(record)["x_spread"] == 3.0
    outcome = summary.Outcome(Status.FORMED, 1, 0, 3, None, 1, "fsync", 1, 0, 0.0)
    outcome = dataclasses.replace(outcome, derived={"x_spread": 3.0})
    assert json.loads(summary.summary_json(outcome, 0))["x_spread"] == 3.0
    assert "x spread 3.000" in summary.summary(outcome)
    schema = record_lines.record_schema(json.loads(SCHEMA.read_text(encoding="utf-8")))
    assert "line_scratch" in schema["$defs"]["result"]["properties"]
    assert "x_spread" in schema["$defs"]["result"]["description"]  # derived: not written


def _record(tmp_path: Path) -> Path:
    target = tmp_path / "run.jsonl"
    with RecordWriter(target) as w:
        w.header(3, 1, "fsync", START, algorithm="gathering", params={})
        w.append(round_entry(1, (0, 1, 2), {}, {}, START))
        w.append(Result(Status.STALLED, 1, START, 1, 0, 0.0, 0))
    return target


def test_a_table_written_before_a_new_model_column_resumes_with_it_blank(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    out = tmp_path / "runs.csv"
    spec = RunSpec("gathering", 3, "clustered", "fsync", 0)
    first = RunTable.open(str(out), models=True)
    first.append(table.make_row(spec, table.RunFigures("formed", rounds=2), "0"))
    first.close()
    # a model axis added later (as grid.MODEL_COLUMNS and KEY_COLUMNS would grow)
    monkeypatch.setattr(table, "KEY_COLUMNS", (*grid.KEY_COLUMNS, "axis_x"))
    monkeypatch.setattr(table, "MODEL_COLUMNS", (*grid.MODEL_COLUMNS, "axis_x"))
    again = RunTable.open(str(out))  # a table with model columns keeps them, and gains the new
    try:
        assert again.columns == table.columns() and "axis_x" in again.columns
        assert again.rows[0]["axis_x"] == "" and again.keys() == {(*spec.key(), "")}
    finally:
        again.close()
    assert out.read_text().startswith(table.header_line(table.columns()))


def _lit(round_no: int, line: Mapping[str, object]) -> int:
    """A scratch figure of the round line: its `lights` entries (0 without)."""
    del round_no
    lights = line.get("lights")
    return len(lights) if isinstance(lights, list) else 0


TALLY_SCRATCH = figures.Figure(
    "lit_scratch",
    int,
    "",
    "A scratch figure of the round line's other fields.",
    figures.Summary.SUM,
    figures.Place.CSV | figures.Place.SUMMARY | figures.Place.DATAFRAME,
    tally=_lit,
    csv="d",
)


def test_a_scratch_figure_of_the_round_line_reaches_progress_records_summary_and_dataframe(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(figures, "FIGURES", (*figures.FIGURES, TALLY_SCRATCH))
    tracker = ProgressTracker(3, lambda _: False)
    tracker.observe([0], [], START, START, line={"lights": ["a", "b", "c"]})
    tracker.observe([1], [], START, START)
    assert tracker.snapshot().derived["lit_scratch"] == 3  # its SUM over the rounds
    target = tmp_path / "run.jsonl"
    with RecordWriter(target) as w:
        w.header(3, 1, "fsync", START, algorithm="gathering", params={})
        w.append(round_entry(1, (0, 1, 2), {}, {}, START, model={"lights": ["a", "b", "c"]}))
        w.append(round_entry(2, (0, 1, 2), {}, {}, START, model={"lights": ["a", "b", "c"]}))
    record = fatswarm.read_record(target)
    assert record.rounds[0].derived["lit_scratch"] == 3
    assert api.summary(record)["lit_scratch"] == 6
    assert "lit_scratch" in table.columns()
    if importlib.util.find_spec("pandas") is not None:
        assert record.to_dataframe().lit_scratch.tolist() == [3] * 6
