"""A compute that fails counts: the move message says so, the world books it at once in the round
line's `failed`, the run's figures count it, the verdict names it the same way under every
scheduler, and a lock-step run with failures resumes byte for byte."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.engine.lockstep import RunResult as LockstepResult
from fatswarm.deploy.sweep import pool, table
from fatswarm.deploy.sweep.grid import RunSpec
from fatswarm.deploy.view import panels
from fatswarm.deploy.view.summary import Outcome, summary_json
from fatswarm.domain import figures
from fatswarm.domain.outcome import ExitCode, Status
from fatswarm.domain.path import Line, to_record
from fatswarm.domain.path import Path as Route
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import MAX_FAILURE, failure_kind, failure_text
from fatswarm.domain.wire import ProtocolError, pack
from fatswarm.world.protocol import LookRequest, MoveSubmitted, Snapshot
from fatswarm.world.record_read import read_record

VIEW_ERROR = "ViewError: the view holds"
OPAQUE = RobotModel.of(visibility="opaque")

# lock-step runs of the paper's algorithm on views it does not expect: (flags, exit code)
FORMED_THROUGH_FAILURES = ["-n", "5", "--seed", "2", "--visibility", "opaque", "--scheduler",
                           "centralized"]  # fmt: skip
STALLED_BY_FAILURES = ["-n", "8", "--seed", "3", "--sight", "10", "--scheduler", "ssync"]


def run(argv: list[str]) -> int:
    return cli.main(["run", "--lockstep", "-q", *argv])


# --- the wire ----------------------------------------------------------------------------------


def test_a_failed_move_round_trips_and_a_move_without_the_field_is_as_before() -> None:
    failed = MoveSubmitted.failing(3, 7, "ViewError: the view holds 4 robots, expected n-1 = 5")
    again = MoveSubmitted.decode(failed.encode())
    assert again == failed and not again.path and again.colour is None
    plain = MoveSubmitted(3, 7, Route((Line((1.0, 0.0)),)))
    assert b"failed" not in plain.encode()  # the bytes of a move that did not fail, as before
    assert MoveSubmitted.decode(plain.encode()).failed is None
    # a Look carrying it, as an agent sends it
    assert MoveSubmitted.decode(LookRequest(0, 6, failed.encode()).move).failed == failed.failed


def test_a_failed_move_that_also_moves_is_refused() -> None:
    path = to_record(Route((Line((1.0, 0.0)),)))
    body = {"robot": 1, "round": 2, "path": path, "failed": "KeyError: 3"}
    with pytest.raises(ProtocolError, match="'failed' stays"):
        MoveSubmitted.decode(pack("move", body))


def test_the_failure_text_is_one_bounded_line_and_its_kind_masks_the_numbers() -> None:
    assert failure_text(ValueError("bad\nsecond line")) == "ValueError: bad"
    assert failure_text(KeyError()) == "KeyError"
    assert len(failure_text(RuntimeError("x" * 500))) == MAX_FAILURE
    a = failure_kind("ViewError: the view holds 4 robots, expected n-1 = 5")
    assert a == failure_kind("ViewError: the view holds 3 robots, expected n-1 = 5")
    assert a != failure_kind("ZeroDivisionError: division by zero")


# --- the record, the figures and the verdict ----------------------------------------------------


def test_failures_are_counted_in_the_record_figures_summary_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "run.jsonl"
    assert run([*STALLED_BY_FAILURES, "--record", str(record), "--json"]) == ExitCode.NOT_FORMED
    shown = json.loads(capsys.readouterr().out)
    rec = read_record(record)
    failed = [(e.round, e.extra["failed"]) for e in rec.rounds if "failed" in e.extra]
    count = sum(len(f) for _, f in failed)
    first_round, first = failed[0]
    robot = min(first, key=int)
    said = f"robot {robot} in round {first_round}: {first[robot]}"
    assert count > 0 and VIEW_ERROR in said
    assert shown["failures"] == count and shown["first_failure"] == said
    assert shown["status"] == "stalled"
    assert shown["verdict"].endswith(f"; the algorithm failed {count} times, first {said}")
    assert fatswarm.summary(fatswarm.read_record(record))["failures"] == count
    result = fatswarm.run(8, seed=3, sight=10, scheduler="ssync")
    assert result.derived["failures"] == count and result.derived["first_failure"] == said
    assert figures.run_derived(rec.rounds)["failures"] == count
    frame = fatswarm.read_record(record).to_dataframe() if _has_pandas() else None
    if frame is not None:
        assert int(frame.groupby("round")["failures"].first().sum()) == count


def _has_pandas() -> bool:
    try:
        import pandas  # noqa: F401  (optional: fatswarm[notebook])
    except ImportError:
        return False
    return True


def test_a_record_without_failures_counts_none_and_its_verdict_is_as_before(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "run.jsonl"
    assert run(["-n", "5", "--seed", "2", "--record", str(record), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["failures"] == 0 and shown["first_failure"] is None
    assert shown["verdict"].endswith("collision-free")
    assert "failed" not in record.read_text()


@pytest.mark.parametrize("scheduler", ["ssync", "fsync", "async", "async-slowest"])
def test_a_run_whose_robots_fail_stalls_and_says_so_under_every_scheduler(scheduler: str) -> None:
    result = fatswarm.run(6, seed=3, visibility="opaque", scheduler=scheduler, max_rounds=200)
    assert result.status == "stalled"  # the same end under round models and async alike
    failures = result.derived["failures"]
    assert isinstance(failures, int) and failures > 0
    unit = "cycle" if scheduler.startswith("async") else "round"
    first = result.derived["first_failure"]
    assert isinstance(first, str) and f" in {unit} " in first and VIEW_ERROR in first
    outcome = json.loads(summary_json(_outcome(result, scheduler), 1))
    assert (
        f"; the algorithm failed {result.derived['failures']} times, first robot"
        in (outcome["verdict"])
    )


def _outcome(result: LockstepResult, scheduler: str) -> Outcome:
    """The summary's outcome of a lock-step result (as `fatswarm run --lockstep` makes it)."""
    return Outcome(
        status=result.status,
        rounds=result.rounds,
        collisions=result.collisions,
        n=len(result.positions),
        a=4.0,
        seed=3,
        scheduler=scheduler,
        epochs=result.epochs,
        moves=result.moves,
        total_distance=result.total_distance,
        derived=result.derived,
    )


