"""`planning.orientation_of` matches robots from the top down when the rows are sorted by y; it
must give the very answer of matching every robot (`mirror_matched`, then `first_ranked`).

The oracle is the plain version it replaced, kept verbatim. Inputs: the clouds of the geometry
equivalence tests (random, on the grid, lattices with rows of equal y, mirror pairs, circles,
duplicates), each sorted and unsorted, about several axes, at tolerances that make windows of one
robot, of several, and of more than MATCH_WINDOW.
"""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.agent import planning


def _clouds(seed: int, count: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        n = int(rng.integers(2, 40))
        kind = int(rng.integers(4))
        if kind == 0:  # a lattice: rows of equal y, mirror pairs about its middle
            side = int(rng.integers(1, 12))
            pts = np.array([(2.0 * (i % side), 2.0 * (i // side)) for i in range(n)])
        elif kind == 1:  # mirror pairs about x = 0, one maybe nudged
            half = rng.uniform(0.5, 20.0, (n // 2 + 1, 2))
            pts = np.vstack([half, half * (-1.0, 1.0)])[:n]
            pts[int(rng.integers(n))] += rng.normal(0.0, 1e-7, 2) * (rng.random() < 0.5)
        elif kind == 2:  # random, on a coarse grid (equal heights)
            pts = np.round(rng.uniform(-6.0, 6.0, (n, 2)))
        else:
            pts = rng.uniform(-40.0, 40.0, (n, 2))
        out.append(np.ascontiguousarray(pts, dtype=np.float64))
    return out


@pytest.mark.parametrize(  # seeds 2 and 3 only in the slow run: other clouds, the same checks
    "seed", [1, pytest.param(2, marks=pytest.mark.slow), pytest.param(3, marks=pytest.mark.slow)]
)
def test_orientation_of_gives_the_plain_answer(seed: int) -> None:
    rng = np.random.default_rng(seed)
    top_down = 0
    for pts in _clouds(seed, 700):
        for ordered in (pts[np.lexsort((pts[:, 0], pts[:, 1]))], pts):
            for cx in (0.0, float(np.median(ordered[:, 0])), float(rng.integers(-3, 3))):
                for tol_at, tol_eq in (
                    (1e-6, 1e-9),
                    (1e-6, 1e-3),
                    (0.5, 0.5),
                    (0.0, 0.0),
                    (3.0, 0.0),
                ):
                    got = planning.orientation_of(ordered, cx, tol_at, tol_eq)
                    assert got == planning.orientation_of_all(ordered, cx, tol_at, tol_eq)
                    top_down += planning._top_unmatched(ordered, cx, tol_at, tol_eq) is not None
    assert top_down > 1000  # the top-down pass was taken, not only the plain one


def test_orientation_of_stays_plain_for_odd_tolerances_and_values() -> None:
    pts = np.array([(0.0, 0.0), (1.0, 2.0), (-1.0, 2.0), (3.0, np.inf), (0.5, np.nan)])
    for rows in (pts, pts[:4], pts[[0, 1, 2, 4]]):
        for tol_at in (-1.0, np.nan, np.inf, 0.0, 1e-6):
            with np.errstate(invalid="ignore"):
                got = planning.orientation_of(rows, 0.0, tol_at, 1e-9)
                assert got == planning.orientation_of_all(rows, 0.0, tol_at, 1e-9)
