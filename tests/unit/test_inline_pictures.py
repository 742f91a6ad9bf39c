"""Pictures in a notebook (deploy/view/inline.py, the records' and results' `animate()`,
`figure()`, `look_figure()`) and what every video frame draws (deploy/view/scene.py): the frames
of `fatswarm plot OUT.gif`, trails only as far as travelled, point robots as dots, the lights'
legend, a chosen robot, a failed compute. Matplotlib's Agg canvas, no process, no pyplot."""

from __future__ import annotations

import argparse
import json
import pathlib
import re
import sys
from typing import Any

import numpy as np
import pytest

from fatswarm.deploy.engine.api import RunRecord, read_record, run
from fatswarm.deploy.view import inline, plot, replay
from fatswarm.deploy.view.animate import clip_line, plan_clip
from fatswarm.deploy.view.inline import InlineVideo, PictureError
from fatswarm.deploy.view.lights import Focus, focus_per_round, look_scene
from fatswarm.deploy.view.scene import Scene, Trails, still_clip
from fatswarm.world.timeline import Timeline

pytest.importorskip("matplotlib")

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
SMALL = DATA / "replay-small.jsonl"  # 3 rounds of 4 robots, a collision in round 2


def run_plot(*argv: object) -> int:
    p = argparse.ArgumentParser()
    plot.add_arguments(p)
    return plot.main(p.parse_args([str(a) for a in argv]))


def legend_texts(ax: Any) -> list[str]:
    legend = ax.get_legend()
    assert legend is not None
    return [t.get_text() for t in legend.get_texts()]


def pyplot_figures() -> list[int]:
    import matplotlib.pyplot as plt

    return list(plt.get_fignums())


