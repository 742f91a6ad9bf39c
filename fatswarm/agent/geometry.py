"""Plane geometry the paper uses: smallest enclosing circle, free paths, symmetry about L, targets.

Everything works on centres of unit discs, as `(n, 2)` float64 arrays, in whatever frame the caller
uses: every function here is equivariant under translation and under the mirror x -> -x.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fatswarm.agent.canonical import canonical
from fatswarm.domain.path import Arc, Line, Path, Point, Points, segment_end
from fatswarm.domain.tolerance import (
    CLEAR_SLACK,
    CONTACT,
    EPS_AT_REL,
    ROUND_ABS,
    SEC_SLACK_REL,
    scale,
    snap,
)

# The tolerance model lives in fatswarm/domain/tolerance.py (one definition for the world and the
# robots).


@dataclass(frozen=True, slots=True)
class Circle:
    """A circle by centre and radius."""

    center: Point
    radius: float


# --- smallest enclosing circle -----------------------------------------------------------------


FAR_FROM_ORIGIN = 64.0
"""`sec` works about the points' box centre when they lie farther than this many spans away."""


Disc = tuple[float, float, float]
"""A circle as (centre x, centre y, radius): `sec`'s working form, cheaper than a `Circle`."""


def _sec_through(support: list[Point], p: Point) -> tuple[Disc, list[Point]]:
    """Smallest circle enclosing `support` (at most 3 points) and p, where p lies outside the
    smallest circle of `support`: p is then on its boundary (Welzl's lemma), so only circles
    through p are tried: the diametral circles of p and each support point, then the circumcircles
    of p and each support pair. Returns the circle and the points that pin it.

    The circle routines and the enclosure test (every point within r (1 + SEC_SLACK_REL) of the
    centre) are written out here, on Python floats: this runs a few times per `sec`, and calls
    cost more than the arithmetic.
    """
    px, py = p
    hypot = math.hypot
    best_r = 0.0  # best's radius (read only once best is set)
    best: Disc | None = None
    pinned: list[Point] = []
    for q in support:
        cx, cy = (px + q[0]) / 2.0, (py + q[1]) / 2.0
        r = hypot(px - cx, py - cy)
        # p's own distance from the centre is r, bit for bit: only the support needs checking.
        if best is None or r < best_r:
            lim = r * (1.0 + SEC_SLACK_REL) + 1e-300
            for x, y in support:
                if not hypot(x - cx, y - cy) <= lim:
                    break
            else:
                best_r, best, pinned = r, (cx, cy, r), [p, q]
    for i in range(len(support) - 1):
        q = support[i]
        bx, by = q[0] - px, q[1] - py
        for s in support[i + 1 :]:
            cx, cy = s[0] - px, s[1] - py
            d = 2.0 * (bx * cy - by * cx)
            # Collinear within rounding: the circumcircle is huge or undefined; the diametral
            # circle of the extreme pair then encloses the third point, so the triple is dropped.
            if abs(d) <= 1e-14 * (bx * bx + by * by + cx * cx + cy * cy):
                continue
            b2, c2 = bx * bx + by * by, cx * cx + cy * cy
            ux = (cy * b2 - by * c2) / d
            uy = (bx * c2 - cx * b2) / d
            r = hypot(ux, uy)
            if best is None or r < best_r:
                ox, oy = px + ux, py + uy
                lim = r * (1.0 + SEC_SLACK_REL) + 1e-300
                for x, y in support:
                    if not hypot(x - ox, y - oy) <= lim:
                        break
                else:
                    if hypot(px - ox, py - oy) <= lim:
                        best_r, best, pinned = r, (ox, oy, r), [p, q, s]
    if best is None:  # only rounding gets here: fall back to the farthest pair
        far = max(support, key=lambda q: math.hypot(q[0] - px, q[1] - py))
        cx, cy = (px + far[0]) / 2.0, (py + far[1]) / 2.0
        best, pinned = (cx, cy, math.hypot(px - cx, py - cy)), [p, far]
    return best, pinned


