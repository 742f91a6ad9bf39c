"""`fatswarm sweep` over robot-model axes on worker processes: each row carries its model in the
model columns and its command, its result is the one `fatswarm.run` gives with the same keywords,
and the same command again runs nothing (the rows tell the models apart)."""

from __future__ import annotations

import csv
import shlex
from pathlib import Path

import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.engine.lockstep import RunResult
from fatswarm.deploy.sweep.grid import KEY_COLUMNS, MODEL_COLUMNS, model_of_cells
from fatswarm.deploy.sweep.table import COLUMNS

pytestmark = pytest.mark.integration


def rows_of(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def run_like(row: dict[str, str]) -> RunResult:
    """`fatswarm.run` with the keywords of a row's configuration, its model by the flags' words."""
    model = model_of_cells(row)
    result: RunResult = fatswarm.run(
        int(row["n"]),
        seed=int(row["seed"]),
        start=row["start"],
        scheduler=row["scheduler"],
        visibility=str(model.visibility),
        sight=model.sight,
        lights=str(model.lights),
        frames=str(model.frames),
        frame_change=str(model.frame_change),
    )
    return result


def assert_row_is_the_run(row: dict[str, str]) -> None:
    """The row's command has its model's flags, its figures are those of `run_like`."""
    command = shlex.split(row["command"])
    assert ("--sight" in command) == bool(row["sight"])
    assert ("--frames" in command) == bool(row["frames"])
    result = run_like(row)
    assert row["status"] == str(result.status), row
    figures = (result.rounds, result.looks, result.moves, result.collisions)
    assert (row["rounds"], row["looks"], row["moves"], row["collisions"]) == tuple(
        map(str, figures)
    )
    assert row["total_distance"] == f"{result.total_distance:.6f}"


def test_a_sweep_over_frames_and_sight_has_a_row_per_model_equal_to_fatswarm_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    argv = ["sweep", "-n", "4,5", "--scheduler", "fsync", "--seeds", "2"]
    argv += ["--frames", "y-axis,chirality", "--sight", "unlimited,6"]
    argv += ["--jobs", "2", "-q", "--out", str(out)]
    assert cli.main(argv) == 0
    summary = capsys.readouterr().out
    rows = rows_of(out)
    assert list(rows[0]) == list(COLUMNS)
    assert len(rows) == 16 and len({tuple(r[c] for c in KEY_COLUMNS) for r in rows}) == 16
    first: dict[tuple[str, ...], dict[str, str]] = {}
    for row in rows:
        first.setdefault(tuple(row[c] for c in MODEL_COLUMNS), row)
    models: tuple[dict[str, str], ...] = (
        {},
        {"frames": "chirality"},
        {"sight": "6.0"},
        {"sight": "6.0", "frames": "chirality"},
    )
    assert set(first) == {tuple(cells.get(c, "") for c in MODEL_COLUMNS) for cells in models}
    for label in ("fsync ", "fsync+chirality ", "fsync+sight6 ", "fsync+sight6+chirality "):
        assert label in summary
    for row in first.values():  # one run of each model, against the API
        assert_row_is_the_run(row)
    before = out.read_bytes()
    assert cli.main([*argv[:-3], "--out", str(out)]) == 0
    assert out.read_bytes() == before  # resumed: every run of every model is there
    assert "16 already in" in capsys.readouterr().err
