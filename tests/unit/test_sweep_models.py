"""The robot model's axes in `fatswarm sweep`: the flags read as lists, the grid crossing them, the
label, the key and model columns of a row, the command that repeats it, the two table schemas
(a grid of the paper's model alone keeps the table without model columns) and the summary.
No process: the end-to-end sweep is tests/integration/test_sweep_models_workers.py."""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.commands.run import add_arguments as add_run_arguments
from fatswarm.deploy.engine.config import model_from_args
from fatswarm.deploy.flags import add_robot_model_arguments
from fatswarm.deploy.sweep.grid import (
    KEY_COLUMNS,
    MODEL_COLUMNS,
    Grid,
    RunSpec,
    SweepInputError,
    model_cells,
    model_label,
    model_of_cells,
    model_suffix,
    parse_choices,
    parse_robot_models,
    parse_sight,
    robot_models_of,
)
from fatswarm.deploy.sweep.pool import RunTable
from fatswarm.deploy.sweep.summary import markdown_table, summarize
from fatswarm.deploy.sweep.table import (
    COLUMNS,
    PLAIN_COLUMNS,
    RunFigures,
    header_line,
    make_row,
    parse_table,
    row_key,
    row_line,
)
from fatswarm.domain.robot_model import PAPER_MODEL, Frames, RobotModel, Visibility

UC = "uniform-circle"


def model_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_robot_model_arguments(p, lists=True)
    return p.parse_args(argv)


def spec(model: RobotModel = PAPER_MODEL, **kw: object) -> RunSpec:
    return RunSpec(UC, 5, "clustered", "fsync", 2, robot_model=model, **kw)  # type: ignore[arg-type]


# -- the flags --------------------------------------------------------------------------------


def test_sight_takes_distances_and_unlimited_without_repeats() -> None:
    assert parse_sight([]) == (None,)
    assert parse_sight(["unlimited,6", "6.0,2.5", "Unlimited"]) == (None, 6.0, 2.5)
    assert parse_sight(["8"]) == (8.0,)


@pytest.mark.parametrize("text", ["0", "-1", "inf", "nan", "far", "1e400"])
def test_a_sight_must_be_a_finite_distance_above_zero(text: str) -> None:
    with pytest.raises(SweepInputError, match="--sight takes distances > 0"):
        parse_sight([text])


def test_word_axes_take_their_choices_and_default_to_the_papers() -> None:
    assert parse_choices([], "frames") == ("y-axis",)
    assert parse_choices(["chirality,y-axis", "chirality"], "frames") == ("chirality", "y-axis")
    assert parse_choices([], "frame_change") == ("fixed",)
    with pytest.raises(SweepInputError, match="--frame-change takes fixed, every-look"):
        parse_choices(["always"], "frame_change")
    with pytest.raises(SweepInputError, match="--visibility takes transparent, opaque, opaque-c"):
        parse_choices(["opaque,Opaque"], "visibility")


def test_the_models_are_every_combination_visibility_slowest() -> None:
    assert parse_robot_models({}) == (PAPER_MODEL,)
    models = robot_models_of(
        model_args(
            [
                "--visibility",
                "transparent,opaque",
                "--sight",
                "unlimited,6",
                "--frames",
                "chirality",
            ]
        )
    )
    assert [(str(m.visibility), m.sight, str(m.frames)) for m in models] == [
        ("transparent", None, "chirality"),
        ("transparent", 6.0, "chirality"),
        ("opaque", None, "chirality"),
        ("opaque", 6.0, "chirality"),
    ]
    repeated = model_args(["--lights", "full", "--lights", "internal,external"])
    assert [str(m.lights) for m in robot_models_of(repeated)] == ["full", "internal", "external"]


# -- the label, the cells, the command ---------------------------------------------------------


def test_the_label_adds_the_axes_that_are_not_the_papers() -> None:
    m = RobotModel.of("opaque", 5.0, frames="chirality")
    assert model_label("fsync", None, None, m) == "fsync+opaque+sight5+chirality"
    assert model_label("fsync", None, None) == model_label("fsync", None, None, PAPER_MODEL)
    assert model_label("async", 0.1, 2, m) == "async+nr0.1+crash2+opaque+sight5+chirality"
    every = RobotModel.of("opaque-centres", 2.5, "internal", "disoriented", "every-look")
    assert model_suffix(every) == "+opaque-centres+sight2.5+lights-internal+disoriented+every-look"
    assert model_suffix(RobotModel.of(lights="external")) == "+lights-external"
    assert model_suffix(PAPER_MODEL) == ""


