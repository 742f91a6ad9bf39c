"""Lockstep runner: private frames, one snapshot per round, records, reproducibility, the ends."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.agent import algorithm
from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import (
    HistoryMismatchError,
    RoundReport,
    RunResult,
    default_max_rounds,
    run_lockstep,
)
from fatswarm.deploy.scenarios.starts import degenerate_starts, random_start
from fatswarm.domain.draws import draw_flip
from fatswarm.domain.path import STAY, Line, Path, Points
from fatswarm.domain.tolerance import GRID, UnsupportedInputError
from fatswarm.world.physics import InvalidConfigurationError
from fatswarm.world.record import RecordWriter, RoundEntry
from fatswarm.world.record_read import read_record


def polygon(n: int, side: float) -> Points:
    radius = side / (2.0 * math.sin(math.pi / n))
    ang = 2.0 * math.pi * np.arange(n) / n
    return np.column_stack([radius * np.cos(ang), radius * np.sin(ang)])


def stay(view: Points, params: Params) -> Path:
    return STAY


def north(view: Points, params: Params) -> Path:
    return Path((Line((0.0, 0.5)),))


def test_uniform_start_with_nobody_moving_is_formed_in_one_fsync_round() -> None:
    result = run_lockstep(
        polygon(5, 4.5), Params(5), make_scheduler("fsync", 5, 0), seed=0, compute=stay
    )
    assert (result.status, result.rounds, result.epochs, result.moves) == ("formed", 1, 1, 0)


def test_nobody_moving_off_the_circle_is_stalled_once_everyone_looked() -> None:
    start = random_start(6, 1, "clustered")
    result = run_lockstep(
        start, Params(6), make_scheduler("centralized", 6, 2), seed=0, compute=stay
    )
    assert result.status == "stalled"
    assert result.rounds >= 6 and result.looks == result.rounds
    np.testing.assert_array_equal(result.positions, start)


def test_endless_movers_hit_the_round_cap() -> None:
    result = run_lockstep(
        polygon(4, 4.0),
        Params(4),
        make_scheduler("fsync", 4, 0),
        seed=0,
        max_rounds=7,
        compute=north,
    )
    assert (result.status, result.rounds, result.moves) == ("max_rounds", 7, 28)
    assert result.total_distance == pytest.approx(14.0)
    np.testing.assert_allclose(result.positions, polygon(4, 4.0) + np.array([0.0, 3.5]), atol=GRID)


def test_each_robot_sees_the_others_in_its_own_flipped_frame() -> None:
    start = polygon(5, 5.0)
    views: list[Points] = []

    def spy(view: Points, params: Params) -> Path:
        views.append(view.copy())
        return STAY

    run_lockstep(start, Params(5), make_scheduler("fsync", 5, 0), seed=11, compute=spy)
    flips = [draw_flip(11, r) for r in range(5)]
    assert len(set(flips)) == 2, "pick a seed with both frame orientations"
    for robot, view in enumerate(views):
        expected = np.delete(start, robot, axis=0) - start[robot]
        if flips[robot]:
            expected[:, 0] *= -1
        key = np.lexsort(view.T)
        np.testing.assert_allclose(view[key], expected[np.lexsort(expected.T)], atol=1e-12)


def test_local_paths_are_mapped_back_through_the_private_flip() -> None:
    def east(view: Points, params: Params) -> Path:
        return Path((Line((0.25, 0.0)),))

    start = polygon(6, 5.0)
    result = run_lockstep(
        start, Params(6), make_scheduler("fsync", 6, 0), seed=11, max_rounds=1, compute=east
    )
    sign = np.array([-1.0 if draw_flip(11, r) else 1.0 for r in range(6)])
    np.testing.assert_allclose(result.positions[:, 0] - start[:, 0], 0.25 * sign)


def test_view_order_is_shuffled_between_looks() -> None:
    orders: list[tuple[float, ...]] = []

    def spy(view: Points, params: Params) -> Path:
        orders.append(tuple(view[:, 1]))
        return Path((Line((0.0, 1.0)),))  # everyone moves north: nobody ends the run early

    run_lockstep(
        polygon(6, 5.0),
        Params(6),
        make_scheduler("fsync", 6, 0),
        seed=3,
        max_rounds=20,
        compute=spy,
    )
    robot0 = [tuple(np.round(order, 9)) for order in orders[::6]]  # same relative view each round
    assert len(set(robot0)) > 1


def test_record_is_written_and_reads_back(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    with RecordWriter(target) as record:
        result = run_lockstep(
            polygon(4, 4.0),
            Params(4),
            make_scheduler("ssync", 4, 5),
            seed=5,
            max_rounds=6,
            record=record,
            compute=north,
        )
    rec = read_record(target)
    assert (rec.header.n, rec.header.seed, rec.header.scheduler) == (4, 5, "ssync")
    assert len(rec.rounds) == result.rounds == 6
    assert rec.result is not None and rec.result.status == "max_rounds"
    assert sum(len(r.moves) for r in rec.rounds) == result.moves
    np.testing.assert_allclose(rec.rounds[-1].positions, result.positions)
    assert all(m.traveled == pytest.approx(0.5) for r in rec.rounds for m in r.moves)


def test_callback_sees_every_round() -> None:
    reports: list[RoundReport] = []
    run_lockstep(
        polygon(4, 4.0),
        Params(4),
        make_scheduler("fsync", 4, 0),
        seed=0,
        max_rounds=3,
        on_round=reports.append,
        compute=north,
    )
    assert [r.entry.round for r in reports] == [1, 2, 3]
    assert reports[-1].progress.status == "max_rounds" and len(reports[0].entry.moves) == 4


def test_same_seed_same_run() -> None:
    start = random_start(7, 3, "clustered")
    runs = [run_lockstep(start, Params(7), make_scheduler("ssync", 7, 3), seed=3) for _ in range(2)]
    assert runs[0].rounds == runs[1].rounds and runs[0].moves == runs[1].moves
    np.testing.assert_array_equal(runs[0].positions, runs[1].positions)


def test_start_and_params_must_agree() -> None:
    with pytest.raises(ValueError, match="params say n=5"):
        run_lockstep(polygon(4, 4.0), Params(5), make_scheduler("fsync", 4, 0), seed=0)
    with pytest.raises(InvalidConfigurationError):
        run_lockstep(
            np.array([[0.0, 0.0], [1.0, 0.0]]), Params(2), make_scheduler("fsync", 2, 0), seed=0
        )


def test_default_round_cap_grows_with_n_and_scheduler() -> None:
    assert default_max_rounds(8, "fsync") < default_max_rounds(8, "ssync")
    assert default_max_rounds(8, "ssync") < default_max_rounds(8, "centralized")
    assert default_max_rounds(8, "centralized") < default_max_rounds(8, "async-slowest")
    assert default_max_rounds(16, "fsync") > default_max_rounds(8, "fsync")


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_the_algorithm_forms_the_circle_without_collisions(scheduler: str) -> None:
    for n, kind, seed in [
        (2, "clustered", 0),
        (3, "dense", 1),
        (5, "clustered", 2),
        (6, "spread", 3),
        (8, "dense", 4),
        (9, "clumped", 5),
    ]:
        start = random_start(n, seed, kind)
        result = run_lockstep(start, Params(n), make_scheduler(scheduler, n, seed), seed=seed)
        assert (result.status, result.collisions) == ("formed", 0), (n, kind, seed)


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_every_named_degenerate_start_forms_without_collisions(scheduler: str) -> None:
    for name, (start, a) in degenerate_starts().items():
        n = len(start)
        result = run_lockstep(start, Params(n, a), make_scheduler(scheduler, n, 7), seed=7)
        assert (result.status, result.collisions) == ("formed", 0), name


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
@pytest.mark.parametrize(("kind", "n"), [("clustered", 9), ("spread", 7), ("dense", 12)])
def test_shared_plans_equal_every_robot_computing_its_own(
    kind: str, n: int, scheduler: str
) -> None:
    # The default lockstep makes the canonical form and the plan once a round; passing the
    # reference `compute` makes every robot compute on its own shuffled view. Same run, bit for bit.
    start = random_start(n, 3, kind)
    runs = []
    for compute in (None, algorithm.compute):
        rounds: list[tuple[int, tuple[int, ...], bytes]] = []

        def keep(
            report: RoundReport,
            rounds: list[tuple[int, tuple[int, ...], bytes]] = rounds,
        ) -> None:
            rounds.append(
                (report.entry.round, report.entry.active, report.entry.positions.tobytes())
            )

        result = run_lockstep(
            start,
            Params(n),
            make_scheduler(scheduler, n, 5),
            seed=5,
            compute=compute,
            on_round=keep,
        )
        runs.append((result.status, result.moves, rounds))
    assert runs[0] == runs[1]
    assert runs[0][0] == "formed"


@pytest.mark.parametrize(("a", "offset"), [(1e10, 0.0), (1e308, 0.0), (4.0, 5e6)])
def test_inputs_outside_the_supported_range_are_refused_before_any_round(
    a: float, offset: float
) -> None:
    start = polygon(4, 4.0) + offset
    with pytest.raises((UnsupportedInputError, InvalidConfigurationError), match="must"):
        run_lockstep(start, Params(4, a), make_scheduler("fsync", 4, 0), seed=0)


# --- resuming after committed rounds (fatswarm run --lockstep --resume) -----------------------


def nudge(view: Points, params: Params) -> Path:
    """Step 0.01 away from whoever comes first in the view: the view order decides the run."""
    x, y = view[0]
    d = float(np.hypot(x, y))
    return Path((Line((-0.01 * x / d, -0.01 * y / d)),))


@pytest.mark.parametrize("compute", [None, nudge], ids=["shared-plans", "order-sensitive"])
@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_a_run_resumed_after_its_committed_rounds_goes_on_as_it_would_have(
    tmp_path: FsPath, scheduler: str, compute: Callable[[Points, Params], Path] | None
) -> None:
    n, seed = 6, 5
    start = random_start(n, 3, "clustered")

    def run(path: FsPath, history: tuple[RoundEntry, ...] | None = None) -> RunResult:
        with RecordWriter(path, append=history is not None) as rec:
            return run_lockstep(
                start,
                Params(n),
                make_scheduler(scheduler, n, seed),
                seed=seed,
                max_rounds=40,
                record=rec,
                compute=compute,
                history=history,
            )

    whole = run(tmp_path / "whole.jsonl")
    lines = (tmp_path / "whole.jsonl").read_text().splitlines(keepends=True)
    k = len(lines[1:-1]) // 2
    assert k >= 2
    cut = tmp_path / "cut.jsonl"
    cut.write_text("".join(lines[: 1 + k]))  # the header and k rounds: no result line
    resumed = run(cut, read_record(cut).rounds)
    assert cut.read_text() == "".join(lines)
    for field in (
        "status",
        "rounds",
        "epochs",
        "moves",
        "total_distance",
        "collisions",
        "looks",
        "moves_by_robot",
    ):
        assert getattr(resumed, field) == getattr(whole, field), field
    np.testing.assert_array_equal(resumed.positions, whole.positions)


def test_a_history_this_run_would_not_have_produced_is_refused(tmp_path: FsPath) -> None:
    n = 6
    start = random_start(n, 3, "clustered")
    target = tmp_path / "run.jsonl"
    with RecordWriter(target) as rec:
        run_lockstep(
            start, Params(n), make_scheduler("ssync", n, 5), seed=5, max_rounds=4, record=rec
        )
    history = read_record(target).rounds
    other = make_scheduler("ssync", n, 6)  # another seed: another schedule
    with pytest.raises(HistoryMismatchError, match=r"round \d+ activated robots"):
        run_lockstep(start, Params(n), other, seed=5, history=history)
