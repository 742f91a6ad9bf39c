"""Disc physics of one round: movers start together at unit speed; continuous collision detection.

Robots are unit discs. Every robot of a round follows its path from t = 0 at unit speed (time equals
arc length). A robot whose disc would overlap another stops at first contact; stopped robots are
still obstacles for the rest of the round. Discs never overlap, at any time of the round.
Point robots (`--bodies points`, `points=True`) have no extent: every mover covers its whole path,
robots may meet and share a point, and nothing is a collision.

`apply_lines` is `apply_round` for a round of straight lines held as arrays (the same bits); a
round whose every path is one Line takes that road too, checked in bulk.

Method: an event loop over the pairs whose path boxes come within 2; per pair, adaptive subdivision
of time proves intervals overlap-free with lower bounds on the distance (exact for straight relative
motion, an arc against a robot at rest and two arcs up to their turning-rate drift; Lipschitz and
chord bounds otherwise) and conservative advancement; contacts are then located by bisection.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from itertools import chain
from math import hypot, isfinite
from numbers import Real
from typing import Any, Final

import numpy as np

from fatswarm.domain.path import (
    MAX_SEGMENTS,
    Arc,
    Line,
    Path,
    PathFormatError,
    Points,
    path_length,
)
from fatswarm.domain.tolerance import (
    CLEAR_SLACK,
    CONTACT,
    GRID,
    GRID_BITS,
    MAX_COORD,
    OVERLAP_DISTANCE,
    OVERLAP_SHOWN,
    OVERLAP_SLACK,
    SNAP_DISTANCE,
    shown_apart,
    snap,
    snap_point,
)
from fatswarm.world.motion import (
    BoolArray,
    FloatArray,
    IntArray,
    Motion,
    build_motion,
    first_contacts,
    line_motion,
    positions_at,
)

CONTACT_SLACK = OVERLAP_SLACK
"""Two discs overlap iff their centres are closer than 2 - CONTACT_SLACK
(fatswarm/domain/tolerance.py)."""
PLAN_ROUNDING = CLEAR_SLACK
"""The algorithm keeps every other centre at >= 2 - PLAN_ROUNDING (or, touching, never brings it
closer); such a path is never stopped: only overlap, below OVERLAP_DISTANCE, stops a robot."""
BOX_MARGIN = 1e-6
"""Slack on bounding-box culling (boxes are exact up to ~1e-13)."""


class InvalidConfigurationError(ValueError):
    """A configuration no run may start from (overlap, NaN, infinity, wrong shape)."""


class InvalidRoundError(ValueError):
    """The moves of a round name a robot that does not exist or are not paths."""


class PhysicsInvariantError(RuntimeError):
    """Discs overlap after a round: a bug in the physics, never the user's fault."""


@dataclass(frozen=True, slots=True)
class Collision:
    """Robot `robot` was stopped at time `t` (= arc length travelled) by contact with `other`.

    `point` is where the centre of `robot` stopped.
    """

    robot: int
    other: int
    t: float
    point: tuple[float, float]


@dataclass(frozen=True, slots=True)
class RoundOutcome:
    """Positions after the round, arc length each mover covered, contacts that stopped movers."""

    positions: Points
    traveled: dict[int, float] = field(default_factory=dict)
    collisions: list[Collision] = field(default_factory=list)
    lengths: dict[int, float] = field(default_factory=dict)  # path_length of movers that moved


# --------------------------------------------------------------------------------------------------
# Validation


