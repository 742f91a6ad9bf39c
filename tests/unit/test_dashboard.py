"""Dashboard frames rendered into a recording console: what is drawn and what the counters say."""

from __future__ import annotations

import argparse
import io
import math
import re
from typing import Any

import numpy as np
import pytest
from rich.console import Console

from fatswarm.deploy.net.watch import StateWatcher, add_arguments, follow
from fatswarm.deploy.view.dashboard import (
    LAYER_ACTIVE,
    LAYER_ROBOT,
    LAYER_SEC,
    LAYER_STOPPED,
    LAYER_TARGET,
    LAYER_TARGET_CIRCLE,
    MAX_FIGURE_ROWS,
    Frame,
    LiveView,
    ProgressLog,
    RateMeter,
    add_run_arguments,
    agent_rows,
    build_canvas,
    derive,
    enclosing_circle,
    figure_text,
    frame_from_state,
    outcome_text,
    print_frame,
    progress_line,
    run_lines,
    save_svg,
)
from fatswarm.domain.outcome import ENDED, Status
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured
from fatswarm.world.observers import AgentInfo, WorldState


def render_text(frame: Frame, width: int = 120, height: int = 40) -> str:
    console = Console(
        width=width, height=height, record=True, color_system=None, file=io.StringIO()
    )
    print_frame(frame, console, height)
    return console.export_text()


def polygon(n: int, side: float) -> np.ndarray:
    """A regular n-gon of side `side` about (10, -5), robot 0 at its north point."""
    r = side / (2 * math.sin(math.pi / n))
    theta = 2 * math.pi * np.arange(n) / n
    return np.column_stack((10 + r * np.sin(theta), -5 + r * np.cos(theta)))


def hook_figures(algorithm: str, positions: np.ndarray, **params: object) -> dict[str, float]:
    """What the algorithm's own `figures` hook gives, as the world publishes it."""
    return Configured.of(load_algorithm(algorithm), len(positions), params).figures(positions)


def paper_frame(**fields: Any) -> Frame:
    """A frame of the paper's algorithm (a = 4 unless given), with the figures its hook gives;
    `fields` are Frame's own."""
    positions = np.asarray(fields["positions"], dtype=np.float64)
    a = fields.pop("a", 4.0)
    figures = hook_figures("uniform-circle", positions, a=a)
    return Frame(params={"a": a}, figures=figures, **fields)


SAMPLE_POSITIONS = np.array([[0.0, 0.0], [8.0, 0.0], [0.0, 8.0], [-6.0, -5.0]])


def sample_frame(**changes: object) -> Frame:
    fields: dict[str, object] = dict(
        round=7,
        n=4,
        a=4.0,
        figures=hook_figures("uniform-circle", SAMPLE_POSITIONS, a=4.0),
        scheduler="ssync",
        positions=SAMPLE_POSITIONS,
        active=(1, 2),
        moved=(1,),
        stopped=(2,),
        collisions_total=3,
        alive=(True, True, False, True),
        last_active=(3, 7, 7, -1),
        last_path_length=(0.0, 1.5, 0.25, 0.0),
        timeouts=(0, 0, 2, 0),
        rounds_per_second=12.5,
        swarm="lab",
    )
    fields.update(changes)
    return Frame(**fields)  # type: ignore[arg-type]


def test_counters_show_round_scheduler_collisions_rate_and_alive() -> None:
    text = render_text(sample_frame())
    assert re.search(r"round\s+7\b", text)
    assert re.search(r"scheduler\s+ssync", text)
    assert re.search(r"collisions\s+3\b", text)
    assert re.search(r"rounds/s\s+12\.5\b", text)
    assert re.search(r"alive\s+3 / 4\b", text)
    assert re.search(r"timeouts\s+2\b", text)
    assert re.search(r"2 active\s+1 moved\s+1 stopped", text)
    assert "swarm lab" in text


