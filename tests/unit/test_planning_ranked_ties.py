"""The tolerant order of `planning.ranked` equals its eager definition, ties and all.

`ranked` makes the later key columns only when a tie needs them and copies the first column only
when a second index is asked for; the order it yields must not depend on either.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from fatswarm.agent.planning import first_ranked, ranked

RNG = np.random.default_rng(11)
TOL = 1e-3


def definition(cols: tuple[np.ndarray, ...], tol: float) -> Iterator[int]:
    """Smallest first column, values within tol of it tied and settled by the next columns,
    full ties by index; the taken row then leaves the race."""
    first = np.array(cols[0], dtype=np.float64)
    for _ in range(len(first)):
        i = int(first.argmin())
        tied = (first <= first[i] + tol).nonzero()[0]
        if len(tied) > 1:
            group = tied
            for col in cols[1:]:
                values = col[group]
                group = group[values <= values.min() + tol]
                if len(group) == 1:
                    break
            i = int(group[0])
        first[i] = np.inf
        yield i


def columns(m: int, width: int) -> tuple[np.ndarray, ...]:
    """Key columns drawn from a few values (many exact and near ties), within-tol jitter."""
    return tuple(
        RNG.integers(0, 3, size=m) * 10 * TOL + RNG.choice([0.0, 0.4 * TOL, -0.0], size=m)
        for _ in range(width)
    )


class TieKeys:
    """The later columns, counting how often they are asked for."""

    def __init__(self, cols: tuple[np.ndarray, ...]) -> None:
        self.cols = cols
        self.made = 0

    def __call__(self) -> tuple[np.ndarray, ...]:
        self.made += 1
        return self.cols[1:]


@pytest.mark.parametrize("m", [1, 2, 3, 7, 30])
@pytest.mark.parametrize("width", [1, 2, 3])
def test_ranked_yields_the_definitions_order(m: int, width: int) -> None:
    for _ in range(20):
        cols = columns(m, width)
        tie_keys = TieKeys(cols)
        got = list(ranked(cols[0], TOL, tie_keys))
        assert got == list(definition(cols, TOL))
        assert first_ranked(cols[0], TOL, TieKeys(cols)) == got[0]
        assert tie_keys.made <= 1  # made once at most


def test_ranked_leaves_the_callers_keys_alone() -> None:
    keys = np.array([3.0, 1.0, 2.0])
    assert list(ranked(keys, TOL)) == [1, 2, 0]
    assert keys.tolist() == [3.0, 1.0, 2.0]
