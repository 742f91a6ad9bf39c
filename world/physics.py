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
from numpy.typing import NDArray

from fatswarm.domain.path import (
    MAX_SEGMENTS,
    Arc,
    Line,
    Path,
    PathFormatError,
    Points,
    path_length,
    segment_end,
    segment_length,
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

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

CONTACT_SLACK = OVERLAP_SLACK
"""Two discs overlap iff their centres are closer than 2 - CONTACT_SLACK
(fatswarm/domain/tolerance.py)."""
PLAN_ROUNDING = CLEAR_SLACK
"""The algorithm keeps every other centre at >= 2 - PLAN_ROUNDING (or, touching, never brings it
closer); such a path is never stopped: only overlap, below OVERLAP_DISTANCE, stops a robot."""
STOP_DISTANCE = 2.0
"""A robot stopped by contact ends at the last time before the overlap at which its centre was at
least this far from the robot it hit: touching, on the safe side (to ~1e-12)."""
TIME_RESOLUTION = 1e-12
"""Contact times are located to this precision (relative to max(1, t)), far below visible motion."""
MAX_LEVELS = 200
"""Subdivision depth cap: 200 halvings resolve TIME_RESOLUTION on paths up to 1e48 long; past it a
pair stops conservatively, as past MAX_WORK."""
MAX_WORK = 2_000_000
"""Cap on the time intervals examined per detection pass, so hostile paths cannot hang the world.
Past it, every pair not yet proven safe stops where the proof stopped: no overlap, but possibly a
contact reported early. Only long near-contact sliding of two curved movers gets there."""
ADVANCE_TARGET = OVERLAP_DISTANCE + 1e-10
"""Conservative advancement moves a pair's proven-safe time only up to where the distance could have
fallen to this, so rounding (~1e-13 at coordinates ~1e3) never lands it inside an overlap."""
BOX_MARGIN = 1e-6
"""Slack on bounding-box culling (boxes are exact up to ~1e-13)."""
BISECTION_STEPS = 200
"""Cap on back-off and bisection steps locating a contact (each doubles or halves a bracket)."""


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
# Motion table: every mover's path as padded per-segment rows, evaluated in bulk

# Columns of the segment table. Times are arc lengths from the robot's start (unit speed).
_T0, _T1, _LEN, _ARC, _SX, _SY, _EX, _EY, _CX, _CY, _SWEEP, _RATE, _CURV = range(13)


@dataclass(frozen=True, slots=True)
class _Motion:
    """The round's motion: rows are movers (paths of positive length), columns are segments.

    `seg[row, k]` holds segment k's start/end times, length, kind, end points, arc centre, sweep,
    turning rate (sweep / length) and curvature (1 / radius); padding has start/end time +inf.
    `stop` is the only mutable part: when each row stops (its length, or a contact time).
    """

    start: Points  # (n, 2) every robot at t = 0
    row_of: IntArray  # (n,) row of each robot, -1 for robots that do not move
    robots: IntArray  # (m,) robot of each row
    nseg: IntArray  # (m,)
    seg: FloatArray  # (m, S, 13)
    t1: FloatArray  # (m, S) segment end times (a contiguous copy for the segment search)
    total: FloatArray  # (m,) path length
    end: Points  # (m, 2) the path's exact end vertex
    box: FloatArray  # (m, 4) xmin, ymin, xmax, ymax of the whole path
    stop: FloatArray  # (m,) time the row stops moving (mutated by contacts)


def _arc_box(start: tuple[float, float], arc: Arc, radius: float) -> list[float]:
    """Exact bounding box of an arc: its ends plus every axis extreme it sweeps over."""
    cx, cy = arc.center
    if abs(arc.sweep) >= 2.0 * math.pi:
        return [cx - radius, cy - radius, cx + radius, cy + radius]
    end = segment_end(start, arc)
    xs, ys = [start[0], end[0]], [start[1], end[1]]
    a0 = math.atan2(start[1] - cy, start[0] - cx)
    for k in range(4):
        ang = k * math.pi / 2.0
        delta = ((ang - a0) * math.copysign(1.0, arc.sweep)) % (2.0 * math.pi)
        if delta <= abs(arc.sweep):
            xs.append(cx + radius * math.cos(ang))
            ys.append(cy + radius * math.sin(ang))
    return [min(xs), min(ys), max(xs), max(ys)]


def _build_motion(start: Points, moves: list[tuple[int, Path]]) -> _Motion:
    """Tabulate the movers' paths; lengths are summed exactly as agent.path.path_length does."""
    rows: list[tuple[int, list[list[float]], float, tuple[float, float], list[float]]] = []
    for robot, path in moves:
        here = (float(start[robot, 0]), float(start[robot, 1]))
        t = 0.0
        segs: list[list[float]] = []
        xs, ys = [here[0]], [here[1]]
        for seg in path.segments:
            length = segment_length(here, seg)
            end = segment_end(here, seg)
            row = [t, t + length, length, 0.0, *here, end[0], end[1], 0.0, 0.0, 0.0, 0.0, 0.0]
            if isinstance(seg, Line):
                xs.append(end[0])
                ys.append(end[1])
            else:
                radius = math.hypot(here[0] - seg.center[0], here[1] - seg.center[1])
                row[_ARC], row[_CX], row[_CY], row[_SWEEP] = 1.0, *seg.center, seg.sweep
                if length > 0.0:
                    row[_RATE], row[_CURV] = seg.sweep / length, 1.0 / radius
                box = _arc_box(here, seg, radius)
                xs += box[0::2]
                ys += box[1::2]
            segs.append(row)
            t += length
            here = (float(end[0]), float(end[1]))
        box = [min(xs), min(ys), max(xs), max(ys)]
        if not (math.isfinite(t) and all(map(math.isfinite, box))):
            raise PathFormatError(f"robot {robot}: the path is too long to simulate (length {t})")
        if t > 0.0:
            rows.append((robot, segs, t, here, box))
    m = len(rows)
    width = max((len(r[1]) for r in rows), default=1)
    table = np.zeros((m, width, 13), dtype=np.float64)
    table[:, :, _T0 : _T1 + 1] = np.inf
    for i, (_, segs, _, _, _) in enumerate(rows):
        table[i, : len(segs)] = segs
    row_of = np.full(len(start), -1, dtype=np.intp)
    robots = np.array([r[0] for r in rows], dtype=np.intp)
    row_of[robots] = np.arange(m, dtype=np.intp)
    total = np.array([r[2] for r in rows], dtype=np.float64)
    return _Motion(
        start=start,
        row_of=row_of,
        robots=robots,
        nseg=np.array([len(r[1]) for r in rows], dtype=np.intp),
        seg=table,
        t1=np.ascontiguousarray(table[:, :, _T1]),
        total=total,
        end=np.array([r[3] for r in rows], dtype=np.float64).reshape(m, 2),
        box=np.array([r[4] for r in rows], dtype=np.float64).reshape(m, 4),
        stop=total.copy(),
    )


def _segments_at(mo: _Motion, rows: IntArray, t: FloatArray) -> FloatArray:
    """The segment each row is on at time t (the next one exactly at a joint): (q, 13)."""
    k = np.minimum((mo.t1[rows] <= t[:, None]).sum(axis=1), mo.nseg[rows] - 1)
    segs: FloatArray = mo.seg[rows, k]
    return segs


def _path_points(mo: _Motion, rows: IntArray, t: FloatArray) -> Points:
    """Where each row is at time t along its path, ignoring stops: (q, 2).

    Same arithmetic as agent.path.point_at: a fraction of the segment, rotated about the centre.
    """
    g = _segments_at(mo, rows, t)
    length = g[:, _LEN]
    f = np.minimum(np.maximum(t - g[:, _T0], 0.0), length) / np.where(length > 0.0, length, 1.0)
    sx, sy = g[:, _SX], g[:, _SY]
    x = sx + f * (g[:, _EX] - sx)
    y = sy + f * (g[:, _EY] - sy)
    arc = g[:, _ARC] > 0.5
    if arc.any():
        phi = g[arc, _SWEEP] * f[arc]
        c, s = np.cos(phi), np.sin(phi)
        cx, cy = g[arc, _CX], g[arc, _CY]
        dx, dy = sx[arc] - cx, sy[arc] - cy
        x[arc] = cx + c * dx - s * dy
        y[arc] = cy + s * dx + c * dy
    done = t >= mo.total[rows]
    if done.any():
        x[done] = mo.end[rows[done], 0]
        y[done] = mo.end[rows[done], 1]
    return np.stack([x, y], axis=1)


def _positions(mo: _Motion, robots: IntArray, t: FloatArray) -> Points:
    """Where each robot is at time t, stops included: (q, 2)."""
    out = mo.start[robots]
    rows = mo.row_of[robots]
    mv = rows >= 0
    if mv.any():
        r = rows[mv]
        out[mv] = _path_points(mo, r, np.minimum(t[mv], mo.stop[r]))
    return out


def _distances(mo: _Motion, pi: IntArray, pj: IntArray, t: FloatArray) -> FloatArray:
    p = _positions(mo, np.concatenate([pi, pj]), np.concatenate([t, t]))
    d = p[: len(pi)] - p[len(pi) :]
    return np.hypot(d[:, 0], d[:, 1])


def _kinematics(mo: _Motion, robots: IntArray, tm: FloatArray) -> tuple[BoolArray, FloatArray]:
    """What each robot does at time tm (constant over an interval): moving?, its segment row.

    The segment row is zeros (a line of no curvature) for robots at rest.
    """
    moving = np.zeros(len(robots), dtype=np.bool_)
    segs = np.zeros((len(robots), 13))
    rows = mo.row_of[robots]
    mv = (rows >= 0).nonzero()[0]
    if mv.size:
        r, t = rows[mv], tm[mv]
        now = t < mo.stop[r]
        moving[mv] = now
        segs[mv[now]] = _segments_at(mo, r[now], t[now])
    return moving, segs


# --------------------------------------------------------------------------------------------------
# Continuous collision detection


def _bounds(
    mo: _Motion, pi: IntArray, pj: IntArray, t0: FloatArray, t1: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per interval: a lower bound of the pair's centre distance, the distances at both ends, and
    how far past t0 the pair is proven not to come within ADVANCE_TARGET (conservative advance).

    Each interval lies within one segment (or rest) of each robot. The bound is exact when the
    relative motion is straight (line or rest against line or rest) and for an arc against a
    robot at rest, exact up to the turning-rate drift for two arcs, and otherwise the best of a
    Lipschitz bound (each robot moves at unit speed) and the chord of the relative motion minus
    its deviation (relative acceleration <= 1/r_i + 1/r_j).
    """
    q = len(pi)
    p = _positions(mo, np.concatenate([pi, pi, pj, pj]), np.concatenate([t0, t1, t0, t1]))
    a0, a1, b0 = p[:q], p[q : 2 * q], p[2 * q : 3 * q]
    r0, r1 = a0 - b0, a1 - p[3 * q :]
    d0, d1 = np.hypot(r0[:, 0], r0[:, 1]), np.hypot(r1[:, 0], r1[:, 1])
    h = t1 - t0
    tm = t0 + 0.5 * h
    moving, g = _kinematics(mo, np.concatenate([pi, pj]), np.concatenate([tm, tm]))
    mi, mj, gi, gj = moving[:q], moving[q:], g[:q], g[q:]
    v = r1 - r0
    vv = (v * v).sum(axis=1)
    tau = np.minimum(np.maximum(-(r0 * v).sum(axis=1) / np.where(vv > 0.0, vv, 1.0), 0.0), 1.0)
    near = r0 + tau[:, None] * v
    chord = np.hypot(near[:, 0], near[:, 1])
    curv = gi[:, _CURV] + gj[:, _CURV]
    speed = mi.astype(np.float64) + mj
    lb = np.maximum(chord - curv * h * h / 8.0, 0.5 * (d0 + d1) - 0.5 * h * speed)
    # Straight relative motion: constant relative velocity, so the speed bound is exact too.
    straight = curv == 0.0
    rate = np.where(straight, np.sqrt(vv) / np.where(h > 0.0, h, 1.0), speed)
    # An arc against a robot at rest: the exact distance from a point to an arc of a circle.
    for arc_g, moves_k, still_m, mover0, other0 in ((gi, mi, mj, a0, b0), (gj, mj, mi, b0, a0)):
        sel = (moves_k & (arc_g[:, _ARC] > 0.5) & ~still_m).nonzero()[0]
        if not sel.size:
            continue
        cx, cy = arc_g[sel, _CX], arc_g[sel, _CY]
        px, py = mover0[sel, 0] - cx, mover0[sel, 1] - cy
        qx, qy = other0[sel, 0] - cx, other0[sel, 1] - cy
        sigma = arc_g[sel, _RATE] * h[sel]
        delta = ((np.arctan2(qy, qx) - np.arctan2(py, px)) * np.sign(sigma)) % (2.0 * np.pi)
        inside = (np.abs(sigma) >= 2.0 * np.pi) | (delta <= np.abs(sigma))
        gap = np.abs(np.hypot(px, py) - np.hypot(qx, qy))
        lb[sel] = np.where(inside, gap, np.minimum(d0[sel], d1[sel]))
    step = np.full(q, np.inf)
    np.divide(d0 - ADVANCE_TARGET, rate, out=step, where=rate > 0.0)
    # Two arcs: p_i - p_j = (c_i - c_j) + R(w_i s) (w0 - drift), where w0 = a - b is the
    # difference of the arms and the drift grows at |w_i - w_j| |b|. Without drift that is a point
    # on a circle about a fixed point: an exact distance, sharp for robots sliding together on one
    # circle or turning side by side (where the generic bounds would subdivide for long).
    sel = ((gi[:, _ARC] > 0.5) & (gj[:, _ARC] > 0.5)).nonzero()[0]
    if sel.size:
        rate_i = gi[sel, _RATE]
        drift = np.abs(rate_i - gj[sel, _RATE]) / gj[sel, _CURV]  # |w_i - w_j| |b|
        dx, dy = gj[sel, _CX] - gi[sel, _CX], gj[sel, _CY] - gi[sel, _CY]  # -(c_i - c_j)
        wx, wy = r0[sel, 0] + dx, r0[sel, 1] + dy
        sigma = rate_i * h[sel]
        c, sn = np.cos(sigma), np.sin(sigma)
        end = np.hypot(c * wx - sn * wy - dx, sn * wx + c * wy - dy)
        delta = ((np.arctan2(dy, dx) - np.arctan2(wy, wx)) * np.sign(sigma)) % (2.0 * np.pi)
        inside = (np.abs(sigma) >= 2.0 * np.pi) | (delta <= np.abs(sigma))
        arm = np.hypot(wx, wy)
        exact = np.where(inside, np.abs(arm - np.hypot(dx, dy)), np.minimum(d0[sel], end))
        lb[sel] = np.maximum(lb[sel], exact - drift * h[sel])
        rel_speed = np.abs(rate_i) * (arm + drift * h[sel]) + drift
        ahead = np.full(sel.size, np.inf)
        np.divide(d0[sel] - ADVANCE_TARGET, rel_speed, out=ahead, where=rel_speed > 0.0)
        step[sel] = np.maximum(step[sel], ahead)
    return np.minimum(lb, np.minimum(d0, d1)), d0, d1, step


def _initial_intervals(
    mo: _Motion, pi: IntArray, pj: IntArray, t_w: float, t_end: FloatArray
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Split each pair's window [t_w, t_end] at every segment joint and stop of either robot."""
    width = mo.seg.shape[1] + 1
    joints = np.full((len(mo.start), width), -np.inf)
    joints[mo.robots] = np.concatenate([mo.seg[:, :, _T0], mo.stop[:, None]], axis=1)
    cuts = np.concatenate(
        [joints[pi], joints[pj], np.full((len(pi), 1), t_w), t_end[:, None]], axis=1
    )
    cuts = np.minimum(np.maximum(cuts, t_w), t_end[:, None])
    cuts.sort(axis=1)
    lo, hi = cuts[:, :-1], cuts[:, 1:]
    ok = hi > lo
    ip = np.nonzero(ok)[0].astype(np.intp)
    return ip, lo[ok], hi[ok]


def _first_unprovable(mo: _Motion, pi: IntArray, pj: IntArray, t_w: float) -> FloatArray:
    """Per pair, the earliest time >= t_w up to which no overlap is proven, or inf if none.

    Adaptive subdivision of all intervals of all pairs at once: an interval whose lower bound is
    >= OVERLAP_DISTANCE is safe; otherwise its start is advanced by the distance it provably cannot
    lose (conservative advancement) and the rest is halved, until the overlap is within
    TIME_RESOLUTION. Intervals after a sampled overlap or after a found contact are dropped.
    """
    size = len(pi)
    t_hit = np.full(size, np.inf)
    rows = mo.row_of[np.concatenate([pi, pj])]
    ends = np.where(rows >= 0, mo.stop[np.maximum(rows, 0)], -np.inf)
    t_end = np.maximum(ends[:size], ends[size:])
    sel = (t_end > t_w).nonzero()[0]
    ip, t0, t1 = _initial_intervals(mo, pi[sel], pj[sel], t_w, t_end[sel])
    ip = sel[ip]
    first_bad = np.full(size, np.inf)
    work = 0
    for _ in range(MAX_LEVELS):
        work += ip.size
        if not ip.size or work > MAX_WORK:
            break
        lb, d0, d1, safe_step = _bounds(mo, pi[ip], pj[ip], t0, t1)
        over0, over1 = d0 < OVERLAP_DISTANCE, d1 < OVERLAP_DISTANCE
        np.minimum.at(first_bad, ip, np.where(over0, t0, np.where(over1, t1, np.inf)))
        at_start = over0 & (t0 <= t_w)  # overlapping already at the window start
        if at_start.any():
            t_hit[ip[at_start]] = t_w
        h = t1 - t0
        keep = (lb < OVERLAP_DISTANCE) & (safe_step < h)
        keep &= (t0 < first_bad[ip]) & (t0 < t_hit[ip])
        res = TIME_RESOLUTION * np.maximum(1.0, np.abs(t1))
        term = keep & ((h <= res) | (safe_step <= res))
        if term.any():
            np.minimum.at(t_hit, ip[term], t0[term])
        split = keep & ~term
        split[split] &= t0[split] < t_hit[ip[split]]
        ip, t0, t1 = ip[split], t0[split] + safe_step[split], t1[split]
        mid = t0 + 0.5 * (t1 - t0)
        ip = np.concatenate([ip, ip])
        t0, t1 = np.concatenate([t0, mid]), np.concatenate([mid, t1])
    if ip.size:  # out of budget: stop where the proof stopped (safe, maybe early)
        np.minimum.at(t_hit, ip, t0)
    # An overlap that was sampled but never bracketed (an advance stepped over the contact) is a
    # contact all the same: stop before it rather than let the discs pass through each other.
    missed = np.isinf(t_hit) & np.isfinite(first_bad)
    t_hit[missed] = first_bad[missed]
    return t_hit


def _contact_times(
    mo: _Motion, pi: IntArray, pj: IntArray, t_w: float, t_hit: FloatArray
) -> FloatArray:
    """Per pair, the last time <= t_hit at which the centres were >= STOP_DISTANCE apart.

    Everything up to t_hit is proven overlap-free, so any such time is a safe place to stop.
    Backs off from t_hit doubling the step, then bisects; t_w if the pair never was that far.
    """
    lo = t_hit.copy()
    hi = t_hit.copy()
    d_hit = _distances(mo, pi, pj, t_hit)
    todo = d_hit < STOP_DISTANCE
    # Distance changes at speed <= 2: going back less than (STOP - d) / 2 cannot reach STOP.
    step = np.maximum((STOP_DISTANCE - d_hit) / 2.0, TIME_RESOLUTION * np.maximum(1.0, t_hit))
    searching = todo.copy()
    for _ in range(BISECTION_STEPS):
        if not searching.any():
            break
        s = searching.nonzero()[0]
        cand = np.maximum(t_hit[s] - step[s], t_w)
        ok = _distances(mo, pi[s], pj[s], cand) >= STOP_DISTANCE
        floor = ~ok & (cand <= t_w)
        lo[s] = np.where(ok, cand, t_w)
        hi[s[~ok]] = cand[~ok]
        searching[s[ok | floor]] = False
        todo[s[floor]] = False  # never STOP_DISTANCE apart since t_w: stop at t_w
        step[s] *= 2.0
    if searching.any():  # unreachable for finite times; stay on the proven side
        lo[searching] = t_w
        todo[searching] = False
    for _ in range(BISECTION_STEPS):
        s = todo.nonzero()[0]
        s = s[(hi[s] - lo[s]) > TIME_RESOLUTION * np.maximum(1.0, np.abs(hi[s]))]
        if not s.size:
            break
        mid = lo[s] + 0.5 * (hi[s] - lo[s])
        ok = _distances(mo, pi[s], pj[s], mid) >= STOP_DISTANCE
        lo[s[ok]] = mid[ok]
        hi[s[~ok]] = mid[~ok]
    return lo


def _contacts(mo: _Motion, pi: IntArray, pj: IntArray, t_w: float) -> FloatArray:
    """Per pair, when it first comes into contact in a way that would overlap (inf: never)."""
    t_hit = _first_unprovable(mo, pi, pj, t_w)
    out = np.full(len(pi), np.inf)
    hit = np.isfinite(t_hit).nonzero()[0]
    if hit.size:
        out[hit] = _contact_times(mo, pi[hit], pj[hit], t_w, t_hit[hit])
    return out


def _candidate_pairs(mo: _Motion, first: IntArray, second: IntArray) -> tuple[IntArray, IntArray]:
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


def _simulate(mo: _Motion, pi: IntArray, pj: IntArray) -> list[Collision]:
    """The round as an event loop: the earliest contact stops its movers, the rest go on.

    `pi`, `pj`: every pair that could meet this round (see _candidate_pairs).
    """
    collisions: list[Collision] = []
    t_c = _contacts(mo, pi, pj, 0.0)
    while t_c.size and np.isfinite(t_c).any():
        k = int(np.argmin(t_c))
        t, a, b = float(t_c[k]), int(pi[k]), int(pj[k])
        stopped: list[int] = []
        for x, y in ((a, b), (b, a)):
            row = int(mo.row_of[x])
            if row >= 0 and t < mo.stop[row]:
                mo.stop[row] = t
                p = _positions(mo, np.array([x], dtype=np.intp), np.array([t]))[0]
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
            t_c = np.concatenate([t_c, _contacts(mo, ni, nj, t)])
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
    mo = _build_motion(local, [(robot, transform(path, shift, False)) for robot, path in moves])
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
    final[mo.robots] = _positions(mo, mo.robots, mo.stop) + np.array(origin)
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