def test_counters_show_sec_radius_against_target_radius() -> None:
    frame = sample_frame()
    fig = derive(frame)
    # r = a* / (2 sin(pi/n)) with a* = max(a, 4) = 4 and n = 4
    assert fig.target_radius == pytest.approx(4 / (2 * math.sin(math.pi / 4)))
    text = render_text(frame)
    assert re.search(rf"r_c / r\s+{fig.sec_radius:.3f} / {fig.target_radius:.3f}", text)


def test_agents_panel_lists_alive_last_activation_path_length_and_timeouts() -> None:
    text = render_text(sample_frame())
    assert re.search(r"\b2\s+NO\s+7\s+0\.250\s+2\b", text)
    assert re.search(r"\b1\s+yes\s+7\s+1\.500\s+0\b", text)
    assert re.search(r"\b3\s+yes\s+never\s+0\.000\s+0\b", text)
    # this round's active robots come first
    assert text.index(" NO ") < text.index("never")


def test_info_grid_names_the_algorithm_and_its_parameters() -> None:
    assert re.search(r"robots\s+n=4  uniform-circle a=4\b", render_text(sample_frame()))
    frame = Frame(
        round=1,
        n=3,
        scheduler="fsync",
        positions=SAMPLE_POSITIONS[:3],
        algorithm="spread-out",
        params={"spacing": 5.0, "step": 1.0, "mode": "wide"},
    )
    # parameters that do not fit go on to the next line, never cut
    lines = run_lines(frame, 31)
    assert " ".join(lines) == "n=3  spread-out spacing=5 step=1 mode=wide" and len(lines) == 2
    text = render_text(frame)
    assert re.search(rf"robots\s+{lines[0]}\s", text) and re.search(rf"\s{lines[1]}\s+│", text)


def test_gathering_frame_draws_the_sec_but_no_targets_and_shows_its_spread() -> None:
    pts = polygon(6, 4.0)
    figures = hook_figures("gathering", pts)
    frame = Frame(
        round=4,
        n=6,
        scheduler="fsync",
        positions=pts,
        algorithm="gathering",
        params={"tolerance": 0.001},
        figures=figures,
    )
    derived = derive(frame)
    assert derived.target_radius is None and derived.filled is None and not len(derived.targets)
    layers = build_canvas(frame, derived, cols=60, rows=30).cell_layers()
    assert (layers == LAYER_SEC).any()
    assert not (layers == LAYER_TARGET).any() and not (layers == LAYER_TARGET_CIRCLE).any()
    text = render_text(frame)
    assert re.search(rf"spread\s+{figures['spread']:.3f}\b", text)
    assert re.search(rf"r_c\s+{derived.sec_radius:.3f}\b", text)
    assert "targets" not in text and "r_c / r" not in text and "circle r" not in text
    assert "target radius" not in text
    assert f"spread {figures['spread']:.3f}" in progress_line(frame)
    assert "targets" not in progress_line(frame)


def test_paper_frame_draws_its_targets_because_its_figures_give_a_target_radius() -> None:
    frame = sample_frame()
    assert set(frame.figures) == {"target radius"}
    derived = derive(frame)
    assert derived.target_radius == frame.figures["target radius"] and derived.filled is not None
    layers = build_canvas(frame, derived, cols=60, rows=30).cell_layers()
    assert (layers == LAYER_TARGET_CIRCLE).any() and (layers == LAYER_TARGET).any()
    text = render_text(frame)
    # the figure is the r of `r_c / r`: not a row of its own as well
    assert re.search(rf"r_c / r\s+\S+ / {derived.target_radius:.3f}\b", text)
    assert "target radius" not in text
    assert "circle r" in text and "targets" in text
    # the same positions without the figure: the paper's algorithm is not assumed
    bare = derive(sample_frame(figures={}))
    assert bare.target_radius is None and not len(bare.targets)


