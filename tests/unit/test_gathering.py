"""The gathering algorithm: pure, order- and mirror-independent, collision-free, and it ends."""

from __future__ import annotations

import math
import sys
from pathlib import Path as FsPath

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent.gathering import ALGORITHM, GatheringParams
from fatswarm.domain.path import STAY, Line, Path, Points, end_point, mirror
from fatswarm.domain.registry import available, load_algorithm
from fatswarm.domain.seam import AlgorithmParamsError, Configured

sys.path.insert(0, str(FsPath(__file__).resolve().parents[1] / "property"))
from straight_moves import closest_during, grid_starts, min_distance, view_of

PARAMS = GatheringParams(8, 1e-3)
SETTINGS = settings(max_examples=60, deadline=None)
STARTS = grid_starts(cells=5, offset=50.0)


def step_vectors(positions: Points, robots: list[int]) -> Points:
    """(n, 2) displacement each of `robots` asks for (zero for the others)."""
    moves = np.zeros_like(positions)
    for robot in robots:
        path = ALGORITHM.compute(view_of(positions, robot), PARAMS)
        assert len(path) <= 1
        moves[robot] = end_point((0.0, 0.0), path)
    return moves


@SETTINGS
@given(STARTS, st.data())
def test_path_is_the_same_for_every_order_of_the_view(
    positions: Points, data: st.DataObject
) -> None:
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        order = data.draw(st.permutations(range(len(view))))
        assert ALGORITHM.compute(view[order], PARAMS) == ALGORITHM.compute(view, PARAMS)
        assert ALGORITHM.compute(view[::-1], PARAMS) == ALGORITHM.compute(view, PARAMS)


@SETTINGS
@given(STARTS)
def test_mirroring_the_view_mirrors_the_path_exactly(positions: Points) -> None:
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        mirrored = view * np.array([-1.0, 1.0])
        assert ALGORITHM.compute(mirrored, PARAMS) == mirror(ALGORITHM.compute(view, PARAMS))


@SETTINGS
@given(STARTS, st.lists(st.lists(st.booleans(), min_size=9, max_size=9), min_size=1, max_size=6))
def test_robots_never_overlap_when_they_move_at_once(
    positions: Points, rounds: list[list[bool]]
) -> None:
    for active in [[True] * 9, *rounds]:  # one fsync round, then any subsets
        robots = [r for r in range(len(positions)) if active[r]]
        moves = step_vectors(positions, robots)
        assert np.isfinite(moves).all()
        assert closest_during(positions, moves) >= 2.0 - 1e-9
        positions = positions + moves
        assert min_distance(positions) >= 2.0 - 1e-9


@SETTINGS
@given(STARTS)
def test_goal_holds_exactly_when_every_robot_stays(positions: Points) -> None:
    stays = all(not ALGORITHM.compute(view_of(positions, r), PARAMS) for r in range(len(positions)))
    assert ALGORITHM.goal(positions, PARAMS) == stays


def test_a_pair_moves_toward_its_midpoint_by_half_the_gap() -> None:
    # G = (2.5, 0) is 2.5 away; half the gap is (5 - 2) / 2 = 1.5
    assert ALGORITHM.compute(np.array([[5.0, 0.0]]), PARAMS) == Path((Line((1.5, 0.0)),))


def test_a_robot_reaches_the_centre_when_it_is_nearer_than_half_the_gap() -> None:
    view = np.array([[-10.0, 0.0], [10.0, 1.5]])  # G = (0, 0.5), neighbours ~10 away
    assert ALGORITHM.compute(view, PARAMS) == Path((Line((0.0, 0.5)),))


def test_a_robot_whose_step_is_within_the_tolerance_stays() -> None:
    tol = GatheringParams(2, 0.1)
    assert ALGORITHM.compute(np.array([[2.18, 0.0]]), tol) == STAY  # step 0.09
    assert ALGORITHM.compute(np.array([[2.22, 0.0]]), tol) != STAY  # step 0.11
    assert ALGORITHM.compute(np.array([[2.0, 0.0]]), PARAMS) == STAY  # touching
    assert ALGORITHM.compute(np.array([[1.9999999, 0.0]]), PARAMS) == STAY  # within the slack


