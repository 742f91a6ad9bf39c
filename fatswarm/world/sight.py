"""Which robots an observer sees: exact visibility among unit discs (pure numpy, no I/O).

Robots are closed discs of radius ROBOT_RADIUS that never overlap. Rules (`Visibility`):

- "transparent": every robot within sight is seen (the paper's model).
- "opaque-centres": j is seen iff the segment between the two centres passes at distance
  >= ROBOT_RADIUS - GRAZE_SLACK from every third centre.
- "opaque": j is seen iff some point of its closed disc is joined to the observer's centre by such
  a segment. Computed exactly on angles: j's closed interval of directions minus the open
  blocking intervals of the discs in front of it must be non-empty.

Grazing rule (both opaque rules): a sight line is blocked by disc k only if it passes strictly
closer than ROBOT_RADIUS - GRAZE_SLACK to k's centre; grazing, or passing up to GRAZE_SLACK inside
k's rim, does not block. Blocking intervals are thus the directions within
beta = asin((1 - GRAZE_SLACK) / d) of k's direction, open. What it implies:

- Two discs touching side by side at the same distance d from the observer leave a pinhole: the
  sight line through their contact point grazes both, and the shrunk intervals leave a gap of
  about 2 * GRAZE_SLACK / sqrt(d**2 - 1) radians around it. A robot whose disc spans that direction
  is seen by "opaque" (and by "opaque-centres" if its centre is on that line).
- Touching discs at different distances overlap in angle, but only to second order in the
  difference (both rims hug the common tangent near the contact), so the pinhole stays open until
  the distances differ by about sqrt(GRAZE_SLACK): 2.7e-4 for two discs at distance 3.2 (pinned in
  the tests). Beyond that, what is behind the contact is hidden.
- A sight line tangent to a nearer disc and to j (a common tangent through the observer) is not
  blocked by that disc: j is seen along it, though a shift of j by 1e-6 hides it (pinned too).

Point robots (`--bodies points`, `points=True`): both opaque rules are the literature's
collinearity: k hides j iff k lies on the segment between the observer and j, strictly between
them: its centre within GRAZE_SLACK of the segment's line, farther than GRAZE_SLACK from the
observer and nearer than j by more than GRAZE_SLACK along it. "On the segment" is thus within the
clearance slack, 10x above the grid's snapping (fatswarm/domain/tolerance.py): a robot sent to a
point of the segment is still on it once snapped. Robots that share a point hide nothing of one
another, and one at the observer's own point hides nothing.

"k in front of j": two disjoint equal discs are separated by the bisector of their centres, so
along every ray that meets both, the nearer-centred one comes first (at equal distances no ray
meets both interiors). k can block j only if |k| < |j|, decided once per pair without rays. Discs
closer than contact by up to OVERLAP_SLACK (allowed as touching) follow the same rule: a grazing
case within 1e-7, like every other one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import Visibility
from fatswarm.domain.tolerance import CLEAR_SLACK, ROBOT_RADIUS, SNAP_DISTANCE

GRAZE_SLACK: Final = CLEAR_SLACK
"""A sight line passing within this of a disc's rim (outside or inside) is not blocked by it: the
clearance slack of planned paths (a path may pass that close to a disc, so may a sight line), far
above rounding, so that a line grazing a disc is clear whatever the frame's rounding."""
SIGHT_REL: Final = 1e-12
"""A robot is within sight V iff its centre distance is <= V * (1 + SIGHT_REL) + SNAP_DISTANCE: a
robot placed at distance exactly V is seen despite the rounding of the distance (about 1e-16
relative) and the snap of both centres to the grid (up to sqrt(2) * 2^-30 absolute: 5.8e-11 of
V = 10 was found beyond it)."""
_PREFILTER_SLACK: Final = 1e-9
"""Cosine margin of the cheap angular prefilter, far above rounding: it only selects the pairs
whose exact angles are then computed, so it must never drop a pair that truly overlaps."""

_Indices = NDArray[np.int64]
_Floats = NDArray[np.float64]
_Bools = NDArray[np.bool_]


def seen(
    positions: Points,
    observer: int,
    rule: Visibility,
    sight: float | None,
    *,
    points: bool = False,
) -> _Indices:
    """Indices (ascending, int64) of the robots other than `observer` that it sees.

    `sight` None is unlimited; a robot at centre distance <= `within_sight(sight)` is within
    sight (so one placed exactly at distance `sight`, then snapped to the grid, is seen). Bodies
    block whether within sight or not. `points`: the robots are points (collinearity hides, see
    the module's docstring).
    """
    pts, how = _checked(positions, rule, sight)
    return _seen_one(pts, _checked_observer(observer, len(pts)), how, sight, points)


