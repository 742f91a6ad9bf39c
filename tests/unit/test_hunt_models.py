"""The robot model's axes in `fatswarm hunt`: drawn per candidate like the scheduler (a hunt of the
paper's model draws what it always drew), held by the failure's case through its replay and
shrinking, and said by its saved command and summary.json. No process: a real hunt whose saved
command replays it is tests/integration/test_hunt_models_workers.py."""

from __future__ import annotations

import argparse
import io
import shlex
from dataclasses import replace
from pathlib import Path

from rich.console import Console

from fatswarm.deploy.commands.run import add_arguments as add_run_arguments
from fatswarm.deploy.engine.config import model_from_args
from fatswarm.deploy.hunt.files import replay_argv, replay_command, summary_data
from fatswarm.deploy.hunt.pool import Saved
from fatswarm.deploy.hunt.report import summary_table
from fatswarm.deploy.hunt.search import (
    Case,
    Hunt,
    configure,
    draw_candidate,
    invariants,
    run_candidate,
    start_families,
)
from fatswarm.deploy.hunt.shrink import replay, shrink
from fatswarm.deploy.sweep.grid import parse_robot_models
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel

ROOT = Path(__file__).resolve().parents[2]
PLANTED = f"{ROOT / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
ROUND_MODELS = ("fsync", "ssync", "centralized")
PLAIN = Hunt(PLANTED, (), start_families(), tuple(range(3, 7)), ROUND_MODELS)
MODELS = parse_robot_models({"frames": ["y-axis,chirality"], "sight": ["unlimited,8"]})


def run_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    add_run_arguments(p)
    return p


def first_failure(hunt: Hunt, seed: int = 1) -> Case:
    for i in range(30):
        outcome, case = run_candidate(hunt, draw_candidate(hunt, seed, i))
        if case is not None and outcome.failure is not None:
            return case
    raise AssertionError("the planted algorithm did not fail in 30 candidates")


def test_the_robot_model_is_drawn_last_so_the_rest_of_a_candidate_is_unchanged() -> None:
    crossed = replace(PLAIN, robot_models=MODELS)
    plain = [draw_candidate(PLAIN, 5, i) for i in range(40)]
    drawn = [draw_candidate(crossed, 5, i) for i in range(40)]
    assert all(c.robot_model == PAPER_MODEL for c in plain)
    assert [replace(c, robot_model=PAPER_MODEL) for c in drawn] == plain
    assert {c.robot_model for c in drawn} == set(MODELS)
    assert drawn == [draw_candidate(crossed, 5, i) for i in range(40)]
    only = replace(PLAIN, robot_models=(MODELS[3],))
    assert {draw_candidate(only, 5, i).robot_model for i in range(10)} == {MODELS[3]}


def test_the_sec_promise_is_held_under_the_papers_model_only() -> None:
    setting = configure(Hunt(), 5)
    assert len(invariants(Hunt(), setting, "fsync")) == 1
    assert len(invariants(Hunt(), setting, "fsync", PAPER_MODEL)) == 1
    for model in MODELS[1:]:
        assert invariants(Hunt(), setting, "fsync", model) == []


def test_a_failure_keeps_its_model_through_replay_shrinking_and_its_files() -> None:
    model = RobotModel.of(sight=8.0, frames="chirality")
    hunt = replace(PLAIN, robot_models=(model,), record_views=True)
    case = first_failure(hunt)
    assert case.robot_model == model
    failure = replay(hunt, case).failure
    assert failure is not None
    shrunk = shrink(hunt, case, failure.kind, budget=8)
    assert shrunk.reproduced and shrunk.case.robot_model == model
    argv = replay_argv(hunt, shrunk.case)
    assert argv[argv.index("--sight") : argv.index("--sight") + 4] == [
        "--sight",
        "8.0",
        "--frames",
        "chirality",
    ]
    assert "--record-views" in argv and "--visibility" not in argv
    args = run_parser().parse_args(argv[2:])
    assert model_from_args(args) == model and args.record_views
    candidate = draw_candidate(hunt, 1, 0)
    summary = summary_data(hunt, 1, candidate, failure, shrunk, case, failure)
    assert summary["found"]["model"] == model.to_header()
    assert summary["hunt"]["record_views"] is True
    assert summary["command"] == replay_command(hunt, shrunk.case)
    out = io.StringIO()
    Console(file=out, width=200).print(summary_table([Saved(candidate, "000000-x", summary)]))
    assert f"{candidate.model}+sight8+chirality" in out.getvalue()


def test_a_failure_of_the_papers_model_saves_what_it_always_saved() -> None:
    case = first_failure(PLAIN)
    assert case.robot_model == PAPER_MODEL
    argv = replay_argv(PLAIN, case)
    for flag in ("--visibility", "--sight", "--lights", "--frames", "--frame-change"):
        assert flag not in argv
    assert "--record-views" not in argv
    args = run_parser().parse_args(shlex.split(replay_command(PLAIN, case))[2:])
    assert model_from_args(args) == PAPER_MODEL
    failure = replay(PLAIN, case).failure
    assert failure is not None
    shrunk = shrink(PLAIN, case, failure.kind, budget=2)
    summary = summary_data(PLAIN, 1, draw_candidate(PLAIN, 1, 0), failure, shrunk, case, None)
    assert "model" not in summary["found"] and "record_views" not in summary["hunt"]