def _sq_distances(xs: np.ndarray, ys: np.ndarray, cx: float, cy: float) -> np.ndarray:
    """(xs - cx)**2 + (ys - cy)**2, in place on two fresh arrays."""
    if cx == 0.0 and cy == 0.0:  # a canonical form's first robot: x - (+-0.0) squares to x * x
        sq: np.ndarray = xs * xs
        sq += ys * ys
        return sq
    dx = xs - cx
    dx *= dx
    dy = ys - cy
    dy *= dy
    dx += dy
    return dx


def _overshoot(circle: Circle, xs: np.ndarray, ys: np.ndarray) -> float:
    """How far the farthest point lies outside `circle` (<= 0: none does)."""
    cx, cy = circle.center
    d = np.hypot(xs - cx, ys - cy)
    # the largest (or the first NaN), as np.max gives it (hypot gives no -0.0 to tell apart)
    return float(d[d.argmax()]) - circle.radius


def _far_from_origin(pts: np.ndarray, x0: float, y0: float, reach2: float) -> bool:
    """Whether the points lie farther from the origin than FAR_FROM_ORIGIN spans (see `sec`).

    `reach2` is the largest squared distance of a point from the first, (x0, y0). Every coordinate
    is within max(|x0|, |y0|) + reach of the origin and the span is at least reach / sqrt(2), so
    most calls are decided without a pass over the points (margins cover the rounding).
    """
    reach = math.sqrt(reach2)
    bound = (max(abs(x0), abs(y0)) + reach * (1.0 + 1e-9)) * (1.0 + 1e-9)
    if bound <= FAR_FROM_ORIGIN * max(1.0, reach / 1.5):
        return False
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return float(np.abs(pts).max()) > FAR_FROM_ORIGIN * max(1.0, float((hi - lo).max()))


