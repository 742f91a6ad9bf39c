"""The one-file example algorithm (examples/spread_out.py), loaded by path like a user's own."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.path import STAY, Line, Points, end_point, mirror
from fatswarm.domain.path import Path as RobotPath
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Algorithm, AlgorithmParamsError, Configured

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "property"))
from straight_moves import closest_during, grid_starts, view_of

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "spread_out.py"
SETTINGS = settings(max_examples=60, deadline=None)


@pytest.fixture(scope="module")
def algorithm() -> Algorithm[Any]:
    return load_algorithm(f"{EXAMPLE}:ALGORITHM")


def test_it_loads_by_file_path_as_the_docs_say(
    monkeypatch: pytest.MonkeyPatch, algorithm: Algorithm[Any]
) -> None:
    monkeypatch.chdir(ROOT)
    loaded = load_algorithm("examples/spread_out.py:ALGORITHM")
    assert loaded is algorithm  # a file is imported once per process
    assert loaded.name == "spread-out"
    assert [p.name for p in loaded.parameters] == ["spacing", "step"]


def test_the_file_imports_only_the_seam_the_path_numpy_and_the_standard_library() -> None:
    imports = [
        line.split()[1]
        for line in EXAMPLE.read_text().splitlines()
        if line.startswith(("import ", "from "))
    ]
    fatswarm = {name for name in imports if name.startswith("fatswarm")}
    assert fatswarm <= {"fatswarm.domain.seam", "fatswarm.domain.path"}


@SETTINGS
@given(grid_starts(pitch_max=5.0), st.data())
def test_path_is_the_same_for_every_order_of_the_view(
    algorithm: Algorithm[Any], positions: Points, data: st.DataObject
) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        order = data.draw(st.permutations(range(len(view))))
        assert algorithm.compute(view[order], params) == algorithm.compute(view, params)


@SETTINGS
@given(grid_starts(pitch_max=5.0))
def test_mirroring_the_view_mirrors_the_path_exactly(
    algorithm: Algorithm[Any], positions: Points
) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for robot in range(len(positions)):
        view = view_of(positions, robot)
        mirrored = view * np.array([-1.0, 1.0])
        assert algorithm.compute(mirrored, params) == mirror(algorithm.compute(view, params))


@SETTINGS
@given(grid_starts(pitch_max=5.0))
def test_robots_never_overlap_and_spread_out_when_all_move_at_once(
    algorithm: Algorithm[Any], positions: Points
) -> None:
    params = Configured.of(algorithm, len(positions)).params
    for _ in range(200):
        if algorithm.goal(positions, params):
            break
        moves = np.array(
            [
                end_point((0.0, 0.0), algorithm.compute(view_of(positions, r), params))
                for r in range(len(positions))
            ]
        )
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


@pytest.mark.parametrize(
    "values", [{"spacing": "2"}, {"step": "0"}, {"spacing": "nan"}, {"radius": "6"}]
)
def test_bad_parameters_are_refused(algorithm: Algorithm[Any], values: dict[str, str]) -> None:
    with pytest.raises(AlgorithmParamsError):
        Configured.of(algorithm, 4, values)