def test_every_figure_is_a_row_and_labels_are_shown_as_they_are() -> None:
    figures = {"[bold]x": 0.5, "tiny": 1.5e-7, "huge": 3.2e9, "zero": 0.0}
    text = render_text(sample_frame(algorithm="mine", params={}, a=None, figures=figures))
    assert re.search(r"\[bold\]x\s+0\.500\b", text)
    assert re.search(r"tiny\s+1\.5e-07\b", text) and re.search(r"huge\s+3\.2e\+09\b", text)
    assert re.search(r"zero\s+0\.000\b", text)
    assert figure_text(12.3456) == "12.346"


def test_figure_rows_are_capped_with_a_line_saying_how_many_more() -> None:
    figures = {f"f{i}": float(i) for i in range(MAX_FIGURE_ROWS + 3)}
    text = render_text(sample_frame(figures=figures), height=50)
    assert "… 4 more figures" in text
    assert re.search(rf"f{MAX_FIGURE_ROWS - 2}\s+", text) and "f10" not in text


def test_frame_a_is_the_same_as_the_parameter_a() -> None:
    pts = polygon(3, 4.0)
    assert Frame(round=0, n=3, scheduler="fsync", positions=pts, a=5.0).params == {"a": 5.0}
    assert Frame(round=0, n=3, scheduler="fsync", positions=pts, params={"a": 6}).a == 6.0
    gathering = Frame(
        round=0,
        n=3,
        scheduler="fsync",
        positions=pts,
        algorithm="gathering",
        params={"tolerance": 0.5},
    )
    assert gathering.a is None and gathering.params == {"tolerance": 0.5}


def test_agents_panel_lists_robots_by_number_whoever_is_active() -> None:
    alive = (True, True, True, False, True)
    positions = polygon(5, 4.0)
    frames = [
        Frame(
            round=k, n=5, a=4.0, scheduler="ssync", positions=positions, active=active, alive=alive
        )
        for k, active in enumerate([(4, 1), (0,), (2, 3)], start=1)
    ]
    for frame in frames:  # a row stays where it is from one round to the next
        assert agent_rows(frame) == [0, 1, 2, 3, 4]
        text = render_text(frame)
        rows = [int(m.group(1)) for m in re.finditer(r"│\s+(\d)\s+(?:yes|NO)\b", text)]
        assert rows == [0, 1, 2, 3, 4]


def test_rows_left_out_say_how_many_are_active_or_gone() -> None:
    n = 40
    alive = tuple(i != 35 for i in range(n))
    frame = Frame(
        round=2, n=n, a=4.0, scheduler="ssync", positions=polygon(n, 4.0),
        active=(1, 30, 31), alive=alive,
    )  # fmt: skip
    text = render_text(frame, height=30)
    assert re.search(r"… \d+ more robots \(2 active, 1 gone\)", text), text


def test_agents_panel_says_how_many_rows_did_not_fit() -> None:
    n = 60
    frame = Frame(round=1, n=n, a=4.0, scheduler="fsync", positions=polygon(n, 4.0))
    text = render_text(frame, height=30)
    match = re.search(r"… (\d+) more robots", text)
    assert match is not None and 0 < int(match.group(1)) < n


def test_robots_light_their_cells_with_active_and_stopped_marked() -> None:
    frame = sample_frame()
    canvas = build_canvas(frame, derive(frame), cols=60, rows=30)
    glyphs, layers = canvas.glyphs(), canvas.cell_layers()
    expected = {0: LAYER_ROBOT, 1: LAYER_ACTIVE, 2: LAYER_STOPPED, 3: LAYER_ROBOT}
    for robot, layer in expected.items():
        x, y = frame.positions[robot]
        col, row = canvas.viewport.to_cell(float(x), float(y))
        assert glyphs[row][col] != " ", robot
        assert layers[row, col] == layer, robot


def test_canvas_is_blank_away_from_everything_drawn() -> None:
    frame = sample_frame(positions=np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [2.0, 2.0]]))
    canvas = build_canvas(frame, derive(frame), cols=60, rows=30)
    # the top-left corner lies outside the SEC, the target circle and every disc
    assert canvas.glyphs()[0][0] == " "


