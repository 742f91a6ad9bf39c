"""`fatswarm sweep`: the grid, row keys, the bound, the CSV table (resume, torn rows) and one-line
errors; small real sweeps on worker processes are in tests/integration/test_sweep_workers.py."""

from __future__ import annotations

import io
import math
import shlex
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy import cli
from fatswarm.deploy.sweep.grid import (
    KEY_COLUMNS,
    MODEL_COLUMNS,
    Grid,
    RunSpec,
    SweepInputError,
    model_label,
    params_text,
    parse_crash,
    parse_ints,
    parse_non_rigid,
    parse_seeds,
    sweep_schedulers,
)
from fatswarm.deploy.sweep.pool import RunTable, run_spec
from fatswarm.deploy.sweep.report import summary_table
from fatswarm.deploy.sweep.summary import markdown_table, success_rates, summarize
from fatswarm.deploy.sweep.table import (
    COLUMNS,
    ERROR,
    PLAIN_COLUMNS,
    RunFigures,
    TableError,
    assignment_bound,
    distance_ratio,
    header_line,
    make_row,
    parse_table,
    row_key,
    row_line,
)
from fatswarm.domain.registry import load_algorithm


def sweep(argv: list[str]) -> int:
    return cli.main(["sweep", *argv])


# -- the grid ---------------------------------------------------------------------------------


def test_numbers_take_lists_ranges_steps_and_repeated_flags() -> None:
    assert parse_ints(["4,8", "4..16:4"], "-n", least=1) == (4, 8, 12, 16)
    assert parse_ints([" 3 , 5..6 "], "-n", least=1) == (3, 5, 6)


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("0", ">= 1"),
        ("x", "whole numbers"),
        ("8..4", "LOW <= HIGH"),
        ("4..8:0", "STEP >= 1"),
        (",", "at least one value"),
        ("4.5", "whole numbers"),
    ],
)
def test_bad_numbers_are_refused(text: str, says: str) -> None:
    with pytest.raises(SweepInputError, match=says):
        parse_ints([text], "-n", least=1)


def test_seeds_are_a_count_a_range_or_a_list() -> None:
    assert parse_seeds(["3"]) == (0, 1, 2)
    assert parse_seeds(["5..7"]) == (5, 6, 7)
    assert parse_seeds(["3,7"]) == (3, 7)
    assert parse_seeds(["5..5"]) == (5,)
    with pytest.raises(SweepInputError):
        parse_seeds(["0"])


def test_the_grid_has_every_combination_once_seed_by_seed() -> None:
    grid = Grid(
        (("uniform-circle", ()), ("gathering", ())),
        (4, 8),
        ("clustered", "dense"),
        ("fsync", "ssync"),
        (0, 1, 2),
    )
    runs = grid.runs()
    assert len(runs) == grid.size == 2 * 2 * 2 * 2 * 3
    assert len({spec.key() for spec in runs}) == len(runs)
    assert [spec.seed for spec in runs] == sorted(spec.seed for spec in runs)
    assert runs[0] == RunSpec("uniform-circle", 4, "clustered", "fsync", 0)


def test_a_huge_grid_is_refused() -> None:
    with pytest.raises(SweepInputError, match="sweep it in parts"):
        Grid(
            (("gathering", ()),),
            tuple(range(1, 1001)),
            ("clustered",),
            ("fsync",),
            tuple(range(1001)),
        )


def test_non_rigid_and_crash_take_lists_words_and_default_to_the_plain_model() -> None:
    assert parse_non_rigid([]) == (None,)
    assert parse_non_rigid(["rigid,1", "1.0,0.1", "RIGID"]) == (None, 1.0, 0.1)
    assert parse_crash([]) == (None,)
    assert parse_crash(["0,2", "none", "1..2"]) == (None, 2, 1)
    assert parse_crash(["0..1"]) == (None, 1)  # 0 in a range is no crash as well


@pytest.mark.parametrize("text", ["0", "-1", "inf", "nan", "x", "1e400"])
def test_a_non_rigid_delta_must_be_a_finite_distance_above_zero(text: str) -> None:
    with pytest.raises(SweepInputError, match="--non-rigid takes distances > 0"):
        parse_non_rigid([text])


