"""The canonical form equals, bit for bit, its definition by lexicographic sorts (np.lexsort).

The module sorts by height alone when all heights differ and by complex (y, x) keys otherwise;
these tests pin that to the plain definition on configurations with many equal heights, exact
mirror symmetry, duplicate points, negative zeros and a single robot, for every observer.
"""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.agent.canonical import SharedForm, canonical
from fatswarm.domain.tolerance import snap

RNG = np.random.default_rng(20)


def reference(points: np.ndarray, observer: int) -> tuple[bytes, int, tuple[float, float], float]:
    """The definition: both mirror images sorted by (y, x), the lexicographically smaller taken."""
    xs, ys = points[:, 0], points[:, 1]
    up = np.lexsort((xs, ys))
    down = np.lexsort((-xs, ys))
    x_up = xs[up] - xs[up[0]]
    x_down = xs[down[0]] - xs[down]
    diff = (x_up - x_down).nonzero()[0]
    if len(diff) == 0 or x_up[diff[0]] < x_down[diff[0]]:
        order, cx, sign = up, x_up, 1.0
    else:
        order, cx, sign = down, x_down, -1.0
    out = np.stack([cx, ys[order] - ys[order[0]]], axis=1) + 0.0
    where = int((order == observer).argmax())
    ref = int(order[0])
    return out.tobytes(), where, (sign * float(xs[ref]), float(ys[ref])), sign


def configurations() -> list[np.ndarray]:
    """Grid configurations with few distinct heights (many ties), symmetric ones and oddities."""
    out = [np.array([[0.0, 0.0]]), np.array([[-0.0, 1.0], [0.0, -0.0], [3.0, 1.0]])]
    for size in (2, 3, 5, 8, 16, 40):
        out.append(snap(RNG.uniform(-20, 20, size=(size, 2))))  # all heights differ
        rows = RNG.integers(0, 3, size=size).astype(np.float64)
        out.append(snap(np.stack([RNG.uniform(-20, 20, size), rows * 2.5], axis=1)))
        half = snap(np.stack([RNG.uniform(0.5, 20, size), RNG.integers(0, 4, size) * 3.0], axis=1))
        out.append(np.concatenate([half, half * np.array([-1.0, 1.0])]) + 0.0)  # exact mirror
    dup = snap(RNG.uniform(-5, 5, size=(6, 2)))
    out.append(np.concatenate([dup, dup[:3]]))  # duplicate points: index order breaks ties
    return out


@pytest.mark.parametrize("points", configurations(), ids=lambda p: f"n{len(p)}")
def test_the_canonical_form_is_the_lexicographic_definition(points: np.ndarray) -> None:
    for observer in range(len(points)):
        got = canonical(points, observer)
        key, where, offset, sign = reference(points, observer)
        assert got.points.tobytes() == key
        assert (got.observer, got.flip) == (where, sign)
        assert np.array(got.offset).tobytes() == np.array(offset).tobytes()


@pytest.mark.parametrize("points", configurations(), ids=lambda p: f"n{len(p)}")
def test_the_shared_form_keeps_both_mirror_orders(points: np.ndarray) -> None:
    shared = SharedForm.of(points)
    xs, ys = points[:, 0], points[:, 1]
    assert shared.form.up.tolist() == np.lexsort((xs, ys)).tolist()
    assert shared.form.down.tolist() == np.lexsort((-xs, ys)).tolist()