def seen_all(
    positions: Points,
    observers: Sequence[int],
    rule: Visibility,
    sight: float | None,
    *,
    points: bool = False,
) -> dict[int, _Indices]:
    """`seen` for several observers, keyed by observer (the input is checked once)."""
    pts, how = _checked(positions, rule, sight)
    chosen = [_checked_observer(o, len(pts)) for o in observers]
    return {o: _seen_one(pts, o, how, sight, points) for o in chosen}


def _checked(
    positions: Points, rule: Visibility, sight: float | None
) -> tuple[_Floats, Visibility]:
    """The positions as a float64 (n, 2) array and the rule (its plain string value is accepted
    too); ValueError for a bad shape, rule or sight."""
    pts = np.asarray(positions, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"positions must be an (n, 2) array, got shape {pts.shape}")
    if not np.isfinite(pts).all():
        raise ValueError("positions must be finite")
    try:
        how = Visibility(rule)
    except ValueError:
        known = ", ".join(v.value for v in Visibility)
        raise ValueError(f"unknown visibility rule {rule!r}: expected one of {known}") from None
    if sight is not None and not sight >= 0.0:
        raise ValueError(f"sight must be None or >= 0, got {sight!r}")
    return pts, how


def _checked_observer(observer: int, n: int) -> int:
    """The observer as a plain int; IndexError unless 0 <= observer < n."""
    index = int(observer)
    if not 0 <= index < n:
        raise IndexError(f"observer {observer} is not a robot of the {n} given")
    return index


def within_sight(sight: float) -> float:
    """The largest centre distance at which a robot is within sight `sight` (see SIGHT_REL)."""
    return sight * (1.0 + SIGHT_REL) + SNAP_DISTANCE


def _seen_one(
    pts: _Floats, observer: int, rule: Visibility, sight: float | None, points: bool = False
) -> _Indices:
    """The robots `observer` sees, for checked input."""
    rel = pts - pts[observer]
    dist = np.hypot(rel[:, 0], rel[:, 1])
    dist[observer] = math.inf  # never a candidate nor a blocker (its own body is not an obstacle)
    within = np.isfinite(dist)
    if sight is not None:
        within &= dist <= within_sight(sight)
    cand = np.flatnonzero(within).astype(np.int64)
    if rule is Visibility.TRANSPARENT or cand.size == 0:
        return cand
    if points:  # both opaque rules: collinearity
        return cand[~_points_blocked(rel, dist, cand)]
    if rule is Visibility.OPAQUE_CENTRES:
        return cand[~_centres_blocked(rel, dist, cand)]
    return cand[~_discs_hidden(rel, dist, cand)]


def _dots(pj: _Floats, rel: _Floats) -> _Floats:
    """Every candidate's dot product with every robot, written out (each product rounded, then
    the sum) rather than `pj @ rel.T`: BLAS picks its kernel (fused multiply-add or not) by the
    CPU, and what a robot sees must not depend on it."""
    out: _Floats = pj[:, 0, None] * rel[None, :, 0]
    out += pj[:, 1, None] * rel[None, :, 1]
    return out


def _centres_blocked(rel: _Floats, dist: _Floats, cand: _Indices) -> _Bools:
    """Per candidate j: does a third disc come closer than 1 - slack to the segment O-j?

    Closer than 1 is only possible where the foot of k's centre falls inside the segment (the ends
    are centres of discs that k does not overlap), so the distance is |cross| / |j| there.
    """
    pj = rel[cand]
    dj = dist[cand][:, None]
    dot = _dots(pj, rel)
    cross = pj[:, 0, None] * rel[None, :, 1] - pj[:, 1, None] * rel[None, :, 0]
    inside = (dot > 0.0) & (dot < dj * dj)
    blocked = inside & (np.abs(cross) < (ROBOT_RADIUS - GRAZE_SLACK) * dj)
    blocked[np.arange(cand.size), cand] = False  # j itself (the observer has dot = 0)
    return np.asarray(blocked.any(axis=1), dtype=np.bool_)