@pytest.mark.parametrize(
    ("text", "says"), [("-1", ">= 0"), ("x", "whole numbers"), ("2..1", "LOW <= HIGH")]
)
def test_a_crash_count_must_be_a_whole_number(text: str, says: str) -> None:
    with pytest.raises(SweepInputError, match=says):
        parse_crash([text])


def test_the_model_label_names_the_scheduler_then_non_rigid_then_crash() -> None:
    assert model_label("fsync", None, None) == "fsync"
    assert model_label("fsync", 1.0, None) == "fsync+nr1"
    assert model_label("ssync", None, 2) == "ssync+crash2"
    assert model_label("async-slowest", 0.1, 1) == "async-slowest+nr0.1+crash1"


def test_the_grid_crosses_non_rigid_and_crash_and_leaves_out_crashes_of_n_or_more() -> None:
    grid = Grid(
        (("uniform-circle", ()),),
        (2, 3, 4),
        ("clustered",),
        ("fsync", "async"),
        (0, 1),
        None,
        (None, 1.0),
        (None, 2, 3),
    )
    runs = grid.runs()
    # (f, n) cells: no crash with n = 2, 3, 4; f = 2 with n = 3, 4; f = 3 with n = 4
    assert len(runs) == grid.size == 2 * 2 * 2 * 6
    assert grid.left_out == 2 * 2 * 2 * 3
    assert len({spec.key() for spec in runs}) == len(runs)
    assert all(spec.crash is None or spec.crash < spec.n for spec in runs)
    assert {(spec.non_rigid, spec.crash) for spec in runs} == {
        (d, f) for d in (None, 1.0) for f in (None, 2, 3)
    }
    assert [spec.seed for spec in runs] == sorted(spec.seed for spec in runs)
    assert runs[0] == RunSpec("uniform-circle", 2, "clustered", "fsync", 0)
    assert {spec.model for spec in runs if spec.n == 4 and spec.scheduler == "fsync"} == {
        "fsync",
        "fsync+crash2",
        "fsync+crash3",
        "fsync+nr1",
        "fsync+nr1+crash2",
        "fsync+nr1+crash3",
    }
    with pytest.raises(SweepInputError, match="the grid has no run"):
        Grid(
            (("uniform-circle", ()),), (3, 4), ("clustered",), ("fsync",), (0,), None, (None,), (4,)
        )


def test_the_schedulers_are_the_ones_the_code_names_less_the_scripted_one() -> None:
    assert sweep_schedulers() == tuple(name for name in NAMES if name != "scripted")


def test_parameters_are_canonical_so_one_run_is_one_key() -> None:
    algorithm = load_algorithm("uniform-circle")
    assert params_text(algorithm, ["a=4"]) == params_text(algorithm, ["a=4.0"]) == (("a", "4.0"),)
    assert params_text(algorithm, []) == ()


def test_key_cells_are_the_first_columns_and_the_command_repeats_the_run() -> None:
    spec = RunSpec("gathering", 6, "dense", "ssync", 3, (("tolerance", "0.01"),), 50)
    assert spec.key() == (
        ("gathering", "6", "dense", "ssync", "3", "tolerance=0.01", "50", "", "")
        + ("",) * len(MODEL_COLUMNS)  # the robot model's columns (`AXES`), blank: the paper's
    )
    assert COLUMNS[: len(KEY_COLUMNS)] == KEY_COLUMNS
    assert shlex.split(spec.command()) == [
        "fatswarm",
        "run",
        "--lockstep",
        "-n",
        "6",
        "--seed",
        "3",
        "--start",
        "dense",
        "--scheduler",
        "ssync",
        "--algorithm",
        "gathering",
        "--param",
        "tolerance=0.01",
        "--max-rounds",
        "50",
    ]
    assert "--algorithm" not in RunSpec("uniform-circle", 4, "clustered", "fsync", 0).command()


