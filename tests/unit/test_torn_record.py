"""A record whose last line is torn (a crash mid-write): replay and plot show it, with a note."""

from __future__ import annotations

import argparse
import pathlib
from types import ModuleType

import pytest

from fatswarm.deploy.view import plot, replay
from fatswarm.world.record import RecordFormatError
from fatswarm.world.record_read import iter_record, read_record

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
LOCKSTEP = DATA / "lockstep-n6-seed1.jsonl"  # header, 17 rounds, result


def torn_copy(tmp_path: pathlib.Path, source: pathlib.Path = LOCKSTEP) -> pathlib.Path:
    """`source` with its last line cut in half (no newline): what a crash mid-write leaves."""
    lines = source.read_bytes().splitlines(keepends=True)
    target = tmp_path / "torn.jsonl"
    target.write_bytes(b"".join(lines[:-1]) + lines[-1][: len(lines[-1]) // 2])
    return target


def run_command(module: ModuleType, *argv: object) -> int:
    p = argparse.ArgumentParser()
    module.add_arguments(p)
    code: int = module.main(p.parse_args([str(a) for a in argv]))
    return code


def test_a_torn_last_line_is_still_refused_by_default_with_its_line(
    tmp_path: pathlib.Path,
) -> None:
    torn = torn_copy(tmp_path)
    with pytest.raises(RecordFormatError, match=rf"^{torn}:19: not JSON"):
        read_record(torn)


def test_a_torn_last_line_is_left_out_when_allowed_and_its_line_kept(
    tmp_path: pathlib.Path,
) -> None:
    whole = read_record(LOCKSTEP)
    record = read_record(torn_copy(tmp_path), allow_torn_end=True)
    assert record.torn_line == 19
    assert record.result is None and whole.result is not None
    assert [r.round for r in record.rounds] == [r.round for r in whole.rounds]
    assert whole.torn_line is None
    assert len(list(iter_record(torn_copy(tmp_path), allow_torn_end=True))) == 1 + 17


def test_a_complete_last_line_without_its_newline_is_not_torn(tmp_path: pathlib.Path) -> None:
    target = tmp_path / "no-newline.jsonl"
    target.write_bytes(LOCKSTEP.read_bytes().rstrip(b"\n"))
    record = read_record(target, allow_torn_end=True)
    assert record.torn_line is None and record.result is not None


def test_garbage_before_the_last_line_is_an_error_even_when_a_torn_end_is_allowed(
    tmp_path: pathlib.Path,
) -> None:
    lines = LOCKSTEP.read_bytes().splitlines(keepends=True)
    lines[5] = lines[5][:40] + b"\n"  # torn in the middle: not a crash at the end
    target = tmp_path / "garbage.jsonl"
    target.write_bytes(b"".join(lines))
    with pytest.raises(RecordFormatError, match=rf"^{target}:6: not JSON"):
        read_record(target, allow_torn_end=True)
    invalid = tmp_path / "invalid-last.jsonl"  # JSON, but not a record line: never torn
    invalid.write_bytes(b"".join(lines[:5]) + b'{"type": "noise"}')
    with pytest.raises(RecordFormatError, match=rf"^{invalid}:6: unknown line type"):
        read_record(invalid, allow_torn_end=True)


def test_a_torn_header_is_an_error_even_when_a_torn_end_is_allowed(
    tmp_path: pathlib.Path,
) -> None:
    target = tmp_path / "header.jsonl"
    target.write_bytes(LOCKSTEP.read_bytes()[:30])
    with pytest.raises(RecordFormatError, match=rf"^{target}:1: the header is torn"):
        read_record(target, allow_torn_end=True)


def test_replay_shows_the_complete_rounds_of_a_torn_record_and_says_so(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    torn = torn_copy(tmp_path)
    assert run_command(replay, torn, "--no-play") == 0
    captured = capsys.readouterr()
    assert captured.err == (
        f"fatswarm replay: note: {torn} ends with a torn line (line 19, a crash mid-write); "
        "showing the 17 complete rounds\n"
    )
    assert "round 17" in captured.out


def test_plot_draws_the_complete_rounds_of_a_torn_record_and_says_so(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("matplotlib")
    torn = torn_copy(tmp_path)
    out = tmp_path / "torn.svg"
    assert run_command(plot, torn, out) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"fatswarm plot: note: {torn} ends with a torn line")
    assert err.endswith("showing the 17 complete rounds\n") and err.count("\n") == 1
    assert "after 17 rounds" in out.read_text()


def test_replay_says_nothing_about_a_whole_record(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_command(replay, LOCKSTEP, "--no-play") == 0
    assert capsys.readouterr().err == ""
