"""Replay of the fixed record tests/data/replay-small.jsonl: frames, player keys, command line."""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import re

import pytest

from fatswarm.deploy.view.replay import (
    FrameFigures,
    Player,
    add_arguments,
    build_frames,
    figures_of,
    main,
    parse_keys,
)
from fatswarm.world.record_read import read_record

RECORD = pathlib.Path(__file__).resolve().parents[1] / "data" / "replay-small.jsonl"


def run_replay(*argv: object) -> int:
    p = argparse.ArgumentParser()
    add_arguments(p)
    return main(p.parse_args([str(a) for a in argv]))


def test_one_frame_per_round_starting_from_the_initial_positions() -> None:
    record = read_record(RECORD)
    frames = build_frames(record)
    assert [f.round for f in frames] == [0, 1, 2, 3]
    assert frames[0].positions.tolist() == record.header.initial.tolist()
    assert frames[3].positions.tolist() == record.rounds[2].positions.tolist()
    assert [f.status for f in frames] == ["running", "running", "running", "max_rounds"]


def test_frames_carry_who_was_active_moved_and_stopped_and_the_collision_count() -> None:
    frames = build_frames(read_record(RECORD))
    f2 = frames[2]  # robot 2 turns about the origin and is stopped by robot 3
    assert f2.active == (2,) and f2.moved == (2,) and f2.stopped == (2,)
    assert [f.collisions_total for f in frames] == [0, 0, 1, 1]
    assert f2.last_active == (1, 1, 2, -1)
    assert f2.last_path_length[2] == pytest.approx(3.70046653609408)
    assert frames[3].last_active == (3, 3, 3, 3)


def test_trails_follow_the_arc_covered_until_contact() -> None:
    trail = build_frames(read_record(RECORD))[2].trails[0]
    radii = [math.hypot(x, y) for x, y in trail]
    assert radii == pytest.approx([3.0] * len(radii))
    assert trail[-1].tolist() == pytest.approx([-2.8309475019306793, 0.9928425057945736])


