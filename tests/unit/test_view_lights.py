"""Lights and views in the pictures: each robot in its colour (replay, plot, the dashboard's
canvas), what one chosen robot saw (`replay --robot`, `plot --robot --round`), and the summary's
model lines. Records are written by hand from tests/data/replay-small.jsonl, or run in process."""

from __future__ import annotations

import argparse
import io
import json
import pathlib
import re
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from rich.console import Console

from fatswarm.deploy.engine.api import run
from fatswarm.deploy.view import plot, replay
from fatswarm.deploy.view.dashboard import (
    LAYER_ACTIVE,
    LAYER_FOCUS,
    LAYER_LIGHT,
    LAYER_ROBOT,
    LAYER_SIGHT,
    LAYER_STOPPED,
    LAYER_UNSEEN,
    LEGEND,
    Frame,
    build_canvas,
    derive,
    print_frame,
    robot_layers,
)
from fatswarm.deploy.view.lights import (
    LIGHT_HEX,
    NO_VIEWS,
    Focus,
    LookScene,
    focus_per_round,
    has_views,
    light_hex,
    light_number,
    lights_of,
    look_scene,
    record_palette,
    views_of,
)
from fatswarm.deploy.view.summary import (
    Outcome,
    model_notes,
    print_outcome,
    summary,
    summary_json,
)
from fatswarm.domain.lights import MAX_COLOURS
from fatswarm.domain.outcome import Status
from fatswarm.world.record import RunRecord
from fatswarm.world.record_read import read_record

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
SMALL = DATA / "replay-small.jsonl"  # 4 robots, 3 rounds, no lights
LIT_SPREAD = f"{DATA / 'lit_spread.py'}:ALGORITHM"
ASSUMES = "algorithm x assumes frames y-axis; this run gives it chirality (outside its assumption)"
MODEL = {
    "visibility": "opaque",
    "sight": 5.0,
    "lights": "full",
    "frames": "y-axis",
    "frame_change": "fixed",
}
# each round line of replay-small gets these lights and views; "zeta" comes first, sorts last
LIGHTS = (
    ["zeta", "alpha", "zeta", "zeta"],
    ["zeta", "alpha", "mid", "zeta"],
    ["alpha", "alpha", "mid", "zeta"],
)
VIEWS: tuple[dict[str, list[int]], ...] = ({"0": [1], "1": [0, 2]}, {"2": [3]}, {"0": [1, 2, 3]})


def lit_record(tmp_path: pathlib.Path, *, views: bool = True, lights: bool = True) -> pathlib.Path:
    """replay-small with a model, lights and (if `views`) views and an assumption."""
    lines = [json.loads(line) for line in SMALL.read_text().splitlines()]
    lines[0]["model"] = MODEL
    if views:
        lines[0].update(record_views=True, assumption=ASSUMES)
    for k, line in enumerate(lines[1:-1]):
        if lights:
            line["lights"] = LIGHTS[k]
        if views:
            line["views"] = VIEWS[k]
    path = tmp_path / "lit.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def cell_of(frame: Frame, robot: int, cols: int = 60, rows: int = 30) -> tuple[int, int]:
    canvas = build_canvas(frame, derive(frame), cols, rows)
    col, row = canvas.viewport.to_cell(*map(float, frame.positions[robot]))
    return row, col


def layer_at(frame: Frame, robot: int) -> int:
    canvas = build_canvas(frame, derive(frame), 60, 30)
    row, col = cell_of(frame, robot)
    return int(canvas.cell_layers()[row, col])


def render(frame: Frame, colours: bool = False) -> str:
    """The frame as text, with its colours as ANSI codes if `colours`."""
    console = Console(
        width=120,
        height=40,
        record=True,
        color_system="truecolor" if colours else None,
        file=io.StringIO(),
    )
    print_frame(frame, console, 40)
    return console.export_text(styles=colours)


# --- the colour mapping ---------------------------------------------------------------------------


def test_palette_is_every_name_the_record_shows_sorted_not_in_order_of_appearance(
    tmp_path: pathlib.Path,
) -> None:
    record = read_record(lit_record(tmp_path))
    assert record_palette(record) == ("alpha", "mid", "zeta")
    assert record_palette(read_record(SMALL)) == ()


def test_colour_k_goes_to_name_k_and_the_first_seven_are_okabe_ito() -> None:
    palette = ("alpha", "mid", "zeta")
    assert [light_hex(palette, name) for name in palette] == list(LIGHT_HEX[:3])
    assert light_number(palette, "zeta") == 2
    assert light_hex(palette, "other") is None and light_number(palette, None) is None
    okabe_ito = ["#E69F00", "#56B4E9", "#009E73", "#F0E442", "#0072B2", "#D55E00", "#CC79A7"]
    assert list(LIGHT_HEX[:7]) == okabe_ito
    assert len(set(LIGHT_HEX)) == len(LIGHT_HEX) >= MAX_COLOURS
    many = tuple(f"c{i:02d}" for i in range(len(LIGHT_HEX) + 1))  # more than there are: cycle
    assert light_hex(many, many[-1]) == LIGHT_HEX[0]


