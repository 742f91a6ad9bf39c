"""`fatswarm hunt` on worker processes: it finds, shrinks and saves a planted failure, a run budget
saves the same failures on one worker or two, a saved failure replays through `fatswarm run` (its
own process), and Ctrl-C leaves no worker behind."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fatswarm.coordinator.schedule import load_script
from fatswarm.deploy import cli
from fatswarm.deploy.hunt.search import COLLISION, MAX_ROUNDS
from fatswarm.deploy.scenarios.starts import load_init
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration
ROOT = Path(__file__).resolve().parents[2]
PLANTED = f"{ROOT / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
ROUND_MODELS = ("fsync", "ssync", "centralized")


def hunt(argv: list[str]) -> int:
    return cli.main(["hunt", *argv])


def test_hunt_finds_shrinks_and_saves_the_planted_failure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "found"
    code = hunt(
        [
            "--algorithm",
            PLANTED,
            "--scheduler",
            ",".join(ROUND_MODELS),
            "-n",
            "3..8",
            "--budget-runs",
            "40",
            "--max-failures",
            "2",
            "--jobs",
            "2",
            "--seed",
            "3",
            "--out",
            str(out),
            "-q",
        ]
    )
    assert code == 1
    folders = sorted(out.iterdir())
    assert len(folders) == 2
    printed = capsys.readouterr()
    assert "failures found" in printed.out and folders[0].name in printed.out
    for folder in folders:
        summary = json.loads((folder / "summary.json").read_text())
        assert summary["kind"] in (COLLISION, MAX_ROUNDS) and summary["reproduced"]
        assert summary["replayed"]["kind"] == summary["kind"]
        assert summary["shrunk"]["n"] <= 3 <= summary["found"]["n"]
        positions, a = load_init(str(folder / "start.json"))  # fatswarm run's own readers
        assert a is None and len(positions) == summary["shrunk"]["n"]
        script = load_script(str(folder / "schedule.json"), len(positions))
        assert script.after == "fsync" and len(script.rounds) == summary["shrunk"]["script_rounds"]
        record = read_record(str(folder / "record.jsonl"))
        assert record.header.n == len(positions)
        assert (folder / "command").read_text().splitlines()[-1] == summary["command"]


def test_a_run_budget_saves_the_same_failures_on_one_worker_or_two(tmp_path: Path) -> None:
    saved = {}
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}"
        assert (
            hunt(
                [
                    "--algorithm",
                    PLANTED,
                    "--scheduler",
                    ",".join(ROUND_MODELS),
                    "-n",
                    "3..6",
                    "--budget-runs",
                    "12",
                    "--max-failures",
                    "3",
                    "--jobs",
                    jobs,
                    "--seed",
                    "9",
                    "--out",
                    str(out),
                    "-q",
                ]
            )
            == 1
        )
        saved[jobs] = {
            folder.name: [
                (folder / name).read_text()
                for name in ("start.json", "schedule.json", "summary.json")
            ]
            for folder in out.iterdir()
        }
    assert len(saved["1"]) == 3 and saved["1"] == saved["2"]


def test_a_saved_failure_replays_through_fatswarm_run(tmp_path: Path) -> None:
    out = tmp_path / "found"
    assert (
        hunt(
            [
                "--algorithm",
                PLANTED,
                "--scheduler",
                "fsync",
                "-n",
                "4",
                "--budget-runs",
                "4",
                "--max-failures",
                "1",
                "--jobs",
                "1",
                "--seed",
                "1",
                "--out",
                str(out),
                "-q",
            ]
        )
        == 1
    )
    (folder,) = out.iterdir()
    summary = json.loads((folder / "summary.json").read_text())
    argv = shlex.split(summary["command"])
    assert argv[:2] == ["fatswarm", "run"]
    done = subprocess.run(
        [sys.executable, "-m", "fatswarm.deploy.cli", *argv[1:], "--json"],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode in (1, 3), done.stderr
    result = json.loads(done.stdout)
    if summary["kind"] == COLLISION:
        assert result["collisions"] > 0
    else:
        assert result["status"] == MAX_ROUNDS
    saved, replayed = (
        read_record(str(folder / "record.jsonl")),
        read_record(str(folder / "replay.jsonl")),
    )
    assert [e.active for e in replayed.rounds] == [e.active for e in saved.rounds]
    for mine, theirs in zip(saved.rounds, replayed.rounds, strict=True):
        np.testing.assert_array_equal(mine.positions, theirs.positions)


def test_the_paper_algorithm_under_fsync_gives_nothing_in_a_small_budget(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "none"
    assert (
        hunt(
            [
                "--scheduler",
                "fsync",
                "-n",
                "3..8",
                "--budget-runs",
                "30",
                "--jobs",
                "2",
                "--seed",
                "1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert not out.exists()  # the hunt made it and leaves no empty folder behind
    assert "nothing found in 30 runs" in capsys.readouterr().err


def test_ctrl_c_exits_130_with_no_worker_left(tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-u",
            "-m",
            "fatswarm.deploy.cli",
            "hunt",
            "--algorithm",
            PLANTED,
            "--scheduler",
            "fsync",
            "--budget-seconds",
            "120",
            "--max-failures",
            "1000",
            "--shrink-runs",
            "100000",
            "--jobs",
            "2",
            "--seed",
            "1",
            "--out",
            str(tmp_path / "o"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        assert proc.stderr is not None
        line = proc.stderr.readline()  # the plan line: the workers start right after it
        assert line.startswith("hunt: seed 1"), line
        while time.monotonic() < deadline and not any((tmp_path / "o").iterdir()):
            time.sleep(0.05)  # wait for a saved failure: the workers are surely up
        os.kill(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 130, err
        assert "interrupted" in err
        assert _group_gone(proc.pid, time.monotonic() + 10), _group(proc.pid)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _group(pgid: int) -> str:
    """The processes left in process group `pgid` (for a failure's message)."""
    listing = subprocess.run(
        ["ps", "-o", "pid,pgid,args", "-g", str(pgid)], capture_output=True, text=True, check=False
    )
    return listing.stdout


def _group_gone(pgid: int, deadline: float) -> bool:
    """Whether every process of group `pgid` has ended (by `deadline`: the multiprocessing
    resource tracker ends on its own once the hunt has, a moment later)."""
    while True:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
