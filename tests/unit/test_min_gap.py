"""min_gap: the smallest rim-to-rim distance between two robots after each round, and its minimum
over the run, derived from the positions (no record carries it) and shown everywhere a figure is:
read_record's rounds, on_round, the dashboard and replay, --json, the summary, the sweep CSV (an
older table resumes) and to_dataframe."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.engine.lockstep import RoundReport
from fatswarm.deploy.net.launcher import read_outcome
from fatswarm.deploy.view import panels, replay
from fatswarm.deploy.view.dashboard import frame_from_state
from fatswarm.domain.figures import min_gap
from fatswarm.domain.outcome import Status
from fatswarm.domain.wire import unpack
from fatswarm.world.observers import AgentInfo, WorldState


def brute(positions: np.ndarray) -> float:
    d = np.hypot(*(positions[:, None, :] - positions[None, :, :]).transpose(2, 0, 1))
    return float(d[np.triu_indices(len(positions), 1)].min()) - 2.0


def test_min_gap_is_the_closest_pair_less_two_radii() -> None:
    assert min_gap(np.array([[0.0, 0.0], [3.0, 0.0], [10.0, 10.0]])) == 1.0
    assert min_gap(np.array([[0.0, 0.0], [1.0, 0.0]])) == -1.0  # overlapping discs
    assert min_gap(np.array([[5.0, 5.0]])) is None and min_gap(np.zeros((0, 2))) is None


@pytest.mark.parametrize("n", [2, 3, 16, 64, 257])
def test_min_gap_agrees_with_every_pair(n: int) -> None:
    rng = np.random.default_rng(n)
    for scale in (3.0, 30.0, 1e5):
        pts = rng.uniform(-scale, scale, (n, 2))
        assert min_gap(pts) == pytest.approx(brute(pts), abs=1e-9)
    column = np.c_[np.zeros(n), np.arange(n) * 2.5]  # every pair alike along x
    assert min_gap(column) == pytest.approx(0.5)
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
    circle = np.c_[np.cos(angle), np.sin(angle)] * 3 * n
    assert min_gap(circle) == pytest.approx(brute(circle), abs=1e-9)


@pytest.fixture(scope="module")
def ran(tmp_path_factory: pytest.TempPathFactory) -> tuple[fatswarm.RunResult, Path, list[float]]:
    target = tmp_path_factory.mktemp("min_gap") / "run.jsonl"
    seen: list[float] = []

    def on_round(report: RoundReport) -> None:
        gap, so_far = report.entry.derived["min_gap"], report.progress.derived["min_gap"]
        assert isinstance(gap, float) and isinstance(so_far, float)
        assert so_far == min([*seen, gap])  # the run's: the least of its rounds
        seen.append(gap)

    result = fatswarm.run(n=6, seed=3, scheduler="ssync", record=target, on_round=on_round)
    return result, target, seen


def test_min_gap_reaches_read_record_on_round_and_the_result(
    ran: tuple[fatswarm.RunResult, Path, list[float]],
) -> None:
    result, target, seen = ran
    record = fatswarm.read_record(target)
    assert [entry.derived["min_gap"] for entry in record.rounds] == seen
    assert [min_gap(entry.positions) for entry in record.rounds] == seen
    assert "min_gap" not in target.read_text()  # derived: the record stays as it was
    assert result.derived["min_gap"] == min(seen)
    assert fatswarm.summary(result)["min_gap"] == fatswarm.summary(record)["min_gap"] == min(seen)


def test_min_gap_reaches_the_dataframe(ran: tuple[fatswarm.RunResult, Path, list[float]]) -> None:
    pytest.importorskip("pandas")
    _, target, seen = ran
    df = fatswarm.read_record(target).to_dataframe()
    assert df.groupby("round").min_gap.first().tolist() == seen


def test_min_gap_reaches_replay_and_the_dashboard(
    ran: tuple[fatswarm.RunResult, Path, list[float]],
) -> None:
    _, target, seen = ran
    frames = replay.build_frames(fatswarm.read_record(target))
    shown = [dict((str(k), v) for k, v in panels.derived_rows(f))["min gap"] for f in frames[1:]]
    assert shown == [f"{gap:.3f}  least {min(seen[: k + 1]):.3f}" for k, gap in enumerate(seen)]


def test_the_world_state_carries_the_runs_min_gap_to_the_live_dashboard() -> None:
    positions = np.array([[0.0, 0.0], [2.5, 0.0], [0.0, 9.0]])
    agents = tuple(AgentInfo(True, -1, 0.0, 0) for _ in range(3))
    state = WorldState(
        *(4, 3, "gathering", {}, {}, "fsync", "s", positions, (0,), 0, (), (), 0),
        Status.RUNNING,
        agents,
        derived={"min_gap": 0.125, "not_declared": 1.0},
    )
    back = WorldState.decode(state.encode())
    assert back.derived == {"min_gap": 0.125}  # a figure this fatswarm does not know: left out
    rows = dict((str(k), v) for k, v in panels.derived_rows(frame_from_state(back)))
    assert rows["min gap"] == "0.500  least 0.125"
    bare = WorldState.decode(dataclasses.replace(state, derived={}).encode())
    assert bare.derived == {}
    assert "derived" not in unpack(dataclasses.replace(state, derived={}).encode(), "state")


def test_min_gap_reaches_json_and_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    argv = ["run", "--lockstep", "-n", "5", "--seed", "2", "--record", str(out), "--json"]
    cli.main(argv)
    fields = json.loads(capsys.readouterr().out)
    rounds = fatswarm.read_record(out).rounds
    assert fields["min_gap"] == min(min_gap(r.positions) or math.inf for r in rounds)
    cli.main(["run", "--lockstep", "-n", "5", "--seed", "2", "--record", str(out), "--force"])
    assert f"min gap {fields['min_gap']:.3f}" in capsys.readouterr().out


def test_an_old_record_has_min_gap_and_so_has_the_networked_summary_of_it() -> None:
    old = Path(__file__).resolve().parents[1] / "data" / "lockstep-n6-seed1.jsonl"  # checked in
    record = fatswarm.read_record(old)
    gaps = [entry.derived["min_gap"] for entry in record.rounds]
    assert all(isinstance(g, float) and g >= 0 for g in gaps)  # collision-free
    outcome = read_outcome(str(old))  # what a networked run's summary reads
    assert outcome is not None
    assert outcome.derived["min_gap"] == min(g for g in gaps if g is not None)
    assert fatswarm.summary(record)["min_gap"] == outcome.derived["min_gap"]
