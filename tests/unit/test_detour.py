"""The detour planner: shortest free paths among disc obstacles, or None when there is none."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fatswarm.agent.detour import shortest_free_path
from fatswarm.agent.geometry import path_distances, segment_distances
from fatswarm.domain.path import (
    Arc,
    Line,
    Path,
    Point,
    end_point,
    mirror,
    path_length,
    segment_length,
)

TOL = 1e-9


def assert_free(
    start: Point,
    target: Point,
    path: Path,
    centres: np.ndarray,
    radii: np.ndarray,
    tol: float = TOL,
) -> None:
    """The contract, checked independently: exact clearance of the centre line, end at target."""
    end = end_point(start, path)
    assert math.hypot(end[0] - target[0], end[1] - target[1]) <= 1e-9
    if len(centres):
        assert (path_distances(start, path, centres) >= radii - tol).all()
    here = start
    for seg in path.segments:  # no zero-length segments
        assert segment_length(here, seg) > 0.0
        here = end_point(here, Path((seg,)))


def straight_is_free(start: Point, target: Point, centres: np.ndarray, radii: np.ndarray) -> bool:
    return not len(centres) or bool(
        (segment_distances(start, target, centres) >= radii - TOL).all()
    )


def slide_length(start: Point, target: Point, centre: Point, radius: float) -> float:
    """Closed form: the shorter tangent-arc-tangent way around one circle."""
    ds = math.dist(start, centre)
    dt = math.dist(target, centre)
    a_s = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a_t = math.atan2(target[1] - centre[1], target[0] - centre[0])
    between = abs((a_t - a_s + math.pi) % (2 * math.pi) - math.pi)  # angle start-centre-target
    arc = between - math.acos(radius / ds) - math.acos(radius / dt)
    return (
        math.sqrt(ds * ds - radius * radius) + math.sqrt(dt * dt - radius * radius) + radius * arc
    )


def ring(n: int, side: float, vacant: set[int]) -> tuple[np.ndarray, float]:
    """Centres of robots settled on a regular n-gon of the given side, but for `vacant` ones."""
    radius = side / (2 * math.sin(math.pi / n))
    ang = 2 * math.pi * np.arange(n) / n
    pts = np.stack([radius * np.cos(ang), radius * np.sin(ang)], axis=1)
    return pts[[k for k in range(n) if k not in vacant]], radius


# --- worked cases ------------------------------------------------------------------------------


def test_straight_segment_when_nothing_is_in_the_way() -> None:
    centres = np.array([[0.0, 5.0], [3.0, -4.0]])
    path = shortest_free_path((-5.0, 0.0), (5.0, 1.0), centres, np.full(2, 2.0), tol=TOL)
    assert path == Path((Line((5.0, 1.0)),))
    assert shortest_free_path((1.0, 2.0), (3.0, 4.0), np.empty((0, 2)), np.empty(0), tol=TOL) == (
        Path((Line((3.0, 4.0)),))
    )


def test_staying_put_is_the_empty_path() -> None:
    assert (
        shortest_free_path((1.0, 2.0), (1.0, 2.0), np.array([[5.0, 5.0]]), np.array([2.0]), tol=TOL)
        == Path()
    )


@pytest.mark.parametrize(
    ("start", "target", "centre", "radius"),
    [
        ((-6.0, 0.0), (6.0, 0.0), (0.0, 0.3), 2.0),
        ((-3.0, -1.0), (7.0, 2.5), (2.0, 0.4), 2.0),
        ((-2.5, 0.5), (2.1, -0.4), (0.0, 0.0), 1.9),
    ],
)
def test_one_obstacle_is_rounded_by_tangent_arc_tangent(
    start: Point, target: Point, centre: Point, radius: float
) -> None:
    centres, radii = np.array([centre]), np.array([radius])
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    assert path is not None
    assert_free(start, target, path, centres, radii)
    assert [type(s) for s in path.segments] == [Line, Arc, Line]
    assert path_length(start, path) == pytest.approx(
        slide_length(start, target, centre, radius), abs=1e-8
    )


def test_start_and_target_on_an_obstacle_go_half_way_round_it() -> None:
    centres, radii = np.array([[0.0, 0.0]]), np.array([2.0])
    path = shortest_free_path((-2.0, 0.0), (2.0, 0.0), centres, radii, tol=TOL)
    assert path is not None
    assert_free((-2.0, 0.0), (2.0, 0.0), path, centres, radii)
    assert len(path) == 1 and isinstance(path.segments[0], Arc)
    assert path_length((-2.0, 0.0), path) == pytest.approx(2.0 * math.pi, abs=1e-9)


def single_slides(start: Point, target: Point, centre: Point, radius: float) -> list[Path]:
    """The reference algorithm's other option: tangent, arc round one obstacle, line, both ways."""
    ds, dt = math.dist(start, centre), math.dist(target, centre)
    a_s = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a_t = math.atan2(target[1] - centre[1], target[0] - centre[0])
    out = []
    for sense in (1.0, -1.0):
        a = a_s + sense * math.acos(radius / ds)
        b = a_t - sense * math.acos(radius / dt)
        sweep = sense * ((sense * (b - a)) % (2 * math.pi))
        touch = (centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a))
        out.append(Path((Line(touch), Arc(centre, sweep), Line(target))))
    return out