def sec(points: Points) -> Circle:
    """Smallest enclosing circle of the centres `points` (n, 2), n >= 1.

    Iterative support-set method: keep the smallest circle of a support set of at most three
    points, add the point farthest outside it, and replace the circle by the smallest one enclosing
    the support plus that point. The radius grows strictly, supports are finite, and a circle that
    encloses all points and is the smallest of a subset of them is the smallest of all: so the loop
    ends on the exact SEC. Each step is one vectorised distance pass; a handful of steps is typical.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
        raise ValueError(f"sec needs an (n, 2) array with n >= 1, got shape {pts.shape}")
    xs, ys = pts[:, 0], pts[:, 1]
    x0, y0 = float(xs[0]), float(ys[0])
    if len(pts) == 1:
        return Circle((x0, y0), 0.0)
    # Seed with an approximate diameter: the point farthest from robot 0, then farthest from that.
    d2 = _sq_distances(xs, ys, x0, y0)
    i0 = int(d2.argmax())
    if _far_from_origin(pts, x0, y0, float(d2[i0])):
        # Far from the origin (a world frame at a large offset), the centre's rounding exceeds the
        # relative enclosure slack and the true SEC was refused: work about the box's centre, a
        # point no order or numbering of the points changes. A robot's own frame never gets here.
        mid = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
        c = sec(pts - mid)
        return Circle((c.center[0] + float(mid[0]), c.center[1] + float(mid[1])), c.radius)
    a = (float(xs[i0]), float(ys[i0]))
    i1 = int(_sq_distances(xs, ys, a[0], a[1]).argmax())
    b = (float(xs[i1]), float(ys[i1]))
    cx, cy = (a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0
    disc = (cx, cy, math.hypot(a[0] - cx, a[1] - cy))
    support: list[Point] = [a, b]
    for _ in range(4 * len(pts) + 16):
        cx, cy, r = disc
        d2 = _sq_distances(xs, ys, cx, cy)
        k = int(d2.argmax())
        lim = r * (1.0 + SEC_SLACK_REL) + 1e-300
        if float(d2[k]) <= lim * lim:
            return Circle((cx, cy), r)
        candidate, pinned = _sec_through(support, (float(xs[k]), float(ys[k])))
        if candidate[2] <= r:  # rounding stalled the growth: of two circles of one radius, the
            # one the points overshoot less (here 9e-9 on a radius of 5.5)
            two = (Circle((cx, cy), r), Circle((candidate[0], candidate[1]), candidate[2]))
            return min(two, key=lambda c: _overshoot(c, xs, ys))
        disc, support = candidate, pinned
    return Circle((disc[0], disc[1]), disc[2])


# --- the algorithm's quantities ----------------------------------------------------------------


def effective_side(a: float) -> float:
    """a* = max(a, 4): with sides >= 4 no robot blocks two targets (docs/algorithm.md, G1)."""
    return max(a, 4.0)


def target_radius(n: int, a: float) -> float:
    """ComputeRadius: circumradius of the regular n-gon of side a* (0 for a single robot)."""
    if n < 2:
        return 0.0
    return effective_side(a) / (2.0 * math.sin(math.pi / n))


def north_point(circle: Circle) -> Point:
    """o: the north-most intersection of L (the vertical through the SEC centre) and the SEC."""
    return (circle.center[0], circle.center[1] + circle.radius)


def targets_on(circle: Circle, n: int, robot_at_o: bool) -> Points:
    """ComputeTargetPoint: n equally spaced points on the circle, from o (case i) or o +- pi/n.

    Target k sits at angle theta_k from north. The set is mirror symmetric about L, so a mirrored
    frame yields the same set (in another order: callers must not rely on the order).
    """
    cx, cy = circle.center
    rad = circle.radius
    out = _unit_targets(n, robot_at_o) * rad
    out[:, 0] += cx
    out[:, 1] += cy
    return out


@functools.lru_cache(maxsize=64)
def _unit_targets(n: int, robot_at_o: bool) -> Points:
    """(sin theta_k, cos theta_k) of `targets_on`'s angles (n, 2), read-only: a function of n and
    the case alone, so it is made once per (n, case), not once per plan."""
    theta = np.arange(n, dtype=np.float64)
    theta *= 2.0 * math.pi
    theta /= n
    if not robot_at_o:  # (for case i, adding 0.0 to these non-negative angles changes nothing)
        theta += math.pi / n
    out = np.empty((n, 2))
    out[:, 0] = np.sin(theta)  # on the contiguous array, as before: the same loop, the same bits
    out[:, 1] = np.cos(theta)
    out.flags.writeable = False
    return out


def robot_at(points: Points, p: Point, tol: float) -> int | None:
    """Index of a robot within `tol` of point p, or None."""
    ys = points[:, 1]
    top = float(ys[ys.argmax()]) if len(ys) else math.nan
    # p clear above every robot (the north point o, usually): then no distance is within tol
    # (the margin covers the rounding of the height differences).
    if p[1] - top > tol + 1e-9 * (abs(p[1]) + abs(top) + tol):
        return None
    d = np.hypot(points[:, 0] - p[0], points[:, 1] - p[1])
    k = int(d.argmin())
    return k if d[k] <= tol else None


def target_points(points: Points, n: int | None = None) -> Points:
    """The n target points on the SEC of `points` (case i or ii decided by a robot at o)."""
    pts = np.asarray(points, dtype=np.float64)
    circle = sec(pts)
    tol = EPS_AT_REL * scale(circle.radius)
    at_o = robot_at(pts, north_point(circle), tol) is not None
    return targets_on(circle, len(pts) if n is None else n, at_o)


MATCH_WINDOW = 8
"""Above this many robots sharing one Y (within tolerance), mirror matching compares all pairs."""


def _sq_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(a - b)**2, in place on one fresh array."""
    d: np.ndarray = a - b
    d *= d
    return d


