"""`fatswarm run`'s robot-model flags: refusals in one line, the summary naming the model, and a
resumed model run that refuses a flag contradicting its record."""

from __future__ import annotations

from pathlib import Path

import pytest

from fatswarm.deploy import cli

LIT = str(Path(__file__).resolve().parents[1] / "data" / "lit_spread.py") + ":ALGORITHM"


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--sight", "0"], "--sight: takes distances > 0 (robot radii) or unlimited, got '0'"),
        (["--lights", "internal"], "--lights internal needs an algorithm with lights"),
        (["--visibility", "foggy"], "invalid choice: 'foggy'"),
    ],
)
def test_a_bad_model_flag_is_refused_in_one_line_with_exit_2(
    flags: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(["run", "--lockstep", "-n", "4", "--seed", "1", *flags]) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err


def test_the_summary_names_a_model_and_the_frames_assumption_once(
    capsys: pytest.CaptureFixture[str],
) -> None:
    cli.main(["run", "--lockstep", "-n", "5", "--seed", "1", "--frames", "chirality", "-q"])
    out = capsys.readouterr().out
    assert out.count("model: --frames chirality") == 1
    assert out.count("assumes frames y-axis; this run gives it chirality") == 1
    cli.main(["run", "--lockstep", "-n", "5", "--seed", "1", "--scheduler", "fsync", "-q"])
    assert "model:" not in capsys.readouterr().out


def test_a_luminous_run_resumes_as_its_own_run_and_refuses_a_contradicting_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    full, cut = tmp_path / "full.jsonl", tmp_path / "cut.jsonl"
    flags = ["-n", "6", "--seed", "3", "--algorithm", LIT, "--scheduler", "ssync", "-q"]
    flags += ["--frames", "chirality", "--record-views", "--max-rounds", "60"]
    cli.main(["run", "--lockstep", *flags, "--record", str(full)])
    lines = full.read_text().splitlines(keepends=True)
    assert len(lines) > 8
    cut.write_text("".join(lines[:6]))
    assert cli.main(["run", "--lockstep", "--record", str(cut), "--resume", "-q"]) in (0, 1)
    assert cut.read_bytes() == full.read_bytes()
    cut.write_text("".join(lines[:6]))
    capsys.readouterr()
    code = cli.main(["run", "--lockstep", "--record", str(cut), "--resume", "--frames", "y-axis"])
    assert code == 2
    assert "--frames y-axis contradicts" in capsys.readouterr().err