def test_formed_polygon_fills_every_target_and_says_formed() -> None:
    n = 6
    pts = polygon(n, 4.0)
    frame = paper_frame(round=42, n=n, scheduler="fsync", positions=pts, status="formed")
    fig = derive(frame)
    assert fig.filled == n
    assert fig.sec_radius == pytest.approx(fig.target_radius)
    canvas = build_canvas(frame, fig, cols=60, rows=30)
    for x, y in fig.targets:
        col, row = canvas.viewport.to_cell(float(x), float(y))
        assert canvas.cell_layers()[row, col] >= LAYER_ROBOT  # a disc sits on each target
    text = render_text(frame)
    assert re.search(r"targets\s+6 / 6 filled", text)
    assert "FORMED: uniform-circle goal reached by 6 robots after 42 rounds, 0 collisions" in text


def test_empty_targets_are_marked_on_the_canvas() -> None:
    n = 6
    pts = polygon(n, 4.0) * 0.0 + np.array([[0.0, 0.0]]) + np.arange(n)[:, None] * [2.5, 0.0]
    frame = paper_frame(round=1, n=n, scheduler="fsync", positions=pts)
    fig = derive(frame)
    assert fig.filled is not None and fig.filled < n
    canvas = build_canvas(frame, fig, cols=80, rows=40)
    marked = [
        canvas.cell_layers()[row, col]
        for col, row in (canvas.viewport.to_cell(float(x), float(y)) for x, y in fig.targets)
    ]
    assert LAYER_TARGET in marked


@pytest.mark.parametrize(
    ("status", "words"),
    [
        ("stalled", "STALLED after 9 rounds"),
        ("max_rounds", "NOT FORMED: stopped at the round limit (9 rounds)"),
        ("running", "running: round 9"),
    ],
)
def test_outcome_line_names_how_the_run_ended(status: str, words: str) -> None:
    assert outcome_text(sample_frame(round=9, status=status)).startswith(words)


def test_progress_log_prints_every_k_rounds_and_the_outcome() -> None:
    lines: list[str] = []
    log = ProgressLog(out=lines.append, every=10)
    for r in range(0, 26):
        log.show(sample_frame(round=r, status="running"))
    log.close(sample_frame(round=26, status="formed"))
    assert [int(line.split()[1]) for line in lines[:-2]] == [0, 10, 20]
    assert lines[-2].startswith("round 26 formed")
    assert lines[-1].startswith("FORMED")
    assert "collisions 3" in lines[0] and "12.5 rounds/s" in lines[0]


def test_rate_meter_counts_rounds_per_second_over_its_window() -> None:
    meter = RateMeter(window=2.0)
    assert meter.add(0.0, 0) is None
    assert meter.add(0.5, 10) == pytest.approx(20.0)
    assert meter.add(1.0, 30) == pytest.approx(30.0)
    meter.add(10.0, 40)  # older samples leave the window
    assert meter.add(10.5, 45) == pytest.approx(10.0)
    assert meter.add(11.0, 1) is None  # a new run starts over


def test_frame_from_world_state_carries_every_field() -> None:
    agents = tuple(
        AgentInfo(alive=i != 1, last_active=i, last_path_length=0.5 * i, timeouts=i)
        for i in range(3)
    )
    state = WorldState(
        round=5, n=3,
        algorithm="uniform-circle", params={"a": 4.5}, figures={"target radius": 2.598},
        scheduler="centralized", swarm="s",
        positions=np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]]), active=(2,), open_round=0,
        moved=(2,),
        stopped=(), collisions_total=0, status=Status.RUNNING, agents=agents,
    )  # fmt: skip
    frame = frame_from_state(WorldState.decode(state.encode()), rounds_per_second=3.0)
    assert (frame.round, frame.n, frame.a, frame.seed, frame.scheduler) == (
        5,
        3,
        4.5,
        None,  # the seed is never published: it would give away the private frames
        "centralized",
    )
    assert (frame.algorithm, frame.params) == ("uniform-circle", {"a": 4.5})
    assert frame.figures == {"target radius": 2.598}
    assert frame.alive == (True, False, True)
    assert frame.last_active == (0, 1, 2) and frame.timeouts == (0, 1, 2)
    assert frame.last_path_length == (0.0, 0.5, 1.0)
    assert frame.active == (2,) and frame.rounds_per_second == 3.0
    assert re.search(r"rounds/s\s+3\.0", render_text(frame))


