"""The canonical form of a configuration: the one frame in which every robot decides.

Robots see the swarm in private frames (own origin, X maybe flipped). On grid positions
(agent/tolerance.py, GRID) every such view is an exact translate, possibly mirrored, of every
other, so this module maps each view, exactly, to the same array: translate so that the lowest
robot (then the leftmost) is at the origin, sort by (y, x), and of the two mirror images take the
lexicographically smaller. The algorithm then runs on bit-identical numbers in every robot, and
ties are broken by canonical position, which is geometry, never by the order of a view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from agent.path import Path, Points, transform


@dataclass(frozen=True, slots=True)
class Canonical:
    """A configuration in canonical form, and where one robot of it (the observer) sits.

    `points` (n, 2) is sorted by (y, x) with its first row at the origin. The observer's frame is
    recovered as x_frame = flip * (x + offset_x), y_frame = y + offset_y. `mirror_symmetric` is
    True when the configuration is exactly its own mirror image (both choices give these points).
    """

    points: Points
    observer: int
    offset: tuple[float, float]
    flip: float
    mirror_symmetric: bool

    def key(self) -> bytes:
        """Bytes equal for exactly the configurations with equal canonical points."""
        return self.points.tobytes()

    def to_frame(self, path: Path) -> Path:
        """A path given in canonical coordinates, in the observer's frame."""
        if not path:
            return path
        ox, oy = self.offset
        return transform(path, (self.flip * ox, oy), self.flip < 0.0)


def canonical(points: Points, observer: int = 0) -> Canonical:
    """The canonical form of `points` (n, 2, on the grid), with `observer`'s row located in it."""
    xs, ys = points[:, 0], points[:, 1]
    up = np.argsort(ys, kind="stable")
    ys_sorted = ys[up]
    if (ys_sorted[1:] == ys_sorted[:-1]).any():  # equal heights: order them by x, both ways
        up = np.lexsort((xs, ys))
        down = np.lexsort((-xs, ys))
    else:
        down = up
    # Both orders list the same y values; the mirror image differs only in x.
    ref_up, ref_down = up[0], down[0]
    x_up = xs[up] - xs[ref_up]
    x_down = xs[ref_down] - xs[down]
    diff = (x_up - x_down).nonzero()[0]
    symmetric = len(diff) == 0
    if symmetric or x_up[diff[0]] < x_down[diff[0]]:
        order, cx, flip = up, x_up, 1.0
    else:
        order, cx, flip = down, x_down, -1.0
    ref = order[0]
    out = np.empty((len(points), 2), dtype=np.float64)
    out[:, 0] = cx
    out[:, 1] = ys_sorted - ys[ref]
    out += 0.0  # -0.0 -> +0.0: equal positions are equal bits
    where = int((order == observer).argmax())
    return Canonical(out, where, (flip * float(xs[ref]), float(ys[ref])), flip, symmetric)