def test_model_cells_are_blank_at_the_papers_values_and_read_back() -> None:
    assert model_cells(PAPER_MODEL) == dict.fromkeys(MODEL_COLUMNS, "")
    m = RobotModel.of("opaque", 6, frames="chirality")
    assert model_cells(m) == {
        "visibility": "opaque",
        "sight": "6.0",
        "lights": "",
        "frames": "chirality",
        "frame_change": "",
        "noise": "",
        "bodies": "",
    }
    every = RobotModel.of("opaque-centres", 0.1, "external", "disoriented", "every-look")
    points = RobotModel.of(bodies="points", frames="both-axes")
    for model in (PAPER_MODEL, m, every, points):
        assert model_of_cells(model_cells(model)) == model
    assert model_of_cells({}) == PAPER_MODEL


def test_the_model_is_in_the_key_and_a_papers_run_has_the_key_it_always_had() -> None:
    axes = len(MODEL_COLUMNS)
    assert KEY_COLUMNS[-axes:] == MODEL_COLUMNS and COLUMNS[: len(KEY_COLUMNS)] == KEY_COLUMNS
    plain, chiral = spec(), spec(RobotModel.of(frames="chirality"))
    assert plain.key()[-axes:] == ("",) * axes and plain.model == "fsync"
    assert dict(zip(KEY_COLUMNS, chiral.key(), strict=True))["frames"] == "chirality"
    assert chiral.model == "fsync+chirality"
    models = parse_robot_models({"frames": ["y-axis,chirality"], "sight": ["unlimited,6"]})
    assert len({spec(m).key() for m in models}) == 4
    # the command of the paper's model is the one a sweep always wrote
    assert plain.command() == (
        "fatswarm run --lockstep -n 5 --seed 2 --start clustered --scheduler fsync"
    )


def test_the_command_gives_fatswarm_run_the_same_model() -> None:
    p = argparse.ArgumentParser()
    add_run_arguments(p)
    for model in (
        PAPER_MODEL,
        RobotModel.of("opaque", 6.5, frames="chirality", frame_change="every-look"),
        RobotModel.of("opaque-centres", 0.1, "internal", "disoriented"),
    ):
        argv = shlex.split(spec(model, non_rigid=0.5, crash=1).command())
        assert argv[:3] == ["fatswarm", "run", "--lockstep"]
        assert model_from_args(p.parse_args(argv[3:])) == model


# -- the grid -----------------------------------------------------------------------------------


def test_the_grid_crosses_the_models_seed_by_seed() -> None:
    models = parse_robot_models({"frames": ["y-axis,chirality"], "sight": ["unlimited,6"]})
    grid = Grid(((UC, ()),), (4, 5), ("clustered",), ("fsync",), (0, 1), models=models)
    runs = grid.runs()
    assert grid.size == len(runs) == 2 * 4 * 2 and grid.has_models
    assert len({r.key() for r in runs}) == len(runs)
    assert [r.seed for r in runs] == [0] * 8 + [1] * 8
    assert {r.robot_model for r in runs} == set(models)
    assert not Grid(((UC, ()),), (4,), ("clustered",), ("fsync",), (0,)).has_models
    only_paper = parse_robot_models({"frames": ["y-axis"], "sight": ["unlimited"]})
    assert only_paper == (PAPER_MODEL,)


# -- the table ----------------------------------------------------------------------------------


def test_a_table_without_model_columns_keeps_them_off_until_a_grid_has_model_axes(
    tmp_path: Path,
) -> None:
    out = tmp_path / "runs.csv"
    plain = RunTable.open(str(out))
    row = make_row(spec(), RunFigures("formed", rounds=5), "0.1.0")
    plain.append(row)
    plain.close()
    assert tuple(c for c in COLUMNS if c not in MODEL_COLUMNS) == PLAIN_COLUMNS
    assert out.read_text() == header_line(PLAIN_COLUMNS) + row_line(row, PLAIN_COLUMNS)
    again = RunTable.open(str(out))  # resumed: its row has the key of the run
    assert again.keys() == {spec().key()} and again.columns == PLAIN_COLUMNS
    again.close()
    widened = RunTable.open(str(out), models=True)  # a grid with model axes: columns added
    assert widened.keys() == {spec().key()} and widened.columns == COLUMNS
    widened.close()
    assert out.read_text() == header_line() + row_line(row)  # its row: the paper's model