def _points_blocked(rel: _Floats, dist: _Floats, cand: _Indices) -> _Bools:
    """Per candidate j: does a third point lie on the segment O-j, strictly between (within
    GRAZE_SLACK of its line, more than GRAZE_SLACK from either end along it)?"""
    pj = rel[cand]
    dj = dist[cand][:, None]
    dot = _dots(pj, rel)  # |j| times k's coordinate along O-j
    cross = pj[:, 0, None] * rel[None, :, 1] - pj[:, 1, None] * rel[None, :, 0]
    inside = (dot > GRAZE_SLACK * dj) & (dot < (dj - GRAZE_SLACK) * dj)
    blocked = inside & (np.abs(cross) < GRAZE_SLACK * dj) & np.isfinite(dist)[None, :]
    return np.asarray(blocked.any(axis=1), dtype=np.bool_)


def _discs_hidden(rel: _Floats, dist: _Floats, cand: _Indices) -> _Bools:
    """Per candidate j: is its closed interval of directions covered by blocking intervals?"""
    rows, lo, hi, alpha = _blocking_pairs(rel, dist, cand)
    if rows.size == 0:
        return np.zeros(cand.size, dtype=np.bool_)
    return _covered(rows, lo, hi, alpha)


def _blocking_pairs(
    rel: _Floats, dist: _Floats, cand: _Indices
) -> tuple[_Indices, _Floats, _Floats, _Floats]:
    """The pairs (j, k) with k nearer than j and k's open blocking interval meeting j's interval.

    Returns the candidate row of each pair, the blocking interval (lo, hi) of k in directions
    relative to j's centre (in (-pi, pi], within about 60 degrees), and every candidate's
    half-angle alpha_j. A cheap cosine test on all pairs selects those worth an atan2.
    """
    dj = np.maximum(dist[cand], ROBOT_RADIUS)  # overlap-free input has dist >= 2 - 1e-7 anyway
    dk = np.maximum(dist, ROBOT_RADIUS)
    sin_a = ROBOT_RADIUS / dj
    sin_b = (ROBOT_RADIUS - GRAZE_SLACK) / dk  # the observer's inf gives 0
    alpha = np.arcsin(sin_a)
    beta = np.arcsin(sin_b)
    cos_a = np.sqrt(1.0 - sin_a * sin_a)
    cos_b = np.sqrt(1.0 - sin_b * sin_b)
    pj = rel[cand]
    dot = _dots(pj, rel)
    # cos(alpha_j + beta_k) < 1 exactly where the two intervals can meet (their sum is < 90 deg)
    cos_sum = cos_a[:, None] * cos_b[None, :] - sin_a[:, None] * sin_b[None, :]
    nearer = dk[None, :] < dj[:, None]  # the observer (inf) and j itself are never nearer
    near = nearer & (dot > (cos_sum - _PREFILTER_SLACK) * (dj[:, None] * dk[None, :]))
    jj, kk = np.nonzero(near)
    pk = rel[kk]
    cross = pj[jj, 0] * pk[:, 1] - pj[jj, 1] * pk[:, 0]
    phi = np.arctan2(cross, dot[jj, kk])
    lo = phi - beta[kk]
    hi = phi + beta[kk]
    a = alpha[jj]
    meet = (lo < a) & (hi > -a)
    return jj[meet].astype(np.int64), lo[meet], hi[meet], alpha


def _covered(rows: _Indices, lo: _Floats, hi: _Floats, alpha: _Floats) -> _Bools:
    """Per candidate: is [-alpha, alpha] inside the union of its open intervals (lo, hi)?

    A sweep, vectorised over candidates: with the intervals sorted by lo, the first uncovered
    point (if any) is R_i = max(-alpha, hi_0..hi_{i-1}) for the first i with lo_i >= R_i; a padding
    interval (inf, -inf) at the end of each row finds the point past the last interval.
    """
    order = np.lexsort((lo, rows))
    rows, lo, hi = rows[order], lo[order], hi[order]
    groups, start, count = np.unique(rows, return_index=True, return_counts=True)
    group = np.repeat(np.arange(groups.size), count)
    col = np.arange(rows.size) - start[group]
    width = int(count.max()) + 1
    los = np.full((groups.size, width), math.inf)
    his = np.full((groups.size, width), -math.inf)
    los[group, col] = lo
    his[group, col] = hi
    a = alpha[groups][:, None]
    reach = np.maximum.accumulate(his, axis=1)
    before = np.empty_like(reach)
    before[:, 0] = -math.inf
    before[:, 1:] = reach[:, :-1]
    before = np.maximum(before, -a)
    gap = ((los >= before) & (before <= a)).any(axis=1)
    hidden = np.zeros(alpha.size, dtype=np.bool_)
    hidden[groups[~gap]] = True
    return hidden