def mirror_matched(points: Points, axis_x: float, tol: float) -> np.ndarray:
    """Boolean (n,): robot i has a robot (itself, when on the axis) at its mirror image about x.

    Mirroring keeps Y, so only robots with the same Y (within `tol`) can match: sort by Y and
    compare each robot with the few neighbours in its Y window. O(n log n) unless many robots
    share a Y, where it falls back to all pairs.
    """
    n = len(points)
    ys, xs = points[:, 1], points[:, 0]
    order: np.ndarray | None = None
    found: np.ndarray
    if n > 1:
        gaps = ys[1:] - ys[:-1]
        # Sorted by Y (as a canonical form is) with every gap beyond tol (and a margin for the
        # rounding of y +- tol): each robot is alone in its window, so only itself can match.
        reach = tol + 1e-9 * (max(abs(float(ys[0])), abs(float(ys[-1]))) + tol)
        if tol >= 0.0 and np.count_nonzero(gaps > reach) == n - 1:
            return _sq_diff(xs, 2.0 * axis_x - xs) <= tol * tol
        if np.count_nonzero(gaps >= 0.0) < n - 1:
            order = np.argsort(ys, kind="stable")
            ys, xs = ys.take(order), xs.take(order)
    lo = ys.searchsorted(ys - tol, side="left")
    hi = ys.searchsorted(ys + tol, side="right")
    span = hi - lo
    width = int(span[span.argmax()]) if n else 0
    mx = 2.0 * axis_x - xs
    tol2 = tol * tol
    if width > MATCH_WINDOW:
        dx = mx[:, None] - xs[None, :]
        dy = ys[:, None] - ys[None, :]
        found = (dx * dx + dy * dy).min(axis=1) <= tol2
    elif width == 1 and tol >= 0.0:  # each robot alone in its window: only itself can match
        found = _sq_diff(xs, mx) <= tol2
    else:
        found = np.zeros(n, dtype=bool)
        for offset in range(width):
            j = lo + offset
            dx = xs.take(j, mode="clip")
            dx -= mx
            dx *= dx
            dy = ys.take(j, mode="clip")
            dy -= ys
            dy *= dy
            dx += dy
            hit = dx <= tol2
            hit &= offset < span
            found |= hit
    if order is None:
        return found
    out = np.empty(n, dtype=bool)
    out[order] = found
    return out


def is_uniform_circle(points: Points, a: float, circle: Circle | None = None) -> bool:
    """True when the centres form a regular n-gon with side >= a (the paper's goal; G10), within
    the tolerance of "settled" (G8): radii within EPS_AT of the SEC's, angular gaps within twice.

    `circle`, if given, must be the SEC of `points` (saves recomputing it).
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n <= 1:
        return True
    if n == 2:
        return bool(np.hypot(*(pts[0] - pts[1])) >= a - EPS_AT_REL * scale(a))
    circle = sec(pts) if circle is None else circle
    tol = EPS_AT_REL * scale(circle.radius)
    cx, cy = circle.center
    # The usual early exit, someone inside, tried first on one robot, by the same operations: the
    # middle one of a canonical form (sorted by height) is rarely on the circle.
    x, y = pts[n // 2].tolist()
    if abs(math.sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy)) - circle.radius) > tol:
        return False
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    off = dx * dx
    off += dy * dy
    off = np.sqrt(off, out=off)
    off -= circle.radius
    off = np.abs(off, out=off)
    if np.count_nonzero(off > tol):  # the usual early exit: someone is inside
        return False
    ang = np.sort(np.arctan2(dy, dx))
    gaps = np.diff(np.append(ang, ang[0] + 2.0 * math.pi))
    # Two neighbours each within tol of their targets (settled, G8) are 2 tol off in their gap:
    # with every robot settled the swarm must count as formed, or nobody could ever end it.
    if (np.abs(gaps - 2.0 * math.pi / n) * circle.radius > 2.0 * tol).any():
        return False
    side = 2.0 * circle.radius * math.sin(math.pi / n)
    return side >= a - tol


def is_formed(points: Points, a: float) -> bool:
    """The goal test of the world and of every robot: `is_uniform_circle` on the canonical form,
    so that it is decided on the same bits as the robots' own G10 test, wherever the swarm is."""
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) <= 1:
        return True
    return is_uniform_circle(canonical(snap(pts)).points, a)


