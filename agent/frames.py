"""Private frames: origin at the robot, shared +Y, X axis flipped at random (no chirality)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fatswarm.agent.path import Path, Point, Points, transform

FRAME_STREAM = 0xF1A9  # keeps frame draws apart from other seeded streams of the same run


def draw_flip(seed: int, robot: int) -> bool:
    """Robot `robot`'s X mirroring in a run seeded with `seed` (same in lockstep and networked)."""
    rng = np.random.default_rng([FRAME_STREAM, seed & 0xFFFFFFFF, robot])
    return bool(rng.random() < 0.5)


def to_local(others_world: Points, me_world: Point, flip_x: bool) -> Points:
    """Other robots' positions as the robot at `me_world` sees them in its own frame."""
    view = np.subtract(others_world, me_world, dtype=np.float64)
    if flip_x:
        view[:, 0] *= -1.0
    return view


def path_to_world(path_local: Path, me_world: Point, flip_x: bool) -> Path:
    """A path computed in the robot's frame, expressed in the world frame."""
    return transform(path_local, me_world, flip_x)


def compute_in_frame(view: Points, flip_x: bool, compute: Callable[[Points], Path]) -> Path:
    """One robot's Compute: `view` (others relative to it, world axes) mirrored into its private
    frame, the path computed there and mirrored back: relative to the robot, world axes.

    The agent process and the lock step both call this, so both hand the world the same path."""
    local = view.copy()
    if flip_x:
        local[:, 0] = -local[:, 0]
    return path_to_world(compute(local), (0.0, 0.0), flip_x)
