"""A round without the round hook: the lock step computes each robot alone on its row of the
round's views built at once where it can (`lockstep._Bus._act_each`), and hands a round of
straight lines and stays over as arrays (`straight_lines`, `_hand_over_round`), the paper's shared
plans and views built robot by robot included. The records are the very bytes of the robot-by-robot
way, whatever the algorithm answers: lines, stays, arcs, colours, failures, numbers the wire
refuses."""

from __future__ import annotations

import math
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest

import fatswarm
from fatswarm.agent.oblot_go_to_rightmost import ALGORITHM as GO_TO_RIGHTMOST
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine import lockstep
from fatswarm.deploy.engine.lockstep import run_lockstep, straight_lines
from fatswarm.domain.path import STAY, Arc, Line, Path, Points, StraightMoves
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.record import RecordWriter

RUNS = [
    ("oblot-go-to-rightmost", {"scheduler": "fsync", "frames": "both-axes", "bodies": "points"}),
    ("oblot-go-to-rightmost", {"scheduler": "ssync", "frames": "both-axes"}),
    ("oblot-move-along-sec", {"scheduler": "fsync", "non_rigid": 0.3, "bodies": "points"}),
    ("oblot-gathering-multiplicity", {"scheduler": "fsync", "bodies": "points"}),
    ("uniform-circle", {"scheduler": "ssync", "frames": "disoriented", "max_rounds": 40}),
    ("uniform-circle", {"scheduler": "async", "frames": "both-axes", "max_rounds": 60}),
    ("oblot-go-to-rightmost", {"scheduler": "centralized", "frames": "both-axes", "crash": 2}),
    ("oblot-go-to-rightmost", {"scheduler": "async", "frames": "both-axes", "max_rounds": 50}),
    # views built robot by robot (the model's views are not all alike), moves still as arrays
    ("gathering", {"scheduler": "fsync", "visibility": "opaque"}),
    ("gathering", {"scheduler": "ssync", "sight": 6.0}),
    ("oblot-go-to-cog", {"scheduler": "fsync", "bodies": "points", "noise": 0.01}),
    ("uniform-circle", {"scheduler": "ssync", "record_views": True, "max_rounds": 40}),
    ("uniform-circle-lights", {"scheduler": "async", "max_rounds": 60}),
]


ARRAYS_FROM = lockstep.ARRAYS_FROM  # the lock step's own, before the fixture below