def test_malformed_lights_and_views_are_left_out(tmp_path: pathlib.Path) -> None:
    entry = read_record(lit_record(tmp_path)).rounds[0]
    assert lights_of(entry, 4) == ("zeta", "alpha", "zeta", "zeta")
    assert lights_of(entry, 5) is None  # not one name per robot
    for bad in (["a", 1, "b", "c"], "abcd", None):
        assert lights_of(replace(entry, extra={"lights": bad}), 4) is None
    assert views_of(entry, 4) == {0: (1,), 1: (0, 2)}
    odd = {"0": [1, 9], "x": [1], "7": [0], "2": [True], "3": [2, 0]}
    assert views_of(replace(entry, extra={"views": odd}), 4) == {3: (0, 2)}
    assert views_of(replace(entry, extra={"views": [1, 2]}), 4) == {}


# --- replay and the dashboard's canvas ------------------------------------------------------------


def test_replay_frames_carry_each_robots_light_and_one_palette(tmp_path: pathlib.Path) -> None:
    frames = replay.build_frames(read_record(lit_record(tmp_path)))
    assert frames[0].lights == ()  # no line records the start's colours
    assert [f.lights for f in frames[1:]] == [tuple(names) for names in LIGHTS]
    assert {f.palette for f in frames} == {("alpha", "mid", "zeta")}


def test_each_robot_is_drawn_on_its_colours_layer_with_a_legend_naming_them(
    tmp_path: pathlib.Path,
) -> None:
    frame = replay.build_frames(read_record(lit_record(tmp_path)))[2]  # zeta alpha mid zeta
    alpha, mid, zeta = LAYER_LIGHT, LAYER_LIGHT + 1, LAYER_LIGHT + 2
    assert robot_layers(frame, 4) == [zeta, alpha, mid, zeta]
    assert layer_at(frame, 1) == LAYER_LIGHT
    assert re.search(r"alpha mid zeta path SEC", render(frame))
    assert "idle" not in render(frame)
    styled = render(frame, colours=True)
    assert "38;2;230;159;0" in styled  # #E69F00, alpha's orange, on the canvas and the legend


def test_a_record_without_lights_draws_as_before() -> None:
    frames = replay.build_frames(read_record(SMALL))
    assert all(f.lights == () and f.palette == () and f.focus is None for f in frames)
    f2 = frames[2]  # robot 2 active and stopped
    assert robot_layers(f2, 4) == [LAYER_ROBOT, LAYER_ROBOT, LAYER_STOPPED, LAYER_ROBOT]
    assert robot_layers(frames[3], 4) == [LAYER_ACTIVE] * 4
    # the same picture as a frame made without the new fields (as the live view makes them)
    plain = Frame(
        round=f2.round, n=f2.n, scheduler=f2.scheduler, positions=f2.positions,
        algorithm=f2.algorithm, params=f2.params, active=f2.active, moved=f2.moved,
        stopped=f2.stopped, collisions_total=f2.collisions_total, seed=f2.seed,
        last_active=f2.last_active, last_path_length=f2.last_path_length,
        last_round=f2.last_round, trails=f2.trails, source=f2.source,
        derived=f2.derived,  # the run's min_gap so far: the live view's state carries it too
        model=f2.model,  # the robot model in one word: the live view's state carries it too
    )  # fmt: skip
    assert render(f2, colours=True) == render(plain, colours=True)
    legend = re.sub(r"\[/?[^\]]*\]", "", LEGEND)
    assert legend == "idle active stopped path SEC" and legend in render(f2)
    assert "[/]" not in replay.Player(count=4).footer()


# --- what one robot saw ---------------------------------------------------------------------------


def test_focus_says_in_each_round_whether_the_robot_looked_and_whom_it_saw(
    tmp_path: pathlib.Path,
) -> None:
    record = read_record(lit_record(tmp_path))
    focus = focus_per_round(record, 0)
    assert [f.looked for f in focus] == [False, True, False, True]
    assert focus[3].seen == (1, 2, 3) and focus[3].sight == 5.0
    assert focus[1].origin == (0.0, 0.0)  # where it was when it Looked: before round 1
    assert focus[1].dims(3) and not focus[1].dims(1) and not focus[1].dims(0)
    assert not focus[2].dims(3)  # a round it did not Look in dims nobody
    assert focus[1].line() == "saw 1: 1" and focus[2].line() == "did not Look this round"


