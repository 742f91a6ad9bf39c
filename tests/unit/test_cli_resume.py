"""`fatswarm run --resume`: the run is the record's (a contradicting flag is refused with one
line), a record that cannot be continued is refused with one line, and a lockstep run continues
a cut record exactly as the uninterrupted run went, appending to it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.engine.config import RunSetup
from fatswarm.deploy.net import launcher
from fatswarm.domain.outcome import ExitCode
from fatswarm.world.record_read import read_record

MODES = pytest.mark.parametrize("mode", [["--lockstep"], []], ids=["lockstep", "networked"])


pytestmark = pytest.mark.usefixtures("no_launch")  # tests/unit/conftest.py


def fatswarm(argv: list[str]) -> int:
    return cli.main(["run", *argv])


def one_line_refusal(capsys: pytest.CaptureFixture[str], *words: str) -> None:
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err
    assert err.startswith("fatswarm run: ") and err.count("\n") == 1, err
    for word in words:
        assert word in err, err


def whole_run(tmp_path: Path, scheduler: str, *flags: str) -> Path:
    """A finished lockstep run's record (n 8, seed 3)."""
    target = tmp_path / f"whole-{scheduler}.jsonl"
    code = fatswarm(
        [
            "--lockstep",
            "-n",
            "8",
            "--seed",
            "3",
            "--scheduler",
            scheduler,
            "-q",
            "--record",
            str(target),
            *flags,
        ]
    )
    assert code == ExitCode.FORMED
    return target


def cut(whole: Path, rounds: int, name: str = "cut.jsonl") -> Path:
    """The record of the same run cut after `rounds` rounds: no result line (a crash)."""
    lines = whole.read_text().splitlines(keepends=True)
    assert len(lines) > rounds + 2, "the run is too short to cut there"
    target = whole.with_name(name)
    target.write_text("".join(lines[: 1 + rounds]))
    return target


