"""The words a user reads for counts, decided in one place (fatswarm.domain.words): "1 round" and
never "1 rounds"; "cycle" wherever an async run is counted (the dashboard, the summary, the hunt's);
the robot model named in one word wherever a run is summed up."""

from __future__ import annotations

import io
from collections import Counter
from typing import Any

import pytest
from rich.console import Console

from fatswarm.deploy.hunt import search
from fatswarm.deploy.hunt.pool import Saved, Tally
from fatswarm.deploy.hunt.report import print_summary, summary_table
from fatswarm.deploy.view import summary
from fatswarm.domain.outcome import Status
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.words import counted, plural, unit, units


def test_a_count_of_one_is_singular_and_every_other_plural() -> None:
    assert counted(1, "round") == "1 round" and counted(0, "round") == "0 rounds"
    assert counted(1.0, "round") == "1 round" and counted(0.5, "round") == "0.5 rounds"
    assert counted(2, "process", "processes") == "2 processes"
    assert counted(1, "process", "processes") == "1 process"
    assert plural("robot model", 1) == "robot model" and plural("robot model", 3) == "robot models"


@pytest.mark.parametrize(
    ("scheduler", "word"),
    [("fsync", "round"), ("ssync", "round"), ("scripted", "round"), ("async", "cycle"),
     ("async-slowest", "cycle")],
)  # fmt: skip
def test_one_function_of_the_scheduler_says_what_a_run_counts(scheduler: str, word: str) -> None:
    assert unit(scheduler) == word and units(scheduler) == word + "s"
    assert summary.unit is unit  # the summary's is the same one


def _saved(scheduler: str, at: int) -> Saved:
    data: dict[str, Any] = {
        "kind": "max_rounds",
        "round": at,
        "replayed": {"kind": "max_rounds"},
        "found": {"family": "rim", "n": 5, "scheduler": scheduler, "decimals": 16,
                  "model": {"visibility": "opaque"}},
        "shrunk": {"n": 3, "script_rounds": None, "decimals": 4, "runs": 9},
    }  # fmt: skip
    return Saved(None, "out/000000-max_rounds", data)  # type: ignore[arg-type]


def test_the_hunts_table_says_where_each_failure_is_in_its_runs_unit() -> None:
    out = io.StringIO()
    table = summary_table([_saved("async-slowest", 40), _saved("ssync", 7)])
    Console(file=out, width=200, color_system=None).print(table)
    text = out.getvalue()
    assert "cycle 40" in text and "round 7" in text and "async-slowest+opaque" in text


def test_the_hunts_counts_say_one_run_not_one_runs() -> None:
    out = io.StringIO()
    print_summary(Tally(runs=1, refused=1, kinds=Counter()), out)
    assert out.getvalue().startswith("1 run, 1 start refused; failures found: none")


@pytest.mark.parametrize("word", ["round", "cycle"])
def test_a_hunts_failure_of_an_ended_run_is_told_in_its_unit(word: str) -> None:
    capped = search._ended_failure(Status.MAX_ROUNDS, 1, word)
    assert capped is not None and capped.detail == f"still running at the {word} cap (1 {word})"
    stalled = search._ended_failure(Status.STALLED, 12, word)
    assert stalled is not None and stalled.detail.startswith(f"stalled after 12 {word}s:")


def _outcome(**changes: Any) -> summary.Outcome:
    fields: dict[str, Any] = dict(
        status=Status.FORMED, rounds=1, collisions=0, n=8, a=4.0, seed=3, scheduler="ssync",
        epochs=1, moves=8, total_distance=12.5,
    )  # fmt: skip
    return summary.Outcome(**{**fields, **changes})


def test_the_summary_names_the_robot_model_in_one_word() -> None:
    assert summary.summary(_outcome()).splitlines()[1].endswith(" model=paper")
    header = {"model": RobotModel.of(visibility="opaque", sight=5.0).to_header()}
    noted = _outcome().noted(header)
    lines = summary.summary(noted).splitlines()
    assert lines[1].endswith(" model=opaque+sight5")
    assert "model: --visibility opaque --sight 5.0" in lines  # the flags that repeat it
    assert _outcome().noted({"model": {"visibility": "foggy"}}).model_label == "unreadable"


def test_every_line_of_a_summary_fits_80_columns_but_the_verdict_is_one_line() -> None:
    o = _outcome(
        scheduler="async-slowest", rounds=12345, epochs=321, moves=4321, time=1234.5,
        derived={"min_gap": 0.125, "failures": 1, "first_failure": "robot 2 in cycle 3: boom"},
    )  # fmt: skip
    lines = summary.summary(o).splitlines()
    assert lines[0].startswith("formed in 12345 cycles, collision-free; the algorithm failed")
    assert all(len(line) <= 80 for line in lines[1:]), lines
    figures = "  ".join(lines[2:])
    for part in ("cycles 12345", "epochs 321", "min gap 0.125", "virtual time 1234.500"):
        assert part in figures


@pytest.mark.parametrize(
    ("is_async", "one", "two"),
    [(False, "1 round", "2 rounds"), (True, "1 unit of virtual time", "2 units of virtual time")],
)
def test_a_video_of_one_round_a_second_says_one_round(is_async: bool, one: str, two: str) -> None:
    from fatswarm.deploy.view.animate import Clip, clip_line

    line = clip_line(Clip(0, 9, 0.0, 9.0, 181, 20.0, 1.0), is_async, "run.gif")
    assert f"20 fps, {one} per second) to run.gif" in line
    twice = clip_line(Clip(0, 9, 0.0, 9.0, 91, 20.0, 2.0), is_async, "run.gif")
    assert f"20 fps, {two} per second) to run.gif" in twice


def test_a_results_repr_and_summary_name_the_robot_model(tmp_path: Any) -> None:
    import fatswarm

    path = tmp_path / "run.jsonl"
    result = fatswarm.run(n=4, seed=1, visibility="opaque", sight=9.0, record=path)
    assert "model='opaque+sight9'" in repr(result)
    assert fatswarm.summary(result)["model"] == "opaque+sight9"
    assert fatswarm.summary(fatswarm.read_record(path))["model"] == "opaque+sight9"
    assert fatswarm.summary(fatswarm.run(n=4, seed=1))["model"] == "paper"
