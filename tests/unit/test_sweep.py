"""`fatswarm sweep`: the grid, row keys, the bound, the CSV table (resume, torn rows), one-line
errors, and small real sweeps (two worker processes) that resume to the same rows."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from fatswarm.agent.registry import load_algorithm
from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy import cli
from fatswarm.deploy.sweep import (
    COLUMNS,
    ERROR,
    KEY_COLUMNS,
    Grid,
    RunFigures,
    RunSpec,
    SweepInputError,
    TableError,
    assignment_bound,
    distance_ratio,
    header_line,
    make_row,
    params_text,
    parse_ints,
    parse_seeds,
    parse_table,
    row_line,
    summarize,
    sweep_schedulers,
)
from fatswarm.deploy.sweep_cli import summary_table
from fatswarm.deploy.sweep_run import RunTable, run_spec

ROOT = Path(__file__).resolve().parents[2]
SLOW = f"{ROOT / 'tests' / 'data' / 'slow_gathering.py'}:ALGORITHM"
VOLATILE = ("wall_s",)  # the only cells that differ between two runs of one configuration


def sweep(argv: list[str]) -> int:
    return cli.main(["sweep", *argv])


def rows_of(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def stable(rows: list[dict[str, str]]) -> set[tuple[str, ...]]:
    return {tuple(v for k, v in row.items() if k not in VOLATILE) for row in rows}


# -- the grid ---------------------------------------------------------------------------------


def test_numbers_take_lists_ranges_steps_and_repeated_flags() -> None:
    assert parse_ints(["4,8", "4..16:4"], "-n", least=1) == (4, 8, 12, 16)
    assert parse_ints([" 3 , 5..6 "], "-n", least=1) == (3, 5, 6)


@pytest.mark.parametrize(("text", "says"), [
    ("0", ">= 1"), ("x", "whole numbers"), ("8..4", "LOW <= HIGH"), ("4..8:0", "STEP >= 1"),
    (",", "at least one value"), ("4.5", "whole numbers"),
])
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
    grid = Grid((("uniform-circle", ()), ("gathering", ())), (4, 8), ("clustered", "dense"),
                ("fsync", "ssync"), (0, 1, 2))
    runs = grid.runs()
    assert len(runs) == grid.size == 2 * 2 * 2 * 2 * 3
    assert len({spec.key() for spec in runs}) == len(runs)
    assert [spec.seed for spec in runs] == sorted(spec.seed for spec in runs)
    assert runs[0] == RunSpec("uniform-circle", 4, "clustered", "fsync", 0)


def test_a_huge_grid_is_refused() -> None:
    with pytest.raises(SweepInputError, match="sweep it in parts"):
        Grid((("gathering", ()),), tuple(range(1, 1001)), ("clustered",), ("fsync",),
             tuple(range(1001)))


def test_the_schedulers_are_the_ones_the_code_names_less_the_scripted_one() -> None:
    assert sweep_schedulers() == tuple(name for name in NAMES if name != "scripted")


def test_parameters_are_canonical_so_one_run_is_one_key() -> None:
    algorithm = load_algorithm("uniform-circle")
    assert params_text(algorithm, ["a=4"]) == params_text(algorithm, ["a=4.0"]) == (("a", "4.0"),)
    assert params_text(algorithm, []) == ()


def test_key_cells_are_the_first_columns_and_the_command_repeats_the_run() -> None:
    spec = RunSpec("gathering", 6, "dense", "ssync", 3, (("tolerance", "0.01"),), 50)
    assert spec.key() == ("gathering", "6", "dense", "ssync", "3", "tolerance=0.01", "50")
    assert COLUMNS[: len(KEY_COLUMNS)] == KEY_COLUMNS
    assert shlex.split(spec.command()) == [
        "fatswarm", "run", "--lockstep", "-n", "6", "--seed", "3", "--start", "dense",
        "--scheduler", "ssync", "--algorithm", "gathering", "--param", "tolerance=0.01",
        "--max-rounds", "50"]
    assert "--algorithm" not in RunSpec("uniform-circle", 4, "clustered", "fsync", 0).command()


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
    figures = RunFigures(ERROR, wall_s=0.25, error="ValueError: bad\nthing, \"quoted\"")
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


def test_a_torn_header_is_written_again(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    out.write_text(header_line()[:10])
    RunTable.open(str(out)).close()
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
    # a = 20000 is refused for 4 robots (agent/tolerance.py) only once the start is drawn
    figures = run_spec(RunSpec("uniform-circle", 4, "clustered", "fsync", 0, (("a", "20000.0"),)))
    assert figures.status == ERROR
    assert figures.error.startswith("UnsupportedInputError")
    assert figures.values == "a=20000.0"


# -- the summary ------------------------------------------------------------------------------


def _row(scheduler: str, n: int, seed: int, status: str, rounds: int, collisions: int,
         ratio: str) -> dict[str, str]:
    spec = RunSpec("uniform-circle", n, "clustered", scheduler, seed)
    row = make_row(spec, RunFigures(status, rounds=rounds, collisions=collisions), "0.1.0")
    return {**row, "ratio": ratio}


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
        "fsync", 4, 3, 2, 1)
    assert (fsync4.collided, fsync4.stalled, fsync4.errors) == (1, 1, 0)
    assert fsync4.rounds is not None and fsync4.rounds[1] == 7.0
    assert fsync4.ratio is not None and fsync4.ratio[1] == pytest.approx(1.2)
    assert (ssync8.runs, ssync8.errors, ssync8.rounds) == (1, 1, None)
    out = io.StringIO()
    Console(file=out, width=100, color_system=None).print(summary_table([fsync4, ssync8]))
    text = out.getvalue()
    assert "collided" in text and "errors" in text and "capped" not in text
    assert any(line.split()[:4] == ["fsync", "4", "3", "2"] for line in text.splitlines())


# -- the command ------------------------------------------------------------------------------


@pytest.mark.parametrize(("argv", "says"), [
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
])
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
    ]
    for argv, says in cases:
        assert sweep(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err


def test_help_explains_the_grid(capsys: pytest.CaptureFixture[str]) -> None:
    assert sweep(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for word in ("--scheduler", "--seeds", "LOW..HIGH", "Resumable", "docs/sweep.md",
                 "130 interrupted"):
        assert word in text


def test_a_small_sweep_writes_one_row_per_run_and_a_second_one_adds_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    argv = ["-n", "4,5", "--scheduler", "fsync,ssync", "--seeds", "2", "--jobs", "2",
            "--out", str(out)]
    assert sweep(argv) == 0
    summary = capsys.readouterr().out
    rows = rows_of(out)
    assert list(rows[0]) == list(COLUMNS)
    assert sorted((r["n"], r["scheduler"], r["seed"]) for r in rows) == sorted(
        (n, s, seed) for n in ("4", "5") for s in ("fsync", "ssync") for seed in ("0", "1"))
    for row in rows:
        assert row["status"] == "formed" and row["collisions"] == "0", row
        assert float(row["total_distance"]) >= float(row["bound"]) - 1e-6
        assert float(row["ratio"]) >= 1.0 - 1e-9
        assert row["values"] == "a=4.0" and int(row["round_cap"]) > int(row["rounds"])
    assert "median" in summary and "ssync" in summary
    before = out.read_bytes()
    assert sweep([*argv, "--plot", str(tmp_path / "figs")]) == 0
    assert out.read_bytes() == before
    assert "nothing to run" in capsys.readouterr().err
    # a sub-grid against the same table: its run is there, the others are left as they are
    assert sweep(["-n", "4", "--scheduler", "fsync", "--seeds", "1", "--out", str(out)]) == 0
    assert "1 already in" in capsys.readouterr().err
    assert out.read_bytes() == before
    pytest.importorskip("matplotlib")
    assert sorted(os.listdir(tmp_path / "figs")) == ["ratio.png", "rounds.png", "success.png"]
    # the command column repeats a run exactly
    row = rows[-1]
    assert cli.main([*shlex.split(row["command"])[1:], "-q", "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert (again["status"], str(again["rounds"]), str(again["collisions"])) == (
        row["status"], row["rounds"], row["collisions"])
    assert f"{again['total_distance']:.6f}" == row["total_distance"]


def test_an_interrupted_sweep_resumes_to_the_rows_of_an_uninterrupted_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    grid = ["--algorithm", SLOW, "-n", "3,4", "--scheduler", "fsync,ssync", "--seeds", "2",
            "--jobs", "2"]
    whole, broken = tmp_path / "whole.csv", tmp_path / "broken.csv"
    assert sweep([*grid, "--out", str(whole), "-q"]) == 0
    # the same sweep, slowed down (0.3 s per run), stopped by Ctrl-C after its second row
    env = {**os.environ, "FATSWARM_TEST_SLOW": "0.3"}
    proc = subprocess.Popen(
        [sys.executable, "-u", "-m", "fatswarm.deploy.cli", "sweep", *grid, "--out",
         str(broken)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True)  # its own process group: Ctrl-C reaches the workers too
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if broken.exists() and broken.read_text().count("\n") >= 3:  # header + 2 rows
                break
            time.sleep(0.02)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err
    assert "interrupted:" in err and "Traceback" not in err
    assert _group_ends(proc.pid), "processes of the interrupted sweep are left running"
    text = broken.read_text()
    assert text.endswith("\n")
    assert 2 <= len(rows_of(broken)) < 8
    with broken.open("a") as fh:  # as if it had been killed mid-row as well
        fh.write(f"{SLOW},4,clust")
    assert sweep([*grid, "--out", str(broken), "-q"]) == 0
    assert "cut a torn last row" in capsys.readouterr().err
    assert len(rows_of(broken)) == 8
    assert stable(rows_of(broken)) == stable(rows_of(whole))


def _group_ends(pgid: int, within_s: float = 10.0) -> bool:
    """Whether every process of the group is gone within `within_s` (workers, their tracker)."""
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def test_a_worker_that_dies_ends_the_sweep_with_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("FATSWARM_TEST_DIE", "1")
    out = tmp_path / "runs.csv"
    assert sweep(["--algorithm", SLOW, "-n", "3", "--seeds", "2", "--jobs", "1", "--out",
                  str(out), "-q"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a worker process died" in err, err
    assert out.read_text() == header_line()
