"""`fatswarm hunt`: drawing from the seed, classifying failures, the SEC invariant, shrinking (a
planted failure, deterministically), the saved files (read back by `fatswarm run`'s readers and
replayed by `fatswarm run` itself), one-line errors, and Ctrl-C."""

from __future__ import annotations

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

from fatswarm.coordinator.schedule import load_script
from fatswarm.deploy import cli
from fatswarm.deploy.hunt.search import (
    COLLISION,
    MAX_ROUNDS,
    Case,
    Hunt,
    configure,
    decimals,
    draw_candidate,
    drop_robots,
    hunt_models,
    replay,
    run_candidate,
    sec_invariant,
    shrink,
    start_families,
)
from fatswarm.deploy.scenarios.starts import load_init
from fatswarm.deploy.sweep.grid import sweep_schedulers
from fatswarm.world.record import read_record

ROOT = Path(__file__).resolve().parents[2]
PLANTED = f"{ROOT / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
ROUND_MODELS = ("fsync", "ssync", "centralized")
PLANTED_HUNT = Hunt(PLANTED, (), start_families(), tuple(range(3, 9)), ROUND_MODELS)


def hunt(argv: list[str]) -> int:
    return cli.main(["hunt", *argv])


def planted_failure(index: int = 0) -> tuple[Case, str]:
    """The first failure of the planted algorithm from candidate `index` on (seed 3)."""
    for i in range(index, index + 20):
        outcome, case = run_candidate(PLANTED_HUNT, draw_candidate(PLANTED_HUNT, 3, i))
        if case is not None and outcome.failure is not None:
            return case, outcome.failure.kind
    raise AssertionError("the planted algorithm did not fail in 20 candidates")


# -- drawing ------------------------------------------------------------------------------------


def test_a_candidate_is_a_function_of_the_hunt_seed_and_its_index() -> None:
    first = [draw_candidate(PLANTED_HUNT, 5, i) for i in range(30)]
    assert first == [draw_candidate(PLANTED_HUNT, 5, i) for i in range(30)]
    assert first != [draw_candidate(PLANTED_HUNT, 6, i) for i in range(30)]
    assert len({c.family for c in first}) > 3 and len({c.model for c in first}) == 3
    assert all(3 <= c.n <= 8 for c in first)


def test_families_keep_the_n_they_build_and_a_crash_keeps_a_survivor() -> None:
    small = Hunt(PLANTED, (), ("rim", "clustered"), (2, 3), ("fsync",), crash=2)
    assert small.choices() == [("rim", (3,)), ("clustered", (3,))]
    assert Hunt(PLANTED, (), ("rim",), (2,), ("fsync",)).choices() == []


def test_the_models_are_the_schedulers_that_need_no_file_read_in_one_place() -> None:
    assert hunt_models() == sweep_schedulers()
    assert "scripted" not in hunt_models() and set(ROUND_MODELS) <= set(hunt_models())


# -- the SEC invariant of the paper's algorithm --------------------------------------------------


def square(radius: float) -> np.ndarray:
    return np.array([[radius, 0.0], [0.0, radius], [-radius, 0.0], [0.0, -radius]])


def test_a_robot_leaving_the_sec_in_formucircle_breaks_the_invariant() -> None:
    check = sec_invariant(configure(Hunt(), 4))  # r = 4 / (2 sin(pi/4)) = 2.83 for a = 4
    before = square(5.0) + 1e5
    inside = before.copy()
    inside[0] += (-1.0, 0.5)
    assert check(before, inside) is None
    out = before.copy()
    out[0] += (0.01, 0.0)
    broken = check(before, out)
    assert broken is not None and "robot 0 left the SEC" in broken


