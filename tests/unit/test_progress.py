"""Progress tracker: rounds, epochs, moves, distance, and the formed/stalled/max_rounds ends."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from fatswarm.agent.geometry import is_formed
from fatswarm.domain.outcome import Status
from fatswarm.world.progress import MOVE_TOLERANCE, ProgressTracker, configuration_changed

_goal_holds: bool | None = None  # the fixtures below decide the goal, else the paper's does


def CIRCLE(points: np.ndarray) -> bool:
    """The paper's goal with a = 4 (unless a fixture says whether it holds)."""
    return is_formed(points, 4.0) if _goal_holds is None else _goal_holds


P0 = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
P1 = P0 + np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.0]])


@pytest.fixture
def uniform(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys.modules[__name__], "_goal_holds", True)


@pytest.fixture
def not_uniform(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys.modules[__name__], "_goal_holds", False)


def test_counts_moves_distance_collisions() -> None:
    t = ProgressTracker(3, CIRCLE)
    t.observe([0, 1], [0], P0, P1, {0: 1.0}, collisions=0)
    t.observe([1, 2], [1, 2], P1, P1, {1: 0.0, 2: 0.0}, collisions=2)
    snap = t.snapshot()
    assert (snap.rounds, snap.moves, snap.total_distance, snap.collisions) == (2, 3, 1.0, 2)
    assert snap.moves_by_robot == (1, 1, 1)


def test_epoch_ends_when_every_robot_was_active() -> None:
    t = ProgressTracker(3, CIRCLE)
    for active in ([0], [1, 0], [2], [2], [0]):
        t.observe(active, [0], P0, P1)  # the configuration keeps changing: the run goes on
    assert t.snapshot().epochs == 1
    t.observe([1], [0], P0, P1)
    assert t.snapshot().epochs == 2


def test_fsync_epochs_equal_rounds() -> None:
    t = ProgressTracker(3, CIRCLE)
    for _ in range(4):
        t.observe([0, 1, 2], [0], P0, P1)
    assert t.snapshot().epochs == t.snapshot().rounds == 4


def test_formed_needs_everyone_active_with_empty_path_after_last_change(uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE)
    assert t.observe([0], [0], P0, P1) is None  # change: nobody has looked at P1 yet
    assert t.observe([0, 1], [], P1, P1) is None
    assert t.observe([2], [], P1, P1) == Status.FORMED
    assert t.done and t.snapshot().status == Status.FORMED


def test_robots_active_in_the_changing_round_must_look_again(uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE)
    t.observe([0, 1, 2], [0], P0, P1)
    assert t.status is None
    assert t.observe([0, 1, 2], [], P1, P1) == Status.FORMED


def test_uniform_but_someone_blocked_is_stalled(uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE)
    assert t.observe([0, 1, 2], [1], P0, P0) == Status.STALLED


def test_unchanged_and_not_uniform_is_stalled(not_uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE)
    t.observe([0, 1], [], P0, P0)
    assert t.observe([2], [], P0, P0) == Status.STALLED


def test_max_rounds_ends_a_run_that_keeps_moving(not_uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE, max_rounds=3)
    positions = [P0 + k for k in range(4)]
    results = [t.observe([0, 1, 2], [0], positions[k], positions[k + 1]) for k in range(3)]
    assert results == [None, None, Status.MAX_ROUNDS]
    with pytest.raises(RuntimeError, match="already ended"):
        t.observe([0], [], positions[3], positions[3])


def test_a_final_round_that_forms_wins_over_max_rounds(uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE, max_rounds=1)
    assert t.observe([0, 1, 2], [], P0, P0) == Status.FORMED


def test_moves_below_tolerance_do_not_change_the_configuration() -> None:
    assert not configuration_changed(P0, P0 + MOVE_TOLERANCE / 2)
    assert configuration_changed(P0, P0 + np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 1e-6]]))


def test_unknown_robot_and_bad_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match=r"not in 0\.\.2"):
        ProgressTracker(3, CIRCLE).observe([3], [], P0, P0)
    with pytest.raises(ValueError, match="at least one robot"):
        ProgressTracker(0, CIRCLE)
    with pytest.raises(ValueError, match="max_rounds"):
        ProgressTracker(3, CIRCLE, max_rounds=0)


def test_a_crashed_robot_counts_as_seen_staying_until_it_recovers(uniform: None) -> None:
    t = ProgressTracker(3, CIRCLE)
    t.crash([2])
    t.observe([0, 1], [], P0, P0)  # robot 2 is never active: it crashed
    assert t.status == "formed" and t.crashed == {2}
    u = ProgressTracker(3, CIRCLE)
    u.crash([2])
    u.recover([2])
    u.observe([0, 1], [], P0, P0)
    assert u.status is None  # waited for again


def test_a_stale_line_counts_neither_as_seen_nor_as_wanting(uniform: None) -> None:
    # an async cycle Looked before the last change and is booked after it (its blocked move ended
    # later): its robot saw the old configuration, so it must Look again before the run can end
    t = ProgressTracker(2, CIRCLE)
    t.observe([1], [1], P0, P1, {1: 1.0})  # a change
    assert t.observe([0], [0], P1, P1, {0: 0.0}, stale=True) is None  # not "stalled"
    assert t.observe([1], [], P1, P1) is None
    assert t.observe([0], [], P1, P1) == Status.FORMED
