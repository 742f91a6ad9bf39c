"""`uniform-circle-stepped`: the paper's algorithm with every move cut to `step`, the variant for
asynchronous robots (docs/results.md)."""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.agent import stepped as stepped_variant
from fatswarm.agent import uniform_circle
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain.draws import draw_flip
from fatswarm.domain.path import path_length, truncate
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import AlgorithmParamsError, Configured

STEPPED = load_algorithm("uniform-circle-stepped")


def test_it_is_registered_with_the_papers_parameters_and_a_step() -> None:
    assert STEPPED.name == "uniform-circle-stepped"
    assert [p.name for p in STEPPED.parameters] == ["a", "step"]
    setting = Configured.of(STEPPED, 6, {"a": 5.0, "step": 0.5})
    assert setting.values == {"a": 5.0, "step": 0.5}
    for bad in (0.0, -1.0, float("nan"), True):
        with pytest.raises(AlgorithmParamsError):
            Configured.of(STEPPED, 6, {"step": bad})


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_each_move_is_the_papers_move_cut_to_the_step(seed: int) -> None:
    n, step = 7, 0.75
    positions = random_start(n, seed)
    paper = Configured.of(uniform_circle.ALGORITHM, n, {})
    stepped = Configured.of(STEPPED, n, {"step": step})
    moved = 0
    for robot in range(n):
        view = np.delete(positions, robot, axis=0) - positions[robot]
        whole = paper.compute(view)
        cut = stepped.compute(view)
        assert cut == (truncate((0.0, 0.0), whole, step) if whole else whole)
        assert path_length((0.0, 0.0), cut) <= step + 1e-12
        moved += bool(whole)
    assert moved  # the start needs moves: the test is not vacuous
    flips = [draw_flip(seed, r) for r in range(n)]
    # the variant itself: the registry's Algorithm protocol leaves the round_planner hook out
    planner = stepped_variant.ALGORITHM.round_planner(stepped.params)
    planned = planner.paths(positions, list(range(n)), flips)
    paper_planned = uniform_circle.SharedPlans(stepped.params.paper).paths(
        positions, list(range(n)), flips
    )
    assert planned == {
        r: truncate((0.0, 0.0), p, step) if p else p for r, p in paper_planned.items()
    }


def test_the_papers_async_counterexample_forms_collision_free_with_steps() -> None:
    # docs/results.md: under async the paper's algorithm collides from this start (seed 0)
    start = np.array([[-1.0, 4.0], [0.934, 3.49], [1.283, 1.52], [-0.901, -8.0]])
    model = make_scheduler("async", 4, 0)
    paper = run_lockstep(start, Configured.of(uniform_circle.ALGORITHM, 4, {}), model, seed=0)
    assert paper.collisions > 0
    stepped = run_lockstep(start, Configured.of(STEPPED, 4, {}), model, seed=0)
    assert (stepped.status, stepped.collisions) == ("formed", 0)
