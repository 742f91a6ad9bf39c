"""`fatswarm hunt`: drawing from the seed, classifying failures, the SEC invariant, shrinking (a
planted failure, deterministically) and one-line errors; real hunts on worker processes are in
tests/integration/test_hunt_workers.py."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.hunt import pool
from fatswarm.deploy.hunt.pool import Tally
from fatswarm.deploy.hunt.search import (
    COMPUTE,
    STALLED,
    Case,
    Hunt,
    configure,
    draw_candidate,
    hunt_models,
    run_candidate,
    sec_invariant,
    start_families,
)
from fatswarm.deploy.hunt.shrink import decimals, drop_robots, replay, shrink
from fatswarm.deploy.sweep.grid import sweep_schedulers
from fatswarm.domain.robot_model import RobotModel

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


def test_a_run_whose_computes_fail_is_filed_as_the_algorithm_failing_not_a_stall() -> None:
    opaque = RobotModel.of(visibility="opaque")
    paper = Hunt(families=("clustered",), sizes=(6,), models=("ssync",), robot_models=(opaque,))
    kinds = []
    for i in range(4):
        outcome, case = run_candidate(paper, draw_candidate(paper, 3, i))
        assert outcome.failure is not None and case is not None
        kinds.append(outcome.failure.kind)
        if outcome.failure.kind == COMPUTE:
            assert outcome.failure.detail.startswith("the algorithm failed: robot ")
            assert "ViewError: the view holds" in outcome.failure.detail
            assert replay(paper, case).failure == outcome.failure  # the case replays it
    assert COMPUTE in kinds and STALLED not in kinds


# -- the command --------------------------------------------------------------------------------


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
        (["--non-rigid", "-1"], "--non-rigid takes distances > 0"),
        (["--non-rigid", "rigid,1"], "--non-rigid takes one value in a hunt"),
        (["--crash", "1,2"], "--crash takes one value in a hunt"),
        (["--start", "square"], "not a start family"),
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


# -- where failures go -------------------------------------------------------------------------


def test_an_out_that_cannot_be_made_is_one_line_and_exit_two(
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = "/proc/fatswarm-hunt-out"  # /proc takes no new directory, not even from root
    assert hunt(["--budget-runs", "1", "--out", out]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured.err
    assert captured.err.startswith(f"fatswarm hunt: --out {out}: cannot make it in /proc: ")
    assert "Traceback" not in captured.err


def test_an_out_it_cannot_write_in_is_one_line_and_exit_two(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def denied(path: object, *args: object, **kwargs: object) -> None:
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(os, "makedirs", denied)
    assert hunt(["--budget-runs", "1", "--out", str(tmp_path / "found")]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"fatswarm hunt: --out {tmp_path / 'found'}: cannot make it in {tmp_path}: Permission "
        "denied; name a directory you can write in\n"
    )
    monkeypatch.undo()
    (tmp_path / "locked").mkdir()
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    assert hunt(["--budget-runs", "1", "--out", str(tmp_path / "locked")]) == 2
    assert "cannot write in it" in capsys.readouterr().err


def fake_hunt(saves: bool) -> Callable[..., tuple[Tally, bool]]:
    """A `run_hunt` that runs nothing and saves one failure folder, or none."""

    def run_hunt(
        hunt: Hunt, seed: int, budget: object, jobs: int, out: str, *rest: object
    ) -> tuple[Tally, bool]:
        tally = Tally(runs=3)
        if saves:
            os.makedirs(os.path.join(out, "000001-collision"))
        return tally, True

    return run_hunt


@pytest.mark.parametrize("saves", [False, True])
def test_a_hunt_that_finds_nothing_leaves_no_out_folder(
    saves: bool, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(pool, "run_hunt", fake_hunt(saves))
    out = tmp_path / "found"
    assert hunt(["--budget-runs", "3", "--out", str(out), "-q", "--seed", "1"]) == 0
    assert out.exists() is saves
    empty = tmp_path / "mine"
    empty.mkdir()  # a folder of the user's, empty: it stays
    assert hunt(["--budget-runs", "3", "--out", str(empty), "-q", "--seed", "1"]) == 0
    assert empty.is_dir()
