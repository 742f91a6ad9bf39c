"""Disc physics of one round: movers start together at unit speed; continuous collision detection.

Robots are unit discs. Every robot of a round follows its path from t = 0 at unit speed (time equals
arc length). A robot whose disc would overlap another stops at first contact; stopped robots are
still obstacles for the rest of the round. Discs never overlap, at any time of the round.

Method: an event loop over the pairs whose path boxes come within 2; per pair, adaptive subdivision
of time proves intervals overlap-free with lower bounds on the distance (exact for straight relative
motion, an arc against a robot at rest and two arcs up to their turning-rate drift; Lipschitz and
chord bounds otherwise) and conservative advancement; contacts are then located by bisection.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from numbers import Real
from typing import Any

import numpy as np

from fatswarm.domain.path import (
    MAX_SEGMENTS,
    Arc,
    Line,
    Path,
    PathFormatError,
    Points,
    path_length,
    transform,
)
from fatswarm.domain.tolerance import (
    CLEAR_SLACK,
    CONTACT,
    GRID,
    MAX_COORD,
    OVERLAP_DISTANCE,
    OVERLAP_SLACK,
    snap,
    snap_point,
)
from fatswarm.world.motion import IntArray, Motion, build_motion, first_contacts, positions_at

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


def validate_configuration(positions: Points) -> Points:
    """Return positions on the grid as an (n, 2) float64 copy or raise InvalidConfigurationError.

    Positions are snapped to the nearest multiples of GRID (moving each by at most 6.6e-10), so
    that every robot's view is exact (fatswarm/domain/tolerance.py). Refused: a wrong shape, no
    robot, NaN or infinite coordinates, coordinates beyond +-MAX_COORD, two centres closer than
    2 - CONTACT_SLACK (overlapping unit discs) once on the grid.
    """
    points = _as_points(positions)
    far = float(np.abs(points).max())
    if far > MAX_COORD:
        raise InvalidConfigurationError(
            f"coordinates must lie within +-{MAX_COORD:.0f} (where positions on the grid of "
            f"{GRID:.2g} stay exact), got {far:.6g}"
        )
    points = snap(points)
    pair = _first_overlap(points, np.arange(len(points), dtype=np.intp))
    if pair is not None:
        a, b, dist = pair
        raise InvalidConfigurationError(
            f"robots {a} and {b} overlap: their centres are {dist:.9g} apart, closer than 2 "
            "(unit discs); place every pair of robots at least 2 apart"
        )
    return points


def _finite_number(value: Any) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


def _finite_point(value: Any) -> bool:
    return (
        isinstance(value, (tuple, list, np.ndarray))
        and len(value) == 2
        and all(_finite_number(v) for v in value)
    )


def _check_moves(paths: Mapping[int, Path], n: int) -> list[tuple[int, Path]]:
    """The (robot, path) pairs of a round, checked; raises before anything moves."""
    moves: list[tuple[int, Path]] = []
    for key, path in paths.items():
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)):
            raise InvalidRoundError(f"robot ids must be integers, got {key!r}")
        robot = int(key)
        if not 0 <= robot < n:
            raise InvalidRoundError(f"robot {robot} does not exist: ids run from 0 to {n - 1}")
        if not isinstance(path, Path):
            raise InvalidRoundError(f"robot {robot}: expected a Path, got {type(path).__name__}")
        if len(path.segments) > MAX_SEGMENTS:
            raise PathFormatError(
                f"robot {robot}: a path has at most {MAX_SEGMENTS} segments, got {len(path)}"
            )
        for seg in path.segments:
            if isinstance(seg, Line):
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


def _candidate_pairs(mo: Motion, first: IntArray, second: IntArray) -> tuple[IntArray, IntArray]:
    """Pairs (a in `first`, b in `second`, a != b, once each) whose path boxes come within 2."""
    pi = np.repeat(first, len(second))
    pj = np.tile(second, len(first))
    boxes = np.concatenate([mo.start, mo.start], axis=1)
    boxes[mo.robots] = mo.box
    bi, bj = boxes[pi], boxes[pj]
    gx = np.maximum(0.0, np.maximum(bj[:, 0] - bi[:, 2], bi[:, 0] - bj[:, 2]))
    gy = np.maximum(0.0, np.maximum(bj[:, 1] - bi[:, 3], bi[:, 1] - bj[:, 3]))
    in_first = np.zeros(len(mo.start), dtype=np.bool_)
    in_first[first] = True
    keep = (gx * gx + gy * gy < (2.0 + BOX_MARGIN) ** 2) & (pi != pj) & ~(in_first[pj] & (pj < pi))
    return pi[keep], pj[keep]


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


def _snap_movers(final: Points, movers: IntArray) -> None:
    """Put the movers' end positions on the grid, in place, without bringing anyone closer.

    Of the four grid points around an end position the nearest is taken unless it brings some
    other robot closer than it was and closer than 2 (into the touching band); then the nearest
    corner that does not. Planned paths thus keep what the planner promised (CLEAR_SLACK) after
    snapping, and touching neighbours do not creep towards each other round after round.
    """
    for robot in movers:
        p = final[robot].copy()
        base = np.floor(p / GRID) * GRID
        corners = base + _CORNERS * GRID
        order = np.argsort(np.hypot(corners[:, 0] - p[0], corners[:, 1] - p[1]), kind="stable")
        others = np.delete(final, robot, axis=0)
        before = np.hypot(others[:, 0] - p[0], others[:, 1] - p[1])
        floor = np.minimum(before, CONTACT)
        chosen = corners[order[0]]
        for k in order:
            c = corners[k]
            if (np.hypot(others[:, 0] - c[0], others[:, 1] - c[1]) >= floor).all():
                chosen = c
                break
        final[robot] = chosen + 0.0


def apply_round(positions: Points, paths: Mapping[int, Path]) -> RoundOutcome:
    """Move every robot of `paths` along its path (world frame) at once, stopping at contact.

    All movers start at t = 0 and move at unit speed; a robot whose disc would overlap another
    (centres closer than 2 - CONTACT_SLACK) stops at first contact and the contact is recorded
    (both robots if both were moving). An empty path means stay. `positions` is not modified.
    Movers end on the grid (fatswarm/domain/tolerance.py): `_snap_movers`.
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
    mo = build_motion(local, [(robot, transform(path, shift, False)) for robot, path in moves])
    if not len(mo.robots):
        return RoundOutcome(positions=start, traveled=traveled)
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
    collisions = _simulate(mo, pi, pj)
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
    world_paths = dict(moves)
    for row, robot in enumerate(mo.robots):
        done = mo.stop[row] >= mo.total[row]  # the whole path: its length as the world measures it
        here = (float(start[robot, 0]), float(start[robot, 1]))
        length = path_length(here, world_paths[int(robot)]) if done else float(mo.stop[row])
        traveled[int(robot)] = length
    return RoundOutcome(positions=final, traveled=traveled, collisions=collisions)
