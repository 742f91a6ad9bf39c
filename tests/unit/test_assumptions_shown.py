"""A run outside its algorithm's declared assumptions goes ahead and says so everywhere a result is
shown: before it starts, the header, the summary, `--json`, `RunResult`, `fatswarm.summary()`,
the sweep's `outside` column, the hunt's summary, the dashboard and `fatswarm algorithms`."""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.commands.catalog import describe
from fatswarm.deploy.hunt.pool import Tally
from fatswarm.deploy.hunt.report import outside_text, print_summary
from fatswarm.deploy.sweep.grid import RunSpec
from fatswarm.deploy.sweep.table import RunFigures, make_row
from fatswarm.deploy.view.dashboard import render_frame
from fatswarm.deploy.view.panels import Frame
from fatswarm.domain.outcome import Status
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel
from fatswarm.domain.seam import assumptions_of
from fatswarm.world.observers import AgentInfo, WorldState

ASYNC = (
    "algorithm uniform-circle assumes scheduler fsync, ssync, centralized, scripted; "
    "this run gives it async (outside its assumption)"
)


def test_a_lockstep_run_outside_says_so_before_in_its_header_summary_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "r.jsonl"
    flags = ["run", "--lockstep", "-n", "3", "--seed", "1", "--scheduler", "async"]
    cli.main([*flags, "--max-rounds", "30", "--record", str(record)])
    captured = capsys.readouterr()
    assert captured.err.splitlines()[0] == f"fatswarm run: {ASYNC}"
    assert captured.out.count(ASYNC) == 1
    assert json.loads(record.read_text().splitlines()[0])["assumption"] == ASYNC
    cli.main([*flags, "--max-rounds", "30", "--json", "-q"])
    assert json.loads(capsys.readouterr().out)["assumption"] == ASYNC


def test_a_run_within_its_assumptions_says_nothing_and_its_header_has_no_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "r.jsonl"
    cli.main(["run", "--lockstep", "-n", "3", "--seed", "1", "--record", str(record)])
    captured = capsys.readouterr()
    assert "outside" not in captured.out + captured.err
    assert "assumption" not in json.loads(record.read_text().splitlines()[0])


def test_the_api_result_and_summary_carry_the_line_only_when_outside(tmp_path: Path) -> None:
    path = str(tmp_path / "r.jsonl")
    result = fatswarm.run(3, seed=1, scheduler="async", max_rounds=30, record=path)
    assert result.outside == ASYNC and f"outside={ASYNC!r}" in repr(result)
    assert fatswarm.summary(result)["outside"] == ASYNC
    assert fatswarm.summary(fatswarm.read_record(path))["outside"] == ASYNC
    within = fatswarm.run(3, seed=1, scheduler="ssync", max_rounds=30)
    assert within.outside == "" and "outside" not in fatswarm.summary(within)


def test_the_sweep_row_has_the_line_in_its_outside_column() -> None:
    spec = RunSpec("uniform-circle", 3, "random", "async", 1, (), None)
    row = make_row(spec, RunFigures("formed", outside=ASYNC), "0")
    assert row["outside"] == ASYNC
    assert make_row(spec, RunFigures("formed"), "0")["outside"] == ""


def test_the_hunt_says_each_way_its_draws_are_outside_once() -> None:
    assumptions = assumptions_of(load_algorithm("uniform-circle"))
    models = (PAPER_MODEL, RobotModel.of(frames="chirality"))
    text = outside_text("uniform-circle", assumptions, ("ssync", "async"), models, None)
    assert text == (
        "outside the assumptions of algorithm uniform-circle: scheduler async (it assumes "
        "fsync, ssync, centralized, scripted); frames chirality (it assumes y-axis)"
    )
    assert outside_text("uniform-circle", assumptions, ("ssync",), (PAPER_MODEL,), None) == ""
    out = io.StringIO()
    print_summary(Tally(), out, text)
    assert text in out.getvalue()


def test_the_dashboard_shows_the_line_and_the_state_carries_it() -> None:
    n = 3
    frame = Frame(round=1, n=n, scheduler="async", positions=np.zeros((n, 2)), outside=ASYNC)
    console = Console(width=200, height=40, record=True, color_system=None, file=io.StringIO())
    console.print(render_frame(frame, screen=(200, 40)), height=40)
    assert "this run gives it async (outside its assumption)" in console.export_text()
    state = WorldState(
        round=1, n=n, algorithm="uniform-circle", params={"a": 4.0}, figures={},
        scheduler="async", swarm="s", positions=np.zeros((n, 2)), active=(), open_round=0,
        moved=(), stopped=(), collisions_total=0, status=Status.RUNNING,
        agents=(AgentInfo(True, -1, 0.0, 0),) * n, outside=ASYNC,
    )  # fmt: skip
    assert WorldState.decode(state.encode()).outside == ASYNC
    assert b"outside" not in dataclasses.replace(state, outside="").encode()


def test_the_catalogue_lists_each_algorithms_assumptions() -> None:
    text = describe("uniform-circle-lights")
    assert "    lights: full" in text and "    schedulers: any" in text
    assert "    knows n: no" in describe("gathering")