def test_the_sec_falling_below_r_breaks_it_and_expansion_is_not_checked() -> None:
    check = sec_invariant(configure(Hunt(), 4))
    r = 4.0 / (2.0 * math.sin(math.pi / 4))
    before = square(r + 1e-3)
    shrunk = before.copy()
    shrunk[[0, 2], 0] *= 0.99  # the diameter pinning the SEC comes in
    shrunk[[1, 3], 1] *= 0.99
    broken = check(before, shrunk)
    assert broken is not None and "below r" in broken
    expanding = square(r - 0.5)  # SECExpansion: leaders leave the SEC on purpose
    assert check(expanding, expanding * 2.0) is None


# -- running, shrinking -------------------------------------------------------------------------


def test_the_planted_failure_shrinks_to_two_robots_deterministically() -> None:
    case, kind = planted_failure()
    first = shrink(PLANTED_HUNT, case, kind)
    again = shrink(PLANTED_HUNT, case, kind)
    assert first.reproduced and first.failure.kind == kind
    assert first.case == again.case and first.steps == again.steps and first.runs == again.runs
    assert first.case.n == 2 < case.n
    assert first.case.rounds is not None and len(first.case.rounds) <= 2
    assert max(decimals(v) for p in first.case.positions for v in p) <= 1
    assert replay(PLANTED_HUNT, first.case).failure == first.failure


def test_the_case_of_a_failure_replays_it_exactly_under_its_script() -> None:
    case, kind = planted_failure(5)
    outcome = replay(PLANTED_HUNT, case)
    assert outcome.failure is not None and outcome.failure.kind == kind
    assert case.rounds is not None and outcome.active == case.rounds[: len(outcome.active)]


def test_dropping_robots_renumbers_the_script_and_drops_empty_rounds() -> None:
    case = Case(
        ((0.0, 0.0), (3.0, 0.0), (6.0, 0.0), (9.0, 0.0)),
        ((1,), (0, 2), (3,)),
        "fsync",
        7,
        100,
        "ssync",
    )
    smaller = drop_robots(PLANTED_HUNT, case, [1])
    assert smaller is not None
    assert smaller.positions == ((0.0, 0.0), (6.0, 0.0), (9.0, 0.0))
    assert smaller.rounds == ((0, 1), (2,))
    assert drop_robots(PLANTED_HUNT, case, [0, 1, 2]) is None  # one robot cannot fail


def test_the_paper_algorithm_formed_cleanly_is_no_failure() -> None:
    paper = Hunt(families=("clustered", "near-symmetric"), sizes=(4, 5), models=("fsync",))
    for i in range(6):
        outcome, case = run_candidate(paper, draw_candidate(paper, 11, i))
        assert outcome.failure is None and case is None and outcome.status == "formed"


# -- the command --------------------------------------------------------------------------------


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
    assert list(out.iterdir()) == []
    assert "nothing found in 30 runs" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--scheduler", "scripted"], "needs a schedule file"),
        (["--scheduler", "nope"], "is not a scheduler"),
        (["--starts", "square"], "not a start family"),
        (["-n", "5..3"], "LOW <= HIGH"),
        (["-n", "1", "--starts", "rim"], "widen -n"),
        (["--budget-runs", "0"], "--budget-runs must be at least 1"),
        (["--budget-seconds", "nan"], "--budget-seconds must be"),
        (["--max-failures", "0"], "--max-failures must be at least 1"),
        (["--param", "a=2"], "a must be > 3"),
        (["--algorithm", "no_such_module:X"], "no_such_module"),
        (["--non-rigid", "-1"], "--non-rigid must be"),
        (["--jobs", "0"], "--jobs must be at least 1"),
    ],
)
def test_bad_input_is_one_line_and_exit_two(
    argv: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    budget = [] if "--budget-runs" in argv else ["--budget-runs", "1"]
    assert hunt([*argv, *budget, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1, err
    assert not (tmp_path / "x").exists()


def test_a_non_empty_out_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "000001-collision").mkdir()
    assert hunt(["--out", str(tmp_path / "old"), "--budget-runs", "1"]) == 2
    err = capsys.readouterr().err
    assert "is not empty" in err and err.count("\n") == 1


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
