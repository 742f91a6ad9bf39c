"""A lock-step run stopped by Ctrl-C, SIGTERM or a record it cannot write says after which round and
how to go on (one line, `stopped_line`); the resume says where it goes on from and estimates only
what is left, and ends with the very record of the uninterrupted run."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.commands import run_lockstep
from fatswarm.deploy.commands.resume import stopped_line
from fatswarm.deploy.engine import estimate
from fatswarm.deploy.engine.lockstep import RoundReport
from fatswarm.deploy.flags import Terminated
from fatswarm.domain.outcome import ExitCode
from fatswarm.world.record import RecordWriteError, RecordWriter

RUN = ["--lockstep", "-n", "8", "--seed", "3", "--scheduler", "ssync"]


def fatswarm(*argv: str) -> int:
    return cli.main(["run", *argv])


@pytest.fixture
def stop_after(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[BaseException | int | None]]:
    """`[exception, round]`: the lock step raises the exception (once one is set) as soon as that
    round is committed."""
    how: list[BaseException | int | None] = [None, 4]
    seen = run_lockstep._Watch.__call__

    def watch(self: run_lockstep._Watch, report: RoundReport) -> None:
        seen(self, report)
        if how[0] is not None and report.entry.round == how[1]:
            raise how[0]  # type: ignore[misc]

    monkeypatch.setattr(run_lockstep._Watch, "__call__", watch)
    yield how
    monkeypatch.undo()


@pytest.mark.parametrize(
    ("stop", "code", "word"),
    [
        (KeyboardInterrupt(), ExitCode.INTERRUPTED, "interrupted"),
        (Terminated(), ExitCode.TERMINATED, "terminated"),
    ],
)
def test_a_stopped_run_says_after_which_round_and_its_resume_ends_as_the_whole_run(
    stop: BaseException,
    code: ExitCode,
    word: str,
    tmp_path: Path,
    stop_after: list[BaseException | int | None],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    target = tmp_path / "run.jsonl"
    assert fatswarm(*RUN, "-q", "--record", str(target)) == ExitCode.FORMED
    whole = target.read_bytes()
    target.unlink()  # the same command again: the same header
    capsys.readouterr()
    stop_after[0] = stop
    assert fatswarm(*RUN, "-q", "--record", str(target)) == code
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (
        f"{word} after round 4; go on with `fatswarm run --lockstep --record {target} --resume`\n"
    )
    monkeypatch.undo()
    assert fatswarm("--lockstep", "--record", str(target), "--resume", "--no-dashboard") == 0
    err = capsys.readouterr().err
    assert err.splitlines()[0] == f"resuming {target} after round 4 (its round cap: 720)", err
    assert target.read_bytes() == whole  # the uninterrupted run's record, byte for byte


def test_a_stopped_run_without_a_record_says_there_is_nothing_to_resume(
    stop_after: list[BaseException | int | None], capsys: pytest.CaptureFixture[str]
) -> None:
    stop_after[0] = KeyboardInterrupt()
    assert fatswarm(*RUN, "-q") == ExitCode.INTERRUPTED
    assert capsys.readouterr().err == "interrupted after round 4 (no --record: nothing to resume)\n"


def test_a_stopped_async_run_says_how_to_go_on_and_its_resume_ends_as_the_whole_run(
    tmp_path: Path, stop_after: list[BaseException | int | None], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["--lockstep", "-n", "5", "--seed", "3", "--scheduler", "async", "-q"]
    target = tmp_path / "a.jsonl"
    assert fatswarm(*argv, "--record", str(target)) == 0
    whole = target.read_bytes()
    target.unlink()  # the same command again: the same header
    stop_after[0] = KeyboardInterrupt()
    assert fatswarm(*argv, "--record", str(target)) == ExitCode.INTERRUPTED
    assert capsys.readouterr().err == (
        f"interrupted after cycle 4; go on with `fatswarm run --lockstep --record {target} "
        "--resume`\n"
    )
    stop_after[0] = None
    assert fatswarm("--lockstep", "--record", str(target), "--resume", "-q") == 0
    assert target.read_bytes() == whole


def test_a_record_that_cannot_be_written_says_after_which_round_and_how_to_go_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "full.jsonl"
    assert fatswarm(*RUN, "-q", "--record", str(target)) == ExitCode.FORMED
    whole = target.read_bytes()
    target.unlink()  # the same command again: the same header
    capsys.readouterr()
    put = RecordWriter.put  # (every line goes through it as text)

    def full_disk(self: RecordWriter, text: str) -> None:
        if text.startswith('{"type":"round","round":6,'):  # half of it is written: disk full
            assert self._fh is not None
            self._fh.write('{"type":"round","round":6,"act')
            self._fh.flush()
            raise RecordWriteError(f"cannot write the run record {self.path}: No space left")
        put(self, text)

    monkeypatch.setattr(RecordWriter, "put", full_disk)
    assert fatswarm(*RUN, "-q", "--record", str(target)) == ExitCode.RECORD_FAILED
    err = capsys.readouterr().err
    assert err == (
        f"fatswarm run: cannot write the run record {target}: No space left; the run stopped "
        "after round 5; once that is fixed, go on with `fatswarm run --lockstep --record "
        f"{target} --resume`\n"
    )
    monkeypatch.undo()
    assert fatswarm("--lockstep", "--record", str(target), "--resume", "-q") == 0
    assert "dropped the torn last line" in capsys.readouterr().err
    assert target.read_bytes() == whole


def test_the_shared_line_quotes_the_record_and_names_the_networked_command() -> None:
    line = stopped_line(
        "terminated", 12, record="my run.jsonl", scheduler="fsync", lockstep=False, seed=1
    )
    assert (
        line
        == "terminated after round 12; go on with `fatswarm run --record 'my run.jsonl' --resume`"
    )


def test_a_resume_estimates_only_what_is_left() -> None:
    fresh = estimate.estimate_lockstep(300, "ssync", 10**6)
    resumed = estimate.estimate_lockstep(300, "ssync", 10**6, done=200)
    assert resumed.rounds == fresh.rounds - 200 and resumed.cap_rounds == 10**6 - 200
    assert resumed.seconds < fresh.seconds
    text = estimate.estimate_text(resumed, 300, record=True)
    assert text.startswith(
        f"estimate for the rest of n=300 after round 200 (a rough model): ~{resumed.rounds} "
        "rounds more, "
    ), text
    assert "appended to the record" in text and "at the round cap of 1000000:" in text
    late = estimate.estimate_lockstep(300, "ssync", 10**6, done=10**5)
    assert late.rounds == 0
    assert estimate.estimate_text(late, 300, record=False).startswith(
        "estimate for the rest of n=300 after round 100000 (a rough model): longer than a "
        "correct run takes; at most 900000 rounds more (the cap): "
    )


def test_a_resumed_large_run_prints_the_estimate_of_what_is_left(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "big.jsonl"
    argv = ["--lockstep", "-n", "200", "--seed", "1", "--scheduler", "fsync"]
    assert fatswarm(*argv, "--max-rounds", "3", "-q", "--record", str(target)) == 1
    lines = target.read_text().splitlines(keepends=True)
    target.write_text("".join(lines[:3]))  # header and two rounds: no result
    capsys.readouterr()
    assert fatswarm("--lockstep", "--record", str(target), "--resume", "--no-dashboard") == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"resuming {target} after round 2 (its round cap: 3)"
    assert err[1].startswith(
        "estimate for the rest of n=200 after round 2 (a rough model): ~1 round"
    )
