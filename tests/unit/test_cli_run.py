"""`fatswarm run --lockstep`: summary, exit codes, record, one-line errors for bad input."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pytest

from deploy import run
from world.record import read_record


def fatswarm_run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="fatswarm run")
    run.add_arguments(parser)
    return run.main(parser.parse_args(argv))


def test_formed_run_exits_zero_and_prints_the_summary(capsys: pytest.CaptureFixture[str]) -> None:
    code = fatswarm_run(["--lockstep", "-n", "5", "--seed", "2", "--scheduler", "fsync", "-q"])
    out = capsys.readouterr().out
    assert code == 0
    assert out.startswith("formed: n=5 a=4 seed=2 scheduler=fsync")
    for word in ("rounds", "epochs", "moves", "total distance", "collisions 0"):
        assert word in out


def test_record_is_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "run.jsonl"
    code = fatswarm_run(["--lockstep", "-n", "4", "--seed", "1", "--record", str(target), "-q"])
    record = read_record(target)
    assert record.result is not None
    assert code == (0 if record.result.status == "formed" else 1)
    assert (record.header.n, record.header.seed, record.header.scheduler) == (4, 1, "ssync")
    assert f"record: {target}" in capsys.readouterr().out


def test_run_not_formed_exits_one(capsys: pytest.CaptureFixture[str]) -> None:
    code = fatswarm_run(["--lockstep", "-n", "6", "--seed", "0", "--max-rounds", "1", "-q"])
    assert code == 1
    assert capsys.readouterr().out.startswith("max_rounds:")


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
    argv = ["--lockstep", "-n", "3", "--seed", "4", "--scheduler", "scripted", "--schedule",
            str(schedule), "--max-rounds", "3", "--record", str(target), "-q"]
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
        (["--record", str(tmp_path / "no" / "dir" / "run.jsonl")], "cannot write run record"),
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


def test_networked_mode_without_launcher_exits_two(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "deploy.launcher", None)
    assert fatswarm_run(["-n", "3"]) == 2
    assert "use --lockstep" in capsys.readouterr().err


def test_svg_of_the_final_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("deploy.dashboard")
    target = tmp_path / "final.svg"
    assert fatswarm_run(["--lockstep", "-n", "4", "--seed", "3", "-q", "--svg", str(target)]) == 0
    assert target.read_text().lstrip().startswith("<svg")