def test_the_chosen_robot_is_ringed_its_unseen_robots_dimmed_and_its_sight_drawn(
    tmp_path: pathlib.Path,
) -> None:
    record = read_record(lit_record(tmp_path))
    frame = replay.focus_on(replay.build_frames(record), record, 1)[1]  # 1 saw 0 and 2
    assert robot_layers(frame, 4) == [LAYER_LIGHT + 2, LAYER_LIGHT, LAYER_LIGHT + 2, LAYER_UNSEEN]
    layers = build_canvas(frame, derive(frame), 60, 30).cell_layers()
    assert (layers == LAYER_FOCUS).any() and (layers == LAYER_SIGHT).any()
    text = render(frame)
    assert re.search(r"robot 1\s+saw 2: 0 2", text)
    assert "◯ robot 1 unseen sight" in text


def test_replay_robot_on_a_record_without_views_says_so_in_one_line(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_replay(lit_record(tmp_path, views=False), "--robot", "2", "--no-play") == 0
    out, err = capsys.readouterr()
    assert err.count("record it with --record-views") == 1 and NO_VIEWS in err
    assert "views not recorded" in out
    assert "model: --visibility opaque --sight 5.0" in err


def test_replay_robot_shows_its_look_and_refuses_a_robot_that_is_not_there(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = lit_record(tmp_path)
    assert run_replay(path, "--robot", "0", "--round", "3", "--no-play") == 0
    out, err = capsys.readouterr()
    assert re.search(r"robot 0\s+saw 3: 1 2 3", out) and "record-views" not in err
    assert err.count(ASSUMES) == 1
    assert run_replay(path, "--robot", "4", "--no-play") == 2
    assert "--robot must be a robot number between 0 and 3, got 4" in capsys.readouterr().err


def test_player_jumps_between_the_chosen_robots_looks() -> None:
    player = replay.Player(count=10, marks=(2, 5, 8))
    player.key("]")
    assert (player.index, player.playing) == (2, False)
    player.key("]")
    player.key("]")
    player.key("]")
    assert player.index == 8
    player.key("[")
    assert player.index == 5
    assert "[/] its Looks" in player.footer()


def run_replay(*argv: object) -> int:
    p = argparse.ArgumentParser()
    replay.add_arguments(p)
    return replay.main(p.parse_args([str(a) for a in argv]))


# --- one Look, for plot ---------------------------------------------------------------------------


def test_a_look_in_rounds_shows_the_positions_and_colours_before_the_round(
    tmp_path: pathlib.Path,
) -> None:
    record = read_record(lit_record(tmp_path))
    scene = look_scene(record, 2, 2)
    assert isinstance(scene, LookScene)
    assert scene.positions.tolist() == record.rounds[0].positions.tolist()
    assert scene.lights == tuple(LIGHTS[0]) and scene.seen == (3,) and scene.sight == 5.0
    assert scene.move is not None and scene.move[0] == (0.0, 3.0)  # it turned from (0, 3)
    first = look_scene(record, 0, 1)
    assert isinstance(first, LookScene) and first.lights is None  # the start's are not recorded
    never = "robot 3 did not Look in round 2 (it never Looked with views recorded)"
    assert look_scene(record, 3, 2) == never
    assert look_scene(record, 0, 2) == "robot 0 did not Look in round 2 (it Looked in rounds 1, 3)"
    assert look_scene(record, 0, 9) == "the record has no round 9"
    assert look_scene(read_record(SMALL), 0, 1) == NO_VIEWS


@pytest.fixture(scope="module")
def async_record(tmp_path_factory: pytest.TempPathFactory) -> RunRecord:
    path = tmp_path_factory.mktemp("async") / "lit.jsonl"
    run(6, algorithm=LIT_SPREAD, seed=3, scheduler="async", sight=6.0, visibility="opaque",
        record_views=True, record=path)  # fmt: skip
    return read_record(path)


def test_an_async_look_rebuilds_where_everyone_was_at_its_time(async_record: RunRecord) -> None:
    assert has_views(async_record) and record_palette(async_record)
    checked = 0
    for entry in async_record.rounds:
        (robot,) = entry.active
        scene = look_scene(async_record, robot, entry.round)
        assert isinstance(scene, LookScene)
        # the looker stands where its cycle line says it Looked from
        assert scene.positions[robot].tolist() == pytest.approx(entry.extra["origin"], abs=1e-6)
        checked += bool(entry.moves)
    assert checked  # some of them moved


# --- plot -----------------------------------------------------------------------------------------


def run_plot(*argv: object) -> int:
    p = argparse.ArgumentParser()
    plot.add_arguments(p)
    return plot.main(p.parse_args([str(a) for a in argv]))


def test_plot_draws_each_move_in_the_colour_shown_during_it(tmp_path: pathlib.Path) -> None:
    record = read_record(lit_record(tmp_path))
    routes = plot.lit_routes(record, record_palette(record))
    # round 1: robot 1 (alpha); round 2: robot 2 (mid); round 3: robots 0 (alpha) and 3 (zeta)
    alpha, mid, zeta = LIGHT_HEX[:3]
    assert [colour for _, colour in routes] == [alpha, mid, alpha, zeta]
    assert routes[0][0][0].tolist() == [3.0, 0.0] and routes[0][0][-1].tolist() == [6.0, 0.0]
    assert plot.final_lights(record) == tuple(LIGHTS[2])
    no_lights = read_record(lit_record(tmp_path, lights=False))
    assert plot.lit_routes(no_lights, ())[0][1] == plot.NO_LIGHT


def test_plot_writes_the_lit_run_and_one_look_and_names_the_model(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("matplotlib")
    path = lit_record(tmp_path)
    assert run_plot(path, tmp_path / "run.svg") == 0
    picture = (tmp_path / "run.svg").read_text()
    assert all(name in picture for name in ("alpha", "mid", "zeta"))
    assert run_plot(path, tmp_path / "look.svg", "--robot", "1", "--round", "1") == 0
    assert "robot 1" in (tmp_path / "look.svg").read_text()
    record = read_record(path)
    assert "model: --visibility opaque --sight 5.0" in plot.default_title(record, 1.0)
    assert "model" not in plot.default_title(read_record(SMALL), 1.0)
    assert run_plot(path, tmp_path / "x.svg", "--robot", "1") == 2
    assert "--robot I and --round K go together" in capsys.readouterr().err
    assert run_plot(SMALL, tmp_path / "x.svg", "--robot", "1", "--round", "1") == 2
    assert "record it with --record-views" in capsys.readouterr().err
    assert run_plot(path, tmp_path / "x.svg", "--robot", "7", "--round", "1") == 2
    assert not (tmp_path / "x.svg").exists()


# --- the summary ----------------------------------------------------------------------------------


def outcome(**fields: Any) -> Outcome:
    base: dict[str, Any] = dict(
        status=Status.FORMED, rounds=6, collisions=0, n=6, a=None, seed=3, scheduler="fsync",
        epochs=6, moves=8, total_distance=3.2, algorithm="lit-spread", params={"gap": 3.0},
    )  # fmt: skip
    return Outcome(**{**base, **fields})


def test_summary_names_a_model_that_is_not_the_papers_and_the_assumption_once() -> None:
    plain = summary(outcome())
    noted = summary(outcome().noted({"model": MODEL, "assumption": ASSUMES}))
    assert noted.startswith(plain.replace("model=paper", "model=opaque+sight5") + "\n")
    assert noted[len(plain) :].splitlines()[1:] == [
        "model: --visibility opaque --sight 5.0",
        ASSUMES,
    ]
    assert noted.count(ASSUMES) == 1
    paper = {**MODEL, "visibility": "transparent", "sight": None}
    assert summary(outcome().noted({"model": paper})) == plain
    assert model_notes({}) == (None, None)
    assert model_notes({"model": {"sight": "far"}})[0] == (
        "unreadable (--sight must be a finite distance > 0 (robot radii), got 'far')"
    )
    assert model_notes({"assumption": "two\nlines "}) == (None, "two lines")


def test_the_summary_names_the_model_and_assumption_and_json_adds_keys_only_when_there(
    tmp_path: pathlib.Path,
) -> None:
    path = lit_record(tmp_path)
    noted = outcome().noted(read_record(str(path)).header.extra)
    out = io.StringIO()
    print_outcome(noted, 0, out, as_json=False, record=str(path), svg=None)
    lines = out.getvalue().splitlines()
    assert lines[3:] == ["model: --visibility opaque --sight 5.0", ASSUMES, f"record: {path}"]
    out = io.StringIO()
    print_outcome(noted, 0, out, as_json=True, record=str(path), svg=None)
    fields = json.loads(out.getvalue())
    assert (fields["model"], fields["assumption"]) == ("--visibility opaque --sight 5.0", ASSUMES)
    plain = json.loads(summary_json(outcome(), 0))
    assert "model" not in plain and "assumption" not in plain
    out = io.StringIO()  # the paper's model: the summary as it always was
    print_outcome(outcome(), 0, out, as_json=False, record=None, svg=None)
    assert out.getvalue() == summary(outcome()) + "\n"


def test_focus_of_a_robot_that_never_looked_dims_nobody() -> None:
    focus = Focus(2, recorded=False)
    assert not any(focus.dims(i) for i in range(4)) and focus.line() == "views not recorded"
    frame = replace(replay.build_frames(read_record(SMALL))[1], focus=focus)
    assert robot_layers(frame, 4) == [LAYER_ACTIVE, LAYER_ACTIVE, LAYER_ROBOT, LAYER_ROBOT]
    assert np.isfinite(frame.positions).all()
