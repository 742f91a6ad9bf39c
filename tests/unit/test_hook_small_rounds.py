"""The round hooks' two ways (robot by robot up to EACH_UP_TO view rows, as arrays past it) give
every robot the path of its own `compute`, at the sizes on either side of the threshold."""

from __future__ import annotations

import numpy as np
import pytest

from fatswarm.agent import gathering, oblot_go_to_cog
from fatswarm.agent.gathering import GatheringParams
from fatswarm.agent.oblot_common import make_oblot_params
from fatswarm.domain.path import Line, Path, StraightMoves
from fatswarm.domain.tolerance import snap


def views_of(n: int, seed: int) -> np.ndarray:
    """Every robot's view of n snapped positions, x mirrored for odd robots (a -0.0 where two
    robots share an x), rows shuffled."""
    rng = np.random.default_rng(seed)
    positions = snap(rng.uniform(-3.0 * n, 3.0 * n, size=(n, 2)))
    positions[1, 0] = positions[0, 0]
    out = np.empty((n, n - 1, 2))
    for robot in range(n):
        others = np.delete(positions, robot, axis=0) - positions[robot]
        if robot % 2:
            others[:, 0] *= -1.0
        out[robot] = others[rng.permutation(n - 1)]
    return out


def assert_same(answer: StraightMoves, paths: list[Path]) -> None:
    assert answer.paths() == paths
    for end, go, path in zip(answer.ends.tolist(), answer.goes.tolist(), paths, strict=True):
        if go:
            (segment,) = path.segments
            assert type(segment) is Line
            assert np.array(end).tobytes() == np.array(segment.end).tobytes()


@pytest.mark.parametrize("n", [2, 3, 8, 10, 11, 12, 16])
@pytest.mark.parametrize("each", [0, 10**6])
def test_gathering_hook_either_way_is_compute(
    n: int, each: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(gathering, "EACH_UP_TO", each)
    params = GatheringParams(n, 1e-3)
    for seed in range(4):
        views = views_of(n, seed)
        want = [gathering.ALGORITHM.compute(view, params) for view in views]
        assert_same(gathering.ALGORITHM.compute_views(views, params), want)


@pytest.mark.parametrize("n", [2, 3, 7, 8, 16])
@pytest.mark.parametrize("each", [0, 10**6])
def test_go_to_cog_hook_either_way_is_compute(
    n: int, each: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(oblot_go_to_cog, "EACH_UP_TO", each)
    params = make_oblot_params(n, {"tolerance": 0.0})
    for seed in range(4):
        views = views_of(n, seed)
        want = [oblot_go_to_cog.ALGORITHM.compute(view, params) for view in views]
        assert_same(oblot_go_to_cog.ALGORITHM.compute_views(views, params), want)