def test_a_failing_robot_keeps_a_run_from_forming_but_not_from_ending(tmp_path: Path) -> None:
    record = tmp_path / "run.jsonl"
    assert run([*FORMED_THROUGH_FAILURES, "--record", str(record)]) == ExitCode.FORMED
    rec = read_record(record)
    failed = [e for e in rec.rounds if "failed" in e.extra]
    assert failed and all(set(e.extra["failed"]) <= {str(r) for r in e.active} for e in failed)
    assert not any("timed_out" in e.extra for e in rec.rounds)  # booked at once, not timed out
    last = rec.rounds[-1]
    assert "failed" not in last.extra  # formed: the last robots asked to stay
    assert np.array_equal(rec.result.positions, last.positions)  # type: ignore[union-attr]


# --- resume ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("flags", "code", "at"),
    [
        (FORMED_THROUGH_FAILURES, ExitCode.FORMED, 2),
        (FORMED_THROUGH_FAILURES, ExitCode.FORMED, 9),
        (STALLED_BY_FAILURES, ExitCode.NOT_FORMED, 6),
    ],
)
def test_a_lockstep_run_with_failures_resumes_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], code: int, at: int
) -> None:
    whole = tmp_path / "whole.jsonl"
    assert run([*flags, "--record", str(whole)]) == code
    summary = capsys.readouterr().out.split("record: ")[0]
    lines = whole.read_text().splitlines(keepends=True)
    assert any('"failed"' in line for line in lines[1 : 1 + at]) == (at > 2)
    part = tmp_path / "part.jsonl"
    part.write_text("".join(lines[: 1 + at]))  # the run cut after `at` rounds, as by a crash
    assert run(["--record", str(part), "--resume"]) == code
    assert capsys.readouterr().out == f"{summary}record: {part}\n"  # the same verdict, figures
    assert part.read_text() == whole.read_text()  # the very record, byte for byte


