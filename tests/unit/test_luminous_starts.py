"""The start families added for the async hunts of `uniform-circle-lights` (docs/results.md):
`rows` (touching horizontal rows) and `stacked-rows` (touching rows on one another)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fatswarm.deploy.hunt.search import start_families
from fatswarm.deploy.scenarios.adversarial import (
    FAMILIES,
    adversarial_start,
    build_adversarial,
)
from fatswarm.deploy.scenarios.shapes import horizontal_rows, min_separation
from fatswarm.world.physics import validate_configuration

OLD_FAMILIES = (
    "near-symmetric",
    "exact-symmetric",
    "near-touching",
    "lattice",
    "vertical-line",
    "offset",
    "rim",
    "formed",
)


def test_the_new_families_come_after_the_old_ones_which_keep_their_seeds() -> None:
    assert FAMILIES[: len(OLD_FAMILIES)] == OLD_FAMILIES
    assert FAMILIES[len(OLD_FAMILIES) :] == ("rows", "stacked-rows")
    assert {"rows", "stacked-rows"} <= set(start_families())


def test_horizontal_rows_places_each_row_from_its_first_robot() -> None:
    pts = horizontal_rows([(0.0, 0.0, [2.0, 2.0]), (1.0, 2.0, [])])
    np.testing.assert_array_equal(pts, [[0.0, 0.0], [2.0, 0.0], [4.0, 0.0], [1.0, 2.0]])


def heights(pts: np.ndarray) -> list[float]:
    return sorted({float(y) for y in pts[:, 1]})


@pytest.mark.parametrize("n", [2, 3, 5, 8, 12, 20])
def test_rows_are_one_to_three_rows_of_touching_or_near_touching_robots(n: int) -> None:
    touching = 0
    for seed in range(30):
        built = build_adversarial("rows", n, seed)
        pts = built.positions
        validate_configuration(pts)
        levels = heights(pts)
        assert 1 <= len(levels) <= 3 and int(built.variant[0]) >= len(levels)
        assert all(b - a >= 2.0 for a, b in itertools.pairwise(levels))
        touching += abs(min_separation(pts) - 2.0) < 1e-6
    if n >= 5:
        assert touching >= 20  # most draws have robots in contact


@pytest.mark.parametrize("n", [2, 3, 5, 8, 12, 20])
def test_stacked_rows_touch_the_row_below(n: int) -> None:
    for seed in range(30):
        built = build_adversarial("stacked-rows", n, seed)
        pts = built.positions
        validate_configuration(pts)
        levels = heights(pts)
        if "nudged" in built.variant:
            continue  # one robot moved off its row by 1e-9..1e-6
        assert len(levels) >= 2
        for low, high in itertools.pairwise(levels):
            below = pts[pts[:, 1] == low]
            above = pts[pts[:, 1] == high]
            gaps = np.hypot(*(above[:, None, :] - below[None, :, :]).transpose(2, 0, 1))
            # each row rests on the one below (brick rows: sqrt(3) written to 3-7 decimals)
            assert abs(float(gaps.min()) - 2.0) < 1e-3


def test_a_single_row_of_touching_robots_is_drawn_for_large_n() -> None:
    singles = [
        s
        for s in range(40)
        if len(heights(adversarial_start("rows", 10, s))) == 1
        and build_adversarial("rows", 10, s).variant == "1-row-touching"
    ]
    assert singles  # the start on which uniform-circle-stepped collides (docs/results.md)
