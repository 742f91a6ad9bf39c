"""`fatswarm.Swarm`: the lock step advanced one record line at a time. Its record equals `fatswarm
run --lockstep`'s byte for byte (the header's `command` aside), stepped or run straight through;
its views are what the world serves the next Look; its refusals are one line each."""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import io
import json
import sys
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.engine import api, swarm
from fatswarm.domain import figures
from fatswarm.world.record import RecordWriter

DATA = Path(__file__).resolve().parents[1] / "data"
LIT = f"{DATA / 'lit_spread.py'}:ALGORITHM"  # a luminous test algorithm (limited sight)
DOC = Path(__file__).resolve().parents[2] / "docs" / "notebook.md"

# name: (flags of `fatswarm run --lockstep`, the same as keywords, a key its round lines carry)
CASES: dict[str, tuple[list[str], dict[str, Any], str | None]] = {
    "fsync": (["-n", "5", "--seed", "2", "--scheduler", "fsync"], {"n": 5, "seed": 2,
              "scheduler": "fsync"}, None),
    "ssync": (["-n", "6", "--seed", "1"], {"n": 6, "seed": 1}, None),
    "async": (["-n", "4", "--seed", "3", "--scheduler", "async"], {"n": 4, "seed": 3,
              "scheduler": "async"}, "end"),
    "luminous": (["-n", "5", "--seed", "1", "--algorithm", LIT, "--sight", "6"],
                 {"n": 5, "seed": 1, "algorithm": LIT, "sight": 6.0}, "lights"),
    "opaque-views": (["-n", "5", "--seed", "4", "--scheduler", "fsync", "--algorithm",
                      "gathering", "--visibility", "opaque", "--record-views"],
                     {"n": 5, "seed": 4, "scheduler": "fsync", "algorithm": "gathering",
                      "visibility": "opaque", "record_views": True}, "views"),
}  # fmt: skip


