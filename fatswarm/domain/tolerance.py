"""The one tolerance model of fatswarm: the grid positions live on, touching, overlap and clearance.

The world and every robot use these names and nothing else, so that what the world accepts as "not
overlapping" is exactly what the algorithm treats as "touching" (docs/algorithm.md, "Agreement").
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import NDArray

GRID_BITS: Final = 30
GRID: Final = 2.0**-GRID_BITS
"""Every committed position is a multiple of GRID (about 9.3e-10). Differences of such numbers are
exact while they stay below 2**(53 - GRID_BITS) = 2**23, so every robot's view is an exact
translate (and mirror) of every other robot's view: all robots compute on the very same bits."""
SNAP_DISTANCE: Final = 2.0 * GRID
"""The most snapping both ends of a segment to the grid can change its length: each coordinate of
the difference moves by at most GRID, so the length by at most sqrt(2) * GRID (about 1.3e-9),
rounded up. A distance given exactly before the snap (a robot placed at exactly the sight
distance V, a touching pair) is within this of it after."""
MAX_COORD: Final = 2.0e6
"""Supported start coordinates: |x|, |y| <= MAX_COORD. With swarms of radius <= MAX_SPAN the run
stays inside |x|, |y| < 2**22, where differences of grid values are exact (see GRID)."""
MAX_SPAN: Final = 1.0e4
"""Supported swarm radius (the start's smallest enclosing circle, and the target circle): the
relative tolerance EPS_AT_REL * MAX_SPAN = 1e-2 is then still 1% of a robot's radius."""

ROBOT_RADIUS: Final = 1.0
CONTACT: Final = 2.0 * ROBOT_RADIUS
"""Centre distance at which two unit discs touch."""
OVERLAP_SLACK: Final = 1e-7
"""Two discs overlap iff their centres are closer than CONTACT - OVERLAP_SLACK: the world refuses
such a start and counts such a contact as a collision. Anything from there up to CONTACT is
touching: 7 decimals of sqrt(3) in a start file are still a touching lattice."""
OVERLAP_DISTANCE: Final = CONTACT - OVERLAP_SLACK
CLEAR_SLACK: Final = 1e-8
"""A planned path keeps every other centre at >= CONTACT - CLEAR_SLACK, or, for a robot that starts
closer than that (still touching), never brings it closer than it was. 10x above the grid's
snapping (<= 6.6e-10), 10x below OVERLAP_SLACK: a path planned free is never stopped by contact."""
ROUND_ABS: Final = 1e-10
"""Float rounding of a distance computed in the canonical frame, whose coordinates stay below
4 * MAX_SPAN in the supported range (4e4 * 2.2e-16 * a few operations is about 1e-11)."""

EPS_EQ_REL: Final = 1e-9
"""Equalities and ties: far above the float error of O(n) sums, far below any real gap."""
EPS_AT_REL: Final = 1e-6
""""Robot at o / at p / on the SEC / settled on a target / mirror image of": above the precision of
any computed position (~1e-12), below any distance the algorithm creates on purpose."""
SEC_SLACK_REL: Final = 1e-12
"""A point counts as inside a candidate circle if within radius*(1 + this): rounding only."""


def scale(radius: float) -> float:
    """The length scale relative tolerances are multiplied by."""
    return max(1.0, radius)


