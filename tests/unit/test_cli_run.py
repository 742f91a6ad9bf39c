"""`fatswarm run --lockstep`: summary, exit codes, record, one-line errors for bad input."""

from __future__ import annotations

import argparse
import functools
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

from fatswarm.agent.params import Params
from fatswarm.deploy.commands import run
from fatswarm.deploy.engine import lockstep
from fatswarm.deploy.view import summary
from fatswarm.domain.outcome import ExitCode, Status, exit_code_for
from fatswarm.domain.path import STAY, Line, Points
from fatswarm.domain.path import Path as RobotPath
from fatswarm.world.record_read import read_record

NOT_COLLISION_FREE = "not the collision-free formation the paper guarantees"


def fatswarm_run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="fatswarm run")
    run.add_arguments(parser)
    return run.main(parser.parse_args(argv))


def test_formed_run_exits_zero_and_prints_the_summary(capsys: pytest.CaptureFixture[str]) -> None:
    code = fatswarm_run(["--lockstep", "-n", "5", "--seed", "2", "--scheduler", "fsync", "-q"])
    verdict, setup, figures = capsys.readouterr().out.splitlines()[:3]
    assert code == 0
    assert re.fullmatch(r"formed in \d+ rounds, collision-free", verdict)
    assert setup == "n=5 a=4 seed=2 scheduler=fsync model=paper"
    for word in ("rounds", "epochs", "moves", "total distance", "collisions 0"):
        assert word in figures


def test_record_is_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "run.jsonl"
    code = fatswarm_run(["--lockstep", "-n", "4", "--seed", "1", "--record", str(target), "-q"])
    record = read_record(target)
    assert record.result is not None
    assert code == exit_code_for(record.result.status, record.result.collisions or 0)
    assert (record.header.n, record.header.seed, record.header.scheduler) == (4, 1, "ssync")
    assert f"record: {target}" in capsys.readouterr().out


def test_run_not_formed_exits_one(capsys: pytest.CaptureFixture[str]) -> None:
    code = fatswarm_run(["--lockstep", "-n", "6", "--seed", "0", "--max-rounds", "1", "-q"])
    assert code == 1
    assert capsys.readouterr().out.startswith("not formed: stopped at the round limit (1 round)")


