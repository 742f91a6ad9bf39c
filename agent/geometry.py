"""Plane geometry the paper uses: smallest enclosing circle, free paths, symmetry about L, targets.

Everything works on centres of unit discs, as `(n, 2)` float64 arrays, in whatever frame the caller
uses: every function here is equivariant under translation and under the mirror x -> -x.
"""

from __future__ import annotations

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


def _circle2(p: Point, q: Point) -> Circle:
    cx, cy = (p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0
    return Circle((cx, cy), math.hypot(p[0] - cx, p[1] - cy))


def _circle3(p: Point, q: Point, s: Point) -> Circle | None:
    """Circumcircle of three points, or None when they are (nearly) collinear."""
    bx, by = q[0] - p[0], q[1] - p[1]
    cx, cy = s[0] - p[0], s[1] - p[1]
    d = 2.0 * (bx * cy - by * cx)
    # Collinear within rounding: the circumcircle is huge or undefined; the diametral circle of the
    # extreme pair then encloses the third point, so dropping the triple loses nothing.
    if abs(d) <= 1e-14 * (bx * bx + by * by + cx * cx + cy * cy):
        return None
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux = (cy * b2 - by * c2) / d
    uy = (bx * c2 - cx * b2) / d
    return Circle((p[0] + ux, p[1] + uy), math.hypot(ux, uy))


def _encloses(circle: Circle, pts: list[Point]) -> bool:
    lim = circle.radius * (1.0 + SEC_SLACK_REL) + 1e-300
    cx, cy = circle.center
    return all(math.hypot(x - cx, y - cy) <= lim for x, y in pts)


def _sec_through(support: list[Point], p: Point) -> tuple[Circle, list[Point]]:
    """Smallest circle enclosing `support` (at most 3 points) and p, where p lies outside the
    smallest circle of `support`: p is then on its boundary (Welzl's lemma), so only circles
    through p are tried. Returns the circle and the points that pin it."""
    pts = [*support, p]
    best: tuple[Circle, list[Point]] | None = None
    for q in support:
        c = _circle2(p, q)
        if (best is None or c.radius < best[0].radius) and _encloses(c, pts):
            best = (c, [p, q])
    for i in range(len(support)):
        for j in range(i + 1, len(support)):
            c3 = _circle3(p, support[i], support[j])
            if (
                c3 is not None
                and (best is None or c3.radius < best[0].radius)
                and _encloses(c3, pts)
            ):
                best = (c3, [p, support[i], support[j]])
    if best is None:  # only rounding gets here: fall back to the farthest pair
        far = max(support, key=lambda q: math.hypot(q[0] - p[0], q[1] - p[1]))
        best = (_circle2(p, far), [p, far])
    return best


def _overshoot(circle: Circle, xs: np.ndarray, ys: np.ndarray) -> float:
    """How far the farthest point lies outside `circle` (<= 0: none does)."""
    cx, cy = circle.center
    return float(np.max(np.hypot(xs - cx, ys - cy))) - circle.radius


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
    if len(pts) == 1:
        return Circle((float(xs[0]), float(ys[0])), 0.0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if float(np.abs(pts).max()) > FAR_FROM_ORIGIN * max(1.0, float((hi - lo).max())):
        # Far from the origin (a world frame at a large offset), the centre's rounding exceeds the
        # relative enclosure slack and the true SEC was refused: work about the box's centre, a
        # point no order or numbering of the points changes. A robot's own frame never gets here.
        mid = (lo + hi) / 2.0
        c = sec(pts - mid)
        return Circle((c.center[0] + float(mid[0]), c.center[1] + float(mid[1])), c.radius)
    # Seed with an approximate diameter: the point farthest from robot 0, then farthest from that.
    i0 = int(np.argmax((xs - xs[0]) ** 2 + (ys - ys[0]) ** 2))
    i1 = int(np.argmax((xs - xs[i0]) ** 2 + (ys - ys[i0]) ** 2))
    support: list[Point] = [(float(xs[i0]), float(ys[i0])), (float(xs[i1]), float(ys[i1]))]
    circle = _circle2(support[0], support[1])
    for _ in range(4 * len(pts) + 16):
        cx, cy = circle.center
        d2 = (xs - cx) ** 2 + (ys - cy) ** 2
        k = int(d2.argmax())
        lim = circle.radius * (1.0 + SEC_SLACK_REL) + 1e-300
        if d2[k] <= lim * lim:
            return circle
        candidate, pinned = _sec_through(support, (float(xs[k]), float(ys[k])))
        if candidate.radius <= circle.radius:  # rounding stalled the growth: of two circles of
            # one radius, the one the points overshoot less (here 9e-9 on a radius of 5.5)
            return min(circle, candidate, key=lambda c: _overshoot(c, xs, ys))
        circle, support = candidate, pinned
    return circle


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
    k = np.arange(n, dtype=np.float64)
    theta = 2.0 * math.pi * k / n + (0.0 if robot_at_o else math.pi / n)
    cx, cy = circle.center
    rad = circle.radius
    return np.stack([cx + rad * np.sin(theta), cy + rad * np.cos(theta)], axis=1)


def robot_at(points: Points, p: Point, tol: float) -> int | None:
    """Index of a robot within `tol` of point p, or None."""
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


def mirror_matched(points: Points, axis_x: float, tol: float) -> np.ndarray:
    """Boolean (n,): robot i has a robot (itself, when on the axis) at its mirror image about x.

    Mirroring keeps Y, so only robots with the same Y (within `tol`) can match: sort by Y and
    compare each robot with the few neighbours in its Y window. O(n log n) unless many robots
    share a Y, where it falls back to all pairs.
    """
    n = len(points)
    order = np.argsort(points[:, 1], kind="stable")
    ys, xs = points[order, 1], points[order, 0]
    lo = np.searchsorted(ys, ys - tol, side="left")
    hi = np.searchsorted(ys, ys + tol, side="right")
    width = int((hi - lo).max()) if n else 0
    mx = 2.0 * axis_x - xs
    if width > MATCH_WINDOW:
        dx = mx[:, None] - xs[None, :]
        dy = ys[:, None] - ys[None, :]
        found = (dx * dx + dy * dy).min(axis=1) <= tol * tol
    else:
        found = np.zeros(n, dtype=bool)
        for offset in range(width):
            j = np.minimum(lo + offset, n - 1)
            ddx, ddy = xs[j] - mx, ys[j] - ys
            found |= (lo + offset < hi) & (ddx * ddx + ddy * ddy <= tol * tol)
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
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    radii = np.sqrt(dx * dx + dy * dy)
    if (np.abs(radii - circle.radius) > tol).any():  # the usual early exit: someone is inside
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
    dx, dy = q[0] - px, q[1] - py
    len2 = dx * dx + dy * dy
    ox, oy = others[:, 0] - px, others[:, 1] - py
    if len2 == 0.0:
        return np.asarray(np.hypot(ox, oy))
    t = np.clip((ox * dx + oy * dy) / len2, 0.0, 1.0)
    return np.asarray(np.hypot(ox - t * dx, oy - t * dy))


def _angle_in_sweep(angles: np.ndarray, start: float, sweep: float) -> np.ndarray:
    """Whether each angle lies on the arc that starts at `start` and turns by `sweep`."""
    if sweep >= 0.0:
        rel = np.mod(angles - start, 2.0 * math.pi)
        return np.asarray(rel <= sweep)
    rel = np.mod(start - angles, 2.0 * math.pi)
    return np.asarray(rel <= -sweep)


def arc_distances(start: Point, arc: Arc, others: Points) -> np.ndarray:
    """Distance from every row of `others` to the arc that starts at `start`."""
    cx, cy = arc.center
    radius = math.hypot(start[0] - cx, start[1] - cy)
    end = segment_end(start, arc)
    ox, oy = others[:, 0] - cx, others[:, 1] - cy
    to_circle = np.abs(np.hypot(ox, oy) - radius)
    a0 = math.atan2(start[1] - cy, start[0] - cx)
    inside = _angle_in_sweep(np.arctan2(oy, ox), a0, arc.sweep)
    if abs(arc.sweep) >= 2.0 * math.pi:
        inside = np.ones(len(others), dtype=bool)
    d_ends = np.minimum(
        np.hypot(others[:, 0] - start[0], others[:, 1] - start[1]),
        np.hypot(others[:, 0] - end[0], others[:, 1] - end[1]),
    )
    return np.asarray(np.where(inside, to_circle, d_ends))


def path_distances(start: Point, path: Path, others: Points) -> np.ndarray:
    """Distance from every row of `others` to the whole path (its swept centre line)."""
    best = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    here = start
    for seg in path.segments:
        d = (
            segment_distances(here, seg.end, others)
            if isinstance(seg, Line)
            else (arc_distances(here, seg, others))
        )
        best = np.minimum(best, d)
        here = segment_end(here, seg)
    return np.asarray(best)


def required_clearance(start: Point, others: Points) -> np.ndarray:
    """How close a path from `start` may come to each of `others` (G6 and the tolerance model).

    CONTACT - CLEAR_SLACK, or, for a robot already closer than that (touching within the world's
    overlap slack), its current distance: a path may leave a touching neighbour, never approach it.
    ROUND_ABS absorbs the rounding of the distance computations themselves.
    """
    d0 = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    return np.asarray(np.minimum(d0, CONTACT - CLEAR_SLACK) - ROUND_ABS)


def is_free(start: Point, path: Path, others: Points) -> bool:
    """Free path (G6): the unit disc swept along the path, end disc included, meets no other disc.

    The paper's rectangle of width 2 misses the half disc ahead of the destination; the capsule
    (every other centre >= 2 from every point of the path, up to `required_clearance`) is the
    sound version. Starting in contact is allowed.
    """
    if len(others) == 0:
        return True
    need = required_clearance(start, others)
    return bool((path_distances(start, path, others) >= need).all())


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
            extremes = np.array([0.0, math.pi])
            hit = _angle_in_sweep(extremes, a0, seg.sweep)
            if hit[0]:
                xs.append(cx + radius)
            if hit[1]:
                xs.append(cx - radius)
        here = end
    return min(xs), max(xs)