def test_a_table_with_model_columns_takes_every_model(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    chiral = spec(RobotModel.of(frames="chirality", sight=6))
    table = RunTable.open(str(out), models=True)
    for run in (chiral, spec()):
        table.append(make_row(run, RunFigures("formed", rounds=5), "0.1.0"))
    table.close()
    text = out.read_text()
    assert text.startswith(header_line(COLUMNS))
    assert "fsync --sight 6.0 --frames chirality" in text
    for models in (True, False):  # a grid of the paper's model alone appends to it too
        again = RunTable.open(str(out), models=models)
        assert again.keys() == {chiral.key(), spec().key()} and again.columns == COLUMNS
        again.close()


def test_rows_of_either_schema_read_back_with_every_column() -> None:
    row = make_row(spec(), RunFigures("formed", rounds=5), "0.1.0")
    (plain,) = parse_table(header_line(PLAIN_COLUMNS) + row_line(row, PLAIN_COLUMNS), "t.csv")
    (wide,) = parse_table(header_line() + row_line(row), "t.csv")
    assert plain == wide and list(plain) == list(COLUMNS)
    assert row_key(plain) == spec().key()


# -- the summary --------------------------------------------------------------------------------


def test_the_summary_groups_by_model_and_labels_it() -> None:
    models = parse_robot_models({"visibility": ["transparent,opaque"]})
    grid = Grid(((UC, ()),), (4,), ("clustered",), ("fsync",), (0, 1), models=models)
    rows = [
        make_row(run, RunFigures("formed" if run.seed else "stalled", rounds=5), "0.1.0")
        for run in grid.runs()
    ]
    cells = summarize(rows, grid)
    assert [(c.model, c.runs, c.formed) for c in cells] == [
        ("fsync", 2, 1),
        ("fsync+opaque", 2, 1),
    ]
    md = markdown_table(summarize(rows, grid, by_n=False))
    assert "| crash | robot model | n |" in md
    assert "| none | paper | 4 |" in md and "| none | opaque | 4 |" in md
    paper = Grid(((UC, ()),), (4,), ("clustered",), ("fsync",), (0,))
    plain_rows = [make_row(r, RunFigures("formed", rounds=5), "0.1.0") for r in paper.runs()]
    assert "robot model" not in markdown_table(summarize(plain_rows, paper, by_n=False))


# -- bad input ----------------------------------------------------------------------------------


BAD_AXES = [
    (["--sight", "0"], "--sight takes distances > 0"),
    (["--frames", "chirality,upside-down"], "--frames takes y-axis, chirality, disoriented"),
    (["--lights", "full,internal"], "--lights internal needs an algorithm with lights"),
]


@pytest.mark.parametrize(
    ("command", "argv", "says"),
    [
        *(("sweep", argv, says) for argv, says in BAD_AXES),
        *(("hunt", argv, says) for argv, says in BAD_AXES),
        ("sweep", ["--record-views"], "--record-views: a sweep keeps no records"),
    ],
)
def test_bad_model_axes_are_one_line_and_exit_two(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
    argv: list[str],
    says: str,
) -> None:
    out = tmp_path / "out"
    assert cli.main([command, "-n", "4", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert not out.exists()


def test_the_help_names_the_model_axes(capsys: pytest.CaptureFixture[str]) -> None:
    for command in ("sweep", "hunt"):
        assert cli.main([command, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        for flag in ("--visibility", "--sight", "--lights", "--frames", "--frame-change"):
            assert flag in text
        assert "'unlimited' is no limit" in text


def test_the_papers_model_of_the_axes_is_their_default() -> None:
    assert robot_models_of(model_args([])) == (PAPER_MODEL,)
    (m,) = robot_models_of(model_args(["--visibility", "opaque", "--frames", "disoriented"]))
    assert m.visibility is Visibility.OPAQUE and m.frames is Frames.DISORIENTED