@pytest.mark.parametrize("side", [4.0, 4.0 - 1e-6, 4.0 + 1e-3])
def test_ring_deadlock_reaches_the_vacant_target_several_places_away(side: float) -> None:
    # Robots settled on a 16-gon of side ~4 (touching, overlapping, or with a hair of a gap);
    # the mover sits in the notch between robots 0 and 1, just inside the ring, and heads for
    # vacant vertex 3. The chord and both slides round its first blocker hit ring members.
    n, vacant = 16, 3
    centres, big_r = ring(n, side, {vacant})
    radii = np.full(len(centres), 2.0)
    mid = math.pi / n
    inner = big_r * math.cos(mid) - 0.3
    start = (inner * math.cos(mid), inner * math.sin(mid))
    assert (np.hypot(*(centres - start).T) >= 2.0).all()
    ang = 2 * math.pi * vacant / n
    target = (big_r * math.cos(ang), big_r * math.sin(ang))
    assert not straight_is_free(start, target, centres, radii)
    hit = np.flatnonzero(segment_distances(start, target, centres) < 2.0)
    first = centres[hit[np.argmin((centres[hit] - start) @ np.subtract(target, start))]]
    for slide in single_slides(start, target, (float(first[0]), float(first[1])), 2.0):
        assert (path_distances(start, slide, centres) < 2.0 - TOL).any()
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    assert path is not None
    assert_free(start, target, path, centres, radii)
    assert path_length(start, path) < math.dist(start, target) + 1.0


def test_touching_ring_has_no_gap_to_squeeze_through() -> None:
    # With every vertex taken, the mover inside a touching ring cannot get out: gaps of width 0
    # between robots are closed, however tempting the pinch point is.
    centres, big_r = ring(12, 4.0, set())
    radii = np.full(len(centres), 2.0)
    path = shortest_free_path((0.5, 0.0), (big_r + 5.0, 0.1), centres, radii, tol=TOL)
    assert path is None


def test_enclosed_start_has_no_path() -> None:
    centres, _ = ring(10, 3.5, set())  # overlapping discs
    radii = np.full(len(centres), 2.0)
    assert shortest_free_path((0.3, -0.2), (20.0, 3.0), centres, radii, tol=TOL) is None


def test_enclosed_target_has_no_path() -> None:
    centres, _ = ring(10, 3.5, set())
    field = np.array([[x, y] for x in range(-20, 21, 5) for y in (-15, 15)], dtype=np.float64)
    centres = np.vstack([centres, field])
    radii = np.full(len(centres), 2.0)
    assert shortest_free_path((25.0, 3.0), (0.3, -0.2), centres, radii, tol=TOL) is None


def test_target_inside_an_obstacle_has_no_path() -> None:
    centres, radii = np.array([[0.0, 0.0], [5.0, 5.0]]), np.array([2.0, 2.0])
    assert shortest_free_path((-5.0, 0.0), (5.5, 4.0), centres, radii, tol=TOL) is None
    assert shortest_free_path((-5.0, 0.0), (2.0 - 2e-9, 0.0), centres, radii, tol=TOL) is None


