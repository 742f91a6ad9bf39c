"""`fatswarm` and `fatswarm run` flags, in process: --version, output files, durations, flags a
lockstep run refuses, --json, the estimate of a large lockstep run, and a closed stdout."""

from __future__ import annotations

import argparse
import io
import json
from pathlib import Path
from typing import Any

import pytest

from fatswarm import __version__
from fatswarm.deploy import cli
from fatswarm.deploy.commands import run, run_lockstep
from fatswarm.deploy.engine import estimate
from fatswarm.deploy.view import summary
from fatswarm.domain.outcome import ExitCode
from fatswarm.world.record_read import read_record

MODES = pytest.mark.parametrize("mode", [["--lockstep"], []], ids=["lockstep", "networked"])


pytestmark = pytest.mark.usefixtures("no_launch")  # tests/unit/conftest.py


def fatswarm(argv: list[str]) -> int:
    return cli.main(argv)


def one_line_refusal(capsys: pytest.CaptureFixture[str], message: str) -> None:
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err
    assert err.startswith("fatswarm run: ") and err.count("\n") == 1, err
    assert message in err, err


# --- 1. --version ----------------------------------------------------------------------------


def test_version_prints_the_package_version_and_exits_zero(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert fatswarm(["--version"]) == 0
    assert capsys.readouterr().out == f"fatswarm {__version__}\n"


def test_a_usage_error_exits_two_without_raising(capsys: pytest.CaptureFixture[str]) -> None:
    assert fatswarm(["run", "-n", "many"]) == ExitCode.BAD_INPUT
    assert "invalid int value" in capsys.readouterr().err


# --- 2. output files -------------------------------------------------------------------------


@MODES
def test_an_existing_record_is_kept_unless_force(
    mode: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "run.jsonl"
    target.write_text("precious\n")
    code = fatswarm(["run", *mode, "-n", "3", "--seed", "1", "-q", "--record", str(target)])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, f"--record {target} exists; pass --force to overwrite it")
    assert target.read_text() == "precious\n"


def test_force_overwrites_an_existing_record(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "run.jsonl"
    target.write_text("old\n")
    argv = ["run", "--lockstep", "-n", "3", "--seed", "1", "-q", "--record", str(target)]
    assert fatswarm([*argv, "--force"]) == ExitCode.FORMED
    assert read_record(target).header.n == 3
    assert f"record: {target}" in capsys.readouterr().out


@MODES
@pytest.mark.parametrize(
    ("flag", "path", "message"),
    [
        ("--record", ".", "is a directory; name a file"),
        ("--record", "no/such/dir/run.jsonl", "does not exist; create it first"),
        ("--svg", ".", "is a directory; name a file"),
        ("--svg", "no/such/dir/final.svg", "does not exist; create it first"),
    ],
)
def test_an_output_that_cannot_be_written_is_refused_before_the_run(
    mode: list[str],
    flag: str,
    path: str,
    message: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    record = tmp_path / "also.jsonl"
    given = str(tmp_path / path)
    extra = [] if flag == "--record" else ["--record", str(record)]
    code = fatswarm(["run", *mode, "-n", "3", "--seed", "1", "-q", flag, given, *extra])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, message)
    assert not record.exists()  # nothing ran


def test_resume_and_force_together_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "run.jsonl"
    target.write_text("")
    code = fatswarm(
        ["run", "-n", "3", "--seed", "1", "--record", str(target), "--resume", "--force"]
    )
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, "pass one of them")


# --- 3. durations ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("flag", "value", "bound"),
    [
        ("--move-timeout", "inf", "> 0"),
        ("--move-timeout", "nan", "> 0"),
        ("--move-timeout", "0", "> 0"),
        ("--move-timeout", "-1", "> 0"),
        ("--pace", "inf", ">= 0"),
        ("--pace", "nan", ">= 0"),
        ("--pace", "-1", ">= 0"),
    ],
)
def test_a_duration_that_is_not_finite_and_in_range_is_refused(
    flag: str, value: str, bound: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert fatswarm(["run", "-n", "3", "--seed", "1", flag, value]) == ExitCode.BAD_INPUT
    one_line_refusal(capsys, f"{flag} must be a finite number of seconds {bound}")


# --- 4. flags a lockstep run refuses ---------------------------------------------------------


def networked_group_flags() -> list[list[str]]:
    """Each flag of the networked-run group with a value other than its default."""
    parser = argparse.ArgumentParser()
    run.add_arguments(parser)
    (group,) = [g for g in parser._action_groups if (g.title or "").startswith("networked run")]
    argvs = []
    for action in group._group_actions:
        flag = action.option_strings[-1]
        if action.nargs == 0:
            argvs.append([flag])
        elif action.choices is not None:
            argvs.append([flag, next(c for c in action.choices if c != action.default)])
        elif action.type is float:
            argvs.append([flag, "0.25"])
        else:
            argvs.append([flag, "tcp/127.0.0.1:7447"])
    return argvs


NETWORKED_FLAGS = networked_group_flags()


def test_every_networked_only_flag_is_known() -> None:
    names = {argv[0] for argv in NETWORKED_FLAGS}
    assert {"--connect", "--listen", "--swarm", "--move-timeout", "--pace", "--spawn"} <= names
    assert "--resume" not in names  # a lockstep run resumes too (test_cli_resume.py)


@pytest.mark.parametrize("flag", NETWORKED_FLAGS, ids=[argv[0] for argv in NETWORKED_FLAGS])
def test_lockstep_refuses_a_networked_only_flag_naming_it(
    flag: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    code = fatswarm(["run", "--lockstep", "-n", "3", "--seed", "1", "-q", *flag])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, f"{flag[0]} is for networked runs only")


def test_lockstep_names_every_networked_only_flag_given(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = fatswarm(["run", "--lockstep", "-n", "3", "--pace", "1", "--spawn", "exec"])
    assert code == ExitCode.BAD_INPUT
    one_line_refusal(capsys, "--pace, --spawn are for networked runs only: drop them")


def test_lockstep_accepts_networked_flags_left_at_their_defaults(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = fatswarm(
        [
            "run",
            "--lockstep",
            "-n",
            "3",
            "--seed",
            "1",
            "-q",
            "--spawn",
            "fork",
            "--move-timeout",
            "5",
        ]
    )
    assert code == ExitCode.FORMED
    assert capsys.readouterr().err == ""


# --- 5. --json -------------------------------------------------------------------------------


def test_json_prints_the_summary_as_one_object_and_progress_on_stderr(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(run_lockstep, "PROGRESS_SECONDS", 0.0)  # a progress line every round
    target = tmp_path / "run.jsonl"
    code = fatswarm(
        [
            "run",
            "--lockstep",
            "-n",
            "5",
            "--seed",
            "2",
            "--scheduler",
            "fsync",
            "--record",
            str(target),
            "--json",
        ]
    )
    captured = capsys.readouterr()
    (line,) = captured.out.splitlines()
    summary = json.loads(line)
    assert summary["exit_code"] == code == 0
    assert summary["status"] == "formed"
    assert (summary["n"], summary["a"], summary["seed"], summary["scheduler"]) == (
        5,
        4.0,
        2,
        "fsync",
    )
    assert summary["record"] == str(target)
    assert summary["svg"] is None
    assert summary["verdict"].startswith("formed in")
    for key in ("rounds", "epochs", "moves", "collisions", "total_distance"):
        assert isinstance(summary[key], int | float), key
    result = read_record(target).result
    assert result is not None and summary["rounds"] == result.rounds
    assert "round 1/" in captured.err


def test_json_of_a_run_without_result_says_unfinished() -> None:
    assert json.loads(summary.summary_json(None, 1)) == {
        "status": "unfinished",
        "exit_code": 1,
        "record": None,
        "svg": None,
    }


# --- 8. the estimate of a large lockstep run -------------------------------------------------


def test_a_large_lockstep_run_prints_an_estimate_before_it_starts(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = fatswarm(["run", "--lockstep", "-n", "200", "--seed", "1", "--max-rounds", "1"])
    assert code == ExitCode.NOT_FORMED
    err = capsys.readouterr().err
    assert "estimate for n=200 (a rough model, not a measurement): ~1 round," in err
    assert "a --record would take ~" in err


def test_a_small_lockstep_run_prints_no_estimate(capsys: pytest.CaptureFixture[str]) -> None:
    fatswarm(["run", "--lockstep", "-n", "5", "--seed", "1"])
    assert "estimate" not in capsys.readouterr().err


def test_the_estimate_grows_with_n_and_the_scheduler_and_stops_at_the_cap() -> None:
    fsync, ssync, central = (
        estimate.estimate_lockstep(100, s, 10**9) for s in ("fsync", "ssync", "centralized")
    )
    assert fsync.seconds < ssync.seconds < central.seconds
    assert estimate.estimate_lockstep(400, "ssync", 10**9).seconds > ssync.seconds
    capped = estimate.estimate_lockstep(100, "centralized", 50)
    assert capped.rounds == capped.cap_rounds == 50
    assert capped.record_bytes == capped.cap_record_bytes


def test_the_progress_line_shows_an_eta(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(run_lockstep, "PROGRESS_SECONDS", 0.0)
    fatswarm(["run", "--lockstep", "-n", "5", "--seed", "1", "--scheduler", "fsync"])
    lines = [x for x in capsys.readouterr().err.splitlines() if x.startswith("round ")]
    assert lines and all(" eta" in x and "(round cap)" in x for x in lines), lines


def test_eta_counts_to_the_expected_end_and_at_most_to_the_cap() -> None:
    assert estimate.eta_text(100, 10.0, 400, 4000) == "eta ~30 s, at most ~6.5 min (round cap)"
    assert estimate.eta_text(500, 10.0, 400, 4000) == (
        "eta: longer than estimated, at most ~5.8 min (round cap)"
    )


# --- 7. standard output closed early ---------------------------------------------------------


class ClosedPipe(io.StringIO):
    def write(self, s: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")


def test_a_closed_stdout_ends_quietly_with_141(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("sys.stdout", ClosedPipe())
    code = fatswarm(["run", "--lockstep", "-n", "3", "--seed", "1", "-q"])
    assert code == ExitCode.BROKEN_PIPE.value == 141
    assert capsys.readouterr().err == ""


def test_a_watched_run_paces_itself_to_about_fifteen_seconds() -> None:
    from fatswarm.deploy.net.run_flags import (
        MAX_WATCH_PACE_S,
        MIN_WATCH_PACE_S,
        WATCH_S,
        watchable_pace,
    )

    assert watchable_pace(8, "ssync") == pytest.approx(WATCH_S / (2 * 10))  # ~2 rounds a step
    assert watchable_pace(20, "fsync") == pytest.approx(WATCH_S / 22)
    assert watchable_pace(2000, "centralized") == MIN_WATCH_PACE_S
    assert watchable_pace(1, "fsync") == MAX_WATCH_PACE_S
    assert watchable_pace(8, "async") == pytest.approx(WATCH_S / (3 * 8 * 10))  # ~3n cycles a step


@pytest.mark.parametrize(
    ("tty", "flags", "paced"),
    [
        (True, [], True),
        (False, [], False),
        (True, ["--no-dashboard"], False),
        (True, ["--json"], False),
        (True, ["--pace", "0"], False),
    ],
)
def test_the_default_pace_is_watchable_only_with_the_live_dashboard(
    monkeypatch: pytest.MonkeyPatch, tty: bool, flags: list[str], paced: bool
) -> None:
    import sys

    from fatswarm.deploy import cli
    from fatswarm.deploy.net import launcher

    seen: list[float] = []

    def launch(args: Any, setup: object, record: str, pace: float, swarm: str) -> int:
        seen.append(pace)
        return 1

    monkeypatch.setattr(launcher, "_launch", launch)
    monkeypatch.setattr(launcher, "check_network", lambda *a: None)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: tty)
    cli.main(["run", "-n", "4", "--seed", "1", *flags])
    assert len(seen) == 1 and (seen[0] > 0) == paced


@pytest.mark.parametrize("argv", [["run", "--bogus"], ["run", "-n", "x"], ["nope"], ["world"]])
def test_a_usage_error_is_one_line_pointing_at_help(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fatswarm") and err[0].endswith("--help)"), err