def test_init_file_gives_n_and_a(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    init = tmp_path / "init.json"
    init.write_text(json.dumps({"positions": [[0, 0], [2, 0], [0, 3]], "a": 5}))
    code = fatswarm_run(["--lockstep", "--init", str(init), "--seed", "0", "-q"])
    assert code in (0, 1)
    assert "n=3 a=5 seed=0" in capsys.readouterr().out


def test_unseeded_run_prints_its_seed(capsys: pytest.CaptureFixture[str]) -> None:
    fatswarm_run(["--lockstep", "-n", "3", "--max-rounds", "1"])
    assert "pass --seed" in capsys.readouterr().err


def test_scripted_schedule_is_followed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    schedule = tmp_path / "s.json"
    schedule.write_text(json.dumps({"rounds": [[1], [0, 2]]}))
    target = tmp_path / "run.jsonl"
    argv = [
        "--lockstep",
        "-n",
        "3",
        "--seed",
        "4",
        "--scheduler",
        "scripted",
        "--schedule",
        str(schedule),
        "--max-rounds",
        "3",
        "--record",
        str(target),
        "-q",
    ]
    fatswarm_run(argv)
    actives = [r.active for r in read_record(target).rounds]
    assert actives == [(1,), (0, 2), (1,)][: len(actives)]


def bad_inputs(tmp_path: Path) -> list[tuple[list[str], str]]:
    overlap = tmp_path / "overlap.json"
    overlap.write_text(json.dumps({"positions": [[0, 0], [1, 0]]}))
    bad_schedule = tmp_path / "bad.json"
    bad_schedule.write_text("{")
    return [
        (["-a", "3"], "a must be > 3"),
        (["-n", "0"], "n must be a whole number >= 1"),
        (["--init", str(tmp_path / "absent.json")], "cannot read init file"),
        (["--init", str(overlap)], "robots 0 and 1 overlap"),
        (["--init", str(overlap), "-n", "5"], "robots 0 and 1 overlap"),
        (["--scheduler", "scripted"], "needs a schedule file"),
        (["--scheduler", "scripted", "--schedule", str(bad_schedule)], "not JSON"),
        (["--schedule", str(bad_schedule)], "only goes with --scheduler scripted"),
        (["--max-rounds", "0"], "--max-rounds must be at least 1"),
        (["--fairness", "0"], "fairness bound"),
        (["--record", str(tmp_path / "no" / "dir" / "run.jsonl")], "does not exist; create it"),
        (["--record", str(tmp_path)], "is a directory; name a file"),
        (["--svg", str(tmp_path / "no" / "final.svg")], "does not exist; create it"),
    ]


def test_bad_input_exits_two_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for flags, message in bad_inputs(tmp_path):
        code = fatswarm_run(["--lockstep", "--seed", "0", "-q", *flags])
        err = capsys.readouterr().err
        assert code == 2, flags
        assert message in err and err.count("\n") == 1 and err.startswith("fatswarm run: "), err


def test_n_disagreeing_with_init_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    init = tmp_path / "init.json"
    init.write_text(json.dumps({"positions": [[0, 0], [3, 0]]}))
    assert fatswarm_run(["--lockstep", "--init", str(init), "-n", "3"]) == 2
    assert "disagrees with the 2 robots" in capsys.readouterr().err


def test_svg_of_the_final_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("fatswarm.deploy.view.dashboard")
    target = tmp_path / "final.svg"
    assert fatswarm_run(["--lockstep", "-n", "4", "--seed", "3", "-q", "--svg", str(target)]) == 0
    assert target.read_text().lstrip().startswith("<svg")


# --- collisions: formed through contact is not the paper's collision-free formation -------------


def outcome(status: str, collisions: int, rounds: int = 31) -> summary.Outcome:
    return summary.Outcome(
        status=Status(status),
        rounds=rounds,
        collisions=collisions,
        n=4,
        a=4.0,
        seed=1,
        scheduler="ssync",
        epochs=9,
        moves=12,
        total_distance=30.0,
    )


@pytest.mark.parametrize(
    ("status", "collisions", "code", "verdict"),
    [
        ("formed", 0, 0, "formed in 31 rounds, collision-free"),
        ("formed", 1, 3, f"formed in 31 rounds, but with 1 collision: {NOT_COLLISION_FREE}"),
        ("formed", 2, 3, f"formed in 31 rounds, but with 2 collisions: {NOT_COLLISION_FREE}"),
        ("stalled", 0, 1, "not formed: stalled after 31 rounds"),
        ("stalled", 2, 1, "not formed: stalled after 31 rounds, with 2 collisions"),
        (
            "max_rounds",
            5,
            1,
            "not formed: stopped at the round limit (31 rounds), with 5 collisions",
        ),
    ],
)
def test_exit_code_and_verdict_say_whether_robots_collided(
    status: str, collisions: int, code: int, verdict: str
) -> None:
    o = outcome(status, collisions)
    assert summary.exit_code(o) == code
    assert summary.verdict(o) == verdict
    assert summary.summary(o).splitlines()[0] == verdict
    assert re.search(
        rf"\bcollisions {collisions}\b", "\n".join(summary.summary(o).splitlines()[2:])
    )


def test_exit_codes_are_listed_in_the_help() -> None:
    parser = argparse.ArgumentParser(prog="fatswarm run")
    run.add_arguments(parser)
    text = " ".join(parser.format_help().split())
    for listed in (
        "0 formed with no collision",
        "1 not formed",
        "2 bad input",
        "3 formed, but with collisions",
        "130 interrupted (Ctrl-C)",
        "141 standard output closed early",
        "143 terminated (SIGTERM)",
    ):
        assert listed in text


def test_exit_codes_are_one_enum_whose_old_names_still_import() -> None:
    assert [int(c) for c in ExitCode] == [0, 1, 2, 3, 4, 5, 130, 141, 143]
    assert str(int(ExitCode.RECORD_FAILED)) in run.EXIT_CODES_HELP
    assert (
        ExitCode.FORMED,
        ExitCode.NOT_FORMED,
        ExitCode.BAD_INPUT,
        ExitCode.FORMED_WITH_COLLISIONS,
        ExitCode.INTERRUPTED,
    ) == (0, 1, 2, 3, 130)
    assert ExitCode.TERMINATED is ExitCode.TERMINATED


def bump(view: Points, params: Params) -> RobotPath:
    """Two robots: rush at the other when far (contact stops both), back off to side a when near."""
    ((x, y),) = view
    distance = float(np.hypot(x, y))
    if distance > 6.0:
        return RobotPath((Line((x, y)),))
    if distance < params.a:
        k = (params.a - distance) / (2.0 * distance)
        return RobotPath((Line((-k * x, -k * y)),))
    return STAY


def test_a_formation_reached_through_collisions_exits_three_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    init = tmp_path / "far-apart.json"
    init.write_text(json.dumps({"positions": [[0, 0], [8, 0]], "a": 4}))
    monkeypatch.setattr(
        lockstep, "run_lockstep", functools.partial(lockstep.run_lockstep, compute=bump)
    )
    target = tmp_path / "run.jsonl"
    code = fatswarm_run(
        [
            "--lockstep",
            "--init",
            str(init),
            "--seed",
            "0",
            "--scheduler",
            "fsync",
            "--record",
            str(target),
            "-q",
        ]
    )
    out = capsys.readouterr().out
    assert code == ExitCode.FORMED_WITH_COLLISIONS.value == 3
    assert re.match(rf"formed in \d+ rounds, but with 2 collisions: {NOT_COLLISION_FREE}\n", out)
    assert "collisions 2" in out

    # the networked run reads its summary and exit code back from the same kind of record
    from fatswarm.deploy.net.launcher import print_summary

    printed = io.StringIO()
    read_back = print_summary(str(target), printed)
    assert read_back is not None and summary.exit_code(read_back) == 3
    assert printed.getvalue() == out.split("record: ")[0]


# --- the supported range (fatswarm/domain/tolerance.py) -------------------------------------------


def unsupported_inputs(tmp_path: Path) -> list[tuple[list[str], str]]:
    far = tmp_path / "far.json"
    far.write_text(json.dumps({"positions": [[0, 0], [1e7, 0]]}))
    wide = tmp_path / "wide.json"
    wide.write_text(json.dumps({"positions": [[0, 0], [1e5, 0]]}))
    side = "a must be at most 20000 for n = 2: the target circle must have radius <= 10000"
    return [
        (["-n", "2", "-a", "1e308"], side),
        (["-n", "2", "-a", "1e10"], side),
        (["-a", "1e10"], "the target circle must have radius <= 10000"),
        (["--init", str(far)], "coordinates must lie within +-2000000"),
        (["--init", str(wide)], "the start must fit in a circle of radius 10000"),
    ]


@pytest.mark.parametrize("mode", [["--lockstep"], []], ids=["lockstep", "networked"])
def test_input_outside_the_supported_range_exits_two_with_one_line(
    mode: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for flags, message in unsupported_inputs(tmp_path):
        code = fatswarm_run([*mode, "--seed", "0", "-q", *flags])  # networked: refused up front
        captured = capsys.readouterr()
        assert code == 2, flags
        assert captured.out == ""
        err = captured.err
        assert message in err and err.count("\n") == 1 and err.startswith("fatswarm run: "), err


def test_the_largest_side_inside_the_supported_range_still_runs(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = fatswarm_run(["--lockstep", "-n", "2", "-a", "1e4", "--seed", "1", "-q"])
    captured = capsys.readouterr()
    assert code == 0, captured.out
    assert captured.err == ""
    assert "n=2 a=10000 seed=1" in captured.out
