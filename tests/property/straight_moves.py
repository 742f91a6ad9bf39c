"""Helpers for algorithms whose robots move in straight lines: starts on a jittered grid, views,
and the closest two centres come while all robots move at once."""

from __future__ import annotations

import itertools
import math

import numpy as np
from hypothesis import strategies as st

from fatswarm.domain.path import Points


@st.composite
def grid_starts(
    draw: st.DrawFn, cells: int = 4, pitch_max: float = 8.0, offset: float = 0.0
) -> Points:
    """2..9 robots in distinct cells of a grid of pitch 2..`pitch_max`, jittered (never closer
    than 2), moved by up to `offset` in each coordinate."""
    n = draw(st.integers(2, 9))
    picked = draw(
        st.lists(
            st.tuples(st.integers(0, cells - 1), st.integers(0, cells - 1)),
            min_size=n,
            max_size=n,
            unique=True,
        )
    )
    pitch = draw(st.floats(2.0, pitch_max))
    jitter = (pitch - 2.0) / 4.0  # two jitters of <= jitter * sqrt(2) each leave >= 2
    offsets = draw(
        st.lists(
            st.tuples(st.floats(-jitter, jitter), st.floats(-jitter, jitter)),
            min_size=n,
            max_size=n,
        )
    )
    origin = np.array([draw(st.floats(-offset, offset)), draw(st.floats(-offset, offset))])
    return np.asarray(np.asarray(picked, dtype=np.float64) * pitch + np.asarray(offsets) + origin)


def view_of(positions: Points, robot: int) -> Points:
    """The others relative to `robot` (an identity frame)."""
    return np.asarray(np.delete(positions, robot, axis=0) - positions[robot])


def closest_during(positions: Points, moves: Points) -> float:
    """Least distance between two centres while all move at once at unit speed, straight."""
    lengths = np.hypot(moves[:, 0], moves[:, 1])
    best = math.inf
    n = len(positions)
    for i in range(n):
        for j in range(i + 1, n):
            # relative motion is linear between the times either robot stops
            times = sorted({0.0, float(lengths[i]), float(lengths[j])})
            rel = [
                positions[j]
                - positions[i]
                + moves[j] * (min(t, lengths[j]) / lengths[j] if lengths[j] else 0.0)
                - moves[i] * (min(t, lengths[i]) / lengths[i] if lengths[i] else 0.0)
                for t in times
            ]
            best = min(best, float(np.hypot(*rel[0])))
            for a, b in itertools.pairwise(rel):
                d = b - a
                len2 = float(d @ d)
                f = 0.0 if len2 == 0.0 else min(1.0, max(0.0, -float(a @ d) / len2))
                best = min(best, float(np.hypot(*(a + f * d))))
    return best


def min_distance(positions: Points) -> float:
    """The least distance between two centres."""
    diff = positions[:, np.newaxis, :] - positions[np.newaxis, :, :]
    dist = np.hypot(diff[:, :, 0], diff[:, :, 1])
    np.fill_diagonal(dist, np.inf)
    return float(dist.min())


__all__ = ["closest_during", "grid_starts", "min_distance", "view_of"]