def test_start_touching_two_neighbours_finds_a_way_out() -> None:
    # The mover touches robots at (2, 0) and (0, 2) (centre distance exactly 2) and must go
    # round them to reach (3, 3).
    centres = np.array([[2.0, 0.0], [0.0, 2.0], [-2.5, -1.0]])
    radii = np.full(3, 2.0)
    start, target = (0.0, 0.0), (3.0, 3.0)
    assert not straight_is_free(start, target, centres, radii)
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    assert path is not None
    assert_free(start, target, path, centres, radii)


def test_start_touching_with_lowered_radii_finds_a_way_out() -> None:
    # As the caller does for neighbours already touched: radius = current (rounded) distance.
    centres = np.array([[1.7, -1.0536], [-0.3, 1.977], [4.0, 4.0]])
    start, target = (0.0, 0.0), (6.0, 1.0)
    radii = np.minimum(2.0, np.hypot(centres[:, 0], centres[:, 1]))
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    assert path is not None
    assert_free(start, target, path, centres, radii)


def test_bad_input_is_refused_with_a_reason() -> None:
    with pytest.raises(ValueError, match="centres must be"):
        shortest_free_path((0.0, 0.0), (1.0, 1.0), np.zeros((2, 3)), np.ones(2), tol=TOL)
    with pytest.raises(ValueError, match="tol"):
        shortest_free_path((0.0, 0.0), (1.0, 1.0), np.zeros((1, 2)), np.ones(1), tol=0.0)
    with pytest.raises(ValueError, match="larger than tol"):
        shortest_free_path((0.0, 0.0), (1.0, 1.0), np.zeros((1, 2)), np.zeros(1), tol=TOL)


# --- properties --------------------------------------------------------------------------------

coord = st.floats(min_value=-8.0, max_value=8.0, allow_nan=False)
obstacle = st.tuples(coord, coord, st.floats(min_value=0.8, max_value=2.4))


@st.composite
def scenes(draw: st.DrawFn) -> tuple[Point, Point, np.ndarray, np.ndarray]:
    """Obstacle fields (overlaps allowed) with a valid start, sometimes touching an obstacle."""
    obs = draw(st.lists(obstacle, min_size=1, max_size=10))
    centres = np.array([o[:2] for o in obs], dtype=np.float64)
    radii = np.array([o[2] for o in obs], dtype=np.float64)
    start = (draw(coord), draw(coord))
    if draw(st.booleans()):  # put the start on the circle of one obstacle
        j = draw(st.integers(0, len(obs) - 1))
        ang = draw(st.floats(min_value=-math.pi, max_value=math.pi))
        start = (centres[j, 0] + radii[j] * math.cos(ang), centres[j, 1] + radii[j] * math.sin(ang))
    assume((np.hypot(*(centres - start).T) >= radii - TOL).all())
    target = (draw(coord), draw(coord))
    return start, target, centres, radii


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(scenes())
def test_any_path_returned_is_free_and_straight_when_the_segment_is(
    scene: tuple[Point, Point, np.ndarray, np.ndarray],
) -> None:
    start, target, centres, radii = scene
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    if path is not None:
        assert_free(start, target, path, centres, radii)
    if straight_is_free(start, target, centres, radii):
        assert path is not None
        assert path_length(start, path) == pytest.approx(math.dist(start, target), abs=1e-9)


GRID_CELL = 0.4
GRID_CLEAR = 0.3  # > half a diagonal step (0.283): moves between free cells keep radius clear


