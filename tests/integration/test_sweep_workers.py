"""`fatswarm sweep` on worker processes: small real sweeps write one row per run and resume to the
same rows (after Ctrl-C of a sweep in its own process too), and a worker that dies ends the sweep
with one line."""

from __future__ import annotations

import csv
import json
import os
import shlex
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep.table import PLAIN_COLUMNS, header_line

pytestmark = pytest.mark.integration
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


def test_a_small_sweep_writes_one_row_per_run_and_a_second_one_adds_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    argv = [
        "-n",
        "4,5",
        "--scheduler",
        "fsync,ssync",
        "--seeds",
        "2",
        "--jobs",
        "2",
        "--out",
        str(out),
    ]
    assert sweep(argv) == 0
    summary = capsys.readouterr().out
    rows = rows_of(out)
    assert list(rows[0]) == list(PLAIN_COLUMNS)  # no robot-model axis: no model columns
    assert sorted((r["n"], r["scheduler"], r["seed"]) for r in rows) == sorted(
        (n, s, seed) for n in ("4", "5") for s in ("fsync", "ssync") for seed in ("0", "1")
    )
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
        row["status"],
        row["rounds"],
        row["collisions"],
    )
    assert f"{again['total_distance']:.6f}" == row["total_distance"]


def test_a_sweep_over_models_has_their_rows_summary_and_commands_and_resumes_by_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, md = tmp_path / "runs.csv", tmp_path / "summary.md"
    argv = [
        "-n",
        "3,4",
        "--scheduler",
        "fsync,async",
        "--non-rigid",
        "rigid,1",
        "--crash",
        "0,3",
        "--seeds",
        "1",
        "--jobs",
        "2",
        "--out",
        str(out),
    ]
    assert sweep([*argv, "--summary-md", str(md)]) == 0
    captured = capsys.readouterr()
    assert "4 runs left out" in captured.err  # crash 3 of 3 robots
    assert "fsync+nr1" in captured.out and "async+nr1+crash3" in captured.out
    rows = rows_of(out)
    assert sorted((r["scheduler"], r["non_rigid"], r["crash"], r["n"]) for r in rows) == sorted(
        (s, d, f, n)
        for s in ("fsync", "async")
        for d in ("", "1.0")
        for f, n in (("", "3"), ("", "4"), ("3", "4"))
    )
    for row in rows:  # virtual time: async runs only
        assert (row["time"] != "") == (row["scheduler"] == "async"), row
    assert all(float(r["time"]) > 0 for r in rows if r["time"])
    # the Markdown table: one line per model over every n, its figures as the rows say
    groups: dict[tuple[str, str, str], list[dict[str, str]]] = {}
    for row in rows:
        delta = f"{float(row['non_rigid']):g}" if row["non_rigid"] else "rigid"
        groups.setdefault((row["scheduler"], delta, row["crash"] or "none"), []).append(row)
    lines = md.read_text().splitlines()
    assert len(lines) == 2 + len(groups) == 10
    for line in lines[2:]:
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        group = groups[(cells[1], cells[2], cells[3])]
        formed = [r for r in group if r["status"] == "formed"]
        stalled = sum(r["status"] == "stalled" for r in group)
        assert cells[4] == ",".join(sorted({r["n"] for r in group}))
        assert [int(c) for c in (cells[5], cells[6], cells[8])] == [
            len(group),
            len(formed),
            stalled,
        ]
        rounds = [float(r["rounds"]) for r in formed]
        times = [float(r["time"]) for r in formed if r["time"]]
        assert cells[11] == (f"{statistics.median(rounds):g}" if rounds else "-")
        assert cells[12] == (f"{statistics.median(times):.1f}" if times else "-")
    # the command column repeats an async, a non-rigid and a crash run exactly
    for pick in (
        ("async", "", ""),
        ("fsync", "1.0", ""),
        ("fsync", "", "3"),
        ("async", "1.0", "3"),
    ):
        row = next(r for r in rows if (r["scheduler"], r["non_rigid"], r["crash"]) == pick)
        assert cli.main([*shlex.split(row["command"])[1:], "-q", "--json"]) in (0, 1)
        again = json.loads(capsys.readouterr().out)
        assert (again["status"], str(again["rounds"]), str(again["collisions"])) == (
            row["status"],
            row["rounds"],
            row["collisions"],
        ), row["command"]
        assert f"{again['total_distance']:.6f}" == row["total_distance"]
    # resume: a run is the same run only with the same non_rigid and crash
    before = out.read_bytes()
    assert sweep(argv) == 0
    assert "nothing to run" in capsys.readouterr().err
    assert out.read_bytes() == before
    assert (
        sweep(
            [
                "-n",
                "4",
                "--scheduler",
                "fsync",
                "--non-rigid",
                "1,0.5",
                "--crash",
                "3,2",
                "--seeds",
                "1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert "1 already in" in capsys.readouterr().err
    added = rows_of(out)[len(rows) :]
    assert sorted((r["non_rigid"], r["crash"]) for r in added) == [
        ("0.5", "2"),
        ("0.5", "3"),
        ("1.0", "2"),
    ]


def test_an_interrupted_sweep_resumes_to_the_rows_of_an_uninterrupted_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    grid = [
        "--algorithm",
        SLOW,
        "-n",
        "3,4",
        "--scheduler",
        "fsync,ssync",
        "--seeds",
        "2",
        "--jobs",
        "2",
    ]
    whole, broken = tmp_path / "whole.csv", tmp_path / "broken.csv"
    # the uninterrupted rows on one worker, in this process (two give the rows of one:
    # test_sweep_models_workers.py); the interrupted sweep and its resume on two
    assert sweep([*grid[:-2], "--jobs", "1", "--out", str(whole), "-q"]) == 0
    # the same sweep, slowed down (0.3 s per run), stopped by Ctrl-C after its second row
    env = {**os.environ, "FATSWARM_TEST_SLOW": "0.3"}
    proc = subprocess.Popen(
        [sys.executable, "-u", "-m", "fatswarm.deploy.cli", "sweep", *grid, "--out", str(broken)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )  # its own process group: Ctrl-C reaches the workers too
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
    assert (
        sweep(
            ["--algorithm", SLOW, "-n", "3", "--seeds", "2", "--jobs", "1", "--out", str(out), "-q"]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a worker process died" in err, err
    assert out.read_text() == header_line(PLAIN_COLUMNS)
