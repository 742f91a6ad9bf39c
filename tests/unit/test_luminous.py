"""`uniform-circle-lights`: the paper's algorithm with three colours for asynchronous robots
(agent/luminous.py; docs/algorithm.md, "A luminous variant")."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import fatswarm
from fatswarm.agent import algorithm as paper
from fatswarm.agent import luminous
from fatswarm.agent.luminous import COLOURS, MOVING, OFF, READY
from fatswarm.agent.params import Params
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain.lights import Glance, Lit
from fatswarm.domain.path import Path, mirror
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import AlgorithmParamsError, Configured

LIGHTS = load_algorithm("uniform-circle-lights")


def view_of(positions: np.ndarray, robot: int) -> np.ndarray:
    out: np.ndarray = np.delete(positions, robot, axis=0) - positions[robot]
    return out


def lit(view: np.ndarray, own: str, others: tuple[str, ...], n: int) -> Lit:
    params = Configured.of(LIGHTS, n, {}).params
    return luminous.ALGORITHM.compute_lit(view, Glance(own, others), params)


def row(n: int, y: float = 0.0) -> list[list[float]]:
    return [[2.0 * k, y] for k in range(n)]


def test_it_is_registered_luminous_with_three_colours_and_the_papers_parameters() -> None:
    assert LIGHTS.name == "uniform-circle-lights"
    setting = Configured.of(LIGHTS, 6, {"a": 5.0})
    assert setting.colours == (OFF, READY, MOVING) == COLOURS
    assert setting.values == {"a": 5.0}
    assert setting.params == Params(6, 5.0)
    with pytest.raises(AlgorithmParamsError):
        Configured.of(LIGHTS, 6, {"a": 3.0})


def test_the_rule_step_by_step_on_a_start_with_one_mover() -> None:
    positions = random_start(5, 3)
    movers = [r for r in range(5) if paper.compute(view_of(positions, r), paper_params(5))]
    assert len(movers) == 1  # an asymmetric start: the plan has a lone mover
    mover, other = movers[0], (movers[0] + 1) % 5
    offs = (OFF,) * 4
    # everyone off: the mover announces, the others stay off
    first = lit(view_of(positions, mover), OFF, offs, 5)
    assert first == Lit(Path(), READY)
    assert lit(view_of(positions, other), OFF, offs, 5) == Lit(Path(), OFF)
    # announced and nobody else lit: it moves on the paper's path, showing `moving`
    moved = lit(view_of(positions, mover), READY, offs, 5)
    assert moved.colour == MOVING
    assert moved.path == paper.compute(view_of(positions, mover), paper_params(5))
    # a robot that sees another lit waits, a ready robot that sees one moving gives up
    assert lit(view_of(positions, other), OFF, (READY, OFF, OFF, OFF), 5) == Lit(Path(), OFF)
    gives_up = lit(view_of(positions, mover), READY, (MOVING, OFF, OFF, OFF), 5)
    assert gives_up == Lit(Path(), OFF)
    # after its move: `moving` while any other robot is ready, then off
    assert lit(view_of(positions, mover), MOVING, (READY, OFF, OFF, OFF), 5).colour == MOVING
    assert lit(view_of(positions, mover), MOVING, offs, 5) == Lit(Path(), OFF)
    # a ready robot that is not (or no longer) elected goes off
    assert lit(view_of(positions, other), READY, offs, 5) == Lit(Path(), OFF)


def test_a_ready_mover_waits_for_a_ready_robot_the_plan_does_not_elect() -> None:
    positions = random_start(6, 4)
    params = paper_params(6)
    mover = next(r for r in range(6) if paper.compute(view_of(positions, r), params))
    view = view_of(positions, mover)
    assert lit(view, READY, (READY,) + (OFF,) * 4, 6) == Lit(Path(), READY)


def test_a_mirror_pair_both_announce_and_both_move_from_the_same_configuration() -> None:
    # E3 (docs/algorithm.md, G5): symmetric about x = 0, the mirror leaders expand radially
    h = float(np.sqrt(9.0 - 1.44))
    positions = np.array([[-1.2, h], [1.2, h], [0.0, -3.0], [-1.5, 0.0], [1.5, 0.0]])
    params = paper_params(5)
    pair = [r for r in range(5) if paper.compute(view_of(positions, r), params)]
    assert pair == [0, 1]
    for r in pair:
        others = tuple(READY if k in pair else OFF for k in range(5) if k != r)
        assert lit(view_of(positions, r), OFF, (OFF,) * 4, 5).colour == READY
        moved = lit(view_of(positions, r), READY, others, 5)
        assert moved.colour == MOVING and moved.path


def paper_params(n: int) -> Params:
    return Params(n, 4.0)


COMBOS = [
    (OFF, (OFF,) * 5),
    (READY, (OFF,) * 5),
    (READY, (READY, OFF, OFF, OFF, OFF)),
    (OFF, (READY, OFF, OFF, OFF, OFF)),
    (MOVING, (READY, OFF, OFF, OFF, OFF)),
    (MOVING, (OFF,) * 5),
    (READY, (MOVING, READY, OFF, OFF, OFF)),
]


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
@pytest.mark.parametrize(("own", "others"), COMBOS)
def test_the_answer_ignores_the_view_order(seed: int, own: str, others: tuple[str, ...]) -> None:
    positions = random_start(6, seed)
    rng = np.random.default_rng(seed)
    for robot in range(6):
        view = view_of(positions, robot)
        base = lit(view, own, others, 6)
        assert base.colour in COLOURS
        for _ in range(3):
            order = rng.permutation(5)
            shuffled = tuple(others[i] for i in order)
            assert lit(view[order], own, shuffled, 6) == base


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5, 6])
@pytest.mark.parametrize(("own", "others"), COMBOS)
def test_the_answer_in_a_mirrored_frame_is_the_mirrored_answer(
    seed: int, own: str, others: tuple[str, ...]
) -> None:
    positions = random_start(6, seed)  # asymmetric: no robot on L chooses a side by its own X
    for robot in range(6):
        view = view_of(positions, robot)
        base = lit(view, own, others, 6)
        flipped = lit(view * [-1.0, 1.0], own, others, 6)
        assert flipped.colour == base.colour
        assert flipped.path == mirror(base.path)


def test_every_answer_is_a_colour_of_the_palette_whatever_the_lights() -> None:
    positions = np.array(row(4))
    for own in COLOURS:
        for others in itertools.product(COLOURS, repeat=3):
            for robot in range(4):
                assert lit(view_of(positions, robot), own, others, 4).colour in COLOURS
    # hidden lights (--lights internal / external) read as off
    params = Configured.of(LIGHTS, 4, {}).params
    for glance in (None, Glance(None, (OFF,) * 3), Glance(READY, None)):
        answer = luminous.ALGORITHM.compute_lit(view_of(positions, 0), glance, params)
        assert answer.colour in COLOURS


def test_compute_is_the_first_look_with_every_robot_off() -> None:
    positions = random_start(5, 3)
    params = Configured.of(LIGHTS, 5, {}).params
    for robot in range(5):
        view = view_of(positions, robot)
        assert luminous.ALGORITHM.compute(view, params) == lit(view, OFF, (OFF,) * 4, 5).path


# Hand-made starts of touching horizontal rows: under async-slowest `uniform-circle-stepped`
# collides on the single rows (docs/results.md); the luminous variant forms them collision-free.
ROW_CASES = [
    ("row of 10", row(10), 1),
    ("row of 10", row(10), 16),
    ("row of 12", row(12), 15),
    ("two rows of 4", row(4) + row(4, 2.0), 0),
    ("three rows of 3", row(3) + row(3, 2.0) + row(3, 4.0), 2),
]


@pytest.mark.parametrize("scheduler", ["async-slowest", "async"])
@pytest.mark.parametrize(("name", "start", "seed"), ROW_CASES, ids=[c[0] for c in ROW_CASES])
def test_touching_rows_form_without_collision_under_async(
    scheduler: str, name: str, start: list[list[float]], seed: int
) -> None:
    del name
    result = fatswarm.run(
        algorithm="uniform-circle-lights",
        positions=np.array(start),
        scheduler=scheduler,
        seed=seed,
    )
    assert (str(result.status), result.collisions) == ("formed", 0)


def test_the_stepped_variant_collides_on_the_row_of_ten_the_lights_variant_forms() -> None:
    start = np.array(row(10))
    stepped = fatswarm.run(
        algorithm="uniform-circle-stepped", positions=start, scheduler="async-slowest", seed=1
    )
    assert stepped.collisions > 0  # the finding of docs/results.md
    lights = fatswarm.run(
        algorithm="uniform-circle-lights", positions=start, scheduler="async-slowest", seed=1
    )
    assert (str(lights.status), lights.collisions) == ("formed", 0)


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_it_forms_under_the_round_models_too(scheduler: str) -> None:
    result = fatswarm.run(
        algorithm="uniform-circle-lights",
        positions=np.array(row(3) + row(3, 2.0)),
        scheduler=scheduler,
        seed=3,
    )
    assert (str(result.status), result.collisions) == ("formed", 0)


def test_an_announce_that_ends_the_round_of_looks_does_not_end_the_run() -> None:
    # Every robot stays in its first cycle; the mover's cycle (it only changes its colour) can be
    # the last of them: the world must count the colour to come as a change, or the run would
    # end `stalled` there (docs/model.md, "Lights").
    for seed in range(6):
        result = fatswarm.run(
            algorithm="uniform-circle-lights",
            positions=np.array(row(4)),
            scheduler="async-slowest",
            seed=seed,
        )
        assert (str(result.status), result.collisions) == ("formed", 0)
        assert result.moves >= 1