def test_svg_of_a_frame_holds_the_counters(tmp_path: object) -> None:
    import pathlib

    out = pathlib.Path(str(tmp_path)) / "frame.svg"
    save_svg(sample_frame(), str(out))
    svg = out.read_text()
    assert svg.startswith("<svg") and "collisions" in svg


def test_cli_gives_each_command_its_own_flags() -> None:
    from fatswarm.deploy.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["dashboard", "--connect", "tcp/127.0.0.1:7447", "--exit-at-end"])
    assert (args.connect, args.swarm, args.exit_at_end) == ("tcp/127.0.0.1:7447", "default", True)
    with pytest.raises(SystemExit):
        parser.parse_args(["dashboard", "--no-dashboard"])  # --connect is required


def test_run_flags_and_dashboard_flags_parse() -> None:
    run = argparse.ArgumentParser()
    add_run_arguments(run)
    args = run.parse_args(["--no-dashboard", "--svg", "x.svg"])
    assert args.no_dashboard and args.svg == "x.svg"
    dash = argparse.ArgumentParser()
    add_arguments(dash)
    args = dash.parse_args(["--connect", "tcp/127.0.0.1:7447", "--swarm", "lab"])
    assert (args.connect, args.swarm, args.exit_at_end) == ("tcp/127.0.0.1:7447", "lab", False)


class FakeSample:
    def __init__(self, data: bytes) -> None:
        self.payload = self
        self.data = data

    def to_bytes(self) -> bytes:
        return self.data


class FakeSubscriber:
    def __init__(self, samples: list[bytes]) -> None:
        self.samples = samples
        self.undeclared = False

    def try_recv(self) -> FakeSample | None:
        return FakeSample(self.samples.pop(0)) if self.samples else None

    def undeclare(self) -> None:
        self.undeclared = True


class FakeSession:
    """Stands in for an open Zenoh session: records what the watcher subscribes to."""

    def __init__(self, samples: list[bytes]) -> None:
        self.subscriber = FakeSubscriber(samples)
        self.declared: list[tuple[str, object]] = []

    def declare_subscriber(self, key: str, handler: object) -> FakeSubscriber:
        self.declared.append((key, handler))
        return self.subscriber


def state(round_no: int, status: str = "running") -> WorldState:
    agents = tuple(AgentInfo(True, round_no, 1.0, 0) for _ in range(3))
    positions = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    return WorldState(
        round=round_no, n=3,
        algorithm="uniform-circle", params={"a": 4.0},
        figures=hook_figures("uniform-circle", positions, a=4.0),
        scheduler="fsync", swarm="w",
        positions=positions, active=(0, 1, 2), open_round=0, moved=(),
        stopped=(), collisions_total=0, status=Status(status), agents=agents,
    )  # fmt: skip


def test_watcher_reads_the_state_key_through_a_ring_of_one_and_logs_progress(
    tmp_path: object,
) -> None:
    import pathlib

    import zenoh

    samples = [state(r).encode() for r in (1, 2, 3)] + [b"garbage"] + [state(4, "stalled").encode()]
    session = FakeSession(samples)
    lines: list[str] = []
    svg = pathlib.Path(str(tmp_path)) / "end.svg"
    watcher = StateWatcher(
        "w", ProgressLog(out=lines.append, every=2), session=session, fps=200.0,
        stop_at_end=True, svg=str(svg),
    )  # fmt: skip
    watcher.start()
    assert watcher.finished.wait(10.0)
    watcher.stop()
    key, handler = session.declared[0]
    assert key == "fatswarm/w/world/state"
    assert isinstance(handler, zenoh.handlers.RingChannel)
    assert session.subscriber.undeclared and watcher.error is None
    assert [line.split()[1] for line in lines[:-1]] == ["1", "2", "4"]  # every 2, then the end
    assert lines[-1].startswith("STALLED after 4 rounds")
    assert svg.read_text().startswith("<svg")


