"""The one-file example algorithm (examples/spread_out.py), loaded by path like a user's own."""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent.path import STAY, Line, end_point, mirror
from fatswarm.agent.path import Path as RobotPath
from fatswarm.agent.registry import load_algorithm
from fatswarm.agent.seam import Algorithm, AlgorithmParamsError, Configured, Points

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "spread_out.py"
SETTINGS = settings(max_examples=60, deadline=None)


@pytest.fixture(scope="module")
def algorithm() -> Algorithm[Any]:
    return load_algorithm(f"{EXAMPLE}:ALGORITHM")


@st.composite
def crowded_starts(draw: st.DrawFn) -> Points:
    """2..9 robots in distinct cells of a grid of pitch 2..5, jittered: never closer than 2."""
    n = draw(st.integers(2, 9))
    cells = draw(st.lists(st.tuples(st.integers(0, 3), st.integers(0, 3)),
                          min_size=n, max_size=n, unique=True))
    pitch = draw(st.floats(2.0, 5.0))
    jitter = (pitch - 2.0) / 4.0  # two jitters of <= jitter * sqrt(2) each leave >= 2
    offsets = draw(st.lists(st.tuples(st.floats(-jitter, jitter), st.floats(-jitter, jitter)),
                            min_size=n, max_size=n))
    return np.asarray(np.asarray(cells, dtype=np.float64) * pitch + np.asarray(offsets))


def view_of(positions: Points, robot: int) -> Points:
    """The others relative to `robot` (an identity frame)."""
    return np.asarray(np.delete(positions, robot, axis=0) - positions[robot])


def closest_during(positions: Points, moves: Points) -> float:
    """Least distance between two centres while all move at once at unit speed, straight."""
    lengths = np.hypot(moves[:, 0], moves[:, 1])
    best = math.inf
    for i in range(len(positions)):
        for j in range(i + 1, len(positions)):
            times = sorted({0.0, float(lengths[i]), float(lengths[j])})  # relative motion is
            rel = [positions[j] - positions[i]                             # linear in between
                   + moves[j] * (min(t, lengths[j]) / lengths[j] if lengths[j] else 0.0)
                   - moves[i] * (min(t, lengths[i]) / lengths[i] if lengths[i] else 0.0)
                   for t in times]
            best = min(best, float(np.hypot(*rel[0])))
            for a, b in itertools.pairwise(rel):
                d = b - a
                len2 = float(d @ d)
                f = 0.0 if len2 == 0.0 else min(1.0, max(0.0, -float(a @ d) / len2))
                best = min(best, float(np.hypot(*(a + f * d))))
    return best


def test_it_loads_by_file_path_as_the_docs_say(monkeypatch: pytest.MonkeyPatch,
                                               algorithm: Algorithm[Any]) -> None:
    monkeypatch.chdir(ROOT)
    loaded = load_algorithm("examples/spread_out.py:ALGORITHM")
    assert loaded is algorithm  # a file is imported once per process
    assert loaded.name == "spread-out"
    assert [p.name for p in loaded.parameters] == ["spacing", "step"]


def test_the_file_imports_only_the_seam_the_path_numpy_and_the_standard_library() -> None:
    imports = [line.split()[1] for line in EXAMPLE.read_text().splitlines()
               if line.startswith(("import ", "from "))]
    fatswarm = {name for name in imports if name.startswith("fatswarm")}
    assert fatswarm <= {"fatswarm.agent.seam", "fatswarm.agent.path"}


@SETTINGS
@given(crowded_starts(), st.data())
def test_path_is_the_same_for_every_order_of_the_view(algorithm: Algorithm[Any],
                                                      positions: Points,
                                                      data: st.DataObject) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        order = data.draw(st.permutations(range(len(view))))
        assert algorithm.compute(view[order], params) == algorithm.compute(view, params)


@SETTINGS
@given(crowded_starts())
def test_mirroring_the_view_mirrors_the_path_exactly(algorithm: Algorithm[Any],
                                                     positions: Points) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        mirrored = view * np.array([-1.0, 1.0])
        assert algorithm.compute(mirrored, params) == mirror(algorithm.compute(view, params))


@SETTINGS
@given(crowded_starts())
def test_robots_never_overlap_and_spread_out_when_all_move_at_once(algorithm: Algorithm[Any],
                                                                  positions: Points) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for _ in range(200):
        if algorithm.goal(positions, params):
            break
        moves = np.array([end_point((0.0, 0.0), algorithm.compute(view_of(positions, r), params))
                          for r in range(len(positions))])
        assert closest_during(positions, moves) >= 2.0 - 1e-9
        positions = positions + moves
    assert algorithm.goal(positions, params)


def test_close_robots_move_straight_apart(algorithm: Algorithm[Any]) -> None:
    params = Configured.of(algorithm, 2).params
    assert algorithm.compute(np.array([[2.0, 0.0]]), params) == RobotPath((Line((-1.0, 0.0)),))
    assert algorithm.compute(np.array([[0.0, -3.5]]), params) == RobotPath((Line((0.0, 1.0)),))


def test_a_robot_with_no_neighbour_closer_than_spacing_stays(algorithm: Algorithm[Any]) -> None:
    params = Configured.of(algorithm, 3, {"spacing": "5"}).params
    assert algorithm.compute(np.array([[5.0, 0.0], [0.0, -7.0]]), params) == STAY
    assert algorithm.compute(np.empty((0, 2)), params) == STAY


def test_goal_holds_on_a_spread_start_and_not_on_a_crowded_one(algorithm: Algorithm[Any]) -> None:
    params = Configured.of(algorithm, 9).params
    grid = 4.0 * np.array([[x, y] for x in range(3) for y in range(3)], dtype=np.float64)
    assert algorithm.goal(grid, params)
    assert not algorithm.goal(grid * 0.99, params)
    assert algorithm.goal(np.array([[1.0, 1.0]]), Configured.of(algorithm, 1).params)


@pytest.mark.parametrize("values", [{"spacing": "2"}, {"step": "0"}, {"spacing": "nan"},
                                    {"radius": "6"}])
def test_bad_parameters_are_refused(algorithm: Algorithm[Any], values: dict[str, str]) -> None:
    with pytest.raises(AlgorithmParamsError):
        Configured.of(algorithm, 4, values)
