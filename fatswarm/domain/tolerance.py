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


def check_supported(positions: NDArray[np.float64], a: float) -> None:
    """Raise UnsupportedInputError unless the start and `a` are in the supported range.

    Coordinates must lie within +-MAX_COORD, and both the start's spread (half its bounding box
    diagonal, an upper bound of its enclosing radius) and the target circle's radius within
    MAX_SPAN. `positions` is (n, 2) and finite (the caller checked).
    """
    pts = np.asarray(positions, dtype=np.float64)
    n = len(pts)
    if n and float(np.abs(pts).max()) > MAX_COORD:
        raise UnsupportedInputError(
            f"coordinates must lie within +-{MAX_COORD:.0f} (the grid of 2^-{GRID_BITS} stays "
            f"exact there), got {float(np.abs(pts).max()):.6g}"
        )
    if n:
        spread = 0.5 * float(np.hypot(*(pts.max(axis=0) - pts.min(axis=0))))
        if spread > MAX_SPAN:
            raise UnsupportedInputError(
                f"the start must fit in a circle of radius {MAX_SPAN:.0f} (tolerances are 1e-6 of "
                f"the swarm's radius, and must stay below a robot's size), got about {spread:.6g}"
            )
    limit = max_side(n)
    if not a <= limit:
        raise UnsupportedInputError(
            f"a must be at most {limit:.6g} for n = {n}: the target circle must have radius "
            f"<= {MAX_SPAN:.0f} (tolerances are 1e-6 of the swarm's radius), got a = {a:.6g}"
        )