def test_replay_prints_the_requested_round(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_replay(RECORD, "--round", "2", "--no-play") == 0
    out = capsys.readouterr().out
    assert re.search(r"round\s+2 / 3", out)
    assert re.search(r"collisions\s+1\b", out)
    assert re.search(r"1 active\s+1 moved\s+1 stopped", out)


def test_replay_without_a_round_shows_the_outcome(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_replay(RECORD, "--no-play") == 0
    assert "NOT FORMED: stopped at the round limit (3 rounds)" in capsys.readouterr().out


def test_replay_saves_the_frame_as_svg(tmp_path: pathlib.Path) -> None:
    out = tmp_path / "last.svg"
    assert run_replay(RECORD, "--no-play", "--svg", out) == 0
    assert out.read_text().startswith("<svg")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--round", "9"], "--round must be between 0 and 3, got 9"),
        (["--speed", "0"], "--speed must be a positive number"),
    ],
)
def test_bad_flags_exit_2_with_one_line(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_replay(RECORD, "--no-play", *argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_unreadable_record_exits_2(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_replay(tmp_path / "missing.jsonl", "--no-play") == 2
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type": "round"}\n')
    assert run_replay(bad, "--no-play") == 2
    err = capsys.readouterr().err
    assert "missing.jsonl" in err and "bad.jsonl:1" in err


def test_a_header_with_an_unreadable_model_is_refused_in_one_line(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = pathlib.Path(RECORD).read_text().splitlines()
    header = json.loads(lines[0])
    header["model"] = {"visibility": "foggy"}
    bad = tmp_path / "foggy.jsonl"
    bad.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    assert run_replay(bad, "--no-play") == 2
    err = capsys.readouterr().err
    assert "foggy.jsonl:1: unreadable robot 'model'" in err and err.count("\n") == 1


def test_player_steps_pauses_and_clamps_to_the_record() -> None:
    p = Player(count=4)
    p.key("right")
    assert (p.index, p.playing) == (1, False)
    p.key("left")
    p.key("left")
    assert p.index == 0
    p.key("G")
    p.key(".")
    assert p.index == 3
    p.key("g")
    assert p.index == 0
    p.key("q")
    assert p.quit


def test_player_plays_at_its_speed_and_stops_at_the_end() -> None:
    p = Player(count=100, speed=10.0)
    p.tick(0.25)
    p.tick(0.25)
    assert p.index == 5
    p.key(" ")
    p.tick(5.0)
    assert p.index == 5  # paused
    p.key("+")
    assert p.speed == 20.0
    p.key(" ")
    p.tick(100.0)
    assert (p.index, p.playing) == (99, False)
    p.key(" ")  # play again from the start
    assert (p.index, p.playing) == (0, True)
    p.key("-")
    p.key("-")
    assert p.speed == 5.0


def test_terminal_input_is_split_into_named_keys() -> None:
    assert parse_keys("\x1b[C\x1b[D \x1b[A+q\x1b") == ["right", "left", " ", "up", "+", "q", "esc"]


# A real run: `fatswarm run --lockstep -n 6 --seed 1 --scheduler ssync --record ...`.
LOCKSTEP = RECORD.parent / "lockstep-n6-seed1.jsonl"


def test_real_lockstep_record_replays_to_a_formed_circle(
    capsys: pytest.CaptureFixture[str],
) -> None:
    record = read_record(LOCKSTEP)
    frames = build_frames(record)
    assert len(frames) == len(record.rounds) + 1 == 18
    assert frames[-1].status == "formed" and frames[-1].collisions_total == 0
    assert run_replay(LOCKSTEP, "--no-play") == 0
    out = capsys.readouterr().out
    assert "FORMED: uniform-circle goal reached by 6 robots after 17 rounds, 0 collisions" in out
    assert re.search(r"targets\s+6 / 6 filled", out)
    assert run_replay(LOCKSTEP, "--no-play", "--round", "0") == 0
    assert re.search(r"round\s+0 / 17", capsys.readouterr().out)


def with_header(tmp_path: pathlib.Path, **fields: object) -> pathlib.Path:
    """A copy of the lock-step record whose header says `fields` (e.g. another algorithm)."""
    lines = LOCKSTEP.read_text().splitlines()
    header = {**json.loads(lines[0]), **fields}
    header.pop("a", None)
    out = tmp_path / "changed.jsonl"
    out.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    return out


def test_frames_carry_the_records_algorithm_and_parameters() -> None:
    frame = build_frames(read_record(LOCKSTEP))[0]
    assert (frame.algorithm, frame.params, frame.figures) == ("uniform-circle", {"a": 4.0}, {})


def test_replay_computes_the_figures_of_the_records_algorithm(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = with_header(
        tmp_path, algorithm="gathering", algorithm_ref="gathering", params={"tolerance": 0.25}
    )
    assert run_replay(record, "--no-play", "--round", "3") == 0
    captured = capsys.readouterr()
    assert re.search(r"robots\s+n=6  gathering tolerance=0\.25", captured.out)
    assert re.search(r"spread\s+\d+\.\d{3}", captured.out)
    assert "targets" not in captured.out and captured.err == ""


def test_replay_of_an_algorithm_not_loadable_here_plays_without_figures_and_says_so_once(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    ref = str(tmp_path / "gone.py") + ":ALGORITHM"  # someone's file, not on this machine
    record = with_header(tmp_path, algorithm="mine", algorithm_ref=ref, params={"k": 2})
    assert run_replay(record, "--no-play", "--round", "3") == 0
    captured = capsys.readouterr()
    assert re.search(r"round\s+3 / 17", captured.out)
    assert re.search(r"robots\s+n=6  mine k=2", captured.out)
    assert "targets" not in captured.out
    assert captured.err.count("\n") == 1 and "without the figures" in captured.err
    assert ref in captured.err and "no file" in captured.err
    warned: list[str] = []
    shown_as = FrameFigures(figures_of(read_record(record).header, warned.append), warned.append)
    frames = build_frames(read_record(record))
    assert [shown_as(f) for f in frames] and all(f.figures == {} for f in map(shown_as, frames))
    assert len(warned) == 1


def test_replay_survives_a_figures_hook_that_raises_and_says_so_once(
    tmp_path: pathlib.Path,
) -> None:
    module = tmp_path / "broken.py"
    module.write_text(
        "from fatswarm.agent.gathering import Gathering\n"
        "class Broken(Gathering):\n"
        "    name = 'broken'\n"
        "    def figures(self, positions, params):\n"
        "        raise RuntimeError('no figures\\ntoday')\n"
        "ALGORITHM = Broken()\n"
    )
    record = read_record(
        with_header(tmp_path, algorithm="broken", algorithm_ref=f"{module}:ALGORITHM", params={})
    )
    warned: list[str] = []
    shown_as = FrameFigures(figures_of(record.header, warned.append), warned.append)
    shown = [shown_as(f) for f in build_frames(record)]
    assert all(f.figures == {} for f in shown)
    assert len(warned) == 1 and warned[0].startswith(
        "replaying without figures: the figures of algorithm broken raised RuntimeError: no "
        "figures today (at broken.py:"
    )


def test_figures_are_computed_once_per_round_shown() -> None:
    calls: list[int] = []

    def count(positions: object) -> dict[str, float]:
        calls.append(1)
        return {"calls": float(len(calls))}

    frames = build_frames(read_record(RECORD))
    shown_as = FrameFigures(count, lambda line: None)
    assert shown_as(frames[2]).figures == shown_as(frames[2]).figures == {"calls": 1.0}
    assert shown_as(frames[3]).figures == {"calls": 2.0} and len(calls) == 2


def test_a_record_without_a_result_line_says_it_is_unfinished_not_running(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cut = tmp_path / "cut.jsonl"
    cut.write_text("".join(RECORD.read_text().splitlines(keepends=True)[:3]))  # header, 2 rounds
    frames = build_frames(read_record(cut))
    assert frames[-1].unfinished and not any(f.unfinished for f in frames[:-1])
    assert run_replay(cut, "--no-play") == 0
    captured = capsys.readouterr()
    assert "UNFINISHED: the record stops after round 2 without a result line" in captured.out
    assert "running: round" not in captured.out
    assert captured.err == (
        "fatswarm replay: the record has no result line: the run stopped after round 2 without "
        "finishing (interrupted, killed, or still being written)\n"
    )


@pytest.mark.parametrize(
    ("svg", "message"),
    [
        ("nowhere/last.svg", "--svg: cannot write {path}: no folder"),
        ("last.png", "--svg writes SVG: PATH must end in .svg"),
        ("folder.svg", "--svg: cannot write {path}: it is a folder"),
    ],
)
def test_an_svg_that_cannot_be_written_is_refused_before_the_replay(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str], svg: str, message: str
) -> None:
    (tmp_path / "folder.svg").mkdir()
    path = tmp_path / svg
    assert run_replay(RECORD, "--svg", path) == 2  # not even played: refused first
    captured = capsys.readouterr()
    assert captured.out == ""
    assert message.format(path=path) in captured.err and captured.err.count("\n") == 1


def test_help_lists_every_key(capsys: pytest.CaptureFixture[str]) -> None:
    p = argparse.ArgumentParser(prog="fatswarm replay")
    add_arguments(p)
    with pytest.raises(SystemExit):
        p.parse_args(["--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    for words in ("space play/pause", "one round on", "faster", "the last round", "[ and ]"):
        assert words in help_text
    assert "q or Esc quit" in help_text


def test_off_a_terminal_it_prints_one_frame_as_no_play_does(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert run_replay(RECORD) == 0  # pytest's stdout is no terminal: no playing
    out = capsys.readouterr().out
    assert "NOT FORMED: stopped at the round limit (3 rounds)" in out
    assert "\x1b[?1049h" not in out  # no alternate screen


def test_the_key_help_names_the_looks_keys_only_with_marks() -> None:
    assert "[/]" not in Player(count=3).footer()
    assert "[/] its Looks" in Player(count=3, marks=(1,)).footer()