@pytest.fixture(autouse=True)
def every_round_as_arrays(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rounds of one looker as arrays too (the lock step gives those robot by robot, cheaper):
    so that centralized and async rounds go the arrays' way here as well."""
    monkeypatch.setattr(lockstep, "ARRAYS_FROM", 1)


def robot_by_robot(monkeypatch: pytest.MonkeyPatch) -> None:
    """The lock step as before `_act_each` and `straight_lines`: every robot's Look, Compute and
    Move in turn."""
    monkeypatch.setattr(lockstep._Bus, "_act_each", lambda self, round_no, lookers: False)
    monkeypatch.setattr(lockstep, "straight_lines", lambda decided: None)


def arrays_taken(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Have `_straight` note, in the list returned, the lookers of each round it takes as arrays."""
    taken: list[int] = []
    real = lockstep._Bus._straight

    def noted(self: Any, round_no: int, lookers: Any, *args: Any) -> bool:
        done = bool(real(self, round_no, lookers, *args))
        if done:
            taken.append(len(lookers))
        return done

    monkeypatch.setattr(lockstep._Bus, "_straight", noted)
    return taken


def record_of(tmp_path: FsPath, name: str, algorithm: Any, seed: int, kw: dict[str, Any]) -> bytes:
    target = tmp_path / f"{name}.jsonl"
    kw = {"max_rounds": 30, **kw}
    fatswarm.run(10 + 2 * seed, algorithm=algorithm, seed=seed, start="spread", record=target, **kw)
    return target.read_bytes()


@pytest.mark.parametrize("algorithm, kw", RUNS)
@pytest.mark.parametrize("seed", [0, 3])
def test_a_record_is_the_same_with_a_round_at_once_and_robot_by_robot(
    tmp_path: FsPath,
    monkeypatch: pytest.MonkeyPatch,
    algorithm: str,
    kw: dict[str, Any],
    seed: int,
) -> None:
    taken = arrays_taken(monkeypatch)
    at_once = record_of(tmp_path, "at-once", algorithm, seed, kw)
    if algorithm not in ("oblot-move-along-sec", "uniform-circle-lights"):  # arcs, colours
        assert taken  # some rounds went as arrays
    robot_by_robot(monkeypatch)
    assert record_of(tmp_path, "alone", algorithm, seed, kw) == at_once


class Wild:
    """Go-to-rightmost's declarations, and robots that step a little by their view (the swarm
    never gathers); the rightmost robot, in about half of its Looks (by its view), answers
    instead a raise, an arc, a line of numpy floats, a line past the wire's bounds or to NaN, or
    a stay: some rounds all lines, others mixed."""

    name = "wild-rightmost"

    def __getattr__(self, name: str) -> Any:
        return getattr(GO_TO_RIGHTMOST, name)

    def compute(self, view: Points, params: Any) -> Path:
        total = float(view.sum()) if len(view) else 0.0
        rightmost = len(view) == 0 or float(view[:, 0].max()) < 0.0
        pick = int(abs(total) * 1e3) % 12 if rightmost else 6
        if pick == 0:
            raise ArithmeticError("boom")
        if pick == 1:
            return Path((Arc((0.0, 1.0), 0.5),))
        if pick == 2:
            return Path((Line((np.float64(0.25), np.float64(0.0))),))
        if pick == 3:
            return Path((Line((1e300, 0.0)),))
        if pick == 4:
            return Path((Line((math.nan, 0.0)),))
        if pick == 5:
            return STAY
        return Path((Line((math.copysign(0.01, total), 0.02)),))


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "async"])
@pytest.mark.parametrize("seed", [1, 2])
def test_a_wild_algorithms_record_is_the_same_with_views_at_once_and_robot_by_robot(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch, scheduler: str, seed: int
) -> None:

    def record(name: str) -> bytes:
        target = tmp_path / f"{name}.jsonl"
        start = np.random.default_rng(seed).uniform(-20.0, 20.0, size=(12, 2))
        with RecordWriter(target) as journal:
            run_lockstep(
                start,
                Configured.of(Wild(), 12),
                make_scheduler(scheduler, 12, seed),
                seed=seed,
                max_rounds=300 if scheduler == "async" else 25,
                record=journal,
                robot_model=RobotModel.of(frames="both-axes", bodies="points"),
            )
        return target.read_bytes()

    taken = arrays_taken(monkeypatch)
    at_once = record("at-once")
    assert taken  # some rounds as arrays
    assert b"timed_out" in at_once or b"boom" in at_once  # and wild answers were met
    robot_by_robot(monkeypatch)
    assert record("alone") == at_once


def test_straight_lines_takes_lines_and_stays_of_floats_only() -> None:
    line = (Path((Line((1.5, -2.0)),)), None)
    stay = (STAY, None)
    moves = straight_lines([line, stay, None, line])
    assert isinstance(moves, StraightMoves)
    assert moves.ends.tolist() == [[1.5, -2.0], [0.0, 0.0], [0.0, 0.0], [1.5, -2.0]]
    assert moves.goes.tolist() == [True, False, False, True]
    assert moves.paths()[0] == line[0]
    refused: list[Any] = [
        "ArithmeticError: boom",  # a failure
        (Path((Line((1.5, -2.0)),)), 2),  # a colour
        (Path((Arc((0.0, 0.0), 1.0),)), None),
        (Path((Line((1.0, 0.0)), Line((2.0, 0.0)))), None),
        (Path((Line((np.float64(1.0), 0.0)),)), None),
        (Path((Line((1, 0.0)),)), None),
        (Path([Line((1.0, 0.0))]), None),  # type: ignore[arg-type]
        ("not a path", None),
    ]
    for each in refused:
        assert straight_lines([line, each]) is None, each


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized", "async"])
@pytest.mark.parametrize("start", ["spread", "clumped"])
def test_the_papers_shared_plans_go_as_arrays_with_the_records_of_robot_by_robot(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch, scheduler: str, start: str
) -> None:
    """The paper's model (one shared plan a round): a round whose paths are straight lines or
    stays goes to the world as arrays, with the record of each path handed over alone."""

    def record(name: str) -> bytes:
        target = tmp_path / f"{name}.jsonl"
        fatswarm.run(9, seed=5, start=start, scheduler=scheduler, max_rounds=80, record=target)
        return target.read_bytes()

    taken = arrays_taken(monkeypatch)
    arrays = record("arrays")
    assert taken
    monkeypatch.setattr(lockstep, "straight_lines", lambda decided: None)
    assert record("alone") == arrays


def test_a_round_of_one_looker_goes_robot_by_robot(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Centralized rounds (one robot each) hand their move over as a Path: cheaper than arrays."""
    monkeypatch.setattr(lockstep, "ARRAYS_FROM", ARRAYS_FROM)
    taken = arrays_taken(monkeypatch)
    kw = {"scheduler": "centralized", "frames": "both-axes", "bodies": "points"}
    record_of(tmp_path, "centralized", "oblot-go-to-rightmost", 0, kw)
    assert taken == []
    record_of(tmp_path, "fsync", "oblot-go-to-rightmost", 0, {**kw, "scheduler": "fsync"})
    assert taken and min(taken) >= ARRAYS_FROM
