"""The world core's shortcut for a lock step's whole round (every active robot of the open round,
in order, each once: `admit_looks` and `hold_lines` take the active set as it is) holds and
refuses exactly as the per-robot way does (`admit_look`, `hold`)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from fatswarm.agent.gathering import ALGORITHM as GATHERING
from fatswarm.domain.path import STAY, Line, Path
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.core import WorldCore
from fatswarm.world.protocol import Begin
from fatswarm.world.setup import WorldSetup

N = 6


def open_world(n: int) -> WorldCore:
    """A world of n robots in a row, round 1 open for all of them."""
    start = np.array([[4.0 * i, 0.0] for i in range(n)])
    setup = WorldSetup(
        "t", n, 3, "fsync", start, 50, "gathering", robot_model=RobotModel.of(frames="disoriented")
    )
    world = WorldCore(setup, Configured.of(GATHERING, n))
    world.take_effects()
    assert world.control(Begin(1, tuple(range(n))))[0].ok
    return world


def state(world: WorldCore) -> tuple[Any, ...]:
    """What the world holds (the bits of each held path), waits for, refused and said."""
    held = {
        r: np.array([seg.end for seg in p.segments], dtype=np.float64).tobytes()  # type: ignore[union-attr]
        for r, p in world.held.items()
    }
    return held, sorted(world.missing), dict(world.rejected), world.take_effects()


@pytest.mark.parametrize(
    "goes, looked",
    [
        (None, range(N)),  # every robot goes, every one looked: the shortcut
        (np.array([True, False, True, True, False, True]), range(N)),  # some stay
        (None, [0, 1, 2, 4, 5]),  # robot 3 has not looked: refused, counted
    ],
)
def test_a_whole_round_at_once_holds_and_refuses_as_each_robot_alone(
    goes: np.ndarray | None, looked: range | list[int]
) -> None:
    robots = list(range(N))
    ends = np.random.default_rng(5).normal(size=(N, 2))
    at_once, alone = open_world(N), open_world(N)
    if list(looked) == robots:
        assert at_once.admit_looks(robots) == [True] * N
    else:
        for robot in looked:
            assert at_once.admit_look(robot)
    for robot in looked:
        assert alone.admit_look(robot)
    assert at_once.looked == alone.looked
    at_once.hold_lines(robots, 1, ends, goes)
    each = [True] * N if goes is None else goes.tolist()
    for robot, (x, y), go in zip(robots, ends.tolist(), each, strict=True):
        alone.hold(robot, 1, Path((Line((x, y)),)) if go else STAY, None)
    assert state(at_once) == state(alone)


def test_a_second_batch_in_the_round_is_checked_robot_by_robot() -> None:
    world = open_world(N)
    world.admit_looks(list(range(N)))
    ends = np.ones((N, 2))
    world.hold_lines(list(range(N)), 1, ends)
    world.hold_lines(list(range(N)), 1, ends)  # each one held already: refused, counted
    assert world.rejected["move-duplicate"] == N