def snap(
    values: NDArray[np.float64], out: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """The nearest grid values (exact: scaling by a power of two and rounding lose nothing else).

    `out`, if given, receives the result (it may be `values` itself, a float64 array).
    """
    arr = np.asarray(values, dtype=np.float64)
    res: NDArray[np.float64] = np.multiply(arr, 2.0**GRID_BITS, out=out)
    np.rint(res, out=res)
    res *= GRID
    res += 0.0  # -0.0 -> +0.0, so that equal positions are equal bits
    return res


def snap_point(x: float, y: float) -> tuple[float, float]:
    """One point on the grid."""
    return (round(x * 2.0**GRID_BITS) * GRID + 0.0, round(y * 2.0**GRID_BITS) * GRID + 0.0)


def max_side(n: int) -> float:
    """The largest side a whose target circle (radius a / (2 sin(pi/n))) fits MAX_SPAN."""
    return MAX_SPAN * 2.0 * math.sin(math.pi / max(n, 2))


class UnsupportedInputError(ValueError):
    """A start or side length outside the range where these tolerances hold."""


def enclosing_circle(positions: NDArray[np.float64]) -> tuple[float, float, float]:
    """The smallest enclosing circle of the (n, 2) centres, n >= 1: (centre x, centre y, radius).

    Welzl's algorithm, iterative, over a fixed shuffle of the points (expected linear time, the
    same answer on every run), about the bounding box's centre so that a start far from the origin
    keeps its digits. The range check's own: the algorithms keep theirs (agent/geometry.py).
    """
    pts = np.asarray(positions, dtype=np.float64)
    mid = (pts.max(axis=0) + pts.min(axis=0)) / 2.0
    local = [(float(x), float(y)) for x, y in (pts - mid)[_shuffle(len(pts))]]
    cx, cy, r = local[0][0], local[0][1], 0.0
    for i, p in enumerate(local):
        if _outside((cx, cy, r), p):
            cx, cy, r = p[0], p[1], 0.0
            for j, q in enumerate(local[:i]):
                if _outside((cx, cy, r), q):
                    cx, cy, r = _through_two(p, q)
                    for s in local[:j]:
                        if _outside((cx, cy, r), s):
                            cx, cy, r = _through_three(p, q, s)
    return cx + float(mid[0]), cy + float(mid[1]), r


def _shuffle(n: int) -> NDArray[np.intp]:
    """A fixed permutation of range(n): Welzl's expected time needs a random order, not a new one
    each run."""
    return np.random.default_rng(0).permutation(n)


def _outside(circle: tuple[float, float, float], p: tuple[float, float]) -> bool:
    cx, cy, r = circle
    return math.hypot(p[0] - cx, p[1] - cy) > r * (1.0 + SEC_SLACK_REL) + ROUND_ABS


def _through_two(p: tuple[float, float], q: tuple[float, float]) -> tuple[float, float, float]:
    """The circle with diameter pq."""
    return (p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, math.hypot(p[0] - q[0], p[1] - q[1]) / 2.0


def _through_three(
    p: tuple[float, float], q: tuple[float, float], s: tuple[float, float]
) -> tuple[float, float, float]:
    """The circle through p, q and s; for (nearly) collinear points, the widest pair's."""
    bx, by, cx, cy = q[0] - p[0], q[1] - p[1], s[0] - p[0], s[1] - p[1]
    d = 2.0 * (bx * cy - by * cx)
    if abs(d) <= 1e-12 * (bx * bx + by * by + cx * cx + cy * cy):
        return max((_through_two(p, q), _through_two(p, s), _through_two(q, s)), key=lambda c: c[2])
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux, uy = (cy * b2 - by * c2) / d, (bx * c2 - cx * b2) / d
    return p[0] + ux, p[1] + uy, math.hypot(ux, uy)


def target_radius_of(n: int, a: float) -> float:
    """The paper's target circle for n robots and side a: the regular n-gon of side max(a, 4)
    (agent/geometry.py, `target_radius`); 0 for fewer than 2 robots."""
    return 0.0 if n < 2 else max(a, 4.0) / (2.0 * math.sin(math.pi / n))


def shown_beyond(value: float, limit: float) -> str:
    """`value` with one decimal, or as many more as tell it apart from `limit`: a value just past
    the limit never reads as the limit itself ("got about 10000" for a limit of 10000)."""
    if not abs(value) < 1e9:  # far out (or not a number): the digits no longer matter
        return f"{value:.6g}"
    for decimals in range(1, 13):
        text = f"{value:.{decimals}f}"
        if float(text) != limit:
            return text
    return repr(value)


def shown_apart(value: float, limit: float) -> str:
    """`value` with as few decimals (at least one) as keep it on its own side of `limit`: a
    distance just below a bound never reads as the bound or above it ("1.99999989", not "2")."""
    if not abs(value) < 1e9 or value == limit:
        return repr(value)
    for decimals in range(1, 17):
        text = f"{value:.{decimals}f}"
        if (float(text) < limit) == (value < limit) and float(text) != limit:
            return text
    return repr(value)


OVERLAP_SHOWN: Final = f"2 - {OVERLAP_SLACK:g} = {OVERLAP_DISTANCE!r}"
"""The overlap bound as a refusal names it."""


def check_supported(positions: NDArray[np.float64], a: float) -> None:
    """Raise UnsupportedInputError unless the start, `a` and the run's reach are in the supported
    range.

    Coordinates must lie within +-MAX_COORD; the start's smallest enclosing circle and the target
    circle must have radius at most MAX_SPAN; and the run's reach, the larger of the two circles
    about the start's centre (where the paper's algorithm forms its circle), must stay within
    +-MAX_COORD too. `positions` is (n, 2) and finite (the caller checked).
    """
    pts = np.asarray(positions, dtype=np.float64)
    n = len(pts)
    if n and float(np.abs(pts).max()) > MAX_COORD:
        far = float(np.abs(pts).max())
        raise UnsupportedInputError(
            f"coordinates must lie within +-{MAX_COORD:.0f} (the grid of 2^-{GRID_BITS} stays "
            f"exact there), got {shown_beyond(far, MAX_COORD)}"
        )
    cx, cy, radius = enclosing_circle(pts) if n else (0.0, 0.0, 0.0)
    if radius > MAX_SPAN * (1.0 + EPS_EQ_REL):
        raise UnsupportedInputError(
            f"the start must fit in a circle of radius {MAX_SPAN:.0f} (tolerances are 1e-6 of "
            f"the swarm's radius, and must stay below a robot's size), got "
            f"{shown_beyond(radius, MAX_SPAN)}"
        )
    limit = max_side(n)
    if not a <= limit:
        raise UnsupportedInputError(
            f"a must be at most {limit:.6g} for n = {n}: the target circle must have radius "
            f"<= {MAX_SPAN:.0f} (tolerances are 1e-6 of the swarm's radius), got a = {a:.6g}"
        )
    _check_reach(cx, cy, max(radius, target_radius_of(n, a)))


def _check_reach(cx: float, cy: float, radius: float) -> None:
    """Refuse a run whose circle of `radius` about (cx, cy) leaves +-MAX_COORD."""
    reach = max(abs(cx), abs(cy)) + radius
    if reach > MAX_COORD * (1.0 + EPS_EQ_REL):
        raise UnsupportedInputError(
            f"the run would reach {shown_beyond(reach, MAX_COORD)} (a circle of radius "
            f"{radius:.1f} about the start's centre ({cx:.1f}, {cy:.1f})), but coordinates must "
            f"stay within +-{MAX_COORD:.0f} (the grid of 2^-{GRID_BITS} stays exact there): move "
            "the start towards the origin"
        )
