"""`fatswarm plot RECORD OUT.gif|OUT.mp4`: how many frames a video takes, where each frame puts
the robots (the timeline, not pixels), and the one-line refusals (an mp4 through ffmpeg starts a
process: tests/integration/test_animate_process.py)."""

from __future__ import annotations

import argparse
import io
import pathlib
import shutil

import numpy as np
import pytest

from fatswarm.deploy.view import animate
from fatswarm.deploy.view.animate import (
    Clip,
    Progress,
    lights_at,
    missing_ffmpeg,
    parse_rounds,
    plan_clip,
)
from fatswarm.deploy.view.plot import add_arguments, main
from fatswarm.world.record import Header, RoundEntry, RunRecord
from fatswarm.world.record_read import read_record
from fatswarm.world.timeline import Timeline

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
RECORD = DATA / "lockstep-n6-seed1.jsonl"  # 17 rounds of 6 robots
SMALL = DATA / "replay-small.jsonl"  # 3 rounds of 4 robots, a collision in round 2


def run_plot(*argv: object) -> int:
    p = argparse.ArgumentParser()
    add_arguments(p)
    return main(p.parse_args([str(a) for a in argv]))


def long_record(rounds: int) -> RunRecord:
    """A record of `rounds` rounds in which nobody moves (enough to count frames)."""
    initial = np.array([[0.0, 0.0], [4.0, 0.0]])
    entries = tuple(RoundEntry(k, (0,), (), initial, ()) for k in range(1, rounds + 1))
    return RunRecord(Header(2, 1, "fsync", initial), entries, None)


# --- frames: how many, at which times --------------------------------------------------------


def test_frames_are_rounds_over_speed_times_fps_plus_the_first() -> None:
    timeline = Timeline(read_record(RECORD))
    clip = plan_clip(timeline, None, 20, 2.0)
    assert (clip.frames, clip.t0, clip.t1) == (17 * 20 // 2 + 1, 0.0, 17.0)
    assert plan_clip(timeline, None, 20, None).frames == 171  # default: 2 rounds per second
    clip = plan_clip(timeline, (3, 5), 10, 1.0)
    assert clip.frames == 31
    assert [clip.time_of(i) for i in (0, 10, 15, 30)] == [2.0, 3.0, 3.5, 5.0]
    assert clip.seconds == pytest.approx(3.1)


def test_a_long_record_plays_quicker_by_default_and_an_explicit_speed_is_refused_over_the_cap(
    capsys: pytest.CaptureFixture[str],
) -> None:
    timeline = Timeline(long_record(5000))
    clip = plan_clip(timeline, None, 20, None)
    assert clip.frames == 60 * 20 + 1  # the default speed keeps it to 60 s
    assert plan_clip(timeline, None, 20, 2.0).frames == 50_001
    args = argparse.Namespace(out="x.gif", fps=None, speed=2.0, rounds=None, max_frames=3000)
    refused = animate.plan(args, timeline)
    assert isinstance(refused, str)
    assert "50,001 frames" in refused and "--speed 34" in refused


def test_in_round_positions_of_a_frame_follow_the_timeline() -> None:
    pytest.importorskip("matplotlib")
    record = read_record(SMALL)
    timeline = Timeline(record)
    clip = plan_clip(timeline, (3, 3), 10, 1.0)  # round 3: robot 0 travels 4, robot 3 about 2.24
    scene = animate.Scene(record, timeline, clip, None)
    try:
        scene.update(5)  # halfway through the round: s = 2
        shown = np.asarray(scene.discs.get_offsets())
        assert np.array_equal(shown, timeline.at(2.5))
        assert shown[0] == pytest.approx([0.0, -2.0])  # the corner of its two segments
        assert not np.allclose(shown, record.rounds[1].positions)  # it has moved since the start
        assert not np.allclose(shown, record.rounds[2].positions)  # and not arrived yet
        scene.update(clip.frames - 1)
        assert np.array_equal(scene.discs.get_offsets(), record.rounds[2].positions)
        assert [label.get_text() for label in scene.labels] == ["0", "1", "2", "3"]
        assert tuple(scene.labels[3].get_position()) == tuple(record.rounds[2].positions[3])
        assert scene.clock.get_text() == "round 3 of 3"
    finally:
        scene.close()


def test_collisions_are_marked_from_their_time_on() -> None:
    pytest.importorskip("matplotlib")
    record = read_record(SMALL)
    timeline = Timeline(record)
    scene = animate.Scene(record, timeline, plan_clip(timeline, None, 10, 1.0), None)
    try:
        scene.update(15)  # t = 1.5: round 2's contact (at its end) has not happened yet
        assert np.asarray(scene.contacts.get_offsets()).shape == (0, 2)
        scene.update(20)  # t = 2
        assert np.asarray(scene.contacts.get_offsets()).shape == (1, 2)
        assert "1 collision" in scene.clock.get_text()
    finally:
        scene.close()


def test_lights_of_the_round_in_progress() -> None:
    initial = np.array([[0.0, 0.0], [4.0, 0.0]])
    entries = tuple(
        RoundEntry(k, (0,), (), initial, (), {"lights": [name, "b"]})
        for k, name in enumerate(["a", "c"], start=1)
    )
    timeline = Timeline(RunRecord(Header(2, 1, "fsync", initial), entries, None))
    assert lights_at(timeline, 0.0) is None  # the start: no line says
    assert lights_at(timeline, 0.5) == ("a", "b")
    assert lights_at(timeline, 1.0) == ("a", "b")
    assert lights_at(timeline, 1.2) == ("c", "b")


# --- --rounds ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [("3..10", (3, 10)), ("5..", (5, 17)), ("..4", (1, 4)), ("7", (7, 7)), (" 2 .. 3 ", (2, 3))],
)
def test_rounds_ranges(text: str, expected: tuple[int, int]) -> None:
    assert parse_rounds(text, 17) == expected