def test_non_rigid_and_crash_are_key_cells_and_in_the_command() -> None:
    plain = RunSpec("uniform-circle", 5, "clustered", "async", 2)
    both = RunSpec("uniform-circle", 5, "clustered", "async", 2, non_rigid=0.1, crash=2)
    assert dict(zip(KEY_COLUMNS, both.key(), strict=True))["non_rigid"] == "0.1"
    assert dict(zip(KEY_COLUMNS, both.key(), strict=True))["crash"] == "2"
    assert plain.key()[-2:] == ("", "")
    assert shlex.split(both.command())[-4:] == ["--non-rigid", "0.1", "--crash", "2"]
    assert "--non-rigid" not in plain.command() and "--crash" not in plain.command()
    # resume tells rows apart by them: one more delta or crash count is another run
    keys = {
        row_key(make_row(spec, RunFigures("formed"), "0.1.0"))
        for spec in (
            plain,
            both,
            RunSpec("uniform-circle", 5, "clustered", "async", 2, non_rigid=0.1),
            RunSpec("uniform-circle", 5, "clustered", "async", 2, crash=2),
        )
    }
    assert len(keys) == 4


def test_the_time_column_is_the_virtual_time_and_empty_for_round_models() -> None:
    spec = RunSpec("uniform-circle", 4, "clustered", "async", 0)
    assert make_row(spec, RunFigures("formed", rounds=30, time=20.25), "0.1.0")["time"] == (
        "20.250000"
    )
    assert make_row(spec, RunFigures("formed", rounds=6), "0.1.0")["time"] == ""
    assert make_row(spec, RunFigures(ERROR, time=3.0), "0.1.0")["time"] == ""


# -- the bound --------------------------------------------------------------------------------


def test_the_bound_is_the_best_assignment_not_the_robots_own() -> None:
    initial = np.array([[0.0, 0.0], [10.0, 0.0]])
    final = np.array([[10.0, 1.0], [0.0, 1.0]])  # robot 0 went right, robot 1 left
    assert assignment_bound(initial, final) == pytest.approx(2.0)  # each one up by 1
    own = float(np.hypot(*(final - initial).T).sum())
    assert own == pytest.approx(2 * math.sqrt(101))


def test_the_bound_of_a_three_robot_rotation() -> None:
    initial = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 3.0]])
    final = initial[[1, 2, 0]] + np.array([0.0, 0.5])
    assert assignment_bound(initial, final) == pytest.approx(1.5)


def test_the_ratio_is_undefined_without_a_bound() -> None:
    assert distance_ratio(3.0, 2.0) == 1.5
    assert distance_ratio(0.0, 0.0) is None
    assert distance_ratio(1.0, None) is None


# -- rows and the table -----------------------------------------------------------------------


def test_a_row_is_one_csv_line_that_reads_back() -> None:
    spec = RunSpec("dir with space/alg.py:A", 4, "clustered", "fsync", 1, (("s", "x,y"),))
    figures = RunFigures(ERROR, wall_s=0.25, error='ValueError: bad\nthing, "quoted"')
    row = make_row(spec, figures, "0.1.0")
    line = row_line(row)
    assert line.count("\n") == 1 and line.endswith("\n")
    (back,) = parse_table(header_line() + line, "t.csv")
    assert back == row
    assert back["error"] == 'ValueError: bad thing, "quoted"'
    assert back["rounds"] == "" and back["status"] == ERROR


def test_the_table_refuses_other_columns_and_ragged_rows() -> None:
    with pytest.raises(TableError, match="other columns"):
        parse_table("a,b\n1,2\n", "t.csv")
    with pytest.raises(TableError, match="line 2"):
        parse_table(header_line() + "1,2\n", "t.csv")


def _one_row() -> str:
    spec = RunSpec("gathering", 3, "clustered", "fsync", 0)
    return row_line(make_row(spec, RunFigures("formed", rounds=5), "0.1.0"))