@pytest.fixture
def ssync_cut(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    target = cut(whole_run(tmp_path, "ssync"), 5)
    capsys.readouterr()
    return target


# --- a lockstep run continues a cut record exactly --------------------------------------------


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized", "scripted"])
@pytest.mark.parametrize("at", [0, 3])
def test_lockstep_resume_ends_as_the_uninterrupted_run(
    scheduler: str, at: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    schedule = tmp_path / "schedule.json"
    schedule.write_text(json.dumps({"rounds": [[0, 3, 5], [1, 2], [4, 6, 7], [0, 7]]}))
    extra = ["--schedule", str(schedule)] if scheduler == "scripted" else []
    whole = whole_run(tmp_path, scheduler, *extra)
    summary = capsys.readouterr().out.split("record: ")[0]
    part = cut(whole, at)
    code = fatswarm(["--lockstep", "--record", str(part), "--resume", "-q", *extra])
    out = capsys.readouterr().out
    assert code == ExitCode.FORMED
    assert out == f"{summary}record: {part}\n"  # same verdict, n, a, seed and figures
    done, expected = read_record(part), read_record(whole)
    assert done.result is not None and expected.result is not None
    assert done.result.rounds == expected.result.rounds
    assert done.result.positions.tolist() == expected.result.positions.tolist()
    assert part.read_text() == whole.read_text()  # appended to: the very record, byte for byte


def test_flags_that_agree_with_the_record_are_fine(
    ssync_cut: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = fatswarm(
        [
            "--lockstep",
            "--record",
            str(ssync_cut),
            "--resume",
            "-q",
            "-n",
            "8",
            "-a",
            "4",
            "--seed",
            "3",
            "--scheduler",
            "ssync",
            "--start",
            "clustered",
            "--max-rounds",
            "720",
        ]
    )
    assert code == ExitCode.FORMED, capsys.readouterr().err
    assert read_record(ssync_cut).result is not None


def test_a_resumed_run_does_not_print_a_seed_to_repeat(
    ssync_cut: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert fatswarm(["--lockstep", "--record", str(ssync_cut), "--resume"]) == 0
    assert "pass --seed" not in capsys.readouterr().err


# --- refused with one line, the record untouched ------------------------------------------------


@MODES
@pytest.mark.parametrize(
    ("flags", "words"),
    [
        (["-n", "12"], ["-n 12 contradicts", "n=8"]),
        (["-a", "5"], ["-a 5 contradicts", "a=4"]),
        (["--seed", "4"], ["--seed 4 contradicts", "seed=3"]),
        (["--scheduler", "fsync"], ["--scheduler fsync contradicts", "scheduler=ssync"]),
        (["--max-rounds", "9"], ["--max-rounds 9 contradicts", "max_rounds=720"]),
        (["--start", "dense"], ["--start dense contradicts", "dense start of seed 3"]),
    ],
)
def test_a_flag_that_contradicts_the_record_is_refused_naming_both_values(
    mode: list[str],
    flags: list[str],
    words: list[str],
    ssync_cut: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    before = ssync_cut.read_text()
    code = fatswarm([*mode, "--record", str(ssync_cut), "--resume", "-q", *flags])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, *words, f"drop {flags[0]} to resume it")
    assert ssync_cut.read_text() == before


@MODES
def test_an_init_file_that_contradicts_the_record_is_refused(
    mode: list[str], ssync_cut: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    header = read_record(ssync_cut).header
    init = tmp_path / "init.json"
    moved = [[x + 0.5, y] for x, y in header.initial.tolist()]  # the same start, elsewhere
    init.write_text(json.dumps({"positions": moved}))
    argv = [*mode, "--record", str(ssync_cut), "--resume", "-q", "--init", str(init)]
    assert fatswarm(argv) == ExitCode.BAD_INPUT
    one_line_refusal(capsys, f"--init {init} contradicts", "robot 0 at")
    init.write_text(json.dumps({"positions": moved[:5]}))
    assert fatswarm(argv) == ExitCode.BAD_INPUT
    one_line_refusal(capsys, "n=8 (the file 5 robots)")
    init.write_text(json.dumps({"positions": header.initial.tolist()}))  # the same start: fine
    if mode:
        assert fatswarm(argv) == ExitCode.FORMED
        assert read_record(ssync_cut).result is not None


@MODES
def test_a_record_that_cannot_be_resumed_is_refused_with_one_line(
    mode: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    finished = whole_run(tmp_path, "fsync")
    capsys.readouterr()
    empty = tmp_path / "empty.jsonl"
    empty.write_text("")
    notes = tmp_path / "notes.jsonl"
    notes.write_text("precious notes\n")
    rounds = len(read_record(finished).rounds)
    cases = [
        (tmp_path / "absent.jsonl", "does not exist; nothing to resume"),
        (empty, "is empty, not a run record; nothing to resume"),
        (notes, "not a run record"),
        (finished, f"already finished (formed in {rounds} rounds); nothing to resume"),
    ]
    for path, words in cases:
        before = path.read_text() if path.exists() else None
        assert fatswarm([*mode, "--record", str(path), "--resume", "-q"]) == 2, path
        one_line_refusal(capsys, words)
        assert (path.read_text() if path.exists() else None) == before


@MODES
def test_resume_needs_a_record(mode: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert fatswarm([*mode, "--resume", "-q"]) == ExitCode.BAD_INPUT
    one_line_refusal(capsys, "--resume continues a run record: name it with --record PATH")


def test_resume_takes_the_fairness_from_the_header_and_refuses_another(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = whole_run(tmp_path, "ssync", "--fairness", "3")
    expected = whole.read_text()
    part = cut(whole, 5)
    capsys.readouterr()
    before = part.read_text()
    assert fatswarm(["--lockstep", "--record", str(part), "--resume", "-q", "--fairness", "5"]) == 2
    one_line_refusal(capsys, "--fairness 5 contradicts", "fairness=3")
    assert part.read_text() == before
    assert fatswarm(["--lockstep", "--record", str(part), "--resume", "-q"]) == 0
    assert part.read_text() == expected  # the uninterrupted run's record, byte for byte


def test_lockstep_refuses_a_networked_record_in_which_robots_timed_out(
    ssync_cut: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = ssync_cut.read_text().splitlines(keepends=True)
    third = json.loads(lines[3])
    third["timed_out"] = third["active"][:1]
    lines[3] = json.dumps(third) + "\n"
    ssync_cut.write_text("".join(lines))
    assert fatswarm(["--lockstep", "--record", str(ssync_cut), "--resume", "-q"]) == 2
    one_line_refusal(capsys, "round 3: robots", "timed out")


def test_lockstep_drops_a_torn_last_line_says_so_and_ends_as_the_uninterrupted_run(
    ssync_cut: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = ssync_cut.with_name("whole-ssync.jsonl")
    ssync_cut.write_text(ssync_cut.read_text() + '{"type":"round","rou')
    assert fatswarm(["--lockstep", "--record", str(ssync_cut), "--resume", "-q"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith(f"fatswarm run: --resume: dropped the torn last line of {ssync_cut}")
    assert "(line 7, 20 bytes" in err
    assert ssync_cut.read_text() == whole.read_text()  # the very record, byte for byte


# --- a networked --resume hands the record's run to the parts -------------------------------------


def test_networked_resume_runs_the_records_seed_scheduler_and_robots(
    ssync_cut: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    launched: list[tuple[RunSetup, str]] = []

    def launch(
        args: argparse.Namespace, setup: RunSetup, record: str, pace: float, swarm: str
    ) -> int:
        launched.append((setup, record))
        return ExitCode.NOT_FORMED

    monkeypatch.setattr(launcher, "_launch", launch)
    assert fatswarm(["--record", str(ssync_cut), "--resume", "-q"]) == ExitCode.NOT_FORMED
    ((setup, record),) = launched
    assert (
        setup.seed,
        setup.params.n,
        dict(setup.params.values),
        setup.scheduler.name,
        setup.max_rounds,
        setup.algorithm_ref,
    ) == (3, 8, {"a": 4.0}, "ssync", 720, "uniform-circle")
    assert setup.resumed is not None and len(setup.resumed.rounds) > 0
    assert record == str(ssync_cut)
    assert "pass --seed" not in capsys.readouterr().err


@MODES
def test_every_contradicting_flag_is_named_in_one_line(
    mode: list[str], ssync_cut: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = ssync_cut.read_text()
    flags = ["-n", "12", "--seed", "4", "--crash", "2", "--frames", "chirality", "--record-views"]
    code = fatswarm([*mode, "--record", str(ssync_cut), "--resume", "-q", *flags])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(
        capsys,
        "-n 12 contradicts",
        "n=8",
        "--seed 4 contradicts",
        "seed=3",
        "--crash 2 contradicts",
        "no crashes",
        "--frames chirality contradicts",
        "frames=y-axis",
        "--record-views contradicts",
        "does not record views",
        "drop -n, --seed, --crash, --frames, --record-views to resume it",
    )
    assert ssync_cut.read_text() == before
