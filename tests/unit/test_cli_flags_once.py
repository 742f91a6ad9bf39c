"""The flags of run, sweep and hunt as a user gives them: a flag of one value given twice with two
values is refused in one line naming it; `--sight unlimited` is one value to all three (read by the
axis); a list with an empty item is refused, not run as the default; `run --help` says each model
flag's default; `--resume` names a contradicting model value as its flag takes it."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.engine.config import model_from_args
from fatswarm.deploy.flags import given_flags
from fatswarm.deploy.sweep.grid import robot_models_of
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.robot_model import AXES, RobotModel

pytestmark = pytest.mark.usefixtures("no_launch")  # tests/unit/conftest.py


def parse(*argv: str) -> argparse.Namespace:
    return cli.build_parser().parse_args(list(argv))


def refused(capsys: pytest.CaptureFixture[str], argv: list[str], *words: str) -> None:
    assert cli.main(argv) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err


@pytest.mark.parametrize(
    ("command", "flags", "says"),
    [
        ("run", ["--visibility", "opaque", "--visibility", "transparent"],
         "argument --visibility: given twice (--visibility opaque, then --visibility transparent)"),
        ("run", ["--sight", "5", "--sight", "unlimited"],
         "argument --sight: given twice (--sight 5, then --sight unlimited)"),
        ("run", ["--seed", "1", "--seed", "2"], "argument --seed: given twice"),
        ("run", ["--scheduler", "fsync", "--scheduler", "async"], "argument --scheduler: given"),
        ("sweep", ["--out", "a.csv", "--out", "b.csv"], "argument --out: given twice"),
        ("hunt", ["--seed", "1", "--seed", "2"], "argument --seed: given twice"),
    ],
)  # fmt: skip
def test_a_flag_of_one_value_given_twice_with_two_is_refused_naming_it(
    command: str, flags: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    refused(capsys, [command, *flags], says, "give it once")


def test_a_flag_given_twice_with_the_same_value_is_taken() -> None:
    args = parse("run", "--lockstep", "--visibility", "opaque", "--visibility", "opaque")
    assert model_from_args(args) == RobotModel.of(visibility="opaque")
    assert parse("run", "--seed", "4", "--seed", "4").seed == 4


def test_list_flags_still_gather_when_repeated() -> None:
    args = parse("sweep", "--out", "a.csv", "--sight", "4", "--sight", "unlimited,8")
    assert [m.sight for m in robot_models_of(args)] == [4.0, None, 8.0]


@pytest.mark.parametrize("text", ["unlimited", "UNLIMITED", "6", "6.5"])
def test_run_sweep_and_hunt_read_sight_alike(text: str) -> None:
    run = model_from_args(parse("run", "--sight", text))
    (swept,) = robot_models_of(parse("sweep", "--out", "a.csv", "--sight", text))
    (hunted,) = robot_models_of(parse("hunt", "--sight", text))
    assert run == swept == hunted
    assert run.sight == (None if text.lower() == "unlimited" else float(text))


def test_run_sight_unlimited_is_a_flag_given_for_resume() -> None:
    assert given_flags(parse("run", "--sight", "unlimited"))["sight"] is None
    assert "sight" not in given_flags(parse("run"))


@pytest.mark.parametrize("command", ["sweep", "hunt"])
@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--frames", ""], "argument --frames: an empty list"),
        (["--frames", "y-axis,,"], "argument --frames: an empty item in 'y-axis,,'"),
        (["--sight", ",4"], "argument --sight: an empty item in ',4'"),
        (["-n", "4,,8"], "argument -n/--n: an empty item in '4,,8'"),
        (["--scheduler", "fsync,"], "argument --scheduler: an empty item in 'fsync,'"),
    ],
)
def test_an_empty_list_item_is_refused_not_run_as_the_default(
    command: str, flags: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = ["--out", "never.csv"] if command == "sweep" else ["--out", "never"]
    refused(capsys, [command, *out, *flags], says)


def test_run_help_says_every_model_flags_default(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["run", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    group = text[text.index("robot model (docs/model.md") :]
    for axis in AXES:
        section = group[group.index(f"{axis.flag} ") :]
        said = section[: section.index(" --", len(axis.flag))]
        assert "default" in said, (axis.flag, said)
        assert axis.label(axis.default) in said.split("default", 1)[1], (axis.flag, said)


def test_resume_names_a_contradicting_sight_as_its_flag_takes_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def record(name: str, *flags: str) -> Path:
        whole = tmp_path / name
        argv = ["run", "--lockstep", "-n", "6", "--seed", "2", "-q", "--record", str(whole)]
        cli.main([*argv, *flags])
        lines = whole.read_text().splitlines(keepends=True)
        whole.write_text("".join(lines[:3]))  # cut after two rounds: it can be resumed
        return whole

    plain, near = record("plain.jsonl"), record("near.jsonl", "--sight", "30")
    capsys.readouterr()
    base = ["run", "--lockstep", "--resume", "-q", "--record"]
    refused(capsys, [*base, str(plain), "--sight", "5"], "--sight 5.0 contradicts",
            "whose run has sight=unlimited")  # fmt: skip
    refused(capsys, [*base, str(near), "--sight", "unlimited"], "--sight unlimited contradicts",
            "whose run has sight=30.0")  # fmt: skip
    assert "None" not in capsys.readouterr().err
