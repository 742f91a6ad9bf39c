"""world/timeline.py: every robot's centre at any time of a record, rounds (t in rounds) and
async (virtual time), checked against the positions the record itself holds."""

from __future__ import annotations

import math
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain.path import point_at
from fatswarm.world.record import RunRecord
from fatswarm.world.record_read import read_record
from fatswarm.world.timeline import Timeline, positions_at

DATA = FsPath(__file__).parent.parent / "data"


@pytest.fixture(scope="module")
def rounds_record() -> RunRecord:
    return read_record(DATA / "lockstep-n6-seed1.jsonl")


@pytest.fixture(scope="module")
def small_record() -> RunRecord:
    return read_record(DATA / "replay-small.jsonl")


def _async_record(tmp_path: FsPath, name: str, seed: int) -> RunRecord:
    from fatswarm.world.record import RecordWriter

    path = tmp_path / f"{name}.jsonl"
    with RecordWriter(path) as journal:
        run_lockstep(
            random_start(5, seed), Params(5), make_scheduler(name, 5, seed), seed=seed,
            record=journal,
        )  # fmt: skip
    return read_record(path)


def test_whole_times_give_the_recorded_positions_bit_for_bit(rounds_record: RunRecord) -> None:
    timeline = Timeline(rounds_record)
    assert timeline.end == len(rounds_record.rounds)
    assert np.array_equal(timeline.at(0), rounds_record.header.initial)
    for k, entry in enumerate(rounds_record.rounds, start=1):
        assert np.array_equal(timeline.at(float(k)), entry.positions)
        assert np.array_equal(positions_at(rounds_record, k), entry.positions)


def test_within_a_round_each_mover_is_at_its_share_of_the_longest_move(
    small_record: RunRecord,
) -> None:
    timeline = Timeline(small_record)
    entry = small_record.rounds[1]  # round 2: robot 2 moves along an arc, stopped by contact
    (move,) = entry.moves
    before = small_record.rounds[0].positions
    start = (float(before[2][0]), float(before[2][1]))
    for f in (0.1, 0.25, 0.5, 0.9):
        here = timeline.at(1 + f)
        assert here[2] == pytest.approx(point_at(start, move.path, f * move.traveled), abs=1e-12)
        still = [i for i in range(4) if i != 2]
        assert np.array_equal(here[still], before[still])


def test_shorter_moves_end_early_and_wait_for_the_round_to_end(small_record: RunRecord) -> None:
    timeline = Timeline(small_record)
    entry = small_record.rounds[2]  # round 3: robot 0 travels 4, robot 3 about 2.24
    before = small_record.rounds[1].positions
    start = (float(before[0][0]), float(before[0][1]))
    here = timeline.at(2.5)  # s = 2 into the round: robot 3 is still on its way
    assert here[0] == pytest.approx(point_at(start, entry.moves[0].path, 2.0), abs=1e-12)
    assert here[3] == pytest.approx((-3.0 - 2.0 / math.sqrt(5) * 2.0, -1.0 - 2.0 / math.sqrt(5)))
    here = timeline.at(2.9)  # s = 3.6: robot 3 has arrived, exactly where the line says
    assert np.array_equal(here[3], entry.positions[3])
    assert not np.array_equal(here[0], entry.positions[0])


def test_motion_is_continuous_across_round_boundaries(rounds_record: RunRecord) -> None:
    timeline = Timeline(rounds_record)
    for k in range(1, len(rounds_record.rounds)):
        assert np.allclose(timeline.at(k + 1e-9), timeline.at(float(k)), atol=1e-6)
        assert np.allclose(timeline.at(k - 1e-9), timeline.at(float(k)), atol=1e-6)


@pytest.mark.parametrize("name", ["async", "async-slowest"])
def test_async_each_line_end_puts_its_robot_where_the_line_says(
    name: str, tmp_path: FsPath
) -> None:
    record = _async_record(tmp_path, name, 2)
    timeline = Timeline(record)
    assert timeline.is_async
    assert record.result is not None and timeline.end == record.result.time
    for entry in record.rounds:
        (robot,) = entry.active
        here = timeline.at(entry.extra["end"])
        assert np.array_equal(here[robot], entry.positions[robot])
        assert np.allclose(here, entry.positions, atol=1e-6)  # the others, mid-move or not


def test_async_mid_move_follows_the_path_from_its_origin(tmp_path: FsPath) -> None:
    record = _async_record(tmp_path, "async", 1)
    timeline = Timeline(record)
    entry = next(e for e in record.rounds if e.moves and e.moves[0].traveled > 0.5)
    (move,) = entry.moves
    origin = tuple(entry.extra["origin"])
    t = entry.extra["start"] + move.traveled / 2
    expected = point_at((origin[0], origin[1]), move.path, move.traveled / 2)
    assert timeline.at(t)[move.robot] == pytest.approx(expected, abs=1e-12)
    before_first = min(e.extra["start"] for e in record.rounds if e.moves)
    if before_first > 0:
        assert np.array_equal(timeline.at(before_first / 2), record.header.initial)


@pytest.mark.parametrize("t", [-0.5, 1e9, math.nan, math.inf])
def test_times_outside_the_run_are_refused_in_one_line(rounds_record: RunRecord, t: float) -> None:
    with pytest.raises(ValueError, match=r"^t must be a time between 0 and 17 \(rounds\)") as exc:
        positions_at(rounds_record, t)
    assert "\n" not in str(exc.value)


def test_spans_and_lines_done(rounds_record: RunRecord) -> None:
    timeline = Timeline(rounds_record)
    assert timeline.span(3, 5) == (2.0, 5.0)
    assert timeline.lines_done(2.5) == 2
    assert timeline.lines_done(3.0) == 3
    with pytest.raises(ValueError, match=r"not within 1\.\.17"):
        timeline.span(0, 4)


def test_collisions_are_placed_at_their_time_in_the_round(small_record: RunRecord) -> None:
    timeline = Timeline(small_record)
    contact = next(c for c in timeline.contacts if c.line == 2)
    assert contact.t == pytest.approx(2.0)  # the arc is stopped at its very end: the round's end
    assert contact.point == small_record.rounds[1].collisions[0].point
    assert (contact.robot, contact.other) == (2, 3)