def test_opening_cuts_a_torn_last_row(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    whole = header_line() + _one_row()
    out.write_text(whole + "gathering,3,clus")
    table = RunTable.open(str(out))
    try:
        assert table.cut == len("gathering,3,clus")
        assert len(table.rows) == 1
    finally:
        table.close()
    assert out.read_text() == whole


# a row of a fatswarm 0.1 table (before the non_rigid, crash and time columns)
def test_a_torn_header_is_written_again(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    out.write_text(header_line()[:10])
    RunTable.open(str(out)).close()
    assert out.read_text() == header_line(PLAIN_COLUMNS)  # a grid of the paper's model alone
    out.write_text(header_line()[:10])
    RunTable.open(str(out), models=True).close()
    assert out.read_text() == header_line()


def test_another_file_is_left_untouched(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    out.write_text("name,score\nx,1")
    with pytest.raises(TableError, match="other columns"):
        RunTable.open(str(out))
    assert out.read_text() == "name,score\nx,1"


def test_a_second_sweep_on_one_table_is_refused(tmp_path: Path) -> None:
    out = str(tmp_path / "runs.csv")
    first = RunTable.open(out)
    try:
        with pytest.raises(TableError, match="another fatswarm sweep"):
            RunTable.open(out)
    finally:
        first.close()
    RunTable.open(out).close()  # free again


def test_a_run_that_raises_is_an_error_row() -> None:
    # a = 20000 is refused for 4 robots (fatswarm/domain/tolerance.py) only once the start is drawn
    figures = run_spec(RunSpec("uniform-circle", 4, "clustered", "fsync", 0, (("a", "20000.0"),)))
    assert figures.status == ERROR
    assert figures.error.startswith("UnsupportedInputError")
    assert figures.values == "a=20000.0"


# -- the summary ------------------------------------------------------------------------------


def _row(
    scheduler: str,
    n: int,
    seed: int,
    status: str,
    rounds: int,
    collisions: int,
    ratio: str,
    *,
    non_rigid: float | None = None,
    crash: int | None = None,
    time: float | None = None,
) -> dict[str, str]:
    spec = RunSpec(
        "uniform-circle", n, "clustered", scheduler, seed, non_rigid=non_rigid, crash=crash
    )
    figures = RunFigures(status, rounds=rounds, collisions=collisions, time=time)
    return {**make_row(spec, figures, "0.1.0"), "ratio": ratio}


def test_the_summary_counts_and_takes_medians_of_formed_runs() -> None:
    grid = Grid((("uniform-circle", ()),), (4, 8), ("clustered",), ("fsync", "ssync"), (0, 1, 2))
    rows = [
        _row("fsync", 4, 0, "formed", 6, 0, "1.1"),
        _row("fsync", 4, 1, "formed", 8, 2, "1.3"),
        _row("fsync", 4, 2, "stalled", 40, 0, "2.0"),
        _row("ssync", 8, 0, ERROR, 0, 0, ""),
    ]
    fsync4, ssync8 = summarize(rows, grid)
    assert (fsync4.scheduler, fsync4.n, fsync4.runs, fsync4.formed, fsync4.clean) == (
        "fsync",
        4,
        3,
        2,
        1,
    )
    assert (fsync4.collided, fsync4.stalled, fsync4.errors) == (1, 1, 0)
    assert fsync4.rounds is not None and fsync4.rounds[1] == 7.0
    assert fsync4.ratio is not None and fsync4.ratio[1] == pytest.approx(1.2)
    assert (ssync8.runs, ssync8.errors, ssync8.rounds) == (1, 1, None)
    out = io.StringIO()
    Console(file=out, width=100, color_system=None).print(summary_table([fsync4, ssync8]))
    text = out.getvalue()
    assert "collided" in text and "errors" in text and "capped" not in text
    assert any(line.split()[:4] == ["fsync", "4", "3", "2"] for line in text.splitlines())


def test_the_markdown_summary_groups_every_n_by_model() -> None:
    grid = Grid(
        (("uniform-circle", ()),),
        (4, 8),
        ("clustered",),
        ("fsync", "async"),
        (0, 1),
        None,
        (None, 1.0),
        (None, 2),
    )
    rows = [
        _row("fsync", 4, 0, "formed", 6, 0, "1.1"),
        _row("fsync", 8, 0, "formed", 10, 1, "1.2"),
        _row("fsync", 8, 1, "max_rounds", 900, 0, ""),
        _row("fsync", 4, 0, "formed", 12, 0, "1.1", non_rigid=1.0),
        _row("fsync", 4, 0, "stalled", 3, 0, "", crash=2),
        _row("async", 4, 0, "formed", 30, 0, "1.1", time=20.0),
        _row("async", 8, 0, "formed", 50, 0, "1.1", time=31.0),
        _row("async", 8, 1, ERROR, 0, 0, "", time=None),
    ]
    cells = summarize(rows, grid, by_n=False)
    assert [(c.model, c.n, c.sizes, c.runs) for c in cells] == [  # in the grid's order
        ("fsync", None, (4, 8), 3),
        ("fsync+crash2", None, (4,), 1),
        ("fsync+nr1", None, (4,), 1),
        ("async", None, (4, 8), 3),
    ]
    lines = markdown_table(cells).splitlines()
    assert lines[0].split(" | ")[1:5] == ["scheduler", "non-rigid", "crash", "n"]
    assert lines[0].endswith("| median rounds | median time |")
    assert lines[1].startswith("|---|") and lines[1].count("|") == lines[0].count("|")
    body = [[cell.strip() for cell in line.strip("|").split("|")] for line in lines[2:]]
    assert body == [
        ["uniform-circle", "fsync", "rigid", "none", "4,8", "3", "2", "1", "0", "1", "0", "8", "-"],
        ["uniform-circle", "fsync", "rigid", "2", "4", "1", "0", "0", "1", "0", "0", "-", "-"],
        ["uniform-circle", "fsync", "1", "none", "4", "1", "1", "0", "0", "0", "0", "12", "-"],
        [
            "uniform-circle",
            "async",
            "rigid",
            "none",
            "4,8",
            "3",
            "2",
            "0",
            "0",
            "0",
            "1",
            "40",
            "25.5",
        ],
    ]
    # the figures take the same groups, as model labels
    assert [label for label, *_ in success_rates(summarize(rows, grid))] == [
        "fsync",
        "fsync+crash2",
        "fsync+nr1",
        "async",
    ]


# -- the command ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["-n", "0"], "-n values must be >= 1"),
        (["-n", "x"], "-n takes whole numbers"),
        (["--seeds", "9..3"], "LOW <= HIGH"),
        (["--start", "nowhere"], "not a start kind"),
        (["--scheduler", "scripted"], "needs a schedule file"),
        (["--scheduler", "asynchronous"], "is not a scheduler"),
        (["--algorithm", "nope"], "no algorithm named 'nope'"),
        (["--param", "a=2"], "a must be > 3"),
        (["--param", "zzz=1"], "has no parameter 'zzz'"),
        (["--param", "novalue"], "NAME=VALUE"),
        (["--algorithm", "gathering", "--param", "a=5"], "has no parameter 'a'"),
        (["--jobs", "0"], "--jobs must be at least 1"),
        (["--jobs", "two"], "invalid int value"),
        (["--max-rounds", "0"], "--max-rounds must be at least 1"),
        (["--non-rigid", "0"], "--non-rigid takes distances > 0"),
        (["--non-rigid", "rigid,soft"], "--non-rigid takes distances > 0"),
        (["--crash", "-1"], "--crash values must be >= 0"),
        (["--crash", "two"], "--crash takes whole numbers"),
        (["-n", "3,4", "--crash", "4"], "the grid has no run"),
    ],
)
def test_bad_input_is_one_line_and_exit_two(
    argv: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    assert sweep([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("fatswarm sweep: ")
    assert says in err
    assert not out.exists()


def test_bad_outputs_are_one_line_and_exit_two(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = tmp_path / "other.csv"
    other.write_text("name,score\n")
    cases = [
        (["--out", str(tmp_path)], "is a directory"),
        (["--out", str(tmp_path / "missing" / "runs.csv")], "does not exist"),
        (["--out", str(other)], "other columns"),
        (["--out", str(tmp_path / "r.csv"), "--plot", str(other)], "not a directory"),
        (["--out", str(tmp_path / "r.csv"), "--summary-md", str(tmp_path)], "is a directory"),
        (
            ["--out", str(tmp_path / "r.csv"), "--summary-md", str(tmp_path / "no" / "s.md")],
            "does not exist",
        ),
    ]
    for argv, says in cases:
        assert sweep(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err


def test_help_explains_the_grid(capsys: pytest.CaptureFixture[str]) -> None:
    assert sweep(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for word in (
        "--scheduler",
        "--seeds",
        "LOW..HIGH",
        "Resumable",
        "docs/sweep.md",
        "130 interrupted",
        "--non-rigid DELTAS",
        "--crash COUNTS",
        "--summary-md PATH",
    ):
        assert word in text