# --- free paths --------------------------------------------------------------------------------


def segment_distances(p: Point, q: Point, others: Points) -> np.ndarray:
    """Distance from every row of `others` to the segment pq."""
    px, py = p
    return _to_segment(others[:, 0] - px, others[:, 1] - py, q[0] - px, q[1] - py)


def _to_segment(ox: np.ndarray, oy: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """Distance of the points (ox, oy) to the segment from the origin to (dx, dy); the points are
    given relative to the segment's start, in arrays this overwrites."""
    len2 = dx * dx + dy * dy
    if len2 == 0.0:
        np.hypot(ox, oy, out=ox)
        return ox
    t = ox * dx
    t += oy * dy
    t /= len2
    # clip to [0, 1] (np.clip's wrapper costs more than these two; a zero's sign, the only
    # difference they could make, is lost in the hypot below)
    np.maximum(t, 0.0, out=t)
    np.minimum(t, 1.0, out=t)
    ox -= t * dx
    oy -= t * dy
    np.hypot(ox, oy, out=ox)
    return ox


def _angle_in_sweep(angles: np.ndarray, start: float, sweep: float) -> np.ndarray:
    """Whether each angle lies on the arc that starts at `start` and turns by `sweep`."""
    if sweep >= 0.0:
        rel = np.mod(angles - start, 2.0 * math.pi)
        return np.asarray(rel <= sweep)
    rel = np.mod(start - angles, 2.0 * math.pi)
    return np.asarray(rel <= -sweep)


def arc_distances(start: Point, arc: Arc, others: Points) -> np.ndarray:
    """Distance from every row of `others` to the arc that starts at `start`."""
    return _to_arc(start, arc, others, None)


def _to_arc(start: Point, arc: Arc, others: Points, from_start: np.ndarray | None) -> np.ndarray:
    """`arc_distances`; `from_start`, if given, holds the distances of `others` from `start`
    (this overwrites it)."""
    cx, cy = arc.center
    radius = math.hypot(start[0] - cx, start[1] - cy)
    ox, oy = others[:, 0] - cx, others[:, 1] - cy
    full = abs(arc.sweep) >= 2.0 * math.pi
    if not full:
        a0 = math.atan2(start[1] - cy, start[0] - cx)
        inside = _angle_in_sweep(np.arctan2(oy, ox), a0, arc.sweep)
    to_circle = np.hypot(ox, oy, out=ox)
    to_circle -= radius
    np.abs(to_circle, out=to_circle)
    if full:
        return to_circle
    if from_start is None:
        from_start = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    end = segment_end(start, arc)
    ex, ey = others[:, 0] - end[0], others[:, 1] - end[1]
    d_ends = np.minimum(from_start, np.hypot(ex, ey, out=ex), out=from_start)
    return np.where(inside, to_circle, d_ends)


def path_distances(start: Point, path: Path, others: Points) -> np.ndarray:
    """Distance from every row of `others` to the whole path (its swept centre line)."""
    best = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    here = start
    for seg in path.segments:
        best = np.minimum(best, _to_piece(here, seg, others), out=best)
        here = segment_end(here, seg)
    return best


def _to_piece(here: Point, seg: Line | Arc, others: Points) -> np.ndarray:
    """Distance from every row of `others` to one segment of a path, starting at `here`."""
    if isinstance(seg, Line):
        return segment_distances(here, seg.end, others)
    return arc_distances(here, seg, others)


def required_clearance(start: Point, others: Points) -> np.ndarray:
    """How close a path from `start` may come to each of `others` (G6 and the tolerance model).

    CONTACT - CLEAR_SLACK, or, for a robot already closer than that (touching within the world's
    overlap slack), its current distance: a path may leave a touching neighbour, never approach it.
    ROUND_ABS absorbs the rounding of the distance computations themselves.
    """
    d0 = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    return _clearance(d0)


def _clearance(d0: np.ndarray) -> np.ndarray:
    need: np.ndarray = np.minimum(d0, CONTACT - CLEAR_SLACK)
    need -= ROUND_ABS
    return need


FAR_ENOUGH = (CONTACT - CLEAR_SLACK) - ROUND_ABS
"""The most `required_clearance` asks of any robot (its rounding is monotonic): a piece of path
that keeps this from every robot is free whatever their start distances."""


def is_free(start: Point, path: Path, others: Points) -> bool:
    """Free path (G6): the unit disc swept along the path, end disc included, meets no other disc.

    The paper's rectangle of width 2 misses the half disc ahead of the destination; the capsule
    (every other centre >= 2 from every point of the path, up to `required_clearance`) is the
    sound version. Starting in contact is allowed.
    """
    m = len(others)
    if m == 0:
        return True
    sx, sy = start
    if not path.segments:
        d0 = np.hypot(others[:, 0] - sx, others[:, 1] - sy)
        return bool(np.count_nonzero(d0 >= _clearance(d0)) == m)
    # Each piece is checked on its own (all(min(a, b) >= c) is all(a >= c) and all(b >= c), NaN
    # included: where a start distance is NaN, so is every distance of the path). The start
    # distances are needed only for a piece that comes closer than FAR_ENOUGH to some robot.
    need: np.ndarray | None = None
    here = start
    for k, seg in enumerate(path.segments):
        if isinstance(seg, Line) and k == 0:
            ox, oy = others[:, 0] - sx, others[:, 1] - sy
            d = _to_segment(ox, oy, seg.end[0] - sx, seg.end[1] - sy)
        elif isinstance(seg, Line):
            d = segment_distances(here, seg.end, others)
        else:
            d = _to_arc(here, seg, others, None)
        if np.count_nonzero(d >= FAR_ENOUGH) < m:
            if need is None:
                need = required_clearance(start, others)
            if np.count_nonzero(d >= need) < m:
                return False
        here = segment_end(here, seg)
    return True


def is_vacant(p: Point, others: Points) -> bool:
    """Vacant point: no part of another robot within the unit disc around p (touching allowed)."""
    if len(others) == 0:
        return True
    d = np.hypot(others[:, 0] - p[0], others[:, 1] - p[1])
    return bool(d.min() >= CONTACT - CLEAR_SLACK)


def path_x_range(start: Point, path: Path) -> tuple[float, float]:
    """Smallest and largest x reached along the path (for the distance of a path to L)."""
    xs = [start[0]]
    here = start
    for seg in path.segments:
        end = segment_end(here, seg)
        xs.append(end[0])
        if isinstance(seg, Arc):
            cx, cy = seg.center
            radius = math.hypot(here[0] - cx, here[1] - cy)
            a0 = math.atan2(here[1] - cy, here[0] - cx)
            if _on_sweep(0.0, a0, seg.sweep):
                xs.append(cx + radius)
            if _on_sweep(math.pi, a0, seg.sweep):
                xs.append(cx - radius)
        here = end
    return min(xs), max(xs)


def _on_sweep(angle: float, start: float, sweep: float) -> bool:
    """`_angle_in_sweep` of one angle (Python's float % is numpy's mod, bit for bit)."""
    if sweep >= 0.0:
        return (angle - start) % (2.0 * math.pi) <= sweep
    return (start - angle) % (2.0 * math.pi) <= -sweep
