"""The agreement check shared by the property tests: every robot decides on the same bits."""

from __future__ import annotations

import numpy as np

from fatswarm.agent.algorithm import canonical_view, compute
from fatswarm.agent.canonical import canonical
from fatswarm.agent.geometry import sec
from fatswarm.agent.params import Params
from fatswarm.domain.frames import Frame
from fatswarm.domain.path import end_point, transform
from fatswarm.domain.tolerance import snap


def world_end(
    pts: np.ndarray, robot: int, flip: bool, params: Params, seed: int
) -> tuple[bytes, tuple[float, float] | None]:
    """What `robot` decides in its own frame (shuffled view): its canonical key and where its
    path ends in the world frame (None: it stays)."""
    others = np.delete(pts, robot, axis=0)
    others = others[np.random.default_rng(seed).permutation(len(others))]
    view = Frame(0.0, flip).to_local(others - pts[robot])
    key = canonical_view(view, params).key()
    path = compute(view, params)
    if not path:
        return key, None
    world = transform(
        Frame(0.0, flip).path_to_world(path), (float(pts[robot, 0]), float(pts[robot, 1])), False
    )
    return key, end_point((float(pts[robot, 0]), float(pts[robot, 1])), world)


def assert_observers_agree(pts: np.ndarray, params: Params) -> None:
    """Every robot, in both of its frames and whatever the order of its view, decides on the same
    bits, and so the same thing: it moves in both frames or in neither, to the same end point
    (or, the one exception of G12, a robot on L in an exactly mirror-symmetric swarm, to the
    mirror image of it)."""
    grid = snap(pts)
    keys = set()
    for robot in range(len(grid)):
        (k0, e0), (k1, e1) = (world_end(grid, robot, flip, params, robot) for flip in (False, True))
        keys |= {k0, k1}
        assert (e0 is None) == (e1 is None), f"robot {robot} moves in one frame only"
        if e0 is not None and e1 is not None and not np.allclose(e0, e1, atol=1e-9):
            canon = canonical(grid)
            assert canon.mirror_symmetric, f"robot {robot} goes to {e0} or {e1} by its frame"
            cx = sec(grid).center[0]
            assert abs(grid[robot, 0] - cx) <= 1e-6, "only a robot on L keeps its own side"
            assert np.allclose(e0, (2 * grid[robot, 0] - e1[0], e1[1]), atol=1e-9)
    assert len(keys) == 1, "observers computed on different canonical forms"
