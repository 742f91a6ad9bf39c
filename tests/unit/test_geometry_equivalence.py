"""The fast passes of agent/geometry.py give the very bits of the plain versions they replaced.

The oracles below are the earlier implementations, kept verbatim: each test draws inputs (random,
on the grid, lattices, mirror pairs, circles, far offsets, degenerate and non-finite ones) and
compares every float of the answers, so that a plan can never change because a pass got faster.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent import geometry
from fatswarm.agent.geometry import Circle
from fatswarm.domain.path import Arc, Line, Path, Point, Points, segment_end
from fatswarm.domain.tolerance import (
    CLEAR_SLACK,
    CONTACT,
    EPS_AT_REL,
    ROUND_ABS,
    SEC_SLACK_REL,
    scale,
)

# --- the oracles: the plain versions ------------------------------------------------------------


def _circle2(p: Point, q: Point) -> Circle:
    cx, cy = (p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0
    return Circle((cx, cy), math.hypot(p[0] - cx, p[1] - cy))


def _circle3(p: Point, q: Point, s: Point) -> Circle | None:
    bx, by = q[0] - p[0], q[1] - p[1]
    cx, cy = s[0] - p[0], s[1] - p[1]
    d = 2.0 * (bx * cy - by * cx)
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
    if best is None:
        far = max(support, key=lambda q: math.hypot(q[0] - p[0], q[1] - p[1]))
        best = (_circle2(p, far), [p, far])
    return best


def _overshoot(circle: Circle, xs: np.ndarray, ys: np.ndarray) -> float:
    cx, cy = circle.center
    return float(np.max(np.hypot(xs - cx, ys - cy))) - circle.radius


def plain_sec(points: Points) -> Circle:
    pts = np.asarray(points, dtype=np.float64)
    xs, ys = pts[:, 0], pts[:, 1]
    if len(pts) == 1:
        return Circle((float(xs[0]), float(ys[0])), 0.0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if float(np.abs(pts).max()) > geometry.FAR_FROM_ORIGIN * max(1.0, float((hi - lo).max())):
        mid = (lo + hi) / 2.0
        c = plain_sec(pts - mid)
        return Circle((c.center[0] + float(mid[0]), c.center[1] + float(mid[1])), c.radius)
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
        if candidate.radius <= circle.radius:
            return min(circle, candidate, key=lambda c: _overshoot(c, xs, ys))
        circle, support = candidate, pinned
    return circle


def plain_targets_on(circle: Circle, n: int, robot_at_o: bool) -> Points:
    k = np.arange(n, dtype=np.float64)
    theta = 2.0 * math.pi * k / n + (0.0 if robot_at_o else math.pi / n)
    cx, cy = circle.center
    rad = circle.radius
    return np.stack([cx + rad * np.sin(theta), cy + rad * np.cos(theta)], axis=1)


def plain_mirror_matched(points: Points, axis_x: float, tol: float) -> np.ndarray:
    n = len(points)
    order = np.argsort(points[:, 1], kind="stable")
    ys, xs = points[order, 1], points[order, 0]
    lo = np.searchsorted(ys, ys - tol, side="left")
    hi = np.searchsorted(ys, ys + tol, side="right")
    width = int((hi - lo).max()) if n else 0
    mx = 2.0 * axis_x - xs
    if width > geometry.MATCH_WINDOW:
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


def plain_is_uniform_circle(points: Points, a: float, circle: Circle | None = None) -> bool:
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n <= 1:
        return True
    if n == 2:
        return bool(np.hypot(*(pts[0] - pts[1])) >= a - EPS_AT_REL * scale(a))
    circle = plain_sec(pts) if circle is None else circle
    tol = EPS_AT_REL * scale(circle.radius)
    cx, cy = circle.center
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    radii = np.sqrt(dx * dx + dy * dy)
    if (np.abs(radii - circle.radius) > tol).any():
        return False
    ang = np.sort(np.arctan2(dy, dx))
    gaps = np.diff(np.append(ang, ang[0] + 2.0 * math.pi))
    if (np.abs(gaps - 2.0 * math.pi / n) * circle.radius > 2.0 * tol).any():
        return False
    side = 2.0 * circle.radius * math.sin(math.pi / n)
    return side >= a - tol


def plain_segment_distances(p: Point, q: Point, others: Points) -> np.ndarray:
    px, py = p
    dx, dy = q[0] - px, q[1] - py
    len2 = dx * dx + dy * dy
    ox, oy = others[:, 0] - px, others[:, 1] - py
    if len2 == 0.0:
        return np.asarray(np.hypot(ox, oy))
    t = np.clip((ox * dx + oy * dy) / len2, 0.0, 1.0)
    return np.asarray(np.hypot(ox - t * dx, oy - t * dy))


def _angle_in_sweep(angles: np.ndarray, start: float, sweep: float) -> np.ndarray:
    if sweep >= 0.0:
        rel = np.mod(angles - start, 2.0 * math.pi)
        return np.asarray(rel <= sweep)
    rel = np.mod(start - angles, 2.0 * math.pi)
    return np.asarray(rel <= -sweep)


def plain_arc_distances(start: Point, arc: Arc, others: Points) -> np.ndarray:
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


def plain_path_distances(start: Point, path: Path, others: Points) -> np.ndarray:
    best = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    here = start
    for seg in path.segments:
        d = (
            plain_segment_distances(here, seg.end, others)
            if isinstance(seg, Line)
            else (plain_arc_distances(here, seg, others))
        )
        best = np.minimum(best, d)
        here = segment_end(here, seg)
    return np.asarray(best)


def plain_path_x_range(start: Point, path: Path) -> tuple[float, float]:
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


def plain_robot_at(points: Points, p: Point, tol: float) -> int | None:
    d = np.hypot(points[:, 0] - p[0], points[:, 1] - p[1])
    k = int(d.argmin())
    return k if d[k] <= tol else None


def plain_required_clearance(start: Point, others: Points) -> np.ndarray:
    d0 = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    return np.asarray(np.minimum(d0, CONTACT - CLEAR_SLACK) - ROUND_ABS)


def plain_is_free(start: Point, path: Path, others: Points) -> bool:
    if len(others) == 0:
        return True
    need = plain_required_clearance(start, others)
    return bool((plain_path_distances(start, path, others) >= need).all())


# --- comparing bits ----------------------------------------------------------------------------


def same_circle(a: Circle, b: Circle) -> bool:
    return [float(v).hex() for v in (*a.center, a.radius)] == [
        float(v).hex() for v in (*b.center, b.radius)
    ]


def same_array(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


# --- inputs -------------------------------------------------------------------------------------

GRID = 2.0**-30


def _cloud(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random configuration of one of several shapes, sometimes on the grid."""
    shape = int(rng.integers(9))
    if shape == 0:  # uniform in a box of random size
        pts = rng.uniform(-1.0, 1.0, (n, 2)) * 10.0 ** rng.uniform(-1, 4)
    elif shape == 1:  # points on a circle (exact ties of distance, the stalled-growth case)
        ang = rng.uniform(0.0, 2.0 * math.pi, n)
        r = 10.0 ** rng.uniform(0, 3)
        pts = np.column_stack([r * np.cos(ang), r * np.sin(ang)]) + rng.uniform(-5, 5, 2)
    elif shape == 2:  # a regular polygon, maybe rotated, maybe perturbed
        ang = 2.0 * math.pi * np.arange(n) / n + rng.uniform(0, 1) * (rng.random() < 0.5)
        pts = 10.0 * np.column_stack([np.sin(ang), np.cos(ang)])
        pts += rng.normal(0, 1e-7, (n, 2)) * (rng.random() < 0.5)
    elif shape == 3:  # a square lattice with duplicate rows and columns
        side = max(1, math.isqrt(n))
        cells = np.array([(i % side, i // side) for i in range(n)], dtype=np.float64)
        pts = 2.0 * cells
    elif shape == 4:  # mirror pairs about x = c, some on the axis, some nudged
        c = float(rng.integers(-5, 5))
        half = rng.uniform(0.5, 20, (n // 2, 2))
        mirrored = np.column_stack([c - half[:, 0], half[:, 1]])
        pts = np.vstack([half + np.array([c, 0.0]), mirrored])
        if n % 2:
            pts = np.vstack([pts, (c, rng.uniform(-20, 20))])
        pts[int(rng.integers(n))] += rng.normal(0, 1e-9, 2) * (rng.random() < 0.5)
    elif shape == 5:  # collinear, vertical or slanted
        t = np.sort(rng.uniform(-30, 30, n))
        d = rng.normal(size=2) * (rng.random() < 0.5) + (0.0, 1.0)
        pts = np.column_stack([t * d[0], t * d[1]])
    elif shape == 6:  # far from the origin (sec works about the box centre)
        pts = rng.uniform(-10, 10, (n, 2)) + rng.uniform(1e4, 1e6, 2)
    elif shape == 7:  # a tight cluster with exact duplicates
        pts = np.round(rng.normal(0, 3, (n, 2)))
    else:  # the canonical form: first at the origin, sorted by (y, x)
        pts = rng.uniform(-40, 40, (n, 2))
        pts = pts[np.lexsort((pts[:, 0], pts[:, 1]))]
        pts -= pts[0]
    if rng.random() < 0.5:
        pts = np.rint(pts / GRID) * GRID + 0.0
    return np.ascontiguousarray(pts, dtype=np.float64)


def _clouds(seed: int, count: int, n_max: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [_cloud(rng, int(rng.integers(1, n_max + 1))) for _ in range(count)]


def _path(rng: np.random.Generator, start: Point) -> Path:
    """One to three lines and arcs from `start`, zero-length and full turns included."""
    segs: list[Line | Arc] = []
    here = start
    for _ in range(int(rng.integers(1, 4))):
        kind = int(rng.integers(5))
        if kind == 0:  # zero-length line
            seg: Line | Arc = Line(here)
        elif kind in (1, 2):
            seg = Line((here[0] + rng.normal(0, 8), here[1] + rng.normal(0, 8)))
        else:
            sweep = float(rng.choice([rng.uniform(-7, 7), 2 * math.pi, -2 * math.pi, 0.0]))
            seg = Arc((here[0] + rng.normal(0, 5), here[1] + rng.normal(0, 5)), sweep)
        segs.append(seg)
        here = segment_end(here, seg)
    return Path(tuple(segs))


# --- the tests ------------------------------------------------------------------------------------


def test_sec_gives_the_plain_bits() -> None:
    for pts in _clouds(1, 3000, 80) + _clouds(2, 60, 400):
        assert same_circle(geometry.sec(pts), plain_sec(pts)), pts.tolist()


coords = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(coords, coords), min_size=1, max_size=12))
def test_sec_gives_the_plain_bits_on_drawn_points(raw: list[tuple[float, float]]) -> None:
    pts = np.array(raw, dtype=np.float64)
    assert same_circle(geometry.sec(pts), plain_sec(pts))


def test_sec_stays_plain_on_points_far_away_and_non_finite() -> None:
    far = np.array([[3e6, 1.0], [3e6 + 4.0, 1.0], [3e6 + 2.0, 5.0]])
    assert same_circle(geometry.sec(far), plain_sec(far))
    with np.errstate(invalid="ignore", over="ignore"):
        for bad in (
            np.array([[0.0, 0.0], [np.nan, 1.0], [2.0, 0.0]]),
            np.array([[0, 0], [np.inf, 1]]),
        ):
            a, b = geometry.sec(bad), plain_sec(bad)
            assert repr(a) == repr(b)


def test_targets_on_gives_the_plain_bits() -> None:
    rng = np.random.default_rng(3)
    for n in range(1, 300):
        circle = Circle(
            (float(rng.normal(0, 50)), float(rng.normal(0, 50))), float(rng.uniform(1, 300))
        )
        for at_o in (True, False):
            assert same_array(
                geometry.targets_on(circle, n, at_o), plain_targets_on(circle, n, at_o)
            )


def test_mirror_matched_gives_the_plain_bits() -> None:
    rng = np.random.default_rng(4)
    for pts in _clouds(5, 3000, 80):
        if not len(pts):
            continue
        axis = float(rng.choice([0.0, float(rng.integers(-5, 5)), float(np.median(pts[:, 0]))]))
        tol = float(rng.choice([1e-6, 1e-6 * max(1.0, float(np.ptp(pts))), 0.0, 3.0, 50.0]))
        assert same_array(
            geometry.mirror_matched(pts, axis, tol), plain_mirror_matched(pts, axis, tol)
        )


@pytest.mark.parametrize("tol", [-1.0, -1e-300, math.nan, math.inf])
def test_mirror_matched_stays_plain_for_odd_tolerances(tol: float) -> None:
    for pts in _clouds(6, 200, 30):
        with np.errstate(invalid="ignore"):
            assert same_array(
                geometry.mirror_matched(pts, 0.5, tol), plain_mirror_matched(pts, 0.5, tol)
            )


def test_is_uniform_circle_gives_the_plain_answer() -> None:
    rng = np.random.default_rng(7)
    for pts in _clouds(8, 3000, 60):
        a = float(rng.choice([3.2, 4.0, 6.0]))
        assert geometry.is_uniform_circle(pts, a) == plain_is_uniform_circle(pts, a)


def test_free_path_passes_give_the_plain_bits() -> None:
    rng = np.random.default_rng(9)
    for pts in _clouds(10, 1500, 60):
        if len(pts) < 2:
            continue
        start = (float(pts[0, 0]), float(pts[0, 1]))
        others = pts[1:]
        path = _path(rng, start)
        seg = path.segments[0]
        assert same_array(
            geometry.path_distances(start, path, others),
            plain_path_distances(start, path, others),
        )
        assert same_array(
            geometry.required_clearance(start, others), plain_required_clearance(start, others)
        )
        if isinstance(seg, Line):
            assert same_array(
                geometry.segment_distances(start, seg.end, others),
                plain_segment_distances(start, seg.end, others),
            )
        else:
            assert same_array(
                geometry.arc_distances(start, seg, others),
                plain_arc_distances(start, seg, others),
            )
        assert geometry.is_free(start, path, others) == plain_is_free(start, path, others)


def test_is_free_stays_plain_near_contact_and_on_non_finite_neighbours() -> None:
    rng = np.random.default_rng(11)
    start = (0.0, 0.0)
    for _ in range(2000):
        m = int(rng.integers(0, 6))
        ang = rng.uniform(0, 2 * math.pi, m)
        dist = CONTACT + rng.choice([-1e-7, -1e-8, -1e-10, 0.0, 1e-10, 1e-8, 1.0], m)
        others = np.column_stack([dist * np.cos(ang), dist * np.sin(ang)])
        if m and rng.random() < 0.2:
            others[int(rng.integers(m)), int(rng.integers(2))] = rng.choice([np.nan, np.inf])
        path = _path(rng, start) if rng.random() < 0.9 else Path()
        with np.errstate(invalid="ignore", over="ignore"):
            assert geometry.is_free(start, path, others) == plain_is_free(start, path, others)


def test_path_x_range_gives_the_plain_bits() -> None:
    rng = np.random.default_rng(12)
    for _ in range(5000):
        start = (float(rng.normal(0, 10)), float(rng.normal(0, 10)))
        path = _path(rng, start)
        got, want = geometry.path_x_range(start, path), plain_path_x_range(start, path)
        assert [v.hex() for v in got] == [v.hex() for v in want]


def test_robot_at_gives_the_plain_answer() -> None:
    rng = np.random.default_rng(13)
    for pts in _clouds(14, 3000, 60):
        circle = plain_sec(pts)
        tol = EPS_AT_REL * scale(circle.radius)
        near = pts[int(rng.integers(len(pts)))] + rng.choice([0.0, 0.5, 1.0, 2.0]) * tol
        for p in (geometry.north_point(circle), (float(near[0]), float(near[1]))):
            for t in (tol, 0.0, 1.0):
                assert geometry.robot_at(pts, p, t) == plain_robot_at(pts, p, t)
    with np.errstate(invalid="ignore"):
        odd = np.array([[0.0, 0.0], [np.nan, 5.0], [1.0, np.nan], [2.0, np.inf]])
        for p in ((0.0, 10.0), (0.0, np.inf), (np.nan, 0.0), (1.0, 0.0)):
            assert geometry.robot_at(odd, p, 1e-6) == plain_robot_at(odd, p, 1e-6)