@pytest.mark.parametrize("text", ["5..2", "0..3", "3..18", "x", "", "1-3", "-2..4"])
def test_bad_rounds_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match="--rounds") as exc:
        parse_rounds(text, 17)
    assert "\n" not in str(exc.value)


# --- the command -------------------------------------------------------------------------------


def test_a_gif_is_written_frame_by_frame(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("matplotlib")
    from PIL import Image

    out = tmp_path / "run.gif"
    assert run_plot(SMALL, out, "--fps", "2", "--speed", "3") == 0
    err = capsys.readouterr().err
    assert "writing 3 frames of rounds 1..3 (1.5 s of video at 2 fps, 3 rounds per second)" in err
    assert "frame 3/3 (100%)" in err
    with Image.open(out) as gif:
        assert getattr(gif, "n_frames", 1) == 3
        assert gif.size == (600, 600)
        assert gif.info["duration"] == 500
    assert out.read_bytes().endswith(b";")


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--rounds", "4..9"], "--rounds 4..9: the record's rounds are 1..3"),
        (["--fps", "0"], "--fps must be a whole number between 1 and 50 for .gif, got 0"),
        (["--fps", "60"], "--fps must be a whole number between 1 and 50 for .gif, got 60"),
        (["--speed", "-1"], "--speed must be a positive number, got -1"),
        (["--max-frames", "5"], "that video would take 31 frames (1.6 s at 20 fps), over "),
        (["--robot", "1", "--round", "2"], "--round draws one Look (with --robot)"),
        (["--robot", "4"], "--robot must be between 0 and 3, got 4"),
    ],
)
def test_bad_video_flags_are_refused_in_one_line_before_any_frame(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str], argv: list[str], said: str
) -> None:
    out = tmp_path / "run.gif"
    assert run_plot(SMALL, out, *argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err, err
    assert not out.exists()


def test_video_flags_with_a_still_picture_are_refused(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(SMALL, tmp_path / "x.svg", "--fps", "10", "--rounds", "1..2") == 2
    err = capsys.readouterr().err
    assert (
        err == "fatswarm plot: --fps and --rounds only apply to a video: write OUT.gif or OUT.mp4\n"
    )


def test_an_mp4_without_ffmpeg_says_what_to_install(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("matplotlib")
    monkeypatch.setattr(shutil, "which", lambda name: None)
    out = tmp_path / "run.mp4"
    assert run_plot(SMALL, out) == 2
    assert capsys.readouterr().err == missing_ffmpeg(str(out)) + "\n"
    assert f"writing {out} needs ffmpeg" in missing_ffmpeg(str(out))
    assert f"or write {tmp_path / 'run.gif'}, which" in missing_ffmpeg(str(out))
    assert not out.exists()


@pytest.mark.parametrize("out", ["nowhere/run.gif", "folder.gif"])
def test_a_place_that_cannot_be_written_is_refused_at_the_start(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str], out: str
) -> None:
    (tmp_path / "folder.gif").mkdir()
    assert run_plot(SMALL, tmp_path / out) == 2
    err = capsys.readouterr().err
    assert err.startswith("fatswarm plot: cannot write") and err.count("\n") == 1


def test_progress_off_a_terminal_is_a_line_every_tenth() -> None:
    stream = io.StringIO()
    ticks = iter(range(1000))
    progress = Progress(stream, clock=lambda: float(next(ticks)))
    for frame in range(40):
        progress(frame, 40)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 10
    assert lines[0].startswith("fatswarm plot: frame 4/40 (10%), about ")
    assert lines[-1].startswith("fatswarm plot: frame 40/40 (100%), about 0 s left")


def test_clip_of_an_empty_record_is_one_frame() -> None:
    timeline = Timeline(long_record(0))
    assert plan_clip(timeline, None, 20, None) == Clip(0, 0, 0.0, 0.0, 1, 20, 2.0)