@pytest.fixture(scope="module")
def failing(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A record whose computes fail (an opaque view the paper's algorithm refuses), with views."""
    path = tmp_path_factory.mktemp("failing") / "failed.jsonl"
    run(6, seed=3, visibility="opaque", max_rounds=40, record_views=True, record=path)
    return str(path)


# --- animate(): the GIF of `fatswarm plot`, inline, silent -----------------------------------


def test_animate_is_the_gif_plot_writes_shown_inline_and_prints_nothing(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(SMALL, tmp_path / "run.gif", "--fps", "4", "--speed", "3") == 0
    capsys.readouterr()
    video = read_record(SMALL).animate(fps=4, speed=3)
    assert capsys.readouterr() == ("", "")  # no progress lines in the cell
    assert isinstance(video, InlineVideo)
    assert video.gif == (tmp_path / "run.gif").read_bytes()  # the same frames, byte for byte
    assert video.frames == 5
    shown = video._repr_html_()
    assert shown.startswith('<img src="data:image/gif;base64,') and shown.endswith('"/>')
    assert repr(video) == f"InlineVideo(frames=5, fps=4, seconds=1.2, bytes={len(video.gif):,})"


def test_a_result_animates_the_record_it_wrote_and_says_when_it_wrote_none(
    tmp_path: pathlib.Path,
) -> None:
    record = tmp_path / "run.jsonl"
    result = run(4, seed=1, scheduler="fsync", record=record)
    video = result.animate(speed=20, fps=2)
    assert video.gif == inline.animate(str(record), speed=20, fps=2).gif
    with pytest.raises(PictureError, match=r"^this result wrote no record to draw: run it with "):
        run(4, seed=1, scheduler="fsync").animate()


@pytest.mark.parametrize(
    ("settings", "said"),
    [
        ({"fps": 0}, "fps must be a whole number between 1 and 50 for .gif, got 0"),
        ({"speed": "fast"}, "speed must be a number, got 'fast'"),
        ({"rounds": (2, 9)}, "rounds 2..9: the record's rounds are 1..3"),
        ({"rounds": "x"}, "rounds must be A..B"),
        ({"robot": 4}, "robot must be between 0 and 3, got 4"),
        ({"max_frames": 5}, "over max_frames=5: pass speed=15 or more, fewer rounds A..B, a lo"),
        ({"max_frames": 1}, "one frame shows one instant (a picture, figure(round=K))"),
    ],
)
def test_animate_refuses_a_setting_in_one_line_in_its_keywords(
    settings: dict[str, Any], said: str
) -> None:
    with pytest.raises(PictureError) as refused:
        read_record(SMALL).animate(**settings)
    assert said in str(refused.value) and "\n" not in str(refused.value)
    assert "--" not in str(refused.value)  # keywords, not the command's flags


def test_the_speed_a_refusal_names_fits() -> None:
    assert read_record(SMALL).animate(max_frames=5, speed=15).frames == 5


def test_one_frame_is_never_told_to_pass_speed_0(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(SMALL, tmp_path / "run.gif", "--max-frames", "1") == 2
    err = capsys.readouterr().err
    assert "--speed 0" not in err and "one frame shows one instant (a picture, OUT.png)" in err


def test_the_clip_line_counts_one_round_in_the_singular() -> None:
    timeline = Timeline(read_record(SMALL))
    line = clip_line(plan_clip(timeline, None, 4, 1.0), False, "run.gif")
    assert line.endswith("(3.2 s of video at 4 fps, 1 round per second) to run.gif")
    assert "2 rounds per second" in clip_line(plan_clip(timeline, None, 4, 2.0), False, "x.gif")
    assert "1 unit of virtual time per second" in clip_line(
        plan_clip(timeline, None, 4, 1.0), True, "x.gif"
    )


# --- figure() and look_figure(): Figures to restyle ---------------------------------------------


def test_figure_of_a_round_is_its_frame_returned_open_and_outside_pyplot() -> None:
    from matplotlib.figure import Figure

    record = read_record(SMALL)
    before = pyplot_figures()
    fig = record.figure(round=2)
    assert isinstance(fig, Figure) and pyplot_figures() == before  # nothing shown or managed
    (discs, *_) = [c for c in fig.axes[0].collections if np.asarray(c.get_offsets()).shape[0] == 4]
    assert np.array_equal(discs.get_offsets(), record.rounds[1].positions)
    fig.axes[0].set_title("mine")  # the caller restyles it
    fig.savefig(pathlib.Path("/dev/null"), format="png")
    start = record.figure(round=0)
    assert "start, before round 1 of 3" in [t.get_text() for t in start.axes[0].texts]
    with pytest.raises(PictureError, match=r"^round must be between 0 \(the start\) and 3, got 4"):
        record.figure(round=4)


def test_figure_of_the_whole_run_is_plots_still_picture(tmp_path: pathlib.Path) -> None:
    record = read_record(SMALL)
    fig = record.figure(title="all of it")
    assert fig.axes[0].get_title() == "all of it"
    assert run_plot(SMALL, tmp_path / "run.svg") == 0
    assert len(fig.axes[0].patches) > record.header.n  # start and end discs, the final SEC


def test_look_figure_shows_a_failed_compute_and_refuses_a_look_that_did_not_happen(
    failing: str,
) -> None:
    record = read_record(failing)
    fig = record.look_figure(2, 2)
    title = fig.axes[0].get_title()
    assert title.startswith("robot 2's Look in round 2: saw 4 of 5")
    assert "its compute failed: ViewError: the view holds 4 robots, expected n-1 = 5" in title
    assert "compute failed" in legend_texts(fig.axes[0])
    with pytest.raises(PictureError, match=r"^robot 2 did not Look in round 1 \(it Looked in "):
        record.look_figure(2, 1)


# --- what a frame draws --------------------------------------------------------------------------


def test_a_path_is_drawn_only_as_far_as_its_robot_has_travelled() -> None:
    record = read_record(SMALL)
    timeline = Timeline(record)
    clip = plan_clip(timeline, None, 10, 1.0)  # 31 frames, t = frame / 10
    scene = Scene(record, timeline, clip, None)
    scene.update(0)
    assert len(scene.trails.get_segments()) == 0  # the start: nothing travelled yet
    end_of_round_3 = record.rounds[2].positions[0]  # robot 0 ends round 3 at (0, -4)
    scene.update(25)  # t = 2.5: robot 0 halfway through round 3, at the corner (0, -2)
    points = np.concatenate(scene.trails.get_segments())
    assert np.hypot(*(points - end_of_round_3).T).min() > 1.0  # its future is not drawn
    assert any(np.allclose(p, scene.positions[0]) for p in points)  # its trail reaches it
    counts = []
    for frame in range(clip.frames):
        scene.update(frame)
        counts.append(sum(len(line) for line in scene.trails.get_segments()))
    trails = Trails.of(timeline)
    assert counts == sorted(counts)  # a trail only grows
    assert counts[-1] >= sum(len(p) for p in trails.points)  # by the end, every sample


def point_record(tmp_path: pathlib.Path) -> RunRecord:
    path = tmp_path / "points.jsonl"
    run(
        4, algorithm="oblot-go-to-cog", scheduler="fsync", bodies="points", frames="both-axes",
        seed=1, record=path,
    )  # fmt: skip
    return read_record(path)


def test_point_robots_are_dots_not_unit_discs(tmp_path: pathlib.Path) -> None:
    from matplotlib.collections import EllipseCollection, PathCollection
    from matplotlib.patches import Circle

    record = point_record(tmp_path)
    timeline = Timeline(record)
    scene = Scene(record, timeline, still_clip(timeline, 1), None)
    assert isinstance(scene.discs, PathCollection)
    assert not any(isinstance(c, EllipseCollection) for c in scene.ax.collections)
    still = record.figure()
    unit = [p for p in still.axes[0].patches if isinstance(p, Circle) and p.get_radius() == 1.0]
    assert unit == []  # only the final SEC is a circle
    fat = Scene(read_record(SMALL), Timeline(read_record(SMALL)), still_clip(timeline, 0), None)
    assert isinstance(fat.discs, EllipseCollection)


def lit_record(tmp_path: pathlib.Path) -> RunRecord:
    source = [json.loads(line) for line in SMALL.read_text().splitlines()]
    for line in source:
        if line["type"] == "round":
            line["lights"] = ["off", "on", "off", "on"]
    path = tmp_path / "lit.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in source))
    return read_record(path)


def legend_of(scene: Scene) -> list[str]:
    return legend_texts(scene.ax)


def test_the_legend_names_unknown_only_when_a_frame_shows_a_robot_of_unknown_colour(
    tmp_path: pathlib.Path,
) -> None:
    from matplotlib.colors import to_hex

    record = lit_record(tmp_path)
    timeline = Timeline(record)
    later = Scene(record, timeline, plan_clip(timeline, (2, 3), 4, 1.0), None)
    assert legend_of(later) == ["off", "on"]
    whole = Scene(record, timeline, plan_clip(timeline, None, 4, 1.0), None)
    assert legend_of(whole) == ["off", "on", "unknown"]
    whole.update(0)  # the start: no line says the colours, drawn as unknown
    assert {to_hex(c) for c in whole.discs.get_facecolor()} == {"#808080"}


def test_a_chosen_robot_is_ringed_and_what_it_did_not_see_is_pale(failing: str) -> None:
    from matplotlib.colors import to_hex

    record = read_record(failing)
    timeline = Timeline(record)
    scene = Scene(record, timeline, plan_clip(timeline, None, 4, 1.0), None, robot=2)
    scene.update(6)  # t = 1.5: round 2, robot 2 Looked and did not see robot 4
    assert scene.discs.get_linewidths()[2] > scene.discs.get_linewidths()[0]
    faces = [to_hex(c) for c in scene.discs.get_facecolor()]
    assert faces[4] == "#e8e8e8" and faces[0] != "#e8e8e8"
    assert "robot 2: failed; saw 4: 0 1 3 5" in scene.clock.get_text()


def test_a_video_of_a_robot_without_views_says_so_once(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(SMALL, tmp_path / "run.gif", "--robot", "1", "--fps", "1") == 0
    err = capsys.readouterr().err.splitlines()
    assert err[0] == (
        "fatswarm plot: the record has no views of what each robot saw: record it with "
        "--record-views; robot 1 is ringed, nobody is paled"
    )
    assert err[1].startswith("fatswarm plot: writing 3 frames")


def test_focus_says_a_failed_compute(failing: str) -> None:
    record = read_record(failing)
    focus = focus_per_round(record, 2)[2]  # round 2
    assert focus.failed == "ViewError: the view holds 4 robots, expected n-1 = 5"
    assert focus.line() == "failed; saw 4: 0 1 3 5"
    assert Focus(1, recorded=False, failed="E: x").line() == "failed; views not recorded"
    assert focus_per_round(record, 2)[1].line() == "did not Look this round"


def test_replay_of_a_robot_says_its_compute_failed(
    failing: str, capsys: pytest.CaptureFixture[str]
) -> None:
    p = argparse.ArgumentParser()
    replay.add_arguments(p)
    argv = [failing, "--no-play", "--round", "2", "--robot", "2"]
    assert replay.main(p.parse_args(argv)) == 0
    assert re.search(r"robot 2 +failed; saw 4: 0 1 3 5", capsys.readouterr().out)


def test_an_async_look_says_cycle(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "async.jsonl"
    run(4, seed=1, scheduler="async", record_views=True, record=path)
    record = read_record(path)
    looked = next(e.round for e in record.rounds if 0 in e.active)
    scene = look_scene(record, 0, looked)
    assert not isinstance(scene, str)
    assert plot.look_title(record, scene).startswith(f"robot 0's Look in cycle {looked}: ")
    missing = look_scene(record, 0, len(record.rounds) + 1)
    assert missing == f"the record has no cycle {len(record.rounds) + 1}"


def test_without_matplotlib_a_picture_says_what_to_install_in_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    record = read_record(SMALL)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` fail
    for settings in ({}, {"round": 1}):
        with pytest.raises(ImportError) as missing:
            record.figure(**settings)
        assert str(missing.value) == (
            "pictures need matplotlib: pip install 'fatswarm[notebook]' (or matplotlib)"
        )
    for picture in (record.animate, record.figure):
        with pytest.raises(ImportError) as missing:
            picture()
        assert str(missing.value) == (
            "pictures need matplotlib: pip install 'fatswarm[notebook]' (or matplotlib)"
        )