def test_a_lone_robot_stays_and_has_reached_the_goal() -> None:
    assert ALGORITHM.compute(np.empty((0, 2)), GatheringParams(1, 1e-3)) == STAY
    assert ALGORITHM.goal(np.array([[3.0, 4.0]]), GatheringParams(1, 1e-3))


def test_goal_holds_for_a_touching_pair_and_triangle_not_for_a_spread_start() -> None:
    assert ALGORITHM.goal(np.array([[0.0, 0.0], [2.0, 0.0]]), PARAMS)
    triangle = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, math.sqrt(3.0)]])
    assert ALGORITHM.goal(triangle, PARAMS)
    square = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    assert not ALGORITHM.goal(square, PARAMS)


def test_a_spread_start_gathers_within_a_few_dozen_rounds() -> None:
    angles = np.arange(7) * 2.0 * math.pi / 7.0
    positions = 15.0 * np.column_stack([np.cos(angles), np.sin(angles)])
    for _ in range(60):
        if ALGORITHM.goal(positions, PARAMS):
            break
        positions = positions + step_vectors(positions, list(range(7)))
    assert ALGORITHM.goal(positions, PARAMS)
    assert ALGORITHM.figures(positions, PARAMS)["spread"] < 5.0


def test_figures_give_the_largest_distance_from_the_centre_of_gravity() -> None:
    positions = np.array([[0.0, 0.0], [4.0, 0.0], [8.0, 0.0]])
    assert ALGORITHM.figures(positions, PARAMS) == {"spread": 4.0}


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_a_tolerance_that_is_not_positive_and_finite_is_refused(bad: float) -> None:
    with pytest.raises(AlgorithmParamsError, match=r"tolerance|finite"):
        Configured.of(ALGORITHM, 4, {"tolerance": bad})
    with pytest.raises(AlgorithmParamsError, match=r"tolerance|finite"):
        Configured.of(ALGORITHM, 4, {"tolerance": repr(bad)})
    with pytest.raises(AlgorithmParamsError, match="tolerance"):
        GatheringParams(4, bad)


def test_the_registry_finds_it_by_name_and_parameters_parse_from_text() -> None:
    alg = load_algorithm("gathering")
    assert alg is ALGORITHM
    assert "gathering" in available()
    configured = Configured.of(alg, 5, {"tolerance": "0.01"})
    assert configured.params == GatheringParams(None, 0.01)  # it declares it does not know n
    assert configured.describe() == "gathering tolerance=0.01"
    assert Configured.of(alg, 5).params == GatheringParams(None, 1e-3)
    with pytest.raises(AlgorithmParamsError, match="no parameter 'a'"):
        Configured.of(alg, 5, {"a": "4"})


def test_a_pair_collides_under_async_on_a_stale_view_and_the_run_ends_formed() -> None:
    # the counterexample to "no collision under any scheduler" (docs/algorithms.md, "gathering"):
    # robot 0 Looks at t = 3.03 while robot 1, which Looked at 1.76, has not started its step yet
    # (it starts at 3.04); robot 0 plans 0.125 toward a robot that will be 0.25 nearer, and its
    # move is stopped at contact. Its cycle ends after robot 1's move did: that Look planned on
    # the old configuration, so it does not decide the verdict, and the goal holds.
    import fatswarm

    result = fatswarm.run(
        positions=np.array([[0.0, 0.0], [2.5, 0.0]]),
        algorithm="gathering",
        scheduler="async",
        seed=1,
    )
    assert (result.collisions, result.status, result.rounds) == (1, "formed", 6)
    assert np.array_equal(result.positions, [[0.25, 0.0], [2.25, 0.0]])
