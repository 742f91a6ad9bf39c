"""The motion of one round for world/physics.py: every mover's path tabulated per segment and
evaluated in bulk, and the continuous collision detection over it (when each pair of discs would
first overlap, and the last safe time before it)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.path import (
    Arc,
    Line,
    Path,
    PathFormatError,
    Point,
    Points,
    segment_end,
    segment_length,
)
from fatswarm.domain.tolerance import OVERLAP_DISTANCE

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

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
BISECTION_STEPS = 200
"""Cap on back-off and bisection steps locating a contact (each doubles or halves a bracket)."""


# --------------------------------------------------------------------------------------------------
# Motion table: every mover's path as padded per-segment rows, evaluated in bulk

# Columns of the segment table. Times are arc lengths from the robot's start (unit speed).
_T0, _T1, _LEN, _ARC, _SX, _SY, _EX, _EY, _CX, _CY, _SWEEP, _RATE, _CURV = range(13)


@dataclass(frozen=True, slots=True)
class Motion:
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


_NO_ARC = (0.0, 0.0, 0.0, 0.0, 0.0)  # a line's arc columns: centre, sweep, rate, curvature


def _arc_row(
    here: tuple[float, float], seg: Arc, t: float, xs: list[float], ys: list[float]
) -> tuple[list[float], tuple[float, float]]:
    """An arc's row of the segment table from `here` at time `t`, and its end; its bounding box
    joins `xs`, `ys`."""
    length = segment_length(here, seg)
    end = segment_end(here, seg)
    row = [t, t + length, length, 0.0, *here, end[0], end[1], 0.0, 0.0, 0.0, 0.0, 0.0]
    radius = math.hypot(here[0] - seg.center[0], here[1] - seg.center[1])
    row[_ARC], row[_CX], row[_CY], row[_SWEEP] = 1.0, *seg.center, seg.sweep
    if length > 0.0:
        row[_RATE], row[_CURV] = seg.sweep / length, 1.0 / radius
    box = _arc_box(here, seg, radius)
    xs += box[0::2]
    ys += box[1::2]
    return row, end


def build_motion(
    start: Points, moves: list[tuple[int, Path]], shift: tuple[float, float] | None = None
) -> Motion:
    """Tabulate the movers' paths, each first translated by `shift` if given (exactly as
    `transform(path, shift, False)` would); lengths are summed exactly as path_length does."""
    lines = _single_lines(start, moves, shift)
    return _tabulated(start, moves, shift) if lines is None else lines


def _tabulated(
    start: Points, moves: list[tuple[int, Path]], shift: tuple[float, float] | None
) -> Motion:
    """`build_motion` for any paths, a segment at a time."""
    rows: list[tuple[int, list[list[float]], float, tuple[float, float], list[float]]] = []
    at = start[[robot for robot, _ in moves]].tolist()  # Python floats: the same values
    ox, oy = (0.0, 0.0) if shift is None else shift
    shifted = shift is not None
    for (robot, path), (hx, hy) in zip(moves, at, strict=True):
        here = (hx, hy)
        t = 0.0
        segs: list[list[float]] = []
        xs, ys = [hx], [hy]
        for seg in path.segments:
            if isinstance(seg, Line):  # the common case inline: segment_length's arithmetic
                ex, ey = seg.end[0], seg.end[1]
                if shifted:  # 1.0 * x is x: the floats `transform` gives
                    ex, ey = ex + ox, ey + oy
                length = math.hypot(ex - here[0], ey - here[1])
                segs.append([t, t + length, length, 0.0, *here, ex, ey, *_NO_ARC])
                xs.append(ex)
                ys.append(ey)
                t += length
                here = (float(ex), float(ey))
                continue
            if shifted:
                seg = Arc((seg.center[0] + ox, seg.center[1] + oy), 1.0 * seg.sweep)
            row, end = _arc_row(here, seg, t, xs, ys)
            segs.append(row)
            t += row[_LEN]
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
    counts = [len(r[1]) for r in rows]
    if sum(counts):  # every segment row at once: one conversion, the same floats
        at = np.repeat(np.arange(m, dtype=np.intp), counts)
        col = np.arange(len(at), dtype=np.intp) - np.repeat(np.cumsum(counts) - counts, counts)
        table[at, col] = [seg for r in rows for seg in r[1]]
    return _motion(
        start,
        np.array([r[0] for r in rows], dtype=np.intp),
        np.array(counts, dtype=np.intp),
        table,
        np.array([r[2] for r in rows], dtype=np.float64),
        np.array([r[3] for r in rows], dtype=np.float64).reshape(m, 2),
        np.array([r[4] for r in rows], dtype=np.float64).reshape(m, 4),
    )


def _motion(
    start: Points,
    robots: IntArray,
    nseg: IntArray,
    table: FloatArray,
    total: FloatArray,
    end: Points,
    box: FloatArray,
) -> Motion:
    """The Motion of these rows (robot, segment count, segment table, length, end, box)."""
    row_of = np.full(len(start), -1, dtype=np.intp)
    row_of[robots] = np.arange(len(robots), dtype=np.intp)
    t1 = np.ascontiguousarray(table[:, :, _T1])
    return Motion(start, row_of, robots, nseg, table, t1, total, end, box, total.copy())


def _single_lines(
    start: Points, moves: list[tuple[int, Path]], shift: tuple[float, float] | None
) -> Motion | None:
    """`build_motion` when every path is one Line to a point of two floats (every move of most
    algorithms), as arrays: the same floats (lengths by math.hypot, boxes as min and max of a
    list pick them); None for any other round."""
    ends: list[Point] = []
    for _, path in moves:
        if len(path.segments) != 1 or type(seg := path.segments[0]) is not Line:
            return None
        end = seg.end
        if type(end) is not tuple or type(end[0]) is not float or type(end[1]) is not float:
            return None
        ends.append(end)
    every = np.array([robot for robot, _ in moves], dtype=np.intp)
    here = start[every]
    e = np.array(ends, dtype=np.float64).reshape(len(ends), 2)
    if shift is not None:
        e += shift
    d = (e - here).tolist()
    length = np.array([math.hypot(dx, dy) for dx, dy in d], dtype=np.float64)
    lo = np.where(e < here, e, here)  # min([here, end]): the end only if strictly less
    hi = np.where(e > here, e, here)
    bad = ~(np.isfinite(length) & np.isfinite(lo).all(axis=1) & np.isfinite(hi).all(axis=1))
    if bad.any():
        k = int(bad.argmax())
        raise PathFormatError(
            f"robot {moves[k][0]}: the path is too long to simulate (length {float(length[k])})"
        )
    keep = length > 0.0
    box = np.concatenate((lo[keep], hi[keep]), axis=1)
    return line_motion(start, every[keep], here[keep], e[keep], length[keep], box)


def line_motion(
    start: Points, robots: IntArray, here: Points, end: Points, total: FloatArray, box: FloatArray
) -> Motion:
    """The Motion of rows that each follow one Line of positive length: robot, start point, end
    point, length and bounding box per row (every array of the same m rows)."""
    m = len(robots)
    table = np.zeros((m, 1, 13), dtype=np.float64)
    table[:, 0, _T1] = total
    table[:, 0, _LEN] = total
    table[:, 0, _SX : _SY + 1] = here
    table[:, 0, _EX : _EY + 1] = end
    return _motion(start, robots, np.ones(m, dtype=np.intp), table, total, end, box)


def _segments_at(mo: Motion, rows: IntArray, t: FloatArray) -> FloatArray:
    """The segment each row is on at time t (the next one exactly at a joint): (q, 13)."""
    k = np.minimum((mo.t1[rows] <= t[:, None]).sum(axis=1), mo.nseg[rows] - 1)
    segs: FloatArray = mo.seg[rows, k]
    return segs


def _path_points(mo: Motion, rows: IntArray, t: FloatArray) -> Points:
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


def positions_at(mo: Motion, robots: IntArray, t: FloatArray) -> Points:
    """Where each robot is at time t, stops included: (q, 2)."""
    out = mo.start[robots]
    rows = mo.row_of[robots]
    mv = rows >= 0
    if mv.any():
        r = rows[mv]
        out[mv] = _path_points(mo, r, np.minimum(t[mv], mo.stop[r]))
    return out


def _distances(mo: Motion, pi: IntArray, pj: IntArray, t: FloatArray) -> FloatArray:
    p = positions_at(mo, np.concatenate([pi, pj]), np.concatenate([t, t]))
    d = p[: len(pi)] - p[len(pi) :]
    return np.hypot(d[:, 0], d[:, 1])


def _kinematics(mo: Motion, robots: IntArray, tm: FloatArray) -> tuple[BoolArray, FloatArray]:
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
    mo: Motion, pi: IntArray, pj: IntArray, t0: FloatArray, t1: FloatArray
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
    p = positions_at(mo, np.concatenate([pi, pi, pj, pj]), np.concatenate([t0, t1, t0, t1]))
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
        if sel.size:
            lb[sel] = _arc_to_point(arc_g[sel], mover0[sel], other0[sel], h[sel], d0[sel], d1[sel])
    step = np.full(q, np.inf)
    np.divide(d0 - ADVANCE_TARGET, rate, out=step, where=rate > 0.0)
    # Two arcs: p_i - p_j = (c_i - c_j) + R(w_i s) (w0 - drift), where w0 = a - b is the
    # difference of the arms and the drift grows at |w_i - w_j| |b|. Without drift that is a point
    # on a circle about a fixed point: an exact distance, sharp for robots sliding together on one
    # circle or turning side by side (where the generic bounds would subdivide for long).
    sel = ((gi[:, _ARC] > 0.5) & (gj[:, _ARC] > 0.5)).nonzero()[0]
    if sel.size:
        bound, ahead = _two_arcs(gi[sel], gj[sel], r0[sel], h[sel], d0[sel])
        lb[sel] = np.maximum(lb[sel], bound)
        step[sel] = np.maximum(step[sel], ahead)
    return np.minimum(lb, np.minimum(d0, d1)), d0, d1, step


def _arc_to_point(
    g: FloatArray, mover0: Points, other0: Points, h: FloatArray, d0: FloatArray, d1: FloatArray
) -> FloatArray:
    """_bounds for a robot on an arc (segment rows `g`, from `mover0`) against one at rest at
    `other0`, over intervals of length `h`: the exact distance from the point to the arc."""
    cx, cy = g[:, _CX], g[:, _CY]
    px, py = mover0[:, 0] - cx, mover0[:, 1] - cy
    qx, qy = other0[:, 0] - cx, other0[:, 1] - cy
    sigma = g[:, _RATE] * h
    delta = ((np.arctan2(qy, qx) - np.arctan2(py, px)) * np.sign(sigma)) % (2.0 * np.pi)
    inside = (np.abs(sigma) >= 2.0 * np.pi) | (delta <= np.abs(sigma))
    gap = np.abs(np.hypot(px, py) - np.hypot(qx, qy))
    bound: FloatArray = np.where(inside, gap, np.minimum(d0, d1))
    return bound


def _two_arcs(
    gi: FloatArray, gj: FloatArray, r0: Points, h: FloatArray, d0: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """_bounds for two robots on arcs (segment rows `gi`, `gj`; `r0` = p_i - p_j at the start of
    intervals of length `h`): the lower bound of their distance (exact up to the drift) and how
    far it is proven not to fall to ADVANCE_TARGET."""
    rate_i = gi[:, _RATE]
    drift = np.abs(rate_i - gj[:, _RATE]) / gj[:, _CURV]  # |w_i - w_j| |b|
    dx, dy = gj[:, _CX] - gi[:, _CX], gj[:, _CY] - gi[:, _CY]  # -(c_i - c_j)
    wx, wy = r0[:, 0] + dx, r0[:, 1] + dy
    sigma = rate_i * h
    c, sn = np.cos(sigma), np.sin(sigma)
    end = np.hypot(c * wx - sn * wy - dx, sn * wx + c * wy - dy)
    delta = ((np.arctan2(dy, dx) - np.arctan2(wy, wx)) * np.sign(sigma)) % (2.0 * np.pi)
    inside = (np.abs(sigma) >= 2.0 * np.pi) | (delta <= np.abs(sigma))
    arm = np.hypot(wx, wy)
    exact = np.where(inside, np.abs(arm - np.hypot(dx, dy)), np.minimum(d0, end))
    rel_speed = np.abs(rate_i) * (arm + drift * h) + drift
    ahead = np.full(len(h), np.inf)
    np.divide(d0 - ADVANCE_TARGET, rel_speed, out=ahead, where=rel_speed > 0.0)
    return exact - drift * h, ahead


def _initial_intervals(
    mo: Motion, pi: IntArray, pj: IntArray, t_w: float, t_end: FloatArray
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


def _first_unprovable(mo: Motion, pi: IntArray, pj: IntArray, t_w: float) -> FloatArray:
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
    mo: Motion, pi: IntArray, pj: IntArray, t_w: float, t_hit: FloatArray
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


def first_contacts(mo: Motion, pi: IntArray, pj: IntArray, t_w: float) -> FloatArray:
    """Per pair, when it first comes into contact in a way that would overlap (inf: never)."""
    t_hit = _first_unprovable(mo, pi, pj, t_w)
    out = np.full(len(pi), np.inf)
    hit = np.isfinite(t_hit).nonzero()[0]
    if hit.size:
        out[hit] = _contact_times(mo, pi[hit], pj[hit], t_w, t_hit[hit])
    return out