def _as_points(positions: Any) -> Points:
    """A float64 (n, 2) copy of `positions` with n >= 1 and finite values, else a clear error."""
    try:
        arr = np.array(positions, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidConfigurationError(
            f"positions must be a list of [x, y] number pairs ({exc})"
        ) from None
    if (
        arr.ndim == 2
        and arr.shape[1] == 2
        and arr.size
        and np.count_nonzero(np.isfinite(arr)) == arr.size
    ):
        return arr  # the common case: the checks below all pass
    if arr.size == 0:
        raise InvalidConfigurationError("positions are empty: give at least one robot as [x, y]")
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidConfigurationError(
            f"positions must have shape (n, 2), one [x, y] per robot; got shape {arr.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        i = int(bad[0])
        more = f" (and {bad.size - 1} more)" if bad.size > 1 else ""
        raise InvalidConfigurationError(
            f"robot {i} is at ({arr[i, 0]}, {arr[i, 1]}){more}: coordinates must be finite numbers"
        )
    return arr


def _first_overlap(points: Points, rows: IntArray) -> tuple[int, int, float] | None:
    """The first pair (robot of `rows`, any other robot) closer than OVERLAP_DISTANCE, if any."""
    block = max(1, 4_000_000 // max(1, len(points)))  # bounds memory for very large n
    for lo in range(0, len(rows), block):
        sub = rows[lo : lo + block]
        diff = points[sub][:, None, :] - points[None, :, :]
        dist = np.hypot(diff[..., 0], diff[..., 1])
        dist[np.arange(len(sub)), sub] = np.inf
        hit = np.argwhere(dist < OVERLAP_DISTANCE)
        if hit.size:
            a, b = int(sub[hit[0, 0]]), int(hit[0, 1])
            return min(a, b), max(a, b), float(dist[hit[0, 0], hit[0, 1]])
    return None


def validate_configuration(positions: Points, *, bodies_are_points: bool = False) -> Points:
    """Return positions on the grid as an (n, 2) float64 copy or raise InvalidConfigurationError.

    Positions are snapped to the nearest multiples of GRID (moving each by at most 6.6e-10), so
    that every robot's view is exact (fatswarm/domain/tolerance.py). Refused: a wrong shape, no
    robot, NaN or infinite coordinates, coordinates beyond +-MAX_COORD, two centres closer than
    2 - CONTACT_SLACK (overlapping unit discs) as given and on the grid, unless `bodies_are_points`
    (point robots may share a point). A pair given at least that far apart (touching) stays so
    on the grid: `_keep_touching`.
    """
    points = _as_points(positions)
    far = float(np.abs(points).max())
    if far > MAX_COORD:
        raise InvalidConfigurationError(
            f"coordinates must lie within +-{MAX_COORD:.0f} (where positions on the grid of "
            f"{GRID:.2g} stay exact), got {far:.6g}"
        )
    if bodies_are_points:
        return snap(points)
    return _keep_touching(points, snap(points))


TOUCH_SCALE: Final = 2.0 * SNAP_DISTANCE / OVERLAP_DISTANCE
"""The start's stretch that keeps every touching pair touching on the grid (`_keep_touching`): it
adds at least 2 * SNAP_DISTANCE to a distance of the overlap bound, where the snap takes away at
most SNAP_DISTANCE."""


def _keep_touching(given: Points, points: Points) -> Points:
    """`points` (`given` on the grid), unless the snap brought a pair below OVERLAP_DISTANCE: then,
    if every pair was given at least that far apart (touching, docs/model.md), `given` stretched
    by 1 + TOUCH_SCALE about its middle, on the grid. Only starts the snap alone would break are
    stretched. Raises InvalidConfigurationError for a pair given closer (overlapping)."""
    rows = np.arange(len(points), dtype=np.intp)
    if _first_overlap(points, rows) is None:
        return points
    pair = _first_overlap(given, rows)
    if pair is not None:
        a, b, dist = pair
        raise InvalidConfigurationError(
            f"robots {a} and {b} overlap: their centres are {shown_apart(dist, OVERLAP_DISTANCE)} "
            f"apart, closer than {OVERLAP_SHOWN} (unit discs may touch, not overlap); place every "
            "pair of robots at least 2 apart"
        )
    mid = snap((given.max(axis=0) + given.min(axis=0)) / 2.0)
    # about a grid point: the differences are small, exact enough, and snap back exactly
    stretched = snap((given - mid) * (1.0 + TOUCH_SCALE)) + mid
    pair = _first_overlap(stretched, rows)
    if pair is not None:  # beyond the supported range: say so rather than break physics
        raise InvalidConfigurationError(
            f"robots {pair[0]} and {pair[1]} touch as given but not on the grid of 2^-30: place "
            "them a little further apart (1e-8 is plenty)"
        )
    return stretched


def _finite_number(value: Any) -> bool:
    if type(value) is float:  # the common case first: a float is a Real and no bool
        return math.isfinite(value)
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


def _finite_point(value: Any) -> bool:
    if type(value) is tuple and len(value) == 2:  # the common case first
        return _finite_number(value[0]) and _finite_number(value[1])
    return (
        isinstance(value, (tuple, list, np.ndarray))
        and len(value) == 2
        and all(_finite_number(v) for v in value)
    )


def _check_moves(paths: Mapping[int, Path], n: int) -> list[tuple[int, Path]]:
    """The (robot, path) pairs of a round, checked; raises before anything moves."""
    moves: list[tuple[int, Path]] = []
    for key, path in paths.items():
        if type(key) is not int and (
            isinstance(key, bool) or not isinstance(key, (int, np.integer))
        ):
            raise InvalidRoundError(f"robot ids must be integers, got {key!r}")
        robot = int(key)
        if not 0 <= robot < n:
            raise InvalidRoundError(f"robot {robot} does not exist: ids run from 0 to {n - 1}")
        if type(path) is not Path and not isinstance(path, Path):
            raise InvalidRoundError(f"robot {robot}: expected a Path, got {type(path).__name__}")
        if len(path.segments) > MAX_SEGMENTS:
            raise PathFormatError(
                f"robot {robot}: a path has at most {MAX_SEGMENTS} segments, got {len(path)}"
            )
        for seg in path.segments:
            if type(seg) is Line and type(end := seg.end) is tuple and len(end) == 2:
                x, y = end  # the common case inline: `_finite_point` of two floats
                if type(x) is float and type(y) is float and isfinite(x) and isfinite(y):
                    continue
                ok = _finite_point(end)
            elif isinstance(seg, Line):
                ok = _finite_point(seg.end)
            elif isinstance(seg, Arc):
                ok = _finite_point(seg.center) and _finite_number(seg.sweep)
            else:
                ok = False
            if not ok:
                raise PathFormatError(
                    f"robot {robot}: segment {seg!r} must be a Line or Arc of finite numbers"
                )
        moves.append((robot, path))
    return moves


# --------------------------------------------------------------------------------------------------
# The round: the pairs that can meet, the event loop over their contacts, the end on the grid


def _sweep_pairs(
    lo: FloatArray, hi: FloatArray, first: IntArray, second: IntArray, reach: float
) -> tuple[IntArray, IntArray]:
    """Every pair (a in `first`, b in `second`) whose intervals [lo, hi] (one axis, per robot)
    come within `reach`, and maybe a few more: a sort and sweep, O((m + k) log k) for
    k = len(second); up to BRUTE_PAIRS pairs, every pair (first, then second) instead.
    """
    lo_b, hi_b, count = lo[second], hi[second], len(second)
    if len(first) * count <= BRUTE_PAIRS:  # few: every pair, already in their order
        return np.repeat(first, count), np.tile(second, len(first))
    order = lo_b.argsort(kind="stable")
    lo_sorted = lo_b[order]
    width = float((hi_b - lo_b).max()) if count else 0.0
    pad = reach + width + 1.0  # generous: the exact test of the pairs comes after
    begin = lo_sorted.searchsorted(lo[first] - pad, side="left")
    end = lo_sorted.searchsorted(hi[first] + reach + 1.0, side="right")
    counts = end - begin
    ends = counts.cumsum()
    total = int(ends[-1]) if len(ends) else 0
    offsets = (begin - ends + counts).repeat(counts)
    pi = first.repeat(counts)
    at = order[np.arange(total, dtype=np.intp) + offsets]
    return pi, second[at]


def _candidate_pairs(mo: Motion, first: IntArray, second: IntArray) -> tuple[IntArray, IntArray]:
    """Pairs (a in `first`, b in `second`, a != b, once each) whose path boxes come within 2.

    In the order of a brute force over `first` x `second` (first, then second, the order of the
    arguments), which the event loop's ties depend on; the pairs come from a sweep along the wider
    axis (`_sweep_pairs`) and the test on each is the brute force's very arithmetic.
    """
    boxes = np.concatenate([mo.start, mo.start], axis=1)
    boxes[mo.robots] = mo.box
    xs, ys = boxes[:, 0], boxes[:, 1]  # spans as np.ptp takes them: max - min
    ax = 0 if xs.max() - xs.min() >= ys.max() - ys.min() else 1
    pi, pj = _sweep_pairs(boxes[:, ax], boxes[:, ax + 2], first, second, 2.0 + BOX_MARGIN)
    bi, bj = boxes[pi], boxes[pj]
    gx = np.maximum(0.0, np.maximum(bj[:, 0] - bi[:, 2], bi[:, 0] - bj[:, 2]))
    gy = np.maximum(0.0, np.maximum(bj[:, 1] - bi[:, 3], bi[:, 1] - bj[:, 3]))
    in_first = np.zeros(len(mo.start), dtype=np.bool_)
    in_first[first] = True
    keep = (gx * gx + gy * gy < (2.0 + BOX_MARGIN) ** 2) & (pi != pj) & ~(in_first[pj] & (pj < pi))
    pi, pj = pi[keep], pj[keep]
    if len(first) * len(second) <= BRUTE_PAIRS:  # every pair was taken, in the brute order
        return pi, pj
    rank_first = np.empty(len(mo.start), dtype=np.intp)
    rank_first[first] = np.arange(len(first), dtype=np.intp)
    rank_second = np.empty(len(mo.start), dtype=np.intp)
    rank_second[second] = np.arange(len(second), dtype=np.intp)
    order = np.lexsort((rank_second[pj], rank_first[pi]))
    return pi[order], pj[order]


def _simulate(mo: Motion, pi: IntArray, pj: IntArray) -> list[Collision]:
    """The round as an event loop: the earliest contact stops its movers, the rest go on.

    `pi`, `pj`: every pair that could meet this round (see _candidate_pairs).
    """
    collisions: list[Collision] = []
    t_c = first_contacts(mo, pi, pj, 0.0)
    while t_c.size and np.isfinite(t_c).any():
        k = int(np.argmin(t_c))
        t, a, b = float(t_c[k]), int(pi[k]), int(pj[k])
        stopped: list[int] = []
        for x, y in ((a, b), (b, a)):
            row = int(mo.row_of[x])
            if row >= 0 and t < mo.stop[row]:
                mo.stop[row] = t
                p = positions_at(mo, np.array([x], dtype=np.intp), np.array([t]))[0]
                collisions.append(Collision(x, y, t, (float(p[0]), float(p[1]))))
                stopped.append(x)
        if not stopped:  # cannot happen: a contact always involves a robot still moving
            raise PhysicsInvariantError(f"contact of robots {a} and {b} at t={t} with none moving")
        gone = np.zeros(len(mo.start), dtype=np.bool_)
        gone[stopped] = True
        keep = ~(gone[pi] | gone[pj])
        pi, pj, t_c = pi[keep], pj[keep], t_c[keep]
        still_moving = mo.robots[mo.stop > t]
        others = still_moving[~gone[still_moving]]
        if others.size:
            ni, nj = _candidate_pairs(mo, np.array(stopped, dtype=np.intp), others)
            pi, pj = np.concatenate([pi, ni]), np.concatenate([pj, nj])
            t_c = np.concatenate([t_c, first_contacts(mo, ni, nj, t)])
    return collisions


def _closest_pair(points: Points, pi: IntArray, pj: IntArray) -> tuple[int, int, float]:
    """The pair of (pi, pj) whose centres are closest in `points` (pairs must be non-empty)."""
    d = points[pi] - points[pj]
    dist = np.hypot(d[:, 0], d[:, 1])
    k = int(np.argmin(dist))
    a, b = int(pi[k]), int(pj[k])
    return min(a, b), max(a, b), float(dist[k])


_CORNERS = np.array([[0, 0], [0, 1], [1, 0], [1, 1]], dtype=np.float64)


BRUTE_PAIRS = 2048
"""Up to this many pairs, the candidate pairs are every pair: cheaper than a sort and sweep for
the few movers of a round of the paper's algorithm."""
SNAP_FEW = 2
"""Up to this many movers, `_snap_movers` tests each against every other robot, as one."""
SNAP_REACH = CONTACT + 1e-3
"""Only a robot closer than this to a mover's end can refuse one of its grid corners (a corner is
within GRID * sqrt(2) of the end): `_snap_movers` tests those alone."""
NEAR_REACH = SNAP_REACH + 1e-6
"""A round of Lines whose boxes (local frame) come nowhere within this of another robot's has no
pair that can meet (2 + BOX_MARGIN) and no mover that ends within SNAP_REACH of anyone (the world
frame's rounding of the end, below 1e-9, is far inside the margin)."""


def _snap_movers(final: Points, movers: IntArray) -> None:
    """Put the movers' end positions on the grid, in place, without bringing anyone closer.

    Of the four grid points around an end position the nearest is taken unless it brings some
    other robot closer than it was and closer than 2 (into the touching band); then the nearest
    corner that does not. Planned paths thus keep what the planner promised (CLEAR_SLACK) after
    snapping, and touching neighbours do not creep towards each other round after round.

    A mover with no robot within SNAP_REACH takes its nearest corner (no other robot can refuse
    it, nor can its own snap matter to another's), all such movers at once; the others, one after
    the other in the order of `movers`, test their corners against the robots within SNAP_REACH.
    """
    if len(movers) <= SNAP_FEW:  # few: each against every other robot
        everyone = np.arange(len(final), dtype=np.intp)
        for robot in movers:
            _snap_one(final, int(robot), everyone[everyone != robot])
        return
    pi, pj = _sweep_pairs(final[:, 0], final[:, 0], movers, np.arange(len(final)), SNAP_REACH)
    d = final[pi] - final[pj]
    near = (np.hypot(d[:, 0], d[:, 1]) < SNAP_REACH) & (pi != pj)
    pi, pj = pi[near], pj[near]
    p = final[movers]
    base = np.floor(p / GRID) * GRID
    corners = base[:, None, :] + _CORNERS * GRID
    dist = np.hypot(corners[:, :, 0] - p[:, 0, None], corners[:, :, 1] - p[:, 1, None])
    nearest = corners[np.arange(len(movers)), np.argmin(dist, axis=1)]
    near_someone = np.zeros(len(final), dtype=np.bool_)
    near_someone[pi] = True
    crowded = near_someone[movers]
    alone = ~crowded
    final[movers[alone]] = nearest[alone] + 0.0
    for robot in movers[crowded]:
        _snap_one(final, int(robot), pj[pi == robot])


def _snap_near(
    final: Points,
    movers: IntArray,
    pairs: tuple[IntArray, IntArray] | None,
    everyone: bool = False,
) -> None:
    """`_snap_movers`, given pairs (mover, robot) among which are all pairs closer than SNAP_REACH
    (None: there is none): the same corners (each mover's test is against the same robots, in
    the same order of movers), without searching for the pairs again. `everyone`: the movers are
    arange(n)."""
    crowded: IntArray | None = None
    alone = movers
    if pairs is not None:
        si, sj = pairs
        d = final.take(si, axis=0) - final.take(sj, axis=0)
        near = (np.hypot(d[:, 0], d[:, 1]) < SNAP_REACH) & (si != sj)
        if near.any():
            pi, pj = si[near], sj[near]
            near_someone = np.zeros(len(final), dtype=np.bool_)
            near_someone[pi] = True
            is_crowded = near_someone[movers]
            alone, crowded = movers[~is_crowded], movers[is_crowded]
    if len(alone):  # no robot can refuse their nearest corner: all at once
        every = everyone and crowded is None  # alone is movers, which is arange(n)
        p = final if every else final.take(alone, axis=0)
        nearest = _nearest_corners(p)
        if every:
            final[:] = nearest
        else:
            final[alone] = nearest
    if crowded is not None:
        for robot in crowded.tolist():
            _snap_one(final, robot, pj[pi == robot])


def _nearest_corners(p: Points) -> Points:
    """The nearest of the four grid points around each point of `p` ((m, 2)), the first at the
    least np.hypot in _CORNERS' order: `_snap_movers`' very corners, distances and argmin.

    Where every coordinate lies in [CORNERS_EXACT_LOW, CORNERS_EXACT_HIGH), that is each
    coordinate's nearer grid neighbour, the lower one on a tie: ceil(p / GRID - 0.5) * GRID, every
    step exact. There, a coordinate p between grid points lo and lo + GRID is at a0 = p - lo and
    a1 = GRID - a0 from them, both exact, and a0 != a1 means |a1 - a0| = 2 |p - (lo + GRID / 2)|
    >= 2 ulp(p) >= 2**-68; the two corners that differ in that coordinate alone then differ in
    true distance by a factor of at least 1 + |a1 - a0| / (4 GRID) >= 1 + 2**-40, which no hypot
    within 2**-41 of the truth can reverse or tie; a tie (a0 == a1) gives equal np.hypot inputs
    and the first corner, the lower one. Elsewhere (near 0, or beyond 2**22), the distances."""
    size = np.abs(p)
    low = np.minimum.reduce(size, axis=None) if len(p) else CORNERS_EXACT_LOW
    if low < CORNERS_EXACT_LOW or not np.maximum.reduce(size, axis=None) < CORNERS_EXACT_HIGH:
        return _nearest_corners_by_distance(p)
    nearest: Points = np.multiply(p, _PER_GRID, out=size)  # p / GRID, exactly
    nearest -= _HALF  # exact: |p / GRID| < 2**52
    np.ceil(nearest, out=nearest)
    nearest *= _GRID
    nearest += _ZERO  # -0.0 -> +0.0, as base + 0.0
    return nearest


# `_nearest_corners`' constants as arrays: a Python float costs a conversion in every call
_PER_GRID: Final = np.array(2.0**GRID_BITS)
_HALF: Final = np.array(0.5)
_GRID: Final = np.array(GRID)


CORNERS_EXACT_LOW: Final = 2.0**-17
"""From here on (|coordinate|), `_nearest_corners` rounds each coordinate alone (see there)."""
CORNERS_EXACT_HIGH: Final = 2.0**22
"""Up to here (|coordinate|, excluded), `_nearest_corners` rounds each coordinate alone."""


def _nearest_corners_by_distance(p: Points) -> Points:
    """`_nearest_corners` by the four distances of each point and their argmin."""
    base = np.floor(p / GRID)
    base *= GRID
    corners = base[:, None, :] + _CORNERS * GRID  # (m, 4, 2); corner 0 is base + 0.0
    d = corners - p[:, None, :]
    k = np.hypot(d[:, :, 0], d[:, :, 1]).argmin(axis=1)
    k += np.arange(0, 4 * len(p), 4)
    nearest: Points = corners.reshape(-1, 2).take(k, axis=0)
    return nearest


def _snap_one(final: Points, robot: int, neighbours: IntArray) -> None:
    """`_snap_movers` for one mover, tested against the robots `neighbours` (all those within
    SNAP_REACH: no other can refuse a corner)."""
    p = final[robot].copy()
    base = np.floor(p / GRID) * GRID
    corners = base + _CORNERS * GRID
    order = np.argsort(np.hypot(corners[:, 0] - p[0], corners[:, 1] - p[1]), kind="stable")
    others = final[neighbours]
    before = np.hypot(others[:, 0] - p[0], others[:, 1] - p[1])
    floor = np.minimum(before, CONTACT)
    chosen = corners[order[0]]
    for k in order:
        c = corners[k]
        if (np.hypot(others[:, 0] - c[0], others[:, 1] - c[1]) >= floor).all():
            chosen = c
            break
    final[robot] = chosen + 0.0


def apply_round(
    positions: Points, paths: Mapping[int, Path], *, points: bool = False
) -> RoundOutcome:
    """Move every robot of `paths` along its path (world frame) at once, stopping at contact.

    All movers start at t = 0 and move at unit speed; a robot whose disc would overlap another
    (centres closer than 2 - CONTACT_SLACK) stops at first contact and the contact is recorded
    (both robots if both were moving). An empty path means stay. `positions` is not modified.
    Movers end on the grid (fatswarm/domain/tolerance.py): `_snap_movers`. `points`: the robots
    are points: no contact, each mover covers its path and ends on the nearest grid point.
    Raises InvalidConfigurationError (bad positions, a mover overlapping at the start),
    InvalidRoundError (unknown robot) or PathFormatError (non-finite or oversized path) before
    anything moves; PhysicsInvariantError if discs overlap afterwards (a physics bug).
    """
    start = _as_points(positions)
    lines = _straight_lines(paths, len(start))
    if lines is not None:  # the common round: every path one Line (`apply_lines`)
        keys, ends = lines
        n = len(start)
        everyone = keys == list(range(n))
        robots = _every(n) if everyone else np.array(keys, dtype=np.intp)
        return _line_round(start, robots, keys, ends, points, everyone)
    moves = _check_moves(paths, len(start))
    traveled = {robot: 0.0 for robot, _ in moves}
    # Simulate in a frame centred on a mover (a grid point: the shift is exact for grid positions
    # and for path points near them), so that rounding is that of the round's extent, not of the
    # swarm's offset: at 3e5 the contact search's margin (1e-10) was below the rounding there.
    origin = snap_point(*start[moves[0][0]]) if moves else (0.0, 0.0)
    local = start - np.array(origin)
    shift = (-origin[0], -origin[1])
    mo = build_motion(local, moves, shift)
    if not len(mo.robots):
        return RoundOutcome(positions=start, traveled=traveled)
    if points:  # nothing to meet: every mover to its end (mo.stop is its length), on the grid
        final = start.copy()
        final[mo.robots] = snap(positions_at(mo, mo.robots, mo.stop) + np.array(origin))
        return _outcome(start, final, mo, dict(moves), traveled, [])
    # Every pair that can meet: a robot never leaves its path's box, so no other pair can overlap,
    # before, during or after the round (stills among themselves are the caller's business).
    pi, pj = _candidate_pairs(mo, mo.robots, np.arange(len(start), dtype=np.intp))
    final, collisions = _contacts(start, mo, origin, pi, pj, None)
    return _outcome(start, final, mo, dict(moves), traveled, collisions)


def apply_lines(
    positions: Points, movers: IntArray, ends: Points, *, points: bool = False
) -> RoundOutcome:
    """`apply_round(positions, {r: Path((Line((x, y)),)) for r, (x, y) in zip(movers, ends)})`,
    with the same bits and the same errors, without a Path per robot.

    `movers`: (m,) robot ids, increasing; `ends`: (m, 2) world-frame end points of their straight
    lines (what `transform(Path((Line(end),)), start)` gives). Raises InvalidRoundError if movers
    and ends do not match in shape or the movers are not increasing.
    """
    start = _given_points(positions)  # not written to, nor returned: copied only if returned
    robots = np.asarray(movers)
    e = np.asarray(ends, dtype=np.float64)
    m = len(robots) if robots.ndim == 1 else -1
    if robots.dtype.kind not in "iu" or e.shape != (m, 2):
        raise InvalidRoundError(
            f"apply_lines takes movers as an (m,) int array and ends as (m, 2) floats, got "
            f"{robots.dtype} {robots.shape} and {e.shape}"
        )
    if m == 0:
        return RoundOutcome(positions=start.copy(), traveled={})
    n = len(start)
    keys = robots.tolist()
    if m == n and keys == list(range(n)) and np.count_nonzero(np.isfinite(e)) == 2 * m:
        return _line_round(start, _every(n), keys, e, points, True)  # increasing, in range
    if m > 1 and np.count_nonzero(robots[1:] > robots[:-1]) < m - 1:
        raise InvalidRoundError("apply_lines takes each mover once, in increasing order")
    if keys[0] < 0 or keys[-1] >= n or np.count_nonzero(np.isfinite(e)) < 2 * m:
        xy = e.tolist()  # apply_round says what is wrong, as it would for these paths
        paths = {int(r): Path((Line((x, y)),)) for r, (x, y) in zip(keys, xy, strict=True)}
        return apply_round(start, paths, points=points)
    return _line_round(start, robots.astype(np.intp, copy=False), keys, e, points, m == n)


_FLOAT64: Final = np.dtype(np.float64)


def _given_points(positions: Any) -> Points:
    """`_as_points(positions)`, but `positions` itself where it is a float64 (n, 2) array with
    n >= 1 and finite values (the lock step's every round): for a caller that neither writes to
    it nor returns it."""
    if (
        type(positions) is np.ndarray
        and positions.dtype is _FLOAT64
        and positions.ndim == 2
        and positions.shape[1] == 2
        and len(positions)
        and np.count_nonzero(np.isfinite(positions)) == positions.size
    ):
        return positions
    return _as_points(positions)


_INT: Final = frozenset({int})
_PATH: Final = frozenset({Path})
_ONE: Final = frozenset({1})
_LINE: Final = frozenset({Line})
_TUPLE: Final = frozenset({tuple})
_TWO: Final = frozenset({2})
_FLOAT: Final = frozenset({float})


def _straight_lines(paths: Mapping[int, Path], n: int) -> tuple[list[int], Points] | None:
    """The round as (robots, (m, 2) world ends) if every key is an int robot of the n and every
    path one Line to a tuple of two finite floats, checked in bulk (no loop in Python); None for
    any other round, which `_check_moves` then checks path by path (raising what it must)."""
    keys = list(paths)
    if not keys or set(map(type, keys)) != _INT:
        return None
    if keys != list(range(n)) and (min(keys) < 0 or max(keys) >= n):  # ints: equal means 0 .. n - 1
        return None
    values = list(paths.values())
    if set(map(type, values)) != _PATH:
        return None
    segments = [path.segments for path in values]
    if set(map(len, segments)) != _ONE:
        return None
    firsts: list[Any] = [segs[0] for segs in segments]  # Lines, once their types are checked
    if set(map(type, firsts)) != _LINE:
        return None
    ends = [line.end for line in firsts]
    if set(map(type, ends)) != _TUPLE or set(map(len, ends)) != _TWO:
        return None
    flat = list(chain.from_iterable(ends))
    if set(map(type, flat)) != _FLOAT or not isfinite(sum(flat)):  # any inf or nan: not finite
        return None
    return keys, np.array(flat, dtype=np.float64).reshape(len(keys), 2)


def _line_round(
    start: Points, robots: IntArray, keys: list[int], ends: Points, points: bool, everyone: bool
) -> RoundOutcome:
    """apply_round when every path is one Line, from arrays: `robots` (m,) (`keys` the same as
    ints), world `ends` (m, 2), checked; `everyone`: robots is arange(n). The very arithmetic of
    build_motion's `_single_lines`, the general path and `_outcome`, on arrays; a round whose
    movers' boxes come nowhere near another robot skips the contact search (as the general path
    does when it finds no pair). `start` is not written to, nor returned: the outcome's positions
    are a new array."""
    n = len(start)
    ox, oy = snap_point(*start[keys[0]].tolist())  # as the general path: a frame on a mover
    origin = np.array((ox, oy))
    here_w = start if everyone else start.take(robots, axis=0)
    here = here_w - origin  # the local frame's start points: start - origin, row by row
    e = ends - origin  # ends + (-ox, -oy), as _single_lines: x - y is x + (-y)
    boxes: FloatArray | None = None
    if points:
        step = e - here
        np.abs(step, out=step)
    else:  # the boxes: (2, n, 2), the low corners then the high ones (`_near_pairs`)
        boxes = np.empty((2, n, 2))
        if everyone:
            lo = np.minimum(e, here, out=boxes[0])
            hi = np.maximum(e, here, out=boxes[1])
        else:
            boxes[:] = start - origin
            lo = np.minimum(e, here)
            hi = np.maximum(e, here)
            boxes[0, robots] = lo
            boxes[1, robots] = hi
        step = hi - lo  # |e - here|, to the bit: max - min is the difference's magnitude
    longest = np.maximum(step[:, 0], step[:, 1])  # 0 only for a line of length 0
    total: list[float] | None = None  # the lines' lengths (CPython's hypot, as _single_lines)
    if np.count_nonzero(longest) < len(keys) or not np.maximum.reduce(longest) < LINE_SAFE:
        total = list(map(hypot, *(e - here).T.tolist()))
        if not isfinite(max(total)):
            k = next(k for k, t in enumerate(total) if not isfinite(t))
            raise PathFormatError(
                f"robot {keys[k]}: the path is too long to simulate (length {total[k]})"
            )
    # else every length is finite and above 0, as hypot is 0 only at (0, 0): known uncomputed
    world = list(map(hypot, *(ends - here_w).T.tolist()))  # _outcome's lengths: world frame
    if total is None or min(total) > 0.0:
        traveled = dict(zip(keys, world, strict=True))
        lengths = traveled.copy()
    else:  # a zero-length line moves nobody: not a row, traveled 0.0, no length
        keep = np.array(total) > 0.0
        if not keep.any():
            return RoundOutcome(positions=start.copy(), traveled=dict.fromkeys(keys, 0.0))
        if boxes is not None:  # the box of one that stays is its point, as it is
            still = robots[~keep]
            boxes[:, still] = start.take(still, axis=0) - origin
        robots, here, e = robots[keep], here[keep], e[keep]
        everyone = False
        traveled = dict.fromkeys(keys, 0.0)
        lengths = {r: w for r, w, t in zip(keys, world, total, strict=True) if t > 0.0}
        traveled.update(lengths)
        total = [t for t in total if t > 0.0]
    if points:  # every mover to its end, on the grid
        if everyone:
            return RoundOutcome(snap(e + origin), traveled, [], lengths)
        final = start.copy()
        final[robots] = snap(e + origin)
        return RoundOutcome(final, traveled, [], lengths)
    assert boxes is not None
    pairs = _near_pairs(boxes, robots, everyone)
    if pairs is None:  # no pair can meet, no mover ends near anyone:
        if everyone:  # every mover to the grid point nearest its end (`_snap_near`)
            return RoundOutcome(_nearest_corners(e + origin), traveled, [], lengths)
        final = start.copy()
        final[robots] = _nearest_corners(e + origin)
        return RoundOutcome(final, traveled, [], lengths)
    if everyone:
        final = e + origin
    else:
        final = start.copy()
        final[robots] = e + origin
    si, sj, brute = pairs  # both (a, b) and (b, a) where both move: `_snap_near`
    boxes_t = _rows(boxes)
    close = _boxes_close(boxes_t, si, sj, 2.0 + BOX_MARGIN)
    if everyone:  # each pair once, as (lower id, higher id)
        close &= sj > si
    else:
        is_mover = np.zeros(n, dtype=np.bool_)
        is_mover[robots] = True
        close &= ~(is_mover.take(sj) & (sj < si))
    if not close.any():  # no pair can meet: every mover to its end
        _snap_near(final, robots, (si, sj), everyone)
        return RoundOutcome(final, traveled, [], lengths)
    pi, pj = si[close], sj[close]
    if not brute:  # from the sort: into the brute force's order
        rank = np.empty(n, dtype=np.intp)
        rank[robots] = np.arange(len(robots), dtype=np.intp)
        order = np.lexsort((pj, rank[pi]))
        pi, pj = pi[order], pj[order]
    if total is None:
        total = list(map(hypot, *(e - here).T.tolist()))
    box = np.concatenate((boxes[0].take(robots, axis=0), boxes[1].take(robots, axis=0)), axis=1)
    local = start - origin
    mo = line_motion(local, robots, here, e, np.array(total, dtype=np.float64), box)
    final, collisions = _contacts(start, mo, (ox, oy), pi, pj, (si, sj))  # final anew
    if collisions:  # as _outcome: the whole path's (world) length unless stopped short
        rows = zip(robots.tolist(), mo.stop.tolist(), total, strict=True)
        traveled.update({r: lengths[r] if stop >= t else stop for r, stop, t in rows})
    return RoundOutcome(final, traveled, collisions, lengths)


def _rows(boxes: FloatArray) -> FloatArray:
    """Boxes (2, n, 2) (low corners, high corners) as (4, n) rows: xmin, ymin, xmax, ymax."""
    rows: FloatArray = boxes.transpose(0, 2, 1).reshape(4, -1)
    return rows


LINE_SAFE: Final = 1e300
"""A line whose coordinates differ by less than this has a finite hypot (`_line_round`)."""


def _contacts(
    start: Points,
    mo: Motion,
    origin: tuple[float, float],
    pi: IntArray,
    pj: IntArray,
    near: tuple[IntArray, IntArray] | None,
) -> tuple[Points, list[Collision]]:
    """The round's end positions (on the grid) and contacts, given its candidate pairs (pi, pj),
    in order; `near`: pairs (mover, robot) that include every pair closer than SNAP_REACH at the
    end, if known (else `_snap_movers` finds them)."""
    if pi.size:
        a, b, dist = _closest_pair(start, pi, pj)
        if dist < OVERLAP_DISTANCE:
            raise InvalidConfigurationError(
                f"robots {a} and {b} overlap before the round: centres {dist:.9g} apart (< 2); "
                "start from a valid configuration (see validate_configuration)"
            )
    collisions = _simulate(mo, pi, pj) if pi.size else []  # no pair, no contact
    final = start.copy()
    final[mo.robots] = positions_at(mo, mo.robots, mo.stop) + np.array(origin)
    if near is None:
        _snap_movers(final, mo.robots)
    else:
        _snap_near(final, mo.robots, near)
    collisions = [  # a stopped robot's recorded point is where it is: on the grid
        Collision(c.robot, c.other, c.t, (float(final[c.robot, 0]), float(final[c.robot, 1])))
        for c in collisions
    ]
    if pi.size:
        a, b, dist = _closest_pair(final, pi, pj)
        if dist < OVERLAP_DISTANCE:
            raise PhysicsInvariantError(
                f"physics bug: robots {a} and {b} overlap after the round (centres {dist!r} apart)"
            )
    return final, collisions


def _near_pairs(
    boxes: FloatArray, movers: IntArray, everyone: bool
) -> tuple[IntArray, IntArray, bool] | None:
    """Every pair (mover, other robot) whose boxes ((2, n, 2): the low corners, then the high
    ones) come within NEAR_REACH by `_boxes_close`'s test, both ways round where both move, and
    whether they come in the brute force's order (mover by mover, then robot); None if there is
    none, the common round, proved in a few numpy calls. `everyone`: movers is arange(n).

    Up to NEAR_BRUTE pairs, `_boxes_close`'s arithmetic on every (mover, robot) pair, gathered
    in one call (`_pair_gather`); beyond, on the few pairs a sort along x leaves
    (`_sorted_pairs`)."""
    n = boxes.shape[1]
    m = len(movers)
    if m * n <= NEAR_BRUTE:
        index = _pair_gather(n) if everyone else _pair_gather(n)[:, :, movers]
        near = _close(boxes.take(index), NEAR_REACH_SQUARED).ravel()  # each mover with itself
        if np.count_nonzero(near) == m:
            return None
        pi = _repeated(n) if everyone else movers.repeat(n)
        pj = _tiled(n, m)
        near &= pi != pj
        return pi[near], pj[near], True
    pairs = _sorted_pairs(boxes)
    if pairs is None:
        return None
    pa, pb = pairs
    if not everyone:
        moving = np.zeros(n, dtype=np.bool_)
        moving[movers] = True
        near = moving.take(pa) | moving.take(pb)  # two still robots are no concern of the round
        if not np.count_nonzero(near):
            return None
        pa, pb = pa[near], pb[near]
    if everyone:
        return np.concatenate((pa, pb)), np.concatenate((pb, pa)), False
    a_moves, b_moves = moving.take(pa), moving.take(pb)
    return (
        np.concatenate((pa[a_moves], pb[b_moves])),
        np.concatenate((pb[a_moves], pa[b_moves])),
        False,
    )


NEAR_BRUTE = 512
"""Up to this many (mover, robot) pairs, `_near_pairs` tests every pair rather than sort."""
NEAR_REACH_SQUARED: Final = np.array(NEAR_REACH**2)
"""`_boxes_close`'s bound at NEAR_REACH, as an array (a Python float costs a conversion a call)."""
_ZERO: Final = np.array(0.0)


def _close(gathered: FloatArray, reach_squared: FloatArray) -> BoolArray:
    """`_boxes_close` on pairs gathered as (2, 4, ...): the minuends, then the subtrahends, of
    bj's low - bi's high (x, y), then bi's low - bj's high (x, y); the same arithmetic."""
    d = gathered[0] - gathered[1]
    gap = np.maximum(d[:2], d[2:])
    np.maximum(gap, _ZERO, out=gap)
    gap *= gap
    close: BoolArray = gap[0] + gap[1] < reach_squared
    return close


def _sorted_pairs(boxes: FloatArray) -> tuple[IntArray, IntArray] | None:
    """Pairs of robots (each pair once, a != b) whose boxes ((2, n, 2): the low corners, then the
    high ones) come within NEAR_REACH by `_boxes_close`'s test, or None if there is none: a sort
    of the boxes by their low x. A pair within reach has the later low at most the earlier box's
    high + NEAR_REACH (else the gap on x alone is beyond reach, rounding being monotone), so lies
    at most k places apart in that order, k the most places any box's window spans: each box is
    tested against the next k (the earlier one as bi, the later as bj), in the order of
    `_window`."""
    n = boxes.shape[1]
    order = boxes[0, :, 0].argsort()
    ordered = boxes.take(order, axis=1)
    reach = ordered[0, :, 0].searchsorted(ordered[1, :, 0] + NEAR_REACH, side="right")
    reach -= _every(n)
    k = int(np.maximum.reduce(reach)) - 1  # reach[p] > p: a box's low is at most its high
    if k <= 0:
        return None
    first, later, index = _window(n, k)
    near = _close(ordered.take(index), NEAR_REACH_SQUARED)
    if not np.count_nonzero(near):
        return None
    return order.take(first[near]), order.take(later[near])


@lru_cache(maxsize=64)
def _pair_gather(n: int) -> IntArray:
    """(2, 4, n, n) indices into boxes (2, n, 2) taken flat, for every pair (i, j) (i major):
    `_close`'s minuends (j's low x, y; i's low x, y) and subtrahends (i's high x, y; j's high x,
    y) (shared by the rounds: never written to, yet writeable, as `take` copies a read-only
    index at every call)."""
    i = np.arange(n, dtype=np.intp)[:, None].repeat(n, axis=1)
    j = i.T
    lows = np.stack((2 * j, 2 * j + 1, 2 * i, 2 * i + 1))
    highs = np.stack((2 * i, 2 * i + 1, 2 * j, 2 * j + 1)) + 2 * n
    return np.ascontiguousarray(np.stack((lows, highs)))


@lru_cache(maxsize=64)
def _window(n: int, k: int) -> tuple[IntArray, IntArray, IntArray]:
    """The pairs (p, p + j) for j = 1 .. k, p + j < n, as two flat arrays, and (2, 4, pairs)
    indices into (2, n, 2) boxes taken flat that gather `_close`'s operands of each pair, p as bi
    (shared by the rounds: read-only but the indices, writeable as `_pair_gather`'s)."""
    first = np.repeat(np.arange(n, dtype=np.intp), k)
    later = first + np.tile(np.arange(1, k + 1, dtype=np.intp), n)
    keep = later < n
    first, later = first[keep], later[keep]
    lows = np.stack((2 * later, 2 * later + 1, 2 * first, 2 * first + 1))
    highs = np.stack((2 * first, 2 * first + 1, 2 * later, 2 * later + 1)) + 2 * n
    index = np.stack((lows, highs))
    for out in (first, later):
        out.setflags(write=False)
    return first, later, index


@lru_cache(maxsize=64)
def _repeated(n: int) -> IntArray:
    """0, ..., 0, 1, ..., 1, ..., n - 1: each of arange(n) n times (read-only, shared)."""
    out = np.repeat(np.arange(n, dtype=np.intp), n)
    out.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def _every(n: int) -> IntArray:
    """0, 1, ..., n - 1 (read-only: shared by the rounds that ask for it)."""
    out = np.arange(n, dtype=np.intp)
    out.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def _tiled(n: int, m: int) -> IntArray:
    """0, 1, ..., n - 1, m times over (read-only: shared by the rounds that ask for it)."""
    out = np.tile(np.arange(n, dtype=np.intp), m)
    out.setflags(write=False)
    return out


def _boxes_close(boxes_t: FloatArray, pi: IntArray, pj: IntArray, reach: float) -> BoolArray:
    """Whether the boxes ((4, n)) of each pair come within `reach`; at 2 + BOX_MARGIN,
    `_candidate_pairs`' test, with the same arithmetic."""
    bi, bj = boxes_t.take(pi, axis=1), boxes_t.take(pj, axis=1)
    gap = np.maximum(bj[:2] - bi[2:], bi[:2] - bj[2:])
    np.maximum(gap, 0.0, out=gap)
    gap *= gap
    close: BoolArray = gap[0] + gap[1] < reach**2
    return close


def _outcome(
    start: Points,
    final: Points,
    mo: Motion,
    world_paths: dict[int, Path],
    traveled: dict[int, float],
    collisions: list[Collision],
) -> RoundOutcome:
    """The round's outcome: `final` positions, each mover's path length and the length it
    covered (its whole path unless stopped), and the contacts."""
    starts = start.tolist()  # Python floats: the same values, read faster than numpy scalars
    rows = zip(mo.robots.tolist(), mo.stop.tolist(), mo.total.tolist(), strict=True)
    lengths: dict[int, float] = {}
    for robot, stop, total in rows:
        path, (x, y) = world_paths[robot], starts[robot]
        if len(path.segments) == 1 and type(seg := path.segments[0]) is Line:
            length = 0.0 + math.hypot(seg.end[0] - x, seg.end[1] - y)  # path_length's sum
        else:
            length = path_length((x, y), path)
        lengths[robot] = length
        traveled[robot] = length if stop >= total else stop  # the whole path: the world's length
    return RoundOutcome(final, traveled, collisions, lengths)
