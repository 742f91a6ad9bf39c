"""The canonical form: the same bits from every robot's view, and the way back to each frame."""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.agent.canonical import canonical
from fatswarm.domain.path import Line, Path, end_point
from fatswarm.domain.tolerance import GRID, snap

RNG = np.random.default_rng(7)


def views_of(points: np.ndarray) -> list[tuple[np.ndarray, int, bool]]:
    """Every robot's view (observer first, then the others shuffled), unflipped and flipped."""
    out = []
    for robot in range(len(points)):
        others = np.delete(points, robot, axis=0)
        others = others[RNG.permutation(len(others))]
        view = np.vstack([np.zeros((1, 2)), others - points[robot]])
        for flip in (False, True):
            v = view * np.array([-1.0 if flip else 1.0, 1.0])
            out.append((v + 0.0, robot, flip))
    return out


@pytest.mark.parametrize("offset", [0.0, 1e5, -1.5e6])
def test_every_view_of_a_grid_configuration_has_the_same_canonical_bits(offset: float) -> None:
    pts = snap(RNG.uniform(-20, 20, size=(12, 2)) + offset)
    keys = {canonical(view).key() for view, _, _ in views_of(pts)}
    assert len(keys) == 1


def test_the_canonical_form_starts_at_the_lowest_robot_and_is_sorted_by_height() -> None:
    pts = snap(RNG.uniform(-20, 20, size=(9, 2)))
    c = canonical(pts).points
    assert tuple(c[0]) == (0.0, 0.0)
    assert (np.diff(c[:, 1]) >= 0).all()


def test_the_observer_is_found_and_its_frame_recovered() -> None:
    pts = snap(RNG.uniform(-20, 20, size=(8, 2)))
    for view, robot, _flip in views_of(pts):
        canon = canonical(view)
        # The canonical row of the observer maps back to its own origin.
        to_me = canon.to_frame(Path((Line(tuple(canon.points[canon.observer])),)))
        assert end_point((0.0, 0.0), to_me) == (0.0, 0.0), robot
        # And every canonical row maps back onto a robot of the view.
        for row in canon.points:
            back = end_point((0.0, 0.0), canon.to_frame(Path((Line(tuple(row)),))))
            assert np.hypot(*(view - np.array(back)).T).min() == 0.0


def test_equal_heights_are_ordered_by_x_and_the_smaller_mirror_image_wins() -> None:
    pts = np.array([[0.0, 0.0], [3.0, 0.0], [7.0, 0.0], [1.0, 4.0]])
    c = canonical(pts)
    mirrored = canonical(pts * np.array([-1.0, 1.0]))
    assert c.key() == mirrored.key()
    assert c.points[:3, 1].tolist() == [0.0, 0.0, 0.0]
    assert c.points[:3, 0].tolist() in ([0.0, 3.0, 7.0], [0.0, 4.0, 7.0])
    assert not c.mirror_symmetric


def test_an_exactly_mirror_symmetric_swarm_is_recognised() -> None:
    pts = np.array([[-2.5, 0.0], [2.5, 0.0], [0.0, 3.0], [-4.0, 6.0], [4.0, 6.0]])
    assert canonical(pts).mirror_symmetric
    pts[0, 0] -= GRID  # one grid step off: no longer exactly symmetric
    assert not canonical(pts).mirror_symmetric


def test_negative_zero_gives_the_same_bits_as_zero() -> None:
    a = np.array([[0.0, 0.0], [-0.0, 2.0], [3.0, 5.0]])
    b = np.array([[0.0, 0.0], [0.0, 2.0], [3.0, 5.0]])
    assert canonical(a).key() == canonical(b).key()
    points = canonical(a).points
    assert not np.signbit(points[points == 0.0]).any()