def test_watcher_stop_shows_the_final_state_it_is_given() -> None:
    lines: list[str] = []
    watcher = StateWatcher("w", ProgressLog(out=lines.append), session=FakeSession([]))
    watcher.start()
    watcher.stop(state(9, "formed"))
    assert lines[-1] == (
        "FORMED: uniform-circle goal reached by 3 robots after 9 rounds, 0 collisions"
    )


@pytest.mark.parametrize("quiet", [False, True])
def test_follow_prints_progress_lines_off_a_terminal_unless_quiet(
    quiet: bool, capsys: pytest.CaptureFixture[str]
) -> None:
    args = argparse.Namespace(no_dashboard=False, quiet=quiet, svg=None, max_rounds=100)
    session = FakeSession([state(1).encode(), state(2, "formed").encode()])
    watcher = follow(args, "w", session=session)
    assert watcher.ended.wait(10.0)
    watcher.stop()
    out = capsys.readouterr().out
    if quiet:
        assert out == ""
    else:
        assert out.splitlines()[0].startswith("round 1 running: targets")
        assert out.splitlines()[-1].startswith("FORMED: uniform-circle goal reached by 3 robots")


def test_the_enclosing_circle_is_right_far_from_the_origin() -> None:
    # A swarm at 1e5: the SEC's rounding slack is relative to its radius, so it is computed
    # relative to a robot (on world coordinates an equilateral triangle of side 4 came out r = 2).
    tri = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 2.0 * math.sqrt(3.0)]])
    for offset in (0.0, 1e5, -1.5e6):
        (cx, cy), rc = enclosing_circle(tri + offset)
        assert rc == pytest.approx(4.0 / math.sqrt(3.0), abs=1e-9)
        assert (cx - offset, cy - offset) == pytest.approx((2.0, 2.0 / math.sqrt(3.0)), abs=1e-9)


@pytest.mark.parametrize("status", ENDED)
def test_the_statuses_that_end_a_run_are_world_outcomes(status: Status) -> None:
    watcher = StateWatcher(
        "w", ProgressLog(out=lambda line: None), session=FakeSession([state(3, status).encode()]),
        fps=200.0, stop_at_end=True,
    )  # fmt: skip
    watcher.start()
    assert watcher.finished.wait(10.0) and watcher.ended.is_set()
    watcher.stop()
    lines: list[str] = []
    log = ProgressLog(out=lines.append)
    log.show(sample_frame(status=status))
    assert lines == []  # an ended run is said once, when the log closes
    log.close(None)
    assert lines[-1] == outcome_text(sample_frame(status=status)) != "running: round 7"


def test_the_final_frame_stays_on_the_main_screen_with_room_for_the_summary() -> None:
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=120, height=40, color_system=None)
    view = LiveView(console)
    view.show(sample_frame(round=3))
    view.close(sample_frame(round=9, status="formed", collisions_total=0))
    raw = out.getvalue()
    left = raw.rfind("\x1b[?1049l")  # the live view leaves the alternate screen, then prints
    assert left > raw.find("\x1b[?1049h") >= 0
    after = re.sub(r"\x1b\[[0-?]*[ -/]*[@-~]", "", raw[left:])
    assert "FORMED: uniform-circle goal reached by 4 robots after 9 rounds" in after
    frame_lines = after[after.index("fatswarm · live") :].rstrip("\n").split("\n")
    assert len(frame_lines) <= 40 - 5  # the summary and the prompt fit below it