def cli_record(path: Path, flags: list[str]) -> bytes:
    """`fatswarm run --lockstep -q --record PATH FLAGS` in this process: its record, with the
    header's `command` (the API writes none) left out, every other byte as written."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert cli.main(["run", "--lockstep", "-q", "--record", str(path), *flags]) in (0, 1, 3)
    header, rest = path.read_bytes().split(b"\n", 1)
    fields = json.loads(header)
    assert fields.pop("command")[1:4] == ["run", "--lockstep", "-q"]
    return json.dumps(fields, separators=(",", ":")).encode() + b"\n" + rest


def written(record: fatswarm.RunRecord, path: Path) -> bytes:
    """An in-memory record's lines, written by the record's one writer."""
    with RecordWriter(path) as writer:
        for line in (record.header, *record.rounds, record.result):
            assert line is not None
            writer.append(line)
    return path.read_bytes()


def stepped_to_the_end(sw: swarm.Swarm) -> list[swarm.Step]:
    steps = []
    while sw.status == "running":
        steps.append(sw.step())
    return steps


@pytest.mark.parametrize("case", CASES)
def test_a_swarm_stepped_to_the_end_writes_the_record_of_run_lockstep(
    case: str, tmp_path: Path
) -> None:
    flags, keywords, key = CASES[case]
    expected = cli_record(tmp_path / "cli.jsonl", flags)
    on_file = swarm.Swarm(**keywords, record=tmp_path / "stepped.jsonl")
    steps = stepped_to_the_end(on_file)
    assert (tmp_path / "stepped.jsonl").read_bytes() == expected
    in_memory = swarm.Swarm(**keywords).run()
    assert in_memory.record.path is None
    assert written(in_memory.record, tmp_path / "memory.jsonl") == expected
    lines = expected.splitlines()
    assert [s.round for s in steps] == list(range(1, len(lines) - 1))  # one line a step
    assert key is None or all(key in json.loads(line) for line in lines[1:-1])
    assert repr(in_memory.result) == repr(fatswarm.run(**keywords))  # the API's own result
    assert on_file.result is not None and on_file.result.record == on_file.record.path
    assert repr(dataclasses.replace(on_file.result, record=None)) == repr(in_memory.result)


@pytest.mark.parametrize("case", ["async", "luminous", "opaque-views"])
def test_stepping_then_going_on_gives_the_record_of_a_run_straight_through(
    case: str, tmp_path: Path
) -> None:
    _, keywords, _ = CASES[case]
    fatswarm.run(**keywords, record=tmp_path / "straight.jsonl")
    sw = swarm.Swarm(**keywords, record=tmp_path / "stepped.jsonl")
    for _ in range(3):
        sw.step()
        for robot in range(sw.n):
            sw.view(robot)  # a view asked for changes nothing of the run (views recorded too)
    sw.run(until=6).run(until=lambda s: s.round >= 9)
    assert sw.round == 9 and len(fatswarm.read_record(tmp_path / "stepped.jsonl").rounds) == 9
    sw.run()
    assert (tmp_path / "stepped.jsonl").read_bytes() == (tmp_path / "straight.jsonl").read_bytes()


def test_the_record_so_far_is_the_lines_stepped_to_in_memory_and_on_file(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    sw = swarm.Swarm(6, seed=1, scheduler="fsync", record=path)
    assert len(path.read_bytes().splitlines()) == 1  # the header, at once
    sw.run(until=3)
    record, on_file = sw.record, fatswarm.read_record(path)
    assert isinstance(record, fatswarm.RunRecord) and record.path == str(path)
    assert record.status == on_file.status == "unfinished" and sw.result is None
    assert [e.round for e in record.rounds] == [e.round for e in on_file.rounds] == [1, 2, 3]
    assert np.array_equal(record.rounds[-1].positions, sw.positions)


def test_an_async_step_is_one_ended_cycle_even_when_the_world_ends_several_at_once() -> None:
    sw = swarm.Swarm(4, seed=1, scheduler="async")
    assert sw.time == 0.0 and sw.round == 0
    times: list[float] = []
    ahead = 0
    while sw.status == "running":
        step = sw.step()
        ahead = max(ahead, len(sw._pending))  # lines the world ended in the same exchange
        assert len(step.active) == 1 and step.round == sw.round == len(times) + 1
        assert np.array_equal(sw.positions, step.line.positions) and step.time == sw.time
        assert step.time is not None
        times.append(step.time)
    assert ahead >= 1  # this run has instants at which two or more cycles end
    assert times == sorted(times) and sw.record.result is not None
    assert "cycle=" in repr(sw) and "round=" not in repr(sw)


def test_a_step_says_what_the_round_did() -> None:
    sw = swarm.Swarm(6, seed=1, scheduler="fsync")
    step = sw.step()
    line = sw.record.rounds[-1]
    assert (step.round, step.active, step.moves) == (1, line.active, line.moves)
    assert step.figures == line.derived and step.time is None and step.line is line
    assert set(step.figures) == {f.name for f in figures.derived_figures()}
    assert repr(step).startswith("Step(round=1, active=(0, 1, 2, 3, 4, 5), moved=(")


def test_the_figures_so_far_are_the_declared_ones_the_run_knows() -> None:
    sw = swarm.Swarm(6, seed=1, scheduler="fsync")
    start = sw.figures
    assert (start["rounds"], start["moves"], start["status"], start["min_gap"]) == (
        0, 0, "running", None,
    )  # fmt: skip
    result = sw.run().result
    assert result is not None
    end = sw.figures
    assert list(end) == [f.name for f in figures.FIGURES if f.name in end]  # declared order
    assert {k: end[k] for k in ("rounds", "epochs", "moves", "collisions")} == {
        "rounds": result.rounds, "epochs": result.epochs, "moves": result.moves,
        "collisions": result.collisions,
    }  # fmt: skip
    assert end["total_distance"] == pytest.approx(result.total_distance)
    assert end["status"] == "formed" and end["looks"] == result.looks
    assert {k: end[k] for k in result.derived} == dict(result.derived)


def test_a_figure_declared_in_a_scratch_test_reaches_the_swarm(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    spread = figures.Figure(
        "spread_x", float, "robot radii", "a scratch figure", figures.Summary.MAX,
        derive=lambda p: float(np.ptp(p[:, 0])),
    )  # fmt: skip
    monkeypatch.setattr(figures, "FIGURES", (*figures.FIGURES, spread))
    sw = swarm.Swarm(5, seed=2, scheduler="fsync")
    step = sw.step()
    assert step.figures["spread_x"] == float(np.ptp(sw.positions[:, 0]))
    assert sw.figures["spread_x"] == step.figures["spread_x"]


def test_the_swarm_takes_the_keywords_of_run_from_its_one_signature() -> None:
    run = inspect.signature(fatswarm.run).parameters
    assert inspect.signature(fatswarm.Swarm).parameters == run
    assert {"visibility", "frames", "record_views", "on_round"} <= set(
        inspect.signature(fatswarm.Swarm).parameters
    )


def test_on_round_is_called_for_each_line_stepped_to() -> None:
    seen: list[int] = []
    sw = swarm.Swarm(4, seed=3, scheduler="async", on_round=lambda r: seen.append(r.entry.round))
    sw.step()
    sw.step()
    assert seen == [1, 2]


# --- views ----------------------------------------------------------------------------------------


def test_a_view_names_whom_the_next_look_sees_and_the_colours_it_reads() -> None:
    _, keywords, _ = CASES["opaque-views"]
    sw = swarm.Swarm(**{**keywords, "algorithm": LIT, "sight": 6.0})
    hidden = 0
    while sw.status == "running":
        views = {robot: sw.view(robot) for robot in range(sw.n)}
        lights = sw.lights
        step = sw.step()  # fsync: every robot Looks, as its view said
        recorded = step.line.extra["views"]
        for robot, view in views.items():
            assert view.round == step.round
            assert sorted(view.seen) == recorded[str(robot)]
            assert view.colours == tuple(lights[i] for i in view.seen)
            assert view.own == lights[robot]
            hidden += sw.n - 1 - len(view.seen)
    assert hidden > 0  # some robots were out of sight or hidden


def test_a_view_in_the_robots_frame_is_what_its_compute_is_given(tmp_path: Path) -> None:
    recorder = tmp_path / "swarm_view_recorder.py"
    recorder.write_text(
        "from fatswarm.domain.path import Line, Path\n"
        "SEEN = []\n"
        "class Recorder:\n"
        "    name, summary, parameters = 'recorder', 'records its views (a test)', ()\n"
        "    def make_params(self, n, values): return None\n"
        "    def compute(self, view, params):\n"
        "        SEEN.append(view.copy())\n"
        "        return Path((Line((0.25, 0.0)),))\n"
        "    def goal(self, positions, params): return False\n"
        "ALGORITHM = Recorder()\n"
    )
    sw = swarm.Swarm(
        4, seed=5, start="spread", scheduler="fsync", algorithm=f"{recorder}:ALGORITHM",
        frames="disoriented", frame_change="every-look", max_rounds=3,
    )  # fmt: skip
    views = []
    while sw.status == "running":
        views.append([sw.view(robot) for robot in range(sw.n)])
        before = sw.positions
        sw.step()
        for view in views[-1]:
            assert np.allclose(view.world, before[list(view.seen)], rtol=0.0, atol=1e-9)
    # every robot computes in every round (fsync), round after round (the world may run the
    # next round's Looks before a step returns: a Commit can open the next round at once)
    given = sys.modules["fatswarm_user_swarm_view_recorder"].SEEN
    assert len(given) == len(views) * sw.n == 3 * sw.n
    for k, round_views in enumerate(views):
        computed = given[k * sw.n : (k + 1) * sw.n]
        for view in round_views:
            assert sum(np.array_equal(view.local, c) for c in computed) == 1
    assert len({(v.frame.rotation, v.frame.mirror) for v in views[-1]}) == sw.n
    assert views[0][0].frame != views[1][0].frame  # a new frame at each Look


def test_a_view_in_the_papers_frames_is_the_positions_exactly() -> None:
    sw = swarm.Swarm(6, seed=1, scheduler="fsync")
    sw.step()
    view = sw.view(2)
    assert view.seen == tuple(sorted(view.seen, key=view.seen.index)) and 2 not in view.seen
    assert np.array_equal(view.world, sw.positions[list(view.seen)])
    assert view.colours is None and view.own is None and view.round == 2


# --- refusals -------------------------------------------------------------------------------------


def test_a_step_after_the_end_is_refused_in_one_line() -> None:
    sw = swarm.Swarm(5, seed=2, scheduler="fsync").run()
    with pytest.raises(swarm.SwarmEndedError) as caught:
        sw.step()
    assert str(caught.value) == (
        "the run has ended (formed in 7 rounds, collision-free): nothing left to step "
        "(read .result and .record)"
    )
    assert sw.run() is sw and sw.round == 7  # running on at the end: nothing to do


@pytest.mark.parametrize("robot", [6, -1])
def test_a_view_of_a_robot_out_of_range_is_refused_in_one_line(robot: int) -> None:
    sw = swarm.Swarm(6, seed=1, scheduler="fsync")
    with pytest.raises(swarm.NoSuchRobotError, match=r"^robot -?\d is not in this swarm: its "
                       r"robots are 0 to 5$"):  # fmt: skip
        sw.view(robot)
    with pytest.raises(IndexError):
        sw.view(robot)


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda sw: sw.view(1.0), api.RunArgumentError, "robot must be an int, got 1.0"),
        (lambda sw: sw.view(True), api.RunArgumentError, "robot must be an int, got True"),
        (lambda sw: sw.run(until="5"), api.RunArgumentError,
         "until must be a round number, a function of the swarm or None, got '5'"),
        (lambda sw: sw.run(until=1), ValueError, "round 1 has passed: the swarm is at round 2"),
    ],
)  # fmt: skip
def test_bad_use_is_refused_in_one_line(
    call: Callable[[swarm.Swarm], object], error: type[Exception], message: str
) -> None:
    sw = swarm.Swarm(6, seed=1, scheduler="fsync")
    sw.run(until=2)
    with pytest.raises(error) as caught:
        call(sw)
    assert str(caught.value) == message


@pytest.mark.parametrize(
    ("keywords", "message"),
    [
        ({"seed": "1"}, "seed must be an int, got '1'"),
        ({"n": 4, "colour": "red"}, "Swarm() got an unexpected keyword argument 'colour'"),
        ({"n": 4, "max_rounds": 0}, "max_rounds must be at least 1, got 0"),
        ({"n": 4, "visibility": "foggy"}, "visibility must be one of transparent, opaque, "),
    ],
)
def test_bad_settings_are_refused_as_run_refuses_them(
    keywords: dict[str, Any], message: str
) -> None:
    with pytest.raises(ValueError) as caught:
        swarm.Swarm(**keywords)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    if "Swarm()" not in message:
        with pytest.raises(ValueError) as by_run:
            fatswarm.run(**keywords)
        assert str(by_run.value) == str(caught.value)


def test_a_run_that_raised_half_way_is_not_stepped_on(monkeypatch: pytest.MonkeyPatch) -> None:
    sw = swarm.Swarm(5, seed=2, scheduler="fsync")

    def interrupted(*_: object) -> None:
        raise KeyboardInterrupt  # Ctrl-C in the middle of the round's Looks

    monkeypatch.setattr(sw._lockstep._bus, "_act", interrupted)
    with pytest.raises(KeyboardInterrupt):
        sw.step()
    for again in (sw.step, sw.run):
        with pytest.raises(RuntimeError) as caught:
            again()
        assert str(caught.value) == "the run stopped after round 0 when it raised KeyboardInterrupt"
    assert sw.status == "running" and sw.result is None and sw.record.status == "unfinished"


# --- as a notebook shows it -----------------------------------------------------------------------


def test_the_swarm_shows_as_one_line_and_a_picture() -> None:
    sw = fatswarm.Swarm(
        6, seed=1, scheduler="fsync", algorithm="gathering", visibility="opaque-centres", crash=1
    )
    assert repr(sw) == (
        "Swarm(n=6, algorithm='gathering', model='visibility=opaque-centres', "
        "scheduler='fsync', crash=1, round=0, status='running')"
    )
    sw.step()
    assert "round=1, status='running'" in repr(sw)
    svg = ET.fromstring(sw._repr_svg_())
    assert "running after 1 round" in "".join(svg.itertext())
    assert swarm.model_text(fatswarm.Swarm(3, seed=0).settings.robot_model) == "paper"


def test_the_notebook_page_steps_a_swarm() -> None:
    text = DOC.read_text()
    for part in ("fatswarm.Swarm(", ".step()", ".view(", ".run(until=", ".record", ".result"):
        assert part in text, part