def test_a_lockstep_run_stopped_by_its_round_cap_after_failures_goes_on_as_the_whole_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    whole, part = tmp_path / "whole.jsonl", tmp_path / "part.jsonl"
    assert run([*FORMED_THROUGH_FAILURES, "--record", str(whole)]) == ExitCode.FORMED
    assert run([*FORMED_THROUGH_FAILURES, "--record", str(part), "--max-rounds", "9"]) == 1
    capsys.readouterr()
    lines = part.read_text().splitlines(keepends=True)
    assert json.loads(lines[-1])["status"] == "max_rounds"
    part.write_text("".join(lines[:-1]))  # the round lines of the capped run, its result dropped
    header = json.loads(lines[0])
    assert header["max_rounds"] == 9
    header.update(json.loads(whole.read_text().splitlines()[0]))  # the whole run's cap
    part.write_text(json.dumps(header, separators=(",", ":")) + "\n" + "".join(lines[1:-1]))
    assert run(["--record", str(part), "--resume"]) == ExitCode.FORMED
    assert part.read_text() == whole.read_text()


def test_a_sweep_row_counts_the_failures_and_names_the_first() -> None:
    spec = RunSpec("uniform-circle", 6, "clustered", "ssync", 3, robot_model=OPAQUE)
    run = pool.run_spec(spec)
    row = table.make_row(spec, run, "0")
    assert run.status == "stalled" and int(row["failures"]) > 0
    assert row["first_failure"].startswith("robot ") and VIEW_ERROR in row["first_failure"]
    clean = table.make_row(spec, table.RunFigures("formed", rounds=2, derived={"failures": 0}), "0")
    assert (clean["failures"], clean["first_failure"]) == ("0", "")


def test_the_dashboard_says_how_often_the_algorithm_failed() -> None:
    frame = panels.Frame(
        round=4, n=6, scheduler="ssync", positions=np.zeros((6, 2)), status=Status.STALLED
    )
    assert "failed" not in panels.outcome_text(frame)
    assert "failures" not in dict(panels.tail_rows(frame))
    failing = dataclasses.replace(frame, derived={"failures": 6.0})
    assert panels.outcome_text(failing).endswith("0 collisions, the algorithm failed 6 times")
    assert dict(panels.tail_rows(failing))["failures"] == "6"


def test_the_agent_sends_a_failed_compute_in_its_move_and_says_each_kind_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    from fatswarm.agent import service  # the agent's shell: `_move` is its Compute, no I/O

    robot = service.Robot(load_algorithm("uniform-circle"))
    cfg = service.AgentConfig("s", 2)
    caplog.set_level("INFO", logger="fatswarm.agent")
    moves = []
    for round_no, seen in ((3, 4), (4, 3)):
        view = np.array([[3.0 * (k + 1), 0.0] for k in range(seen)])
        snapshot = Snapshot(round_no, 6, "uniform-circle", {"a": 4.0}, view)
        moves.append(MoveSubmitted.decode(service._move(cfg, snapshot, robot)))
    assert [(m.robot, m.round, bool(m.path), m.failed) for m in moves] == [
        (2, 3, False, "ViewError: the view holds 4 robots, expected n-1 = 5"),
        (2, 4, False, "ViewError: the view holds 3 robots, expected n-1 = 5"),
    ]
    said = [r for r in caplog.records if "compute failed" in r.getMessage()]
    assert len(said) == 1 and said[0].exc_info is None  # one line for the kind, no traceback
