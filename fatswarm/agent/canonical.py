"""The canonical form of a configuration: the one frame in which every robot decides.

Robots see the swarm in private frames (own origin, X maybe flipped). On grid positions
(fatswarm/domain/tolerance.py, GRID) every such view is an exact translate, possibly mirrored, of
every other, so this module maps each view, exactly, to the same array: translate so that the lowest
robot (then the leftmost) is at the origin, sort by (y, x), and of the two mirror images take the
lexicographically smaller. The algorithm then runs on bit-identical numbers in every robot, and
ties are broken by canonical position, which is geometry, never by the order of a view.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.path import Path, Points, transform

IntArray = NDArray[np.intp]


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
    form = _form(points)
    order = form.order()
    ref = int(order[0])
    at = order == observer
    x_ref, y_ref = float(points[ref, 0]), float(points[ref, 1])
    return Canonical(
        form.points, int(at.argmax()), (form.sign * x_ref, y_ref), form.sign, form.symmetric
    )


class _Form(NamedTuple):
    """The canonical array and how it was made: the robots sorted by (y, x) (`up`) and by
    (y, -x) (`down`, the mirror image's order), and which image was taken (`sign` +1: up)."""

    points: Points
    up: IntArray
    down: IntArray
    sign: float
    symmetric: bool

    def order(self) -> IntArray:
        return self.up if self.sign > 0.0 else self.down


def _form(points: Points) -> _Form:
    up = points[:, 1].argsort()  # any sort: with all heights distinct the order is unique
    out = points.take(up, axis=0)
    heights = out[:, 1]
    same = heights[1:] == heights[:-1]
    if len(same) and same[same.argmax()]:
        return _form_with_equal_heights(points)
    # All heights differ: both mirror images list the robots in this order, and their x columns
    # are each other's negatives, so the smaller image has its first non-zero x negative.
    out -= out[0]
    xs = out[:, 0]
    moved = xs.nonzero()[0]
    symmetric = len(moved) == 0
    sign = 1.0 if symmetric or xs[moved[0]] < 0.0 else -1.0
    if sign < 0.0:
        xs *= -1.0
    out += 0.0  # -0.0 -> +0.0: equal positions are equal bits
    return _Form(out, up, up, sign, symmetric)


def _form_with_equal_heights(points: Points) -> _Form:
    """`_form` when some robots share a height: each mirror image sorts them by its own x."""
    xs, ys = points[:, 0], points[:, 1]
    # Complex numbers sort lexicographically: y + ix by (y, x), its conjugate by (y, -x).
    key = np.empty(len(points), dtype=np.complex128)
    key.real = ys
    key.imag = xs
    up = key.argsort(kind="stable")
    down = key.conj().argsort(kind="stable")
    # Both orders list the same y values; the mirror image differs only in x.
    x_up = xs[up]
    x_up -= x_up[0]
    x_down = xs[down]
    x_down = x_down[0] - x_down
    diff = (x_up != x_down).nonzero()[0]
    symmetric = len(diff) == 0
    if symmetric or x_up[diff[0]] < x_down[diff[0]]:
        order, cx, sign = up, x_up, 1.0
    else:
        order, cx, sign = down, x_down, -1.0
    out = np.empty((len(points), 2), dtype=np.float64)
    out[:, 0] = cx
    y = ys[order]
    y -= y[0]
    out[:, 1] = y
    out += 0.0  # -0.0 -> +0.0: equal positions are equal bits
    return _Form(out, up, down, sign, symmetric)


@dataclass(frozen=True, slots=True)
class SharedForm:
    """The canonical form of a whole configuration, made once, and every robot's way into it.

    `for_robot(i, flip)` equals, bit for bit, `canonical` of robot i's own view (itself at the
    origin, X negated if `flip`): on the grid the view is an exact translate or mirror image of
    `world`, so the robot sorts the robots in one of the same two orders and takes the same image.
    Only the lockstep runner uses this, to skip n - 1 identical canonicalisations a round.
    """

    world: Points
    form: _Form
    rank_up: IntArray
    rank_down: IntArray

    @classmethod
    def of(cls, world: Points) -> SharedForm:
        """The shared form of `world` (n, 2, on the grid)."""
        form = _form(world)
        return cls(world, form, _ranks(form.up), _ranks(form.down))

    @property
    def points(self) -> Points:
        return self.form.points

    def key(self) -> bytes:
        """Bytes equal for exactly the configurations with equal canonical points."""
        return self.form.points.tobytes()

    def observer(self, robot: int, flip: bool) -> int:
        """`for_robot(robot, flip).observer`, without the rest: where robot `robot` sits in the
        canonical form it makes."""
        rank = self.rank_up if self._sign(flip) > 0.0 else self.rank_down
        return int(rank[robot])

    def robots_at(self, observer: int) -> set[int]:
        """The robots that may sit at row `observer` of the canonical form they make: the one there
        in either order (which one does, `observer` says by its flip)."""
        return {int(self.form.up[observer]), int(self.form.down[observer])}

    def _sign(self, flip: bool) -> float:
        """Which world order the image taken by a robot with this `flip` lists the robots in (+1:
        up): the world's image, or, in a mirror-symmetric swarm, the one 'up' in its own frame."""
        form = self.form
        if form.symmetric:
            return -1.0 if flip else 1.0
        return form.sign

    def for_robot(self, robot: int, flip: bool) -> Canonical:
        """What `canonical` gives robot `robot` on its own view in its own frame."""
        f = -1.0 if flip else 1.0
        form = self.form
        sign = self._sign(flip)
        order, rank = (form.up, self.rank_up) if sign > 0.0 else (form.down, self.rank_down)
        ref = int(order[0])
        # The reference robot in the robot's own (snapped) view, as `canonical` reads it there.
        x_ref = f * (float(self.world[ref, 0]) - float(self.world[robot, 0])) + 0.0
        y_ref = (float(self.world[ref, 1]) - float(self.world[robot, 1])) + 0.0
        flip_r = sign * f
        return Canonical(
            form.points, int(rank[robot]), (flip_r * x_ref, y_ref), flip_r, form.symmetric
        )


def _ranks(order: IntArray) -> IntArray:
    """rank[i] = position of robot i in `order`."""
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank
