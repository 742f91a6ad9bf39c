"""Disc physics of one round: movers start together at unit speed; continuous collision detection.

Robots are unit discs. Every robot of a round follows its path from t = 0 at unit speed (time equals
arc length). A robot whose disc would overlap another stops at first contact; stopped robots are
still obstacles for the rest of the round. Discs never overlap, at any time of the round.
Point robots (`--bodies points`, `points=True`) have no extent: every mover covers its whole path,
robots may meet and share a point, and nothing is a collision.

Method: an event loop over the pairs whose path boxes come within 2; per pair, adaptive subdivision
of time proves intervals overlap-free with lower bounds on the distance (exact for straight relative
motion, an arc against a robot at rest and two arcs up to their turning-rate drift; Lipschitz and
chord bounds otherwise) and conservative advancement; contacts are then located by bisection.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from math import isfinite
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
    FloatArray,
    IntArray,
    Motion,
    build_motion,
    first_contacts,
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
    """Every pair (a in `first`, b in `second`) whose intervals [lo, hi] (one axis, per robot) come
    within `reach`, and maybe a few more: a sort and sweep, O((m + k) log k) for k = len(second);
    up to BRUTE_PAIRS pairs, every pair (first, then second) instead.
    """
    if len(first) * len(second) <= BRUTE_PAIRS:  # few: every pair, already in their order
        return np.repeat(first, len(second)), np.tile(second, len(first))
    lo_b = lo[second]
    order = lo_b.argsort(kind="stable")
    lo_sorted = lo_b[order]
    width = float((hi[second] - lo_b).max()) if len(second) else 0.0
    pad = reach + width + 1.0  # generous: the exact test of the pairs comes after
    begin = lo_sorted.searchsorted(lo[first] - pad, side="left")
    end = lo_sorted.searchsorted(hi[first] + reach + 1.0, side="right")
    counts = end - begin
    total = int(counts.sum())
    offsets = (begin - counts.cumsum() + counts).repeat(counts)
    pi = first.repeat(counts)
    pj = second[order[np.arange(total, dtype=np.intp) + offsets]]
    return pi, pj


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
    _snap_movers(final, mo.robots)
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
    return _outcome(start, final, mo, dict(moves), traveled, collisions)


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