def grid_path_length(
    start: Point, target: Point, centres: np.ndarray, radii: np.ndarray
) -> float | None:
    """Oracle: length of a free path over a coarse grid (8-neighbour moves between cells clear
    of every disc by GRID_CLEAR), joined to start and target by free segments; None if none."""
    axis = np.arange(-14.0, 14.0 + 1e-9, GRID_CELL)
    gx, gy = np.meshgrid(axis, axis, indexing="ij")
    pts = np.stack([gx.ravel(), gy.ravel()], axis=1)
    d = np.hypot(pts[:, None, 0] - centres[None, :, 0], pts[:, None, 1] - centres[None, :, 1])
    free = (d >= radii + GRID_CLEAR).all(axis=1).reshape(gx.shape)
    size = len(axis)

    def joins(p: Point) -> list[tuple[float, int, int]]:
        near = np.flatnonzero(free.ravel() & (np.hypot(*(pts - p).T) <= 1.5))
        return [
            (math.dist(p, pts[i]), int(i) // size, int(i) % size)
            for i in near
            if straight_is_free(p, (float(pts[i, 0]), float(pts[i, 1])), centres, radii)
        ]

    ends = {(i, j): dist for dist, i, j in joins(target)}
    best = dict(((i, j), dist) for dist, i, j in joins(start))
    heap = [(dist, i, j) for (i, j), dist in best.items()]
    heapq.heapify(heap)
    found = math.inf
    while heap:
        dist, i, j = heapq.heappop(heap)
        if dist > best[(i, j)] or dist >= found:
            continue
        if (i, j) in ends:
            found = min(found, dist + ends[(i, j)])
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                a, b = i + di, j + dj
                if (di or dj) and 0 <= a < size and 0 <= b < size and free[a, b]:
                    nd = dist + GRID_CELL * math.hypot(di, dj)
                    if nd < best.get((a, b), math.inf):
                        best[(a, b)] = nd
                        heapq.heappush(heap, (nd, a, b))
    return None if found == math.inf else found


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(scenes())
def test_finds_a_path_whenever_a_grid_does_and_no_longer_than_it(
    scene: tuple[Point, Point, np.ndarray, np.ndarray],
) -> None:
    start, target, centres, radii = scene
    assume(not straight_is_free(start, target, centres, radii))
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    grid = grid_path_length(start, target, centres, radii)
    if grid is not None:
        assert path is not None
        assert path_length(start, path) <= grid + 1e-9


def generic_scene(seed: int) -> tuple[Point, Point, np.ndarray, np.ndarray]:
    """A seeded scene whose shortest path is not straight (no symmetry, so no ties)."""
    rng = np.random.default_rng(seed)
    while True:
        m = int(rng.integers(4, 30))
        centres = rng.uniform(-10.0, 10.0, (m, 2))
        radii = rng.uniform(1.0, 2.4, m)
        start = (float(rng.uniform(-12, 12)), float(rng.uniform(-12, 12)))
        target = (float(rng.uniform(-12, 12)), float(rng.uniform(-12, 12)))
        if (np.hypot(*(centres - start).T) < radii).any() or straight_is_free(
            start, target, centres, radii
        ):
            continue
        if shortest_free_path(start, target, centres, radii, tol=TOL) is not None:
            return start, target, centres, radii


@pytest.mark.parametrize("seed", range(12))
def test_mirrored_scene_gives_the_mirrored_path(seed: int) -> None:
    start, target, centres, radii = generic_scene(seed)
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    flipped = shortest_free_path(
        (-start[0], start[1]), (-target[0], target[1]), centres * [-1.0, 1.0], radii, tol=TOL
    )
    assert path is not None and flipped == mirror(path)


@pytest.mark.parametrize("seed", range(12))
def test_order_of_the_obstacles_does_not_matter(seed: int) -> None:
    start, target, centres, radii = generic_scene(seed)
    path = shortest_free_path(start, target, centres, radii, tol=TOL)
    order = np.random.default_rng(seed + 1000).permutation(len(radii))
    assert shortest_free_path(start, target, centres[order], radii[order], tol=TOL) == path


def test_exact_ties_are_broken_the_same_way_whatever_the_order() -> None:
    # Symmetric scene: going left or right of the obstacle is equally short.
    centres = np.array([[0.0, 0.0], [0.0, 9.0], [0.0, -9.0]])
    radii = np.array([2.0, 1.0, 1.0])
    first = shortest_free_path((0.0, -5.0), (0.0, 5.0), centres, radii, tol=TOL)
    again = shortest_free_path(
        (0.0, -5.0), (0.0, 5.0), centres[::-1].copy(), radii[::-1].copy(), tol=TOL
    )
    assert first is not None and first == again
