"""Private frames: origin at the robot, shared +Y, X axis flipped at random (no chirality)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fatswarm.domain.path import Path, Point, Points, transform


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
